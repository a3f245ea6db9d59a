//! Ground-truth endpoint impedance against the reference table and against finite
//! differences of the muscle law itself.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use approx::assert_relative_eq;
use nalgebra::{Matrix2, Vector2};
use proptest::prelude::*;
use rigtwin_arm::dynamics::{forward_dynamics, mass_matrix};
use rigtwin_arm::impedance::{
    endpoint_impedance, endpoint_inertia, joint_to_endpoint, principal_axes,
};
use rigtwin_arm::kinematics::{Elbow, forward, inverse, jacobian};
use rigtwin_arm::muscles::{MUSCLES, MuscleModel};
use rigtwin_arm::params::ArmParams;

/// Reference table (arm-parameters.md): K_q = [[15, 6], [6, 16]] N m/rad mapped to the
/// hand with the default segments. Eigenvalues within 1 N/m (the table rounds to 1 N/m)
/// and major axes within 1° (rounded to 1°). Like the table, K = J⁻ᵀ K_q J⁻¹ leaves
/// out the geometric ∂Jᵀ/∂q·F term (zero hand force).
#[test]
fn shadmehr_joint_stiffness_maps_to_the_reference_table() {
    let p = ArmParams::default();
    let kq = Matrix2::new(15.0, 6.0, 6.0, 16.0);
    for (y, major, minor, axis) in [
        (0.30, 184.0, 137.0, 142.0),
        (0.425, 208.0, 81.0, 97.0),
        (0.55, 378.0, 49.0, 93.0),
    ] {
        let q = inverse(&p, Vector2::new(0.0, y), Elbow::Down).unwrap();
        let k = joint_to_endpoint(&p, q, &kq).unwrap();
        let (l_max, l_min, deg) = principal_axes(&k);
        assert!((l_max - major).abs() <= 1.0, "y {y}: major {l_max}");
        assert!((l_min - minor).abs() <= 1.0, "y {y}: minor {l_min}");
        assert!((deg - axis).abs() <= 1.0, "y {y}: axis {deg}");
    }
}

/// Hand force of the muscles' impedance tensions `K_m e` at hand position x around a
/// reference posture, through the full nonlinear chain x → q (inverse kinematics) →
/// stretch → tension → torque → F = J⁻ᵀ τ. The active part `a` of the tension is left
/// out: its torque is constant in q, and its hand force changes with J only through
/// the geometric term the ground truth excludes.
fn muscle_hand_force(
    p: &ArmParams,
    m: &MuscleModel,
    a: &[f64; MUSCLES],
    q_ref: [f64; 2],
    x: Vector2<f64>,
) -> Vector2<f64> {
    let q = inverse(p, x, Elbow::Down).unwrap();
    let e = m.stretch(q, q_ref);
    let t = m.tensions(a, &e, &[0.0; MUSCLES], 1.0);
    let imp: [f64; MUSCLES] = std::array::from_fn(|i| t[i] - a[i]);
    let tau = m.joint_torque(&imp);
    jacobian(p, q).transpose().try_inverse().unwrap() * Vector2::new(tau[0], tau[1])
}

proptest! {
    /// The ground-truth stiffness is −∂F/∂x of the muscle impedance at the reference
    /// (where its force is zero, so no geometric term arises). Central differences
    /// with h = 1e-6 m; tolerance 1e-3 N/m on entries of 10–1000 N/m.
    #[test]
    fn stiffness_is_the_gradient_of_the_muscle_force(
        x in -0.15f64..0.15, y in 0.30f64..0.55, a in proptest::array::uniform6(0.0f64..200.0),
    ) {
        let p = ArmParams::default();
        let m = MuscleModel::new(&p.muscles).unwrap();
        let x0 = Vector2::new(x, y);
        let q_ref = inverse(&p, x0, Elbow::Down).unwrap();
        let h = 1e-6;
        let mut fd = Matrix2::zeros();
        for k in 0..2 {
            let mut d = Vector2::zeros();
            d[k] = h;
            let col = -(muscle_hand_force(&p, &m, &a, q_ref, x0 + d) - muscle_hand_force(&p, &m, &a, q_ref, x0 - d)) / (2.0 * h);
            fd.set_column(k, &col);
        }
        let g = endpoint_impedance(&p, q_ref, &a).unwrap();
        prop_assert!((g.stiffness_n_per_m - fd).abs().max() < 1e-3, "{} vs {}", g.stiffness_n_per_m, fd);
        // Symmetric, positive definite, and D = K/12 with the seed's damping law.
        let k = g.stiffness_n_per_m;
        prop_assert!((k[(0, 1)] - k[(1, 0)]).abs() < 1e-9 * k.norm());
        prop_assert!(k[(0, 0)] > 0.0 && k.determinant() > 0.0);
        prop_assert!((g.damping_n_s_per_m - k / 12.0).norm() < 1e-12 * k.norm());
    }

    /// The endpoint inertia is what a hand force accelerates: at rest, a = J M_q⁻¹ Jᵀ F
    /// must equal M_x⁻¹ F (to 1e-9 m/s² for 10 N).
    #[test]
    fn endpoint_mass_is_the_apparent_inertia(x in -0.15f64..0.15, y in 0.30f64..0.55, phi in 0.0f64..std::f64::consts::TAU) {
        let p = ArmParams::default();
        let q = inverse(&p, Vector2::new(x, y), Elbow::Down).unwrap();
        let f = Vector2::new(10.0 * phi.cos(), 10.0 * phi.sin());
        let tau = jacobian(&p, q).transpose() * f;
        let acc = jacobian(&p, q) * forward_dynamics(&p, q, [0.0, 0.0], [tau.x, tau.y]);
        let mx = endpoint_impedance(&p, q, &[0.0; MUSCLES]).unwrap().mass_kg;
        prop_assert!((mx * acc - f).norm() < 1e-9);
        // The one endpoint inertia the other rooms use is this same matrix.
        let m = endpoint_inertia(&p, q).unwrap();
        prop_assert!((m * acc - f).norm() < 1e-9);
        prop_assert!(mx.determinant() > 0.0);
    }
}

/// The endpoint inertia at the reach midpoint lies in the literature range 0.5–3 kg
/// (arm-parameters.md), and at a straight arm the mapping is an error, not a NaN.
#[test]
fn endpoint_mass_is_plausible_and_singularity_is_an_error() {
    let p = ArmParams::default();
    let q = inverse(&p, Vector2::new(0.0, 0.425), Elbow::Down).unwrap();
    let (major, minor, _) =
        principal_axes(&endpoint_impedance(&p, q, &[0.0; MUSCLES]).unwrap().mass_kg);
    assert!(
        minor > 0.3 && major < 3.0,
        "endpoint mass eigenvalues {major} {minor} kg"
    );
    assert!(joint_to_endpoint(&p, [0.5, 0.0], &mass_matrix(&p, [0.5, 0.0])).is_err());
    assert_relative_eq!(forward(&p, [0.5, 0.0]).norm(), 0.67, max_relative = 1e-12);
}
