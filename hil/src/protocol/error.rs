//! Errors of reading and checking a protocol file.

use std::path::PathBuf;

/// One invalid key of a protocol and what is wrong with it (the device's own type, so
/// controller and protocol errors read alike).
pub use rigtwin_device::config::InvalidKey;

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
    #[error("{path}: invalid protocol: {}", located(.errors, .lines, "not in the file (its default): "))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Every invalid key (never empty).
        errors: Vec<InvalidKey>,
        /// The line of each key in the file (`None` for a key left at its default
        /// outside any table the file has).
        lines: Vec<Option<usize>>,
    },
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

/// ``line 17: `reach.trials` must be > 0, got 0; line 40: ...``; a key without a line
/// is said after `no_line`.
pub(crate) fn located(errors: &[InvalidKey], lines: &[Option<usize>], no_line: &str) -> String {
    errors
        .iter()
        .zip(lines.iter().chain(std::iter::repeat(&None)))
        .map(|(e, l)| match l {
            Some(l) => format!("line {l}: `{}` {}", e.key, e.problem),
            None => format!("{no_line}`{}` {}", e.key, e.problem),
        })
        .collect::<Vec<_>>()
        .join("; ")
}
