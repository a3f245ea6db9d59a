//! The Börner perturbation experiment (000_* section 4.2) on the default subject:
//! a 150 ms, 15 N force bump of the three-section jerk design (eq. 22–23) applied to
//! the handle when the hand reaches x₂ = 0.4 m, at eight angles; deviations from the
//! unperturbed twin run (same seed) within the 150 ms estimation window.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::{Load, loaded_rk4};
use nalgebra::Vector2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigtwin_arm::human::{Admittance, Human, HumanConfig, ReachTask, Task};
use rigtwin_arm::kinematics::forward;
use rigtwin_arm::params::ArmParams;
use rigtwin_arm::time::TICK_HZ;

/// The control tick, s.
const DT: f64 = 1.0 / TICK_HZ as f64;
/// 150 ms in ticks.
const T_PERT: u64 = 600;

/// Normalised force u_p of eq. 22 integrated, peak 1, over [0, T_pert] ticks.
fn bump(elapsed: u64) -> f64 {
    use std::f64::consts::PI;
    let tp = T_PERT as f64 / 3.0;
    let t = elapsed as f64;
    // Closed-form integrals of the three jerk sections.
    let s1 = |t: f64| {
        t / 2.0 - tp / (2.0 * PI) * ((t / tp + 1.5) * PI).cos() + tp / (2.0 * PI) * (1.5 * PI).cos()
    };
    let s2 = |t: f64| -tp / PI * ((t / tp + 0.5) * PI).cos() + tp / PI * (0.5 * PI).cos();
    let s3 = |t: f64| {
        -t / 2.0 - tp / (2.0 * PI) * ((t / tp + 1.5) * PI).cos()
            + tp / (2.0 * PI) * (1.5 * PI).cos()
    };
    let raw = if elapsed >= T_PERT {
        0.0
    } else if t <= tp {
        s1(t)
    } else if t <= 2.0 * tp {
        s1(tp) + s2(t - tp)
    } else {
        s1(tp) + s2(tp) + s3(t - 2.0 * tp)
    };
    raw / (tp * (0.5 + 1.0 / PI))
}

/// Hand path (shoulder frame) of one reach with an optional perturbation at `angle_deg`.
fn run(angle_deg: Option<f64>, seed: u64) -> (Vec<Vector2<f64>>, Option<usize>) {
    let p = ArmParams::default();
    let task = Task::Reach(ReachTask {
        start_rig_m: [0.0, -0.125],
        goal_rig_m: [0.0, 0.125],
        start_tick: 400,
        duration_ticks: 12_000,
        admittance: Admittance::BORNER,
        back_after_ticks: None,
    });
    let mut h = Human::new(
        p.clone(),
        task,
        HumanConfig::default(),
        ChaCha8Rng::seed_from_u64(seed),
    )
    .unwrap();
    let load = Load {
        mass_kg: [5.0, 5.0],
        damping_n_s_per_m: [15.0, 15.0],
    };
    let mut s = h.initial_state();
    let mut path = Vec::new();
    let mut onset = None;
    for tick in 0..9_000u64 {
        let x = forward(&p, s.q);
        if onset.is_none() && x.y >= 0.4 {
            onset = Some(tick as usize);
        }
        let f = match (angle_deg, onset) {
            (Some(a), Some(t0)) => {
                let u = 15.0 * bump(tick - t0 as u64);
                Vector2::new(u * a.to_radians().cos(), u * a.to_radians().sin())
            }
            _ => Vector2::zeros(),
        };
        path.push(x);
        let tau = h.update(tick, &s);
        s = loaded_rk4(&p, &s, tau, &load, f, DT);
    }
    (path, onset)
}

/// The bump is smooth and normalised: zero at both ends, peak 1 at the middle (1e-12).
#[test]
fn perturbation_bump_has_unit_peak_and_zero_ends() {
    assert!(bump(0).abs() < 1e-12);
    assert!((bump(T_PERT / 2) - 1.0).abs() < 1e-12);
    assert!(bump(T_PERT - 1).abs() < 1e-4 && bump(T_PERT) == 0.0);
}

/// Mean maximum deviations within the 150 ms window over the eight angles of 000_*.
/// The seed's simulated arm gave 6.1 (1.8) mm along x₁ and 5.9 (1.7) mm along x₂; the
/// default subject must land within two of those standard deviations.
#[test]
fn borner_perturbation_deviations_match_the_seed() {
    let (base, onset) = run(None, 5);
    let t0 = onset.unwrap();
    let mut dev = [0.0f64; 2];
    let angles = [30.0, 60.0, 120.0, 150.0, 210.0, 240.0, 300.0, 330.0];
    for a in angles {
        let (path, onset_p) = run(Some(a), 5);
        assert_eq!(onset_p, onset);
        for k in 0..2 {
            let m = (t0..t0 + T_PERT as usize)
                .map(|t| (path[t][k] - base[t][k]).abs())
                .fold(0.0, f64::max);
            dev[k] += m / angles.len() as f64;
        }
    }
    eprintln!(
        "mean max deviations: x1 {:.2} mm, x2 {:.2} mm",
        dev[0] * 1e3,
        dev[1] * 1e3
    );
    assert!(
        (dev[0] * 1e3 - 6.1).abs() < 2.0 * 1.8,
        "x1 deviation {} mm",
        dev[0] * 1e3
    );
    assert!(
        (dev[1] * 1e3 - 5.9).abs() < 2.0 * 1.7,
        "x2 deviation {} mm",
        dev[1] * 1e3
    );
}
