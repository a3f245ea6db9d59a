//! Rigid-body dynamics of the planar two-link arm in the horizontal plane (no gravity):
//!
//! M(q) q̈ + C(q, q̇) q̇ = τ
//!
//! with, for l1 the upper-arm length, r1, r2 the centre-of-mass distances, m1, m2 the
//! masses and I1, I2 the inertias about the centres of mass,
//!
//! M11 = I1 + I2 + m1 r1² + m2 (l1² + r2² + 2 l1 r2 cos q2),
//! M12 = M21 = I2 + m2 (r2² + l1 r2 cos q2), M22 = I2 + m2 r2²,
//! C q̇ = h \[−(2 q̇1 q̇2 + q̇2²), q̇1²\]ᵀ with h = m2 l1 r2 sin q2.
//!
//! Torques in N m, angles in rad, time in s.

use nalgebra::{Matrix2, Vector2};

use crate::params::ArmParams;

/// Joint angles \[rad\] and velocities \[rad/s\]; see [`crate::kinematics`] for the angle convention.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct JointState {
    /// Shoulder angle from +x, elbow angle relative to the upper arm \[rad\].
    pub q: [f64; 2],
    /// Their rates \[rad/s\].
    pub qd: [f64; 2],
}

/// Joint-space inertia matrix M(q) \[kg m²\]; symmetric positive definite.
pub fn mass_matrix(p: &ArmParams, q: [f64; 2]) -> Matrix2<f64> {
    let (u, f) = (&p.upper, &p.fore);
    let c2 = q[1].cos();
    let m22 = f.inertia_kg_m2 + f.mass_kg * f.com_m * f.com_m;
    let m12 = m22 + f.mass_kg * u.length_m * f.com_m * c2;
    let m11 = u.inertia_kg_m2
        + u.mass_kg * u.com_m * u.com_m
        + f.inertia_kg_m2
        + f.mass_kg
            * (u.length_m * u.length_m + f.com_m * f.com_m + 2.0 * u.length_m * f.com_m * c2);
    Matrix2::new(m11, m12, m12, m22)
}

/// Coriolis and centrifugal torques C(q, q̇) q̇ \[N m\].
pub fn coriolis(p: &ArmParams, q: [f64; 2], qd: [f64; 2]) -> Vector2<f64> {
    let h = p.fore.mass_kg * p.upper.length_m * p.fore.com_m * q[1].sin();
    Vector2::new(
        -h * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]),
        h * qd[0] * qd[0],
    )
}

/// Torques \[N m\] that produce acceleration `qdd` \[rad/s²\] at state (q, q̇).
pub fn inverse_dynamics(p: &ArmParams, q: [f64; 2], qd: [f64; 2], qdd: [f64; 2]) -> Vector2<f64> {
    mass_matrix(p, q) * Vector2::new(qdd[0], qdd[1]) + coriolis(p, q, qd)
}

/// Joint acceleration \[rad/s²\] under torques `tau` \[N m\].
///
/// Solves the 2×2 system in closed form; M is positive definite for any physical
/// [`ArmParams`] (see [`ArmParams::validate`]), so the determinant is positive.
pub fn forward_dynamics(p: &ArmParams, q: [f64; 2], qd: [f64; 2], tau: [f64; 2]) -> Vector2<f64> {
    let m = mass_matrix(p, q);
    let rhs = Vector2::new(tau[0], tau[1]) - coriolis(p, q, qd);
    let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
    Vector2::new(
        (m[(1, 1)] * rhs.x - m[(0, 1)] * rhs.y) / det,
        (m[(0, 0)] * rhs.y - m[(1, 0)] * rhs.x) / det,
    )
}

/// Kinetic energy ½ q̇ᵀ M q̇ \[J\].
pub fn kinetic_energy(p: &ArmParams, s: &JointState) -> f64 {
    let v = Vector2::new(s.qd[0], s.qd[1]);
    0.5 * v.dot(&(mass_matrix(p, s.q) * v))
}

/// One classical fourth-order Runge–Kutta step of length `dt_s` \[s\] with `tau` \[N m\]
/// held constant over the step.
pub fn rk4_step(p: &ArmParams, s: &JointState, tau: [f64; 2], dt_s: f64) -> JointState {
    let deriv = |q: [f64; 2], qd: [f64; 2]| -> ([f64; 2], [f64; 2]) {
        let a = forward_dynamics(p, q, qd, tau);
        (qd, [a.x, a.y])
    };
    let add = |x: [f64; 2], d: [f64; 2], h: f64| [x[0] + h * d[0], x[1] + h * d[1]];
    let (k1q, k1v) = deriv(s.q, s.qd);
    let (k2q, k2v) = deriv(add(s.q, k1q, dt_s / 2.0), add(s.qd, k1v, dt_s / 2.0));
    let (k3q, k3v) = deriv(add(s.q, k2q, dt_s / 2.0), add(s.qd, k2v, dt_s / 2.0));
    let (k4q, k4v) = deriv(add(s.q, k3q, dt_s), add(s.qd, k3v, dt_s));
    let comb = |x: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]| {
        [
            x[0] + dt_s / 6.0 * (a[0] + 2.0 * b[0] + 2.0 * c[0] + d[0]),
            x[1] + dt_s / 6.0 * (a[1] + 2.0 * b[1] + 2.0 * c[1] + d[1]),
        ]
    };
    JointState {
        q: comb(s.q, k1q, k2q, k3q, k4q),
        qd: comb(s.qd, k1v, k2v, k3v, k4v),
    }
}
