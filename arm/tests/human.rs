//! The simulated human: reach against the Börner admittance, force holding, exact
//! neural delays, seeded noise, stiffness drift, configuration errors.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use approx::assert_relative_eq;
use common::{Load, loaded_rk4};
use nalgebra::Vector2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigtwin_arm::ArmError;
use rigtwin_arm::dynamics::JointState;
use rigtwin_arm::human::{Admittance, HoldTask, Human, HumanConfig, ReachTask, Task};
use rigtwin_arm::kinematics::{forward, jacobian};
use rigtwin_arm::muscles::MuscleParams;
use rigtwin_arm::params::{ArmParams, StiffnessDrift, StretchReflex};
use rigtwin_arm::time::TICK_HZ;

/// The control tick, s.
const DT: f64 = 1.0 / TICK_HZ as f64;

/// 000_* section 4: shoulder-frame (0, 0.30) → (0, 0.55) m in 3 s; with the default
/// shoulder at rig (0, −0.425) that is rig (0, −0.125) → (0, 0.125).
fn borner_reach() -> Task {
    Task::Reach(ReachTask {
        start_rig_m: [0.0, -0.125],
        goal_rig_m: [0.0, 0.125],
        start_tick: 400,
        duration_ticks: 12_000,
        admittance: Admittance::BORNER,
        back_after_ticks: None,
    })
}

fn hold(force_n: [f64; 2], rise: f64) -> Task {
    Task::Hold(HoldTask {
        hand_rig_m: [0.0, 0.0],
        force_n,
        imposed: None,
        co_contraction_rise_per_s: rise,
    })
}

fn quiet() -> ArmParams {
    let mut p = ArmParams::default();
    p.noise.activation_cv = 0.0;
    p
}

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

struct ReachRun {
    max_dev_m: f64,
    final_err_m: f64,
    k_at_04: nalgebra::Matrix2<f64>,
    d_at_04: nalgebra::Matrix2<f64>,
}

/// The default subject reaching with the hand dragging the Börner admittance
/// (5 kg, 15 N s/m), integrated with RK4 at the tick.
fn run_reach(params: ArmParams, seed: u64) -> ReachRun {
    let mut h = Human::new(
        params.clone(),
        borner_reach(),
        HumanConfig::default(),
        rng(seed),
    )
    .unwrap();
    let load = Load {
        mass_kg: [5.0, 5.0],
        damping_n_s_per_m: [15.0, 15.0],
    };
    let mut s = h.initial_state();
    let mut max_dev_m: f64 = 0.0;
    let mut at_04 = None;
    for tick in 0..14_400u64 {
        let tau = h.update(tick, &s);
        s = loaded_rk4(&params, &s, tau, &load, Vector2::zeros(), DT);
        let x = forward(&params, s.q);
        let plan = forward(&params, h.base_reference(tick + 1).unwrap().q);
        max_dev_m = max_dev_m.max((x - plan).norm());
        if tick == 6_400 {
            let g = h.ground_truth(s.q).unwrap();
            eprintln!(
                "midpoint {x:?}: K = {:.1} D = {:.2} M = {:.3}",
                g.stiffness_n_per_m, g.damping_n_s_per_m, g.mass_kg
            );
        }
        if at_04.is_none() && x.y >= 0.4 {
            at_04 = Some(h.ground_truth(s.q).unwrap());
        }
    }
    let g = at_04.unwrap();
    ReachRun {
        max_dev_m,
        final_err_m: (forward(&params, s.q) - Vector2::new(0.0, 0.55)).norm(),
        k_at_04: g.stiffness_n_per_m,
        d_at_04: g.damping_n_s_per_m,
    }
}

/// The reach follows its plan: deviation below 3 mm throughout and within 2 mm of the
/// goal 0.5 s after the end (measured 1.1 mm and 0.7 mm with the default noise; the
/// bounds leave room for other seeds). The intrinsic stiffness where Börner's
/// perturbation starts (x₂ = 0.4 m) lies within one standard deviation of every entry
/// of Table 1 (K = [[110.52 ± 48.54, −106.05 ± 62.91], [·, 313.75 ± 77.46]] N/m), as do
/// D₁₁ and D₁₂ ([[10.98 ± 4.85, −7.94 ± 3.26], ...]); D₂₂ = K₂₂/12 by the seed's law and
/// is not (see the crate docs).
#[test]
fn default_reach_tracks_its_plan_and_lands_on_borner_table_1() {
    let r = run_reach(ArmParams::default(), 7);
    eprintln!(
        "reach: max deviation {:.2} mm, final error {:.2} mm\nK(x2=0.4) = {:.1}\nD(x2=0.4) = {:.2}",
        r.max_dev_m * 1e3,
        r.final_err_m * 1e3,
        r.k_at_04,
        r.d_at_04
    );
    assert!(r.max_dev_m < 3e-3, "max deviation {} m", r.max_dev_m);
    assert!(r.final_err_m < 2e-3, "final error {} m", r.final_err_m);
    let k = r.k_at_04;
    assert!((k[(0, 0)] - 110.52).abs() < 48.54, "K = {k}");
    assert!((k[(0, 1)] + 106.05).abs() < 62.91, "K = {k}");
    assert!((k[(1, 1)] - 313.75).abs() < 77.46, "K = {k}");
    let d = r.d_at_04;
    assert!((d[(0, 0)] - 10.98).abs() < 4.85, "D = {d}");
    assert!((d[(0, 1)] + 7.94).abs() < 3.26, "D = {d}");
    assert_relative_eq!(d[(1, 1)], k[(1, 1)] / 12.0, max_relative = 1e-12);
}

/// Out and back in one trial: the hand follows the way back as it follows the way out
/// (deviation below the one-way reach's 3 mm bound throughout) and ends within the same
/// 2 mm of the start 0.5 s after the way back ends.
#[test]
fn a_reach_out_and_back_returns_to_its_start() {
    let params = ArmParams::default();
    let task = match borner_reach() {
        Task::Reach(r) => Task::Reach(ReachTask {
            back_after_ticks: Some(2_000),
            ..r
        }),
        Task::Hold(_) => unreachable!(),
    };
    let mut h = Human::new(params.clone(), task, HumanConfig::default(), rng(7)).unwrap();
    let load = Load {
        mass_kg: [5.0, 5.0],
        damping_n_s_per_m: [15.0, 15.0],
    };
    let mut s = h.initial_state();
    let (mut max_dev_m, mut farthest_y): (f64, f64) = (0.0, 0.0);
    // 400 still, 12 000 out, 2 000 at the goal, 12 000 back, 2 000 still.
    for tick in 0..28_400u64 {
        let tau = h.update(tick, &s);
        s = loaded_rk4(&params, &s, tau, &load, Vector2::zeros(), DT);
        let x = forward(&params, s.q);
        let plan = forward(&params, h.base_reference(tick + 1).unwrap().q);
        max_dev_m = max_dev_m.max((x - plan).norm());
        farthest_y = farthest_y.max(x.y);
    }
    let end_err_m = (forward(&params, s.q) - Vector2::new(0.0, 0.30)).norm();
    eprintln!(
        "out and back: max deviation {:.2} mm, farthest {:.4} m, end error {:.2} mm",
        max_dev_m * 1e3,
        farthest_y,
        end_err_m * 1e3
    );
    assert!(max_dev_m < 3e-3, "max deviation {max_dev_m} m");
    assert!((farthest_y - 0.55).abs() < 3e-3, "farthest {farthest_y} m");
    assert!(end_err_m < 2e-3, "end error {end_err_m} m");
}

/// Force holding against a rigid handle (hand held at the posture): after the 60 ms
/// feedback has settled the muscles press the commanded 5 N forward, 3 N right to
/// 0.05 N — the bias fixed point is converged to well below that — and keep pressing
/// it while the co-contraction doubles over 2 s, with a shrinking bias and a rising
/// stiffness (the impedance strategy of 001_* eq. 7).
#[test]
fn hold_presses_the_commanded_force_while_co_contraction_rises() {
    let p = quiet();
    let mut h = Human::new(
        p.clone(),
        hold([3.0, 5.0], 0.5),
        HumanConfig::default(),
        rng(1),
    )
    .unwrap();
    let s = h.initial_state();
    let j_inv_t = jacobian(&p, s.q).transpose().try_inverse().unwrap();
    let mut samples = Vec::new();
    for tick in 0..8_001u64 {
        let tau = h.update(tick, &s);
        if tick == 2_000 || tick == 8_000 {
            let f = j_inv_t * Vector2::new(tau[0], tau[1]);
            let bias = Vector2::new(h.bias_rad()[0], h.bias_rad()[1]).norm();
            let k = h.ground_truth(s.q).unwrap().stiffness_n_per_m;
            samples.push((f, bias, k.trace()));
        }
    }
    for (f, _, _) in &samples {
        assert!((f - Vector2::new(3.0, 5.0)).norm() < 0.05, "force {f:?}");
    }
    assert!(
        samples[1].1 < 0.8 * samples[0].1,
        "bias should shrink: {samples:?}"
    );
    assert!(
        samples[1].2 > 1.3 * samples[0].2,
        "stiffness should rise: {samples:?}"
    );
}

/// Record the tick at which the activations first change after a step in the state.
fn first_response(params: ArmParams, divisor: u32, step: JointState) -> u64 {
    let cfg = HumanConfig {
        neural_divisor: divisor,
        ..HumanConfig::default()
    };
    let mut h = Human::new(params, hold([0.0, 0.0], 0.0), cfg, rng(3)).unwrap();
    let s0 = h.initial_state();
    let stepped = JointState {
        q: [s0.q[0] + step.q[0], s0.q[1] + step.q[1]],
        qd: step.qd,
    };
    let mut before = None;
    for tick in 0..2_000u64 {
        let s = if tick >= 800 { stepped } else { s0 };
        h.update(tick, &s);
        match before {
            None if tick == 799 => before = Some(h.activations_n()),
            Some(b) if h.activations_n() != b => return tick,
            _ => {}
        }
    }
    u64::MAX
}

/// A step of the joint angles at tick 800 reaches the activations exactly 60 ms
/// (240 ticks) later, at every neural rate dividing 240 ticks; the stretch reflex
/// (25 ms) answers a velocity step exactly 100 ticks later. Noise is off, so
/// activations change only through the delayed paths.
#[test]
fn feedback_and_reflex_delays_are_exact_in_ticks() {
    let dq = JointState {
        q: [0.01, -0.01],
        qd: [0.0, 0.0],
    };
    for divisor in [1, 4, 8, 16, 40] {
        assert_eq!(
            first_response(quiet(), divisor, dq),
            800 + 240,
            "divisor {divisor}"
        );
    }
    let mut p = quiet();
    p.stretch_reflex = Some(StretchReflex::TYPICAL);
    let dqd = JointState {
        q: [0.0, 0.0],
        qd: [0.5, -0.5],
    };
    assert_eq!(first_response(p, 4, dqd), 800 + 100);
}

/// Torques over a noisy reach, as bytes.
fn torque_bytes(seed: u64) -> Vec<u8> {
    let p = ArmParams::default();
    let mut h = Human::new(p, borner_reach(), HumanConfig::default(), rng(seed)).unwrap();
    let s = h.initial_state();
    let mut out = Vec::new();
    for tick in 0..4_000u64 {
        let tau = h.update(tick, &s);
        out.extend(tau.iter().flat_map(|t| t.to_le_bytes()));
    }
    out
}

/// Same seed → byte-identical torques; another seed → different torques.
#[test]
fn noise_is_determined_by_the_seed() {
    let a = torque_bytes(11);
    assert_eq!(a, torque_bytes(11));
    assert_ne!(a, torque_bytes(12));
}

/// Drift: in trial 10 with +2 %/trial every stiffness is 1.02¹⁰ times trial 0's at the
/// same activations (1e-12 relative); D follows K.
#[test]
fn stiffness_drift_scales_per_trial() {
    let mut p = quiet();
    p.stiffness_drift = Some(StiffnessDrift {
        scale_per_trial: 1.02,
    });
    let gt = |trial| {
        let cfg = HumanConfig {
            trial_index: trial,
            ..HumanConfig::default()
        };
        let h = Human::new(p.clone(), hold([0.0, 0.0], 0.0), cfg, rng(1)).unwrap();
        h.ground_truth(h.initial_state().q).unwrap()
    };
    let (g0, g10) = (gt(0), gt(10));
    let s = 1.02f64.powi(10);
    assert!(
        (g10.stiffness_n_per_m - g0.stiffness_n_per_m * s).norm()
            < 1e-12 * g10.stiffness_n_per_m.norm()
    );
    assert!(
        (g10.damping_n_s_per_m - g0.damping_n_s_per_m * s).norm()
            < 1e-12 * g10.damping_n_s_per_m.norm()
    );
    assert_eq!(g10.mass_kg, g0.mass_kg);
}

/// Configuration errors are reported, not panicked on.
#[test]
fn bad_configurations_are_errors() {
    let p = ArmParams::default();
    let with_div = |d| HumanConfig {
        neural_divisor: d,
        ..HumanConfig::default()
    };
    // 7 does not divide 4000.
    assert!(matches!(
        Human::new(p.clone(), borner_reach(), with_div(7), rng(0)),
        Err(ArmError::InvalidParameter {
            key: "neural_divisor",
            ..
        })
    ));
    // 32 divides 4000 but 60 ms = 7.5 periods of 32 ticks.
    assert!(matches!(
        Human::new(p.clone(), borner_reach(), with_div(32), rng(0)),
        Err(ArmError::InvalidParameter {
            key: "feedback.delay_ms",
            ..
        })
    ));
    let far = Task::Reach(ReachTask {
        goal_rig_m: [0.0, 0.30],
        ..match borner_reach() {
            Task::Reach(r) => r,
            Task::Hold(_) => unreachable!(),
        }
    });
    assert!(matches!(
        Human::new(p, far, HumanConfig::default(), rng(0)),
        Err(ArmError::Unreachable { .. })
    ));
}

/// Holding while the rig moves the hand along a known ±5 cm, 0.5 Hz sinusoid (the hand
/// follows it exactly, as behind a stiff HapticMaster): the muscle torque beyond the
/// arm's own inverse dynamics presses the commanded force to 0.2 N. The bias follows
/// the posture each neural tick while the position feedback lags 60 ms behind, which
/// is where the residual comes from (measured 0.04 N).
#[test]
fn hold_keeps_the_force_on_an_imposed_sinusoid() {
    use rigtwin_arm::human::ImposedSinusoid;
    let p = quiet();
    let task = Task::Hold(HoldTask {
        hand_rig_m: [0.0, 0.0],
        force_n: [0.0, 5.0],
        imposed: Some(ImposedSinusoid {
            amplitude_m: [0.05, 0.0],
            frequency_hz: 0.5,
            start_tick: 0,
            ramp_s: 0.0,
            cycles: None,
        }),
        co_contraction_rise_per_s: 0.0,
    });
    let mut h = Human::new(p.clone(), task, HumanConfig::default(), rng(1)).unwrap();
    let mut worst: f64 = 0.0;
    for tick in 0..8_000u64 {
        let r = h.base_reference(tick).unwrap();
        let s = JointState { q: r.q, qd: r.qd };
        let tau = h.update(tick, &s);
        if tick >= 1_000 {
            // The plan's feed-forward torque is the arm's own inverse dynamics ID(q, q̇, q̈).
            let j = jacobian(&p, s.q);
            let extra = Vector2::new(tau[0] - r.tau_ff_n_m[0], tau[1] - r.tau_ff_n_m[1]);
            let f = j.transpose().try_inverse().unwrap() * extra;
            worst = worst.max((f - Vector2::new(0.0, 5.0)).norm());
        }
    }
    eprintln!("hold on sinusoid: worst force error {worst:.4} N");
    assert!(worst < 0.2, "worst force error {worst} N");
}

/// With [`MuscleParams::table1_damping`] the reach's endpoint damping at x₂ = 0.4 m lies
/// within one std of all four entries of Table 1 (D = [[10.98 ± 4.85, −7.94 ± 3.26],
/// [−8.54 ± 4.16, 6.75 ± 4.27]] N s/m; the symmetric D is compared with both
/// off-diagonals) and the stiffness is the same as with the seed's damping (the
/// damping only changes the motion, by less than 2 %).
#[test]
fn table1_damping_preset_puts_d_within_one_std() {
    let p = ArmParams {
        muscles: MuscleParams::table1_damping(),
        ..ArmParams::default()
    };
    let r = run_reach(p, 7);
    let d = r.d_at_04;
    eprintln!("table1_damping: D(x2=0.4) = {d:.2} K = {:.1}", r.k_at_04);
    assert!((d[(0, 0)] - 10.98).abs() < 4.85, "D = {d}");
    assert!(
        (d[(0, 1)] + 7.94).abs() < 3.26 && (d[(1, 0)] + 8.54).abs() < 4.16,
        "D = {d}"
    );
    assert!((d[(1, 1)] - 6.75).abs() < 4.27, "D = {d}");
    let k0 = run_reach(ArmParams::default(), 7).k_at_04;
    assert!(
        (r.k_at_04 - k0).norm() < 0.02 * k0.norm(),
        "{} vs {}",
        r.k_at_04,
        k0
    );
}
