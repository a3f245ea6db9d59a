//! The position perturbation of 001_*: amplitude, duration, smooth transitions, and the
//! trigger at the imposed sinusoid's zero-acceleration points.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use core::f64::consts::FRAC_PI_4;

use rigtwin_device::config::{PositionPerturbationConfig, TransitionShape};
use rigtwin_device::perturb::ArmError;
use rigtwin_device::perturb::position::{PositionPerturbation, PositionTrigger, transition};
use rigtwin_device::testing::{MockRig, scripted};
use rigtwin_device::{Controller, ControllerConfig, LawKind, PerturbationStatus, Rate, Tick};

fn shapes() -> [TransitionShape; 2] {
    [TransitionShape::Degree6, TransitionShape::MinimumSnap7]
}

#[test]
fn transitions_start_and_end_at_rest() {
    for shape in shapes() {
        let (s0, v0, a0) = transition(shape, 0.0);
        let (s1, v1, a1) = transition(shape, 1.0);
        // Polynomials with integer coefficients evaluated at 0 and 1: exact up to the
        // rounding of a sum of four terms of size ≤ 2100, i.e. 1e-12.
        for v in [s0, v0, a0, v1, a1] {
            assert!(v.abs() < 1e-12, "{shape:?}: {v}");
        }
        assert!((s1 - 1.0).abs() < 1e-12);
        // Numerical check that σ', σ'' are the derivatives of σ (central differences,
        // error ~ δ² σ''''/6 with δ = 1e-4: < 1e-5).
        let d = 1e-4;
        for i in 1..100 {
            let t = f64::from(i) / 100.0;
            let (_, v, a) = transition(shape, t);
            let (sp, vp, _) = transition(shape, t + d);
            let (sm, vm, _) = transition(shape, t - d);
            assert!(
                ((sp - sm) / (2.0 * d) - v).abs() < 1e-5,
                "{shape:?} σ' at {t}"
            );
            assert!(
                ((vp - vm) / (2.0 * d) - a).abs() < 1e-5,
                "{shape:?} σ'' at {t}"
            );
        }
    }
    // Zero end jerk for the 001_* degree-6 polynomial: σ''' (1) = 120 − 1080 + 2160 − 1200 = 0.
    let (_, _, a_hi) = transition(TransitionShape::Degree6, 1.0);
    let (_, _, a_lo) = transition(TransitionShape::Degree6, 1.0 - 1e-6);
    assert!(((a_hi - a_lo) / 1e-6).abs() < 1e-3);
}

#[test]
fn profile_has_the_amplitude_duration_and_rest_at_each_transition_end() {
    for shape in shapes() {
        let config = PositionPerturbationConfig {
            shape,
            ..PositionPerturbationConfig::default()
        };
        let p = PositionPerturbation::new(&config, Rate::CONTROL);
        // 300 ms total, 100 ms transitions at 4 kHz.
        assert_eq!((p.duration_ticks(), p.transition_ticks()), (1200, 400));
        let peak = (0..1300)
            .map(|k| p.profile(k).position_m)
            .fold(0.0, f64::max);
        // Hold at exactly 8 mm (σ = 1 on the hold); tolerance 1e-15 m, rounding.
        assert!((peak - 0.008).abs() < 1e-15, "{peak}");
        assert!((400..800).all(|k| (p.profile(k).position_m - 0.008).abs() < 1e-15));
        // Zero outside [0, 1200); the return ends at rest on the last tick.
        assert_eq!(p.profile(1200).position_m, 0.0);
        for k in [0u64, 400, 800, 1200] {
            let s = p.profile(k);
            // At the transition boundaries σ' = σ'' = 0 exactly up to rounding.
            assert!(
                s.velocity_m_per_s.abs() < 1e-12 && s.acceleration_m_per_s2.abs() < 1e-9,
                "{shape:?} {k} {s:?}"
            );
        }
        // Just inside the ends the motion is nearly at rest: one tick into the Degree6
        // transition the velocity is 60 τ² A / T (τ = 1/400) ≈ 1.9e-5 m/s.
        assert!(p.profile(1).velocity_m_per_s.abs() < 3e-5);
        assert!(p.profile(1199).velocity_m_per_s.abs() < 3e-5);
    }
}

#[test]
fn fires_at_the_next_zero_acceleration_point_of_the_imposed_motion() {
    // Virtual spring with the 001_* sinusoid (±0.10 m, 0.125 Hz, 4 s ramp): the first
    // zero-acceleration point of the full-amplitude part is 4 s = 16 000 ticks after
    // the first active tick (tick 1).
    // The mock's carts stay at the origin while the anchor sweeps ±0.10 m, and its force
    // is zero bit for bit: the stale-force and encoder-stall watchdogs are off
    // ([`scripted`]); the trigger is under test.
    let config = scripted(ControllerConfig {
        law: LawKind::VirtualSpring,
        ..ControllerConfig::default()
    });
    let mut rig = MockRig::default();
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let angle = 3.0 * FRAC_PI_4;
    c.arm_position_perturbation(angle, PositionTrigger::NextZeroAcceleration)
        .unwrap();
    let mut pert = Vec::new();
    let mut at_onset = None;
    for n in 1..=17_500u64 {
        let r = c.tick(&mut rig, Tick(n));
        if n >= 16_001 {
            pert.push(r.pert_position_m);
        }
        if n == 16_001 {
            at_onset = Some(r);
        }
    }
    let r = at_onset.unwrap();
    assert_eq!(
        r.position_perturbation,
        PerturbationStatus::Running {
            onset: Tick(16_001)
        }
    );
    // The anchor is at the centre with zero acceleration there (sin(π) ~ 1e-16).
    assert!(r.anchor_position_m[1].abs() < 1e-12);
    // Hold phase: 8 mm along 135°, to 1e-15 m.
    let hold = pert[600];
    assert!((hold[0].hypot(hold[1]) - 0.008).abs() < 1e-15);
    assert!((hold[1].atan2(hold[0]) - angle).abs() < 1e-12);
    // Ends after exactly 1200 ticks.
    assert!(pert[1199][0] != 0.0 && pert[1200] == [0.0, 0.0]);
    assert_eq!(
        c.position_perturbation_status(),
        PerturbationStatus::Done {
            onset: Tick(16_001)
        }
    );
}

#[test]
fn zero_acceleration_trigger_needs_the_imposed_motion() {
    let mut c = Controller::new(ControllerConfig::default()).unwrap();
    assert_eq!(
        c.arm_position_perturbation(0.0, PositionTrigger::NextZeroAcceleration),
        Err(ArmError::NoImposedMotion)
    );
    // A tick trigger works in admittance mode too.
    assert!(
        c.arm_position_perturbation(FRAC_PI_4, PositionTrigger::AtTick(Tick(10)))
            .is_ok()
    );
}
