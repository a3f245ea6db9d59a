//! Kinematics against closed forms and finite differences.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use approx::assert_abs_diff_eq;
use nalgebra::Vector2;
use proptest::prelude::*;
use rigtwin_arm::ArmError;
use rigtwin_arm::kinematics::{Elbow, elbow, forward, inverse, jacobian, jacobian_dot};
use rigtwin_arm::params::ArmParams;

proptest! {
    /// forward(inverse(x)) = x. Tolerance 1e-12 m: a few dozen flops on 0.3 m lengths
    /// leave round-off near 1e-16 m; 1e-12 m is far below anything physical.
    #[test]
    fn inverse_then_forward_is_identity(r in 0.05f64..0.66, phi in -3.1f64..3.1, up in any::<bool>()) {
        let p = ArmParams::default();
        let x = Vector2::new(r * phi.cos(), r * phi.sin());
        let which = if up { Elbow::Up } else { Elbow::Down };
        let q = inverse(&p, x, which).unwrap();
        prop_assert!((forward(&p, q) - x).norm() < 1e-12);
        let right_side = if up { q[1] <= 0.0 } else { q[1] >= 0.0 };
        prop_assert!(right_side);
    }

    /// inverse(forward(q)) = q for flexed elbows. 1e-10 rad: atan2 keeps full precision
    /// away from the straight arm (q1 >= 0.05 rad).
    #[test]
    fn forward_then_inverse_recovers_angles(q0 in -3.1f64..3.1, q1 in 0.05f64..3.0) {
        let p = ArmParams::default();
        let q = inverse(&p, forward(&p, [q0, q1]), Elbow::Down).unwrap();
        prop_assert!((q[0] - q0).abs() < 1e-10 && (q[1] - q1).abs() < 1e-10, "{q:?} vs {q0} {q1}");
    }

    /// J = ∂x/∂q by central differences, h = 1e-6 rad: truncation ~ l h²/6 ≈ 1e-13 m/rad,
    /// round-off ~ 1e-16 m / 1e-6 = 1e-10 m/rad; tolerance 1e-8 m/rad.
    #[test]
    fn jacobian_matches_central_differences(q0 in -3.1f64..3.1, q1 in -3.0f64..3.0) {
        let p = ArmParams::default();
        let j = jacobian(&p, [q0, q1]);
        let h = 1e-6;
        for k in 0..2 {
            let mut qp = [q0, q1];
            let mut qm = [q0, q1];
            qp[k] += h;
            qm[k] -= h;
            let col = (forward(&p, qp) - forward(&p, qm)) / (2.0 * h);
            prop_assert!((j.column(k) - col).norm() < 1e-8);
        }
    }

    /// J̇ = dJ/dt along q(t) = q + q̇ t, central differences with h = 1e-6 s; same budget
    /// as above scaled by |q̇| ≤ 5 rad/s: tolerance 1e-7 m/(rad s).
    #[test]
    fn jacobian_dot_matches_differences_along_motion(
        q0 in -3.1f64..3.1, q1 in -3.0f64..3.0, w0 in -5.0f64..5.0, w1 in -5.0f64..5.0,
    ) {
        let p = ArmParams::default();
        let h = 1e-6;
        let jp = jacobian(&p, [q0 + w0 * h, q1 + w1 * h]);
        let jm = jacobian(&p, [q0 - w0 * h, q1 - w1 * h]);
        let fd = (jp - jm) / (2.0 * h);
        prop_assert!((jacobian_dot(&p, [q0, q1], [w0, w1]) - fd).norm() < 1e-7);
    }
}

/// The human right-arm posture at the Börner start point (0, 0.30) m: elbow flexed
/// (q1 = 126.83°), shoulder at 24.88°, elbow out to the subject's right (x > 0).
/// Angles from the law of cosines by hand; 0.01° covers the rounding of the reference.
#[test]
fn elbow_down_is_the_human_right_arm_posture() {
    let p = ArmParams::default();
    let q = inverse(&p, Vector2::new(0.0, 0.30), Elbow::Down).unwrap();
    assert_abs_diff_eq!(q[0].to_degrees(), 24.879, epsilon = 0.01);
    assert_abs_diff_eq!(q[1].to_degrees(), 126.825, epsilon = 0.01);
    let e = elbow(&p, q);
    assert!(
        e.x > 0.25 && e.y > 0.0,
        "elbow at {e:?} should be out to the right"
    );
    assert_abs_diff_eq!(e.norm(), 0.33, epsilon = 1e-12);
}

/// Out-of-reach and non-finite hands are errors, not panics or NaN angles.
#[test]
fn unreachable_and_nan_hands_are_errors() {
    let p = ArmParams::default();
    assert!(matches!(
        inverse(&p, Vector2::new(0.0, 0.70), Elbow::Down),
        Err(ArmError::Unreachable { max_m, .. }) if (max_m - 0.67).abs() < 1e-12
    ));
    assert!(matches!(
        inverse(&p, Vector2::new(0.0, 0.005), Elbow::Down),
        Err(ArmError::Unreachable { .. })
    ));
    assert!(matches!(
        inverse(&p, Vector2::new(f64::NAN, 0.3), Elbow::Down),
        Err(ArmError::NonFinite { .. })
    ));
}
