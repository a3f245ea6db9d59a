//! Errors of the arm crate.

use thiserror::Error;

/// Everything that can go wrong in the arm crate on user-supplied input.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ArmError {
    /// A hand position outside the annulus the two links can reach.
    #[error(
        "hand at distance {distance_m:.4} m from the shoulder is out of reach [{min_m:.4}, {max_m:.4}] m"
    )]
    Unreachable {
        /// Distance of the requested hand position from the shoulder \[m\].
        distance_m: f64,
        /// Innermost reachable distance |l1 − l2| \[m\].
        min_m: f64,
        /// Outermost reachable distance l1 + l2 \[m\].
        max_m: f64,
    },
    /// A configuration where the Jacobian is singular (arm straight or folded).
    #[error("kinematic singularity: det J = {det_m2:e} m²")]
    Singular {
        /// Determinant of the Jacobian \[m²\].
        det_m2: f64,
    },
    /// A parameter outside its physical range.
    #[error("invalid parameter `{key}`: {reason}")]
    InvalidParameter {
        /// The config key.
        key: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A non-finite number where a finite one is needed.
    #[error("non-finite input `{what}`")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
}
