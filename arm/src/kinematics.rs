//! Planar two-link kinematics in the shoulder frame.
//!
//! Shoulder frame: origin at the shoulder joint, axes parallel to the rig frame
//! (x to the subject's right, y away from the subject), angles counter-clockwise
//! positive. `q[0]` is the shoulder angle of the upper arm from +x; `q[1]` is the
//! elbow angle of the forearm relative to the upper arm (0 = straight arm,
//! positive = flexion for a right arm). Lengths in metres, angles in radians.

use nalgebra::{Matrix2, Vector2};

use crate::error::ArmError;
use crate::params::ArmParams;

/// Which of the two inverse-kinematics solutions.
///
/// [`Elbow::Down`] has `q[1] > 0`: seen from the shoulder towards the hand, the elbow
/// lies clockwise of that line. For a right arm holding a handle in front of the body
/// this puts the elbow out to the subject's right: **`Elbow::Down` is the human
/// posture** and the one every task of this crate uses. [`Elbow::Up`] (`q[1] < 0`) is
/// the mirror image, a hyper-extended elbow, kept for completeness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Elbow {
    /// `q[1] ∈ [0, π]`: the human right-arm posture.
    #[default]
    Down,
    /// `q[1] ∈ [−π, 0]`: the mirror solution.
    Up,
}

/// Elbow position in the shoulder frame \[m\].
pub fn elbow(p: &ArmParams, q: [f64; 2]) -> Vector2<f64> {
    let l1 = p.upper.length_m;
    Vector2::new(l1 * q[0].cos(), l1 * q[0].sin())
}

/// Hand (handle) position in the shoulder frame \[m\].
pub fn forward(p: &ArmParams, q: [f64; 2]) -> Vector2<f64> {
    let l2 = p.fore.length_m;
    let a = q[0] + q[1];
    elbow(p, q) + Vector2::new(l2 * a.cos(), l2 * a.sin())
}

/// Joint angles \[rad\] that put the hand at `hand` \[m, shoulder frame\].
///
/// Errors with [`ArmError::Unreachable`] outside the annulus |l1 − l2| ≤ r ≤ l1 + l2
/// and [`ArmError::NonFinite`] on NaN/inf input. `q[0]` is wrapped to (−π, π].
pub fn inverse(p: &ArmParams, hand: Vector2<f64>, which: Elbow) -> Result<[f64; 2], ArmError> {
    if !(hand.x.is_finite() && hand.y.is_finite()) {
        return Err(ArmError::NonFinite { what: "hand" });
    }
    let (l1, l2) = (p.upper.length_m, p.fore.length_m);
    let r2 = hand.norm_squared();
    let r = r2.sqrt();
    let (min_m, max_m) = ((l1 - l2).abs(), l1 + l2);
    // A relative slack of 1e-12 admits round-off at the workspace boundary.
    if r > max_m * (1.0 + 1e-12) || r < min_m * (1.0 - 1e-12) {
        return Err(ArmError::Unreachable {
            distance_m: r,
            min_m,
            max_m,
        });
    }
    let c2 = ((r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)).clamp(-1.0, 1.0);
    let s2_abs = (1.0 - c2 * c2).max(0.0).sqrt();
    let s2 = match which {
        Elbow::Down => s2_abs,
        Elbow::Up => -s2_abs,
    };
    let q1 = s2.atan2(c2);
    let q0 = hand.y.atan2(hand.x) - (l2 * s2).atan2(l1 + l2 * c2);
    let q0 = (q0 + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    Ok([q0, q1])
}

/// Jacobian ∂x/∂q of the hand position \[m/rad\].
pub fn jacobian(p: &ArmParams, q: [f64; 2]) -> Matrix2<f64> {
    let (l1, l2) = (p.upper.length_m, p.fore.length_m);
    let (s1, c1) = q[0].sin_cos();
    let (s12, c12) = (q[0] + q[1]).sin_cos();
    Matrix2::new(-l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12)
}

/// Time derivative of the Jacobian, dJ/dt for joint velocity `qd` \[m/(rad s)\].
pub fn jacobian_dot(p: &ArmParams, q: [f64; 2], qd: [f64; 2]) -> Matrix2<f64> {
    let (l1, l2) = (p.upper.length_m, p.fore.length_m);
    let (s1, c1) = q[0].sin_cos();
    let (s12, c12) = (q[0] + q[1]).sin_cos();
    let w12 = qd[0] + qd[1];
    Matrix2::new(
        -l1 * c1 * qd[0] - l2 * c12 * w12,
        -l2 * c12 * w12,
        -l1 * s1 * qd[0] - l2 * s12 * w12,
        -l2 * s12 * w12,
    )
}

/// Hand velocity \[m/s\] for joint velocity `qd` \[rad/s\].
pub fn hand_velocity(p: &ArmParams, q: [f64; 2], qd: [f64; 2]) -> Vector2<f64> {
    jacobian(p, q) * Vector2::new(qd[0], qd[1])
}

/// Joint velocity and acceleration \[rad/s, rad/s²\] that realise a hand velocity \[m/s\]
/// and acceleration \[m/s²\] at `q`: q̇ = J⁻¹ẋ, q̈ = J⁻¹(ẍ − J̇ q̇).
pub fn joint_rates(
    p: &ArmParams,
    q: [f64; 2],
    xd: Vector2<f64>,
    xdd: Vector2<f64>,
) -> Result<([f64; 2], [f64; 2]), ArmError> {
    let j = jacobian(p, q);
    let det = j.determinant();
    let ji = j.try_inverse().ok_or(ArmError::Singular { det_m2: det })?;
    let qd = ji * xd;
    let qd_arr = [qd.x, qd.y];
    let qdd = ji * (xdd - jacobian_dot(p, q, qd_arr) * qd);
    Ok((qd_arr, [qdd.x, qdd.y]))
}
