//! Choosing a Savitzky–Golay window from a cut-off frequency.
//!
//! Papers (both seeds among them) specify a Savitzky–Golay filter by its order and a
//! cut-off frequency, not by its window. Schafer, "What is a Savitzky-Golay
//! filter?", IEEE Signal Processing Magazine 28(4), 2011, gives the 3 dB cut-off of
//! the smoother of order `N` and window `2M + 1` as
//!
//! ```text
//! f_c ≈ (N + 1) / (3.2 M − 4.6) · f_s / 2
//! ```
//!
//! (stated there for `M ≥ 25` and `N < M`). Inverting it,
//! `M = ((N + 1) · (f_s/2) / f_c + 4.6) / 3.2`, rounded to the nearest integer.
//!
//! The seeds' settings give:
//!
//! | setting | M | window |
//! |---|---|---|
//! | order 5, 30 Hz at 4 kHz (Börner, the rig) | 126 | 253 |
//! | order 5, 30 Hz at 1 kHz | 33 | 67 |
//! | order 6, 23.4 Hz at 250 Hz (Piovesan, HapticMaster) | 13 | 27 |
//!
//! The last one lies outside the formula's stated range (`M = 13 < 25`); the tests
//! measure how far the true 3 dB point of that window is from 23.4 Hz.

use super::error::{SignalError, check_rate};

/// Half-width `M` (as a real number) that Schafer's formula gives for `polyorder`
/// `N` and cut-off `cutoff_hz` at `fs_hz`.
fn schafer_half_width(polyorder: usize, cutoff_hz: f64, fs_hz: f64) -> f64 {
    ((polyorder as f64 + 1.0) * (fs_hz / 2.0) / cutoff_hz + 4.6) / 3.2
}

/// 3 dB cut-off in Hz that Schafer's formula predicts for a smoother of `polyorder`
/// and odd `window` at `fs_hz`: `(N + 1) / (3.2 M − 4.6) · f_s / 2`, `M = window / 2`.
///
/// # Errors
/// [`SignalError::BadWindow`] when `window` is even or `M < 2` (the formula's
/// denominator is not positive), [`SignalError::BadRate`] for a bad `fs_hz`.
pub fn savgol_cutoff_for_window(
    polyorder: usize,
    window: usize,
    fs_hz: f64,
) -> Result<f64, SignalError> {
    check_rate("fs_hz", fs_hz)?;
    if window.is_multiple_of(2) || window < 5 {
        return Err(SignalError::BadWindow {
            window,
            why: "must be odd with half-width M >= 2 for Schafer's formula",
        });
    }
    let m = (window / 2) as f64;
    Ok((polyorder as f64 + 1.0) / (3.2 * m - 4.6) * fs_hz / 2.0)
}

/// Odd window length `2M + 1` whose Savitzky–Golay smoother of order `polyorder` has
/// its 3 dB cut-off near `cutoff_hz` at sample rate `fs_hz`, by Schafer (2011)
/// (see the module docs); `M` is rounded to the nearest integer.
///
/// # Errors
/// [`SignalError::BadRate`] for a bad `fs_hz`; [`SignalError::CutoffOutOfRange`]
/// unless `0 < cutoff_hz < fs_hz / 2`; [`SignalError::BadOrder`] when the window
/// found would not exceed `polyorder` (the cut-off is too high for that order) or
/// would overflow.
pub fn savgol_window_for_cutoff(
    polyorder: usize,
    cutoff_hz: f64,
    fs_hz: f64,
) -> Result<usize, SignalError> {
    check_rate("fs_hz", fs_hz)?;
    let nyquist_hz = fs_hz / 2.0;
    if !(cutoff_hz.is_finite() && cutoff_hz > 0.0 && cutoff_hz < nyquist_hz) {
        return Err(SignalError::CutoffOutOfRange {
            cutoff_hz,
            nyquist_hz,
        });
    }
    let m = schafer_half_width(polyorder, cutoff_hz, fs_hz).round();
    if !(m.is_finite() && m < (usize::MAX / 4) as f64) {
        return Err(SignalError::BadOrder {
            order: polyorder,
            why: "the window for this cut-off is too long to represent",
        });
    }
    let window = 2 * (m as usize) + 1;
    if window <= polyorder || m < 2.0 {
        return Err(SignalError::BadOrder {
            order: polyorder,
            why: "the cut-off is too high for a window longer than this polyorder",
        });
    }
    Ok(window)
}
