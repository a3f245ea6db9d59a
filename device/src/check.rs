//! Named-key validation: a [`Checker`] collects every invalid key of a config while it is
//! checked, so one run names them all, and [`ConfigError`] reports them. The controller's
//! config, the force-sensor calibration, the perturbation schedules and the runtime's
//! protocol checks all use it, so every config error reads alike.

use crate::time::Rate;

/// One invalid key and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key} {problem}")]
pub struct InvalidKey {
    /// Dotted path of the key, e.g. `admittance.mass_kg[0]`.
    pub key: String,
    /// What is wrong, e.g. `must be > 0, got -1`.
    pub problem: String,
}

/// Every invalid key found by a config's validation, e.g.
/// [`crate::config::ControllerConfig::validate`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid controller config: {}", join_invalid_keys(.errors))]
pub struct ConfigError {
    /// The invalid keys, in the order the config declares them (never empty).
    pub errors: Vec<InvalidKey>,
}

/// The invalid keys as one line, `; `-separated.
#[must_use]
pub fn join_invalid_keys(errors: &[InvalidKey]) -> String {
    errors
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

impl ConfigError {
    /// True if one of the errors names `key` exactly.
    #[must_use]
    pub fn names(&self, key: &str) -> bool {
        self.errors.iter().any(|e| e.key == key)
    }
}

/// Collects invalid keys while a config is checked, so one run names every bad key.
/// The runtime's protocol checks use it too, so every config error reads alike.
#[derive(Debug, Default)]
pub struct Checker {
    errors: Vec<InvalidKey>,
}

impl Checker {
    /// Records `key` as invalid with `problem`.
    pub fn fail(&mut self, key: impl Into<String>, problem: impl Into<String>) {
        self.errors.push(InvalidKey {
            key: key.into(),
            problem: excerpt(&problem.into(), MAX_QUOTE_CHARS).into_owned(),
        });
    }

    /// The invalid keys so far.
    #[must_use]
    pub fn errors(&self) -> &[InvalidKey] {
        &self.errors
    }

    /// The invalid keys, in the order they were found.
    #[must_use]
    pub fn into_errors(self) -> Vec<InvalidKey> {
        self.errors
    }

    /// `v` must be finite; true if it is.
    pub fn finite(&mut self, key: &str, v: f64) -> bool {
        if v.is_finite() {
            true
        } else {
            self.fail(key, format!("must be finite, got {v}"));
            false
        }
    }

    /// `v` must be finite and > 0.
    pub fn positive(&mut self, key: &str, v: f64) {
        if self.finite(key, v) && v <= 0.0 {
            self.fail(key, format!("must be > 0, got {v}"));
        }
    }

    /// `v` must be finite and ≥ 0.
    pub fn non_negative(&mut self, key: &str, v: f64) {
        if self.finite(key, v) && v < 0.0 {
            self.fail(key, format!("must be >= 0, got {v}"));
        }
    }

    /// Both components must be finite and > 0 (keys `key[0]`, `key[1]`).
    pub fn positive2(&mut self, key: &str, v: [f64; 2]) {
        for (i, x) in v.iter().enumerate() {
            self.positive(&format!("{key}[{i}]"), *x);
        }
    }

    /// Both components must be finite and ≥ 0.
    pub fn non_negative2(&mut self, key: &str, v: [f64; 2]) {
        for (i, x) in v.iter().enumerate() {
            self.non_negative(&format!("{key}[{i}]"), *x);
        }
    }

    /// `v` seconds must be a whole number of ticks at `rate` (durations are whole ticks).
    pub fn whole_ticks(&mut self, key: &str, v: f64, rate: Option<Rate>) {
        let Some(rate) = rate else { return };
        if !v.is_finite() {
            return;
        }
        let ticks = v * f64::from(rate.hz());
        if (ticks - ticks.round()).abs() > 1e-6 {
            self.fail(
                key,
                format!(
                    "must be a whole number of {} Hz ticks, got {v} s ({ticks} ticks)",
                    rate.hz()
                ),
            );
        }
    }

    /// `v` must lie strictly inside walls at `±half_width_m`, m.
    pub fn inside(&mut self, key: &str, v: f64, half_width_m: f64) {
        if self.finite(key, v) && v.abs() >= half_width_m {
            self.fail(
                key,
                format!("must lie inside the walls at ±{half_width_m} m, got {v}"),
            );
        }
    }

    /// `Ok` when no key was invalid, else every invalid key.
    ///
    /// # Errors
    /// [`ConfigError`] listing the invalid keys.
    pub fn finish(self) -> Result<(), ConfigError> {
        if self.errors.is_empty() {
            Ok(())
        } else {
            Err(ConfigError {
                errors: self.errors,
            })
        }
    }
}

/// The most characters of a bad value an error quotes.
pub const MAX_QUOTE_CHARS: usize = 200;

/// `text` cut to its first `max_chars` characters, with how much was left out, so that
/// an error quoting a bad field (a 10 MB string where a name should be) stays a line.
#[must_use]
pub fn excerpt(text: &str, max_chars: usize) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(max_chars) {
        None => std::borrow::Cow::Borrowed(text),
        Some((cut, _)) => std::borrow::Cow::Owned(format!(
            "{}… ({} more bytes)",
            &text[..cut],
            text.len() - cut
        )),
    }
}

#[cfg(test)]
mod excerpt_tests {
    use super::excerpt;

    #[test]
    fn long_text_is_cut_on_a_character_boundary_and_says_how_much_is_left() {
        assert_eq!(excerpt("short", 10), "short");
        let long = "é".repeat(300);
        let cut = excerpt(&long, 200);
        assert!(cut.starts_with(&"é".repeat(200)), "{cut}");
        // 100 characters of 2 bytes each are left out.
        assert!(cut.ends_with("… (200 more bytes)"), "{cut}");
    }
}
