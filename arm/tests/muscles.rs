//! The six-muscle model: torque split, co-contraction, tension law, joint stiffness.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use approx::assert_relative_eq;
use nalgebra::Matrix2;
use proptest::prelude::*;
use rigtwin_arm::ArmError;
use rigtwin_arm::muscles::{MUSCLES, MuscleModel, MuscleParams};

fn model() -> MuscleModel {
    MuscleModel::new(&MuscleParams::default()).unwrap()
}

proptest! {
    /// The split reproduces the torque exactly (1e-12 N m) with non-negative activations,
    /// with and without co-contraction; without it the lift is minimal, so some muscle
    /// sits at zero (1e-9 N).
    #[test]
    fn split_is_exact_nonnegative_and_minimal(t0 in -20.0f64..20.0, t1 in -20.0f64..20.0, level in 0.0f64..3.0) {
        let m = model();
        for co in [[0.0; MUSCLES], m.co_contraction(level)] {
            let a = m.split([t0, t1], &co);
            prop_assert!(a.iter().all(|x| *x >= 0.0));
            let tau = m.joint_torque(&a);
            prop_assert!((tau[0] - t0).abs() < 1e-12 && (tau[1] - t1).abs() < 1e-12, "{tau:?}");
        }
        let a = m.split([t0, t1], &[0.0; MUSCLES]);
        prop_assert!(a.iter().cloned().fold(f64::INFINITY, f64::min) < 1e-9);
    }
}

/// Co-contraction pulls without net torque (1e-12 N m) and with the documented
/// tensions: shoulder pair c/0.0536, elbow flexor c/0.0316, extensor c/0.0267.
#[test]
fn co_contraction_is_torque_free_with_documented_tensions() {
    let m = model();
    let c = m.co_contraction(1.0);
    let tau = m.joint_torque(&c);
    assert!(tau[0].abs() < 1e-12 && tau[1].abs() < 1e-12, "{tau:?}");
    assert_relative_eq!(c[0], 1.0 / 0.0536, max_relative = 1e-12);
    assert_relative_eq!(c[1], 1.0 / 0.0536, max_relative = 1e-12);
    assert_relative_eq!(c[2], 2.6 / 0.0316, max_relative = 1e-12);
    assert_relative_eq!(c[3], 2.6 / 0.0267, max_relative = 1e-12);
    assert_eq!((c[4], c[5]), (0.0, 0.0));
}

/// Tension m = a + K_m (e + ė/12), K_m = K₀ + K₁ a, checked on one muscle by hand:
/// a = 50 N, e = 2 mm, ė = 12 mm/s → K_m = 450 + 5000 = 5450 N/m,
/// m = 50 + 5450 (0.002 + 0.001) = 66.35 N.
#[test]
fn tension_law_by_hand() {
    let m = model();
    let t = m.tensions(&[50.0; MUSCLES], &[0.002; MUSCLES], &[0.012; MUSCLES], 1.0);
    assert_relative_eq!(t[0], 66.35, max_relative = 1e-12);
}

/// −∂τ/∂q of the muscle torques equals K_q = Aᵀ diag(K_m) A (the law is linear in q,
/// so central differences are exact to round-off: 1e-8 N m/rad), and K_q is symmetric
/// with the biarticulars making K_q12 > 0.
#[test]
fn joint_stiffness_is_the_torque_gradient() {
    let m = model();
    let a = [30.0, 20.0, 60.0, 80.0, 10.0, 15.0];
    let q_ref = [0.6, 1.7];
    let torque =
        |q: [f64; 2]| m.joint_torque(&m.tensions(&a, &m.stretch(q, q_ref), &[0.0; MUSCLES], 1.0));
    let h = 1e-5;
    let mut fd = Matrix2::zeros();
    for k in 0..2 {
        let mut qp = q_ref;
        let mut qm = q_ref;
        qp[k] += h;
        qm[k] -= h;
        let (tp, tm) = (torque(qp), torque(qm));
        fd[(0, k)] = -(tp[0] - tm[0]) / (2.0 * h);
        fd[(1, k)] = -(tp[1] - tm[1]) / (2.0 * h);
    }
    let kq = m.joint_stiffness(&a, 1.0);
    assert!((kq - fd).abs().max() < 1e-8, "{kq} vs {fd}");
    assert!(kq[(0, 1)] > 0.0 && kq[(0, 1)] == kq[(1, 0)]);
}

/// Bad parameters are errors naming the key.
#[test]
fn bad_muscle_parameters_are_named() {
    let mut p = MuscleParams::default();
    p.stiffness_passive_n_per_m[2] = -1.0;
    assert!(matches!(
        MuscleModel::new(&p),
        Err(ArmError::InvalidParameter {
            key: "stiffness_passive_n_per_m",
            ..
        })
    ));
    let mut p = MuscleParams::default();
    p.moment_arms_m[1] = [0.0536, 0.0]; // no shoulder extensor left
    p.moment_arms_m[5] = [0.0388, 0.03];
    assert!(matches!(
        MuscleModel::new(&p),
        Err(ArmError::InvalidParameter {
            key: "moment_arms_m",
            ..
        })
    ));
}
