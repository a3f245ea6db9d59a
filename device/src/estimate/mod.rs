//! Impedance estimators the rig runs: Börner involuntary impedance (000_*) and the
//! Piovesan windowed regression (001_*), with ellipse metrics.
//!
//! Everything here works on whole recorded trials given as plain slices (no file
//! I/O, nothing outside `device`) and allocates freely: none of it runs inside the
//! 4 kHz `tick`. Matrices are row-major `[[f64; 2]; 2]` ([`Mat2`]) in SI units.
//!
//! | file | what |
//! |---|---|
//! | `error.rs` | [`EstimateError`] |
//! | `lsq.rs` | least squares with rank check and jackknife covariance ([`LsqFit`]) |
//! | `ellipse.rs` | [`ellipse_metrics`], [`curl_test`], [`impedance_at`] |
//! | `borner.rs` | involuntary impedance, 000_* eq. 19–32 ([`estimate_involuntary_impedance`]) |
//! | `piovesan.rs` | windowed K, B regression and canonical correlation, 001_* eq. 8 |
//! | `force_error.rs` | force errors, skill gain, sign correlation, 001_* eq. 9–13 |
//! | `spectrum.rs` | jerk PSD comparison for the high-pass cut-off, 000_* section 4.3 |

mod borner;
mod ellipse;
mod error;
mod force_error;
mod lsq;
mod piovesan;
mod spectrum;

pub use borner::{
    Admittance, BornerConfig, HighPass, InvoluntaryImpedance, PerturbedTrial, VariationalDynamics,
    VariationalMode, estimate_involuntary_impedance, variational_dynamics,
};
pub use ellipse::{
    ComplexImpedance, CurlTest, EllipseMetrics, curl_test, ellipse_metrics, impedance_at,
};
pub use error::EstimateError;
pub use force_error::{
    CycleForce, WindowForceError, cycle_force_measures, sign_correlation, skill_gain,
    stiffness_change, window_force_errors,
};
pub use lsq::{CovarianceKind, LsqFit};
pub use piovesan::{
    ImposedMotionTrial, PerturbationResponse, PiovesanConfig, PositionPerturbation, WindowEstimate,
    canonical_correlation, estimate_window, perturbation_responses, windowed_impedance,
};
pub use spectrum::{JerkSpectra, SpectrumConfig, compare_jerk_spectra};

/// A 2x2 matrix, row-major: `m[row][col]`.
pub type Mat2 = [[f64; 2]; 2];
