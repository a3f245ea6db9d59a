//! Errors of reading and checking a protocol file.

use std::path::PathBuf;

/// One invalid key of a protocol and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key} {problem}")]
pub struct InvalidKey {
    /// Dotted path of the key in the protocol file, e.g. `schedule.trials`.
    pub key: String,
    /// What is wrong, e.g. `must be > 0, got 0`.
    pub problem: String,
}

/// Why a protocol could not be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProtocolError {
    /// The file could not be read.
    #[error("cannot read protocol {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not valid TOML or does not match the protocol's keys (an unknown or
    /// misspelt key, a wrong type). The message names the key and the line.
    #[error("{path}: {message}")]
    Parse {
        /// The file (or `<embedded>` for a built-in protocol).
        path: PathBuf,
        /// The TOML error, with line, column and key.
        message: String,
    },
    /// The file parsed, but some values are out of range.
    #[error("{path}: invalid protocol: {}", join(.errors))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Every invalid key (never empty).
        errors: Vec<InvalidKey>,
    },
}

fn join(errors: &[InvalidKey]) -> String {
    errors
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

impl ProtocolError {
    /// True if the error names `key` (a dotted path), as an invalid value or in the
    /// parser's message.
    #[must_use]
    pub fn names(&self, key: &str) -> bool {
        match self {
            ProtocolError::Invalid { errors, .. } => errors.iter().any(|e| e.key == key),
            ProtocolError::Parse { message, .. } => message.contains(key),
            ProtocolError::Read { .. } => false,
        }
    }
}

/// Collects invalid keys while a protocol is checked.
#[derive(Debug, Default)]
pub(crate) struct Checker {
    pub(crate) errors: Vec<InvalidKey>,
}

impl Checker {
    pub(crate) fn fail(&mut self, key: impl Into<String>, problem: impl Into<String>) {
        self.errors.push(InvalidKey {
            key: key.into(),
            problem: problem.into(),
        });
    }

    pub(crate) fn finite(&mut self, key: &str, v: f64) -> bool {
        if v.is_finite() {
            true
        } else {
            self.fail(key, format!("must be finite, got {v}"));
            false
        }
    }

    pub(crate) fn positive(&mut self, key: &str, v: f64) {
        if self.finite(key, v) && v <= 0.0 {
            self.fail(key, format!("must be > 0, got {v}"));
        }
    }

    pub(crate) fn non_negative(&mut self, key: &str, v: f64) {
        if self.finite(key, v) && v < 0.0 {
            self.fail(key, format!("must be >= 0, got {v}"));
        }
    }

    /// `v` seconds must be a whole number of 4 kHz ticks.
    pub(crate) fn whole_ticks(&mut self, key: &str, v: f64) {
        if v.is_finite() {
            let ticks = v * crate::rehearse::TICK_HZ as f64;
            if (ticks - ticks.round()).abs() > 1e-6 {
                self.fail(
                    key,
                    format!("must be a whole number of 4 kHz ticks (0.25 ms), got {v} s"),
                );
            }
        }
    }

    pub(crate) fn inside(&mut self, key: &str, v: f64, half_width_m: f64) {
        if self.finite(key, v) && v.abs() >= half_width_m {
            self.fail(
                key,
                format!("must lie inside the walls at ±{half_width_m} m, got {v}"),
            );
        }
    }
}
