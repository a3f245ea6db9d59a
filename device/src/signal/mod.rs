//! Signal processing for the estimators, checked against scipy on golden vectors.
//!
//! One idea per file; every public function names the scipy/numpy call it
//! reproduces, and `device/tests/golden/make_golden.py` produces the vectors that
//! `device/tests/signal_golden.rs` holds it to.
//!
//! | file | what |
//! |---|---|
//! | `error.rs` | [`SignalError`] |
//! | `edge.rs` | [`EdgeMode`]: how windows see past the ends |
//! | `savgol.rs` | Savitzky–Golay coefficients and filtering ([`savgol_coeffs`], [`savgol_filter`]) |
//! | `savgol_cutoff.rs` | window ↔ cut-off by Schafer (2011) ([`savgol_window_for_cutoff`]) |
//! | `butter.rs` | Butterworth design as second-order sections ([`butter`]) |
//! | `zpk2sos.rs` | scipy's pole/zero pairing into sections |
//! | `sos.rs` | [`Sos`], [`sosfilt`], [`sosfilt_zi`], [`sosfiltfilt`] |
//! | `filtfilt.rs` | `(b, a)` filtering: [`lfilter`], [`lfilter_zi`], [`filtfilt`] |
//! | `pad.rs` | odd extension for forward-backward filtering |
//! | `welch.rs` | [`welch`] power spectral density, [`Psd`] |
//! | `calculus.rs` | [`cumulative_trapezoid`], [`gradient`] |
//!
//! None of these run inside the 4 kHz `tick`: they allocate and work on whole
//! recorded trials.

mod butter;
mod calculus;
mod edge;
mod error;
mod filtfilt;
mod pad;
mod savgol;
mod savgol_cutoff;
mod sos;
mod welch;
mod zpk2sos;

pub use butter::{FilterKind, butter, butter_bandpass};
pub use calculus::{cumulative_trapezoid, cumulative_trapezoid_no_initial, gradient};
pub use edge::EdgeMode;
pub use error::SignalError;
pub use filtfilt::{filtfilt, lfilter, lfilter_zi};
pub use savgol::{savgol_coeffs, savgol_filter, savgol_filter_planned};
pub use savgol_cutoff::{
    savgol_cutoff_for_window, savgol_measured_cutoff_hz, savgol_window_for_cutoff,
};
pub use sos::{Sos, sosfilt, sosfilt_with_state, sosfilt_zi, sosfiltfilt};
pub use welch::{Psd, welch};
