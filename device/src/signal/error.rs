//! The one error type of the signal module.
//!
//! Every function that can be fed a bad signal or bad design parameters returns
//! [`SignalError`]; none of them panics on user input.

/// Why a signal-processing call refused its input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SignalError {
    /// The signal is shorter than the operation needs (e.g. shorter than the
    /// Savitzky–Golay window in `interp` mode, or not longer than the padding of a
    /// forward-backward filter).
    #[error("signal has {got} samples but {what} needs at least {needed}")]
    TooShort {
        /// Minimum number of samples.
        needed: usize,
        /// Number of samples given.
        got: usize,
        /// The operation that needed them.
        what: &'static str,
    },
    /// A window length that the operation cannot use (even, zero, too short for
    /// the polynomial order, fewer than two samples for a spectral segment).
    #[error("window length {window} is invalid: {why}")]
    BadWindow {
        /// The window length given, in samples.
        window: usize,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A filter or polynomial order that the operation cannot use.
    #[error("order {order} is invalid: {why}")]
    BadOrder {
        /// The order given.
        order: usize,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A sample that is NaN or infinite.
    #[error("sample {index} is not finite ({value})")]
    NonFinite {
        /// Index of the first offending sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A cut-off frequency outside the open interval (0, fs/2).
    #[error("cut-off {cutoff_hz} Hz is outside (0, {nyquist_hz}) Hz")]
    CutoffOutOfRange {
        /// The cut-off given, in Hz.
        cutoff_hz: f64,
        /// Half the sample rate, in Hz.
        nyquist_hz: f64,
    },
    /// A sample rate or sample spacing that is not finite and positive.
    #[error("{what} must be finite and > 0, got {value}")]
    BadRate {
        /// Which parameter (`fs_hz`, `dt_s`, `delta`).
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// Filter coefficients that cannot be used (empty, leading zero in the
    /// denominator, a pole at z = 1 that has no steady state, non-finite values).
    #[error("filter coefficients are invalid: {why}")]
    BadCoefficients {
        /// What is wrong with them.
        why: &'static str,
    },
    /// The FFT library refused a buffer; indicates a bug in this module.
    #[error("FFT failed: {0}")]
    Fft(String),
}

/// Returns the first non-finite sample as an error.
pub(crate) fn check_finite(x: &[f64]) -> Result<(), SignalError> {
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(SignalError::NonFinite {
            index,
            value: x[index],
        }),
        None => Ok(()),
    }
}

/// Checks that a rate or step is finite and strictly positive.
pub(crate) fn check_rate(what: &'static str, value: f64) -> Result<(), SignalError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SignalError::BadRate { what, value })
    }
}
