//! Two-link dynamics against independent references: link-by-link kinetic energy,
//! the Lagrangian Coriolis term, conservation laws, and RK4's order.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use approx::assert_relative_eq;
use nalgebra::{Matrix2, Vector2};
use proptest::prelude::*;
use rigtwin_arm::dynamics::{
    JointState, coriolis, forward_dynamics, inverse_dynamics, kinetic_energy, mass_matrix, rk4_step,
};
use rigtwin_arm::params::{ArmParams, Segment};
use rigtwin_arm::time::TICK_HZ;

/// Kinetic energy summed link by link (translation of each CoM plus rotation), written
/// without the mass matrix.
fn link_energy(p: &ArmParams, q: [f64; 2], qd: [f64; 2]) -> f64 {
    let (u, f) = (&p.upper, &p.fore);
    let w1 = qd[0];
    let w12 = qd[0] + qd[1];
    let perp = |a: f64| Vector2::new(-a.sin(), a.cos());
    let v1 = perp(q[0]) * (u.com_m * w1);
    let v2 = perp(q[0]) * (u.length_m * w1) + perp(q[0] + q[1]) * (f.com_m * w12);
    0.5 * u.mass_kg * v1.norm_squared()
        + 0.5 * u.inertia_kg_m2 * w1 * w1
        + 0.5 * f.mass_kg * v2.norm_squared()
        + 0.5 * f.inertia_kg_m2 * w12 * w12
}

proptest! {
    /// M is symmetric positive definite and reproduces the link-by-link kinetic energy
    /// to 1e-12 relative (pure round-off).
    #[test]
    fn mass_matrix_is_spd_and_matches_link_energy(
        q0 in -3.1f64..3.1, q1 in -3.1f64..3.1, w0 in -4.0f64..4.0, w1 in -4.0f64..4.0,
    ) {
        let p = ArmParams::default();
        let m = mass_matrix(&p, [q0, q1]);
        prop_assert_eq!(m[(0, 1)], m[(1, 0)]);
        prop_assert!(m[(0, 0)] > 0.0 && m.determinant() > 0.0);
        let ke = kinetic_energy(&p, &JointState { q: [q0, q1], qd: [w0, w1] });
        let reference = link_energy(&p, [q0, q1], [w0, w1]);
        prop_assert!((ke - reference).abs() <= 1e-12 * reference.max(1e-12));
    }

    /// C q̇ = Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q (Lagrange), by central differences of M with
    /// h = 1e-6: tolerance 1e-7 N m against values of order 0.1–1 N m.
    #[test]
    fn coriolis_is_the_lagrangian_velocity_term(
        q0 in -3.1f64..3.1, q1 in -3.1f64..3.1, w0 in -4.0f64..4.0, w1 in -4.0f64..4.0,
    ) {
        let p = ArmParams::default();
        let h = 1e-6;
        let qd = Vector2::new(w0, w1);
        let mdot = (mass_matrix(&p, [q0 + w0 * h, q1 + w1 * h]) - mass_matrix(&p, [q0 - w0 * h, q1 - w1 * h])) / (2.0 * h);
        let dk = |k: usize| {
            let mut qp = [q0, q1];
            let mut qm = [q0, q1];
            qp[k] += h;
            qm[k] -= h;
            let dm: Matrix2<f64> = (mass_matrix(&p, qp) - mass_matrix(&p, qm)) / (2.0 * h);
            0.5 * qd.dot(&(dm * qd))
        };
        let reference = mdot * qd - Vector2::new(dk(0), dk(1));
        prop_assert!((coriolis(&p, [q0, q1], [w0, w1]) - reference).norm() < 1e-7);
    }

    /// forward_dynamics inverts inverse_dynamics to 1e-9 rad/s² (2×2 solve round-off).
    #[test]
    fn forward_inverts_inverse_dynamics(
        q1 in -3.0f64..3.0, w0 in -4.0f64..4.0, w1 in -4.0f64..4.0, a0 in -50.0f64..50.0, a1 in -50.0f64..50.0,
    ) {
        let p = ArmParams::default();
        let tau = inverse_dynamics(&p, [0.3, q1], [w0, w1], [a0, a1]);
        let qdd = forward_dynamics(&p, [0.3, q1], [w0, w1], [tau.x, tau.y]);
        prop_assert!((qdd - Vector2::new(a0, a1)).norm() < 1e-9);
    }
}

fn free_run(p: &ArmParams, s0: JointState, dt: f64, steps: usize) -> JointState {
    let mut s = s0;
    for _ in 0..steps {
        s = rk4_step(p, &s, [0.0, 0.0], dt);
    }
    s
}

/// A free, fast-swinging arm (3 and −5 rad/s) for 2 s at the 4 kHz tick: RK4's energy
/// error is O(dt⁴) per unit time, measured 1e-12 relative here; tolerance 1e-9. The
/// shoulder angle is cyclic, so the shoulder's generalised momentum (M q̇)₀ is
/// conserved too (same tolerance).
#[test]
fn free_arm_conserves_energy_and_shoulder_momentum_under_rk4() {
    let p = ArmParams::default();
    let s0 = JointState {
        q: [0.4, 1.6],
        qd: [3.0, -5.0],
    };
    let s1 = free_run(&p, s0, 1.0 / TICK_HZ as f64, 2 * TICK_HZ as usize);
    let e0 = kinetic_energy(&p, &s0);
    let e1 = kinetic_energy(&p, &s1);
    assert_relative_eq!(e1, e0, max_relative = 1e-9);
    let mom = |s: &JointState| (mass_matrix(&p, s.q) * Vector2::new(s.qd[0], s.qd[1])).x;
    assert_relative_eq!(mom(&s1), mom(&s0), max_relative = 1e-9);
}

/// RK4 is fourth order: halving dt cuts the error at t = 0.5 s by 2⁴ = 16. Reference:
/// dt = 1/64 ms. Accepted ratio band 13–19 (the asymptotic 16 with margin for the
/// higher-order terms at the coarsest step, 4 ms).
#[test]
fn rk4_converges_at_fourth_order() {
    let p = ArmParams::default();
    let s0 = JointState {
        q: [0.4, 1.6],
        qd: [3.0, -5.0],
    };
    let t = 0.5;
    let reference = free_run(&p, s0, t / 32768.0, 32768);
    let err = |n: usize| {
        let s = free_run(&p, s0, t / n as f64, n);
        ((s.q[0] - reference.q[0]).powi(2) + (s.q[1] - reference.q[1]).powi(2)).sqrt()
    };
    let errors: Vec<f64> = [125, 250, 500, 1000].iter().map(|n| err(*n)).collect();
    for w in errors.windows(2) {
        let ratio = w[0] / w[1];
        assert!(
            (13.0..19.0).contains(&ratio),
            "error ratio {ratio} from {errors:?}"
        );
    }
}

/// Per-subject lengths: CoM scales with length, inertia with length², mass kept.
#[test]
fn segment_scaling_is_geometric_at_constant_mass() {
    let s = Segment::SHADMEHR_UPPER.scaled_to_length(0.363).unwrap();
    assert_relative_eq!(s.com_m, 0.165 * 1.1, max_relative = 1e-12);
    assert_relative_eq!(s.inertia_kg_m2, 0.0141 * 1.21, max_relative = 1e-12);
    assert_eq!(s.mass_kg, 1.93);
    assert!(Segment::SHADMEHR_UPPER.scaled_to_length(-0.3).is_err());
    assert!(Segment::SHADMEHR_UPPER.scaled_to_length(f64::NAN).is_err());
    let p = ArmParams::with_lengths(0.30, 0.36).unwrap();
    assert_eq!((p.upper.length_m, p.fore.length_m), (0.30, 0.36));
    assert!(p.validate().is_ok());
}
