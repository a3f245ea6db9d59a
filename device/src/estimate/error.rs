//! The one error type of the estimators.

use crate::signal::SignalError;

/// Why an estimator refused its input. None of the estimators panics on user input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EstimateError {
    /// A filtering, differentiation or spectral step refused the data.
    #[error("signal processing failed while {step}: {source}")]
    Signal {
        /// What the estimator was doing.
        step: &'static str,
        /// The signal module's reason.
        #[source]
        source: SignalError,
    },
    /// A record or window holds fewer samples (or groups) than the step needs.
    #[error("{what} has {got} but needs at least {needed}")]
    TooShort {
        /// What is too short.
        what: &'static str,
        /// Minimum count.
        needed: usize,
        /// Count given.
        got: usize,
    },
    /// A sample that is NaN or infinite.
    #[error("{what}: sample {index} is not finite")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the first offending sample.
        index: usize,
    },
    /// Two inputs that must have the same length do not.
    #[error("{what}: lengths differ ({left} vs {right})")]
    LengthMismatch {
        /// Which inputs.
        what: &'static str,
        /// Length of the first.
        left: usize,
        /// Length of the second.
        right: usize,
    },
    /// A perturbation whose analysis window runs past the end of its trial.
    #[error(
        "perturbation at sample {onset_index} needs samples up to {needed_end} but the trial has {len}"
    )]
    PerturbationBeyondRecord {
        /// Onset sample of the perturbation.
        onset_index: usize,
        /// One past the last sample the analysis needs.
        needed_end: usize,
        /// Number of samples in the trial.
        len: usize,
    },
    /// The regressor does not determine the parameters (collinear or zero columns).
    #[error("regressor is rank deficient: condition number {condition:e} exceeds {limit:e}")]
    RankDeficient {
        /// 2-norm condition number of the column-equilibrated regressor.
        condition: f64,
        /// The limit it exceeded.
        limit: f64,
    },
    /// A covariance matrix that cannot be inverted (constant or collinear signals).
    #[error("covariance of {what} is singular")]
    SingularCovariance {
        /// Which covariance.
        what: &'static str,
    },
    /// A configuration or input value outside its valid range.
    #[error("{what} = {value} is invalid: {why}")]
    BadParameter {
        /// Which parameter.
        what: &'static str,
        /// The value given.
        value: f64,
        /// What is wrong with it.
        why: &'static str,
    },
}

impl EstimateError {
    /// Wraps a [`SignalError`] with the step that raised it.
    pub(crate) fn signal(step: &'static str) -> impl FnOnce(SignalError) -> Self {
        move |source| Self::Signal { step, source }
    }
}

/// Returns the first non-finite sample of `x` as an error.
pub(crate) fn check_finite(what: &'static str, x: &[f64]) -> Result<(), EstimateError> {
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(EstimateError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Checks that a 2x2 matrix is finite.
pub(crate) fn check_finite_mat2(what: &'static str, m: &super::Mat2) -> Result<(), EstimateError> {
    for (i, v) in m.iter().flatten().enumerate() {
        if !v.is_finite() {
            return Err(EstimateError::NonFinite { what, index: i });
        }
    }
    Ok(())
}

/// Checks that a value is finite and strictly positive.
pub(crate) fn check_positive(what: &'static str, value: f64) -> Result<(), EstimateError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(EstimateError::BadParameter {
            what,
            value,
            why: "must be finite and > 0",
        })
    }
}
