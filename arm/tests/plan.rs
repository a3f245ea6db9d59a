//! Minimum-jerk plan: boundary conditions and internal consistency.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use approx::assert_abs_diff_eq;
use nalgebra::Vector2;
use rigtwin_arm::plan::{MinJerk, ReachPlan};
use rigtwin_arm::time::TICK_HZ;

fn borner() -> MinJerk {
    MinJerk::new(
        Vector2::new(0.0, 0.30),
        Vector2::new(0.0, 0.55),
        400,
        12_000,
    )
    .unwrap()
}

/// At rest at the start before and at onset, at rest at the goal at and after the end
/// (position to 1e-15 m, velocity and acceleration exactly zero or to 1e-15).
#[test]
fn boundary_conditions() {
    let p = borner();
    for tick in [0, 399, 400] {
        let h = p.at(tick);
        assert_eq!(h.pos_m, Vector2::new(0.0, 0.30));
        assert_eq!(h.vel_m_s, Vector2::zeros());
        assert_eq!(h.acc_m_s2, Vector2::zeros());
    }
    for tick in [12_400, 12_401, 100_000] {
        let h = p.at(tick);
        assert!((h.pos_m - Vector2::new(0.0, 0.55)).norm() < 1e-15);
        assert!(
            h.vel_m_s.norm() < 1e-15 && h.acc_m_s2.norm() < 1e-15,
            "{h:?}"
        );
    }
}

/// Midpoint: halfway, peak speed 1.875 D/T = 0.15625 m/s, zero acceleration (1e-12).
#[test]
fn midpoint_speed_is_the_closed_form_peak() {
    let h = borner().at(400 + 6_000);
    assert_abs_diff_eq!(h.pos_m.y, 0.425, epsilon = 1e-12);
    assert_abs_diff_eq!(h.vel_m_s.y, 1.875 * 0.25 / 3.0, epsilon = 1e-12);
    assert_abs_diff_eq!(h.acc_m_s2.y, 0.0, epsilon = 1e-12);
}

/// Velocity and acceleration are the tick-wise central differences of position and
/// velocity. Truncation error h² j/6 with h = 0.25 ms and |jerk| ≤ 60 D/T³ = 0.56 m/s³
/// is ~6e-9; tolerances 1e-7 m/s and 1e-5 m/s² (the latter also absorbs round-off
/// 1e-16 m / h²).
#[test]
fn derivatives_match_central_differences() {
    let p = borner();
    let h = 1.0 / TICK_HZ as f64;
    for tick in (500..12_300).step_by(397) {
        let (a, b, c) = (p.at(tick - 1), p.at(tick), p.at(tick + 1));
        assert!(((c.pos_m - a.pos_m) / (2.0 * h) - b.vel_m_s).norm() < 1e-7);
        assert!(((c.vel_m_s - a.vel_m_s) / (2.0 * h) - b.acc_m_s2).norm() < 1e-5);
    }
}

#[test]
fn zero_duration_is_an_error() {
    assert!(MinJerk::new(Vector2::zeros(), Vector2::new(0.0, 0.1), 0, 0).is_err());
}

/// Out and back: the way back is the way out mirrored in time about the dwell's
/// middle (position equal, velocity negated, acceleration equal, to 1e-15), at rest
/// at the goal through the dwell, and at rest at the start after it.
#[test]
fn the_way_back_mirrors_the_way_out() {
    let out = borner();
    let (dwell, dur) = (2_000u64, 12_000u64);
    let back_start = 400 + dur + dwell;
    let plan = ReachPlan::new(
        Vector2::new(0.0, 0.30),
        Vector2::new(0.0, 0.55),
        400,
        dur,
        Some(dwell),
    )
    .unwrap();
    assert_eq!(plan.out, out);
    // The mirror: tick 400 + u on the way out is tick back_start + dur − u on the way back.
    for u in (0..=dur).step_by(373) {
        let (a, b) = (plan.at(400 + u), plan.at(back_start + dur - u));
        assert!((a.pos_m - b.pos_m).norm() < 1e-15, "{u}: {a:?} {b:?}");
        assert!((a.vel_m_s + b.vel_m_s).norm() < 1e-15, "{u}: {a:?} {b:?}");
        assert!((a.acc_m_s2 - b.acc_m_s2).norm() < 1e-12, "{u}: {a:?} {b:?}");
    }
    for tick in [400 + dur, back_start - 1, back_start] {
        let h = plan.at(tick);
        assert!((h.pos_m - Vector2::new(0.0, 0.55)).norm() < 1e-15, "{h:?}");
        assert!(h.vel_m_s.norm() < 1e-15, "{h:?}");
    }
    let end = plan.at(back_start + dur + 1);
    assert!((end.pos_m - Vector2::new(0.0, 0.30)).norm() < 1e-15);
    // Without a way back it is the way out's plan.
    let one_way = ReachPlan { out, back: None };
    assert_eq!(one_way.at(back_start + dur), out.at(back_start + dur));
}
