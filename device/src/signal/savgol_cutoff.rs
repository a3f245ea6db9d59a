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
//! The formula is empirical and rough. Measured with [`savgol_measured_cutoff_hz`],
//! the true 3 dB points of those windows are 26.76 Hz, 25.29 Hz and 21.81 Hz: for odd
//! orders the formula overestimates the cut-off by 12–20 % (an odd-order smoother
//! equals the even one below it, yet the formula counts `N + 1`), for even orders
//! ≥ 2 it is within about 11 %, and for order 0 it is 29 % low. Use
//! [`savgol_measured_cutoff_hz`] when the actual cut-off matters.

use super::error::{SignalError, check_rate};
use super::savgol::savgol_coeffs;

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

/// The true 3 dB cut-off in Hz of the Savitzky–Golay smoother (`deriv = 0`) of
/// `polyorder` and odd `window` at `fs_hz`: the lowest frequency where its (real,
/// zero-phase) response `c₀ + 2 Σ c_k cos(2π f k / f_s)` falls to `1/√2`, found on a
/// grid of `8·window` points below Nyquist and refined by bisection to 1e-12 of
/// `fs_hz`.
///
/// # Errors
/// As [`savgol_coeffs`](super::savgol_coeffs), plus [`SignalError::BadRate`] for a
/// bad `fs_hz` and [`SignalError::BadWindow`] when the response never falls to
/// `1/√2` below Nyquist (window too short for the order: it barely smooths).
pub fn savgol_measured_cutoff_hz(
    polyorder: usize,
    window: usize,
    fs_hz: f64,
) -> Result<f64, SignalError> {
    check_rate("fs_hz", fs_hz)?;
    let c = savgol_coeffs(window, polyorder, 0, 1.0)?;
    let half = window / 2;
    let target = std::f64::consts::FRAC_1_SQRT_2;
    let response = |f: f64| {
        let w = 2.0 * std::f64::consts::PI * f / fs_hz;
        c[half]
            + 2.0
                * (1..=half)
                    .map(|k| c[half + k] * (w * k as f64).cos())
                    .sum::<f64>()
    };
    let steps = 8 * window;
    let df = fs_hz / 2.0 / steps as f64;
    let crossing = (1..=steps).find(|&i| response(i as f64 * df) <= target);
    let Some(i) = crossing else {
        return Err(SignalError::BadWindow {
            window,
            why: "the smoother does not fall to 3 dB below Nyquist",
        });
    };
    let (mut lo, mut hi) = ((i - 1) as f64 * df, i as f64 * df);
    while hi - lo > 1e-12 * fs_hz {
        let mid = 0.5 * (lo + hi);
        if response(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}
