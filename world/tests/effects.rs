//! Each plant effect changes what it names, by its law, and nothing else.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::f64::consts::PI;

use common::{bare, push};
use rigtwin_device::{MotorCommand, RigIo, Tick};
use rigtwin_world::config::{
    ActuationDelay, CableSpring, ForceRipple, Grasp, GripCompliance, HandleMass, RailFriction,
    RigConfig, SensorEffect,
};
use rigtwin_world::effects::{cable_force_n, friction_force_n, ripple_force_n};
use rigtwin_world::{SimRig, StepTruth, TICK_S};

/// Runs `ticks` ticks with command `f(tick)`, returns (positions, truths, readings).
fn run(
    cfg: RigConfig,
    ticks: u64,
    f: impl Fn(u64) -> [f64; 2],
) -> (Vec<[f64; 2]>, Vec<StepTruth>, Vec<[f64; 2]>) {
    let mut rig = SimRig::with_seed(cfg, 7).unwrap();
    let (mut p, mut t, mut r) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..ticks {
        rig.write(Tick(k), MotorCommand { force_n: f(k) }).unwrap();
        rig.step().unwrap();
        p.push(rig.cart_positions_m());
        t.push(*rig.truth());
        r.push(rig.read(Tick(k + 1)).unwrap().force_raw_n);
    }
    (p, t, r)
}

#[test]
fn sensor_sees_the_handle_inertia_on_a_bare_handle() {
    // Nothing holds the handle: the sensor carries only the handle's inertia,
    // F = −m_h a with a = F_motor / (m_carts + m_h). 1e-6 N (3e-6 of the reading): the
    // reading is the momentum balance of rapier's own step, so only the joint solver's
    // residual (measured 1e-8 N) separates it from the closed form.
    let cfg = bare();
    let mh = cfg.handle_mass_kg;
    let (_, truth, _) = run(cfg, 400, |_| [10.0, -5.0]);
    let s = truth[399].sensor_n;
    let (mx, my) = (8.0 + 4.0 + mh, 4.0 + mh);
    assert!((s[0] + mh * 10.0 / mx).abs() < 1e-6, "{s:?}");
    assert!((s[1] - mh * 5.0 / my).abs() < 1e-6, "{s:?}");
}

#[test]
fn rail_friction_acts_by_its_law_at_the_measured_velocity() {
    let law = RailFriction {
        coulomb_n: 2.0,
        viscous_n_s_per_m: 5.0,
        smooth_velocity_m_per_s: 0.005,
    };
    let mut cfg = bare();
    cfg.effects.rail_friction = Some(law);
    let mut rig = SimRig::with_seed(cfg.clone(), 7).unwrap();
    let m = rig.carried_mass_kg();
    for k in 0..4000u64 {
        let v0 = rig.cart_velocities_m_per_s();
        rig.write(Tick(k), MotorCommand { force_n: push(k) })
            .unwrap();
        rig.step().unwrap();
        let t = *rig.truth();
        let v1 = rig.cart_velocities_m_per_s();
        for axis in 0..2 {
            // The law at the start-of-tick velocity (explicit friction).
            assert!((t.friction_n[axis] - friction_force_n(&law, v0[axis])).abs() < 1e-12);
            // And it moved the carts: m Δv/dt = F_motor + F_friction, to 1e-4 N (the
            // coupled rails' solver residual, measured ≤ 1e-6 N, is 1e-6 of the 4 N push).
            let f = m[axis] * (v1[axis] - v0[axis]) / TICK_S;
            let expected = t.motor_n[axis] + t.friction_n[axis];
            assert!(
                (f - expected).abs() < 1e-4,
                "tick {k} axis {axis}: m a = {f} N vs {expected} N"
            );
        }
    }
    // Nothing else: without friction the friction channel stays zero and the motor is
    // the command.
    let (_, truth, _) = run(bare(), 100, push);
    assert!(truth.iter().all(|t| t.friction_n == [0.0, 0.0]));
    assert!(
        truth
            .iter()
            .enumerate()
            .all(|(k, t)| t.motor_n == push(k as u64))
    );
}

#[test]
fn sensor_rotation_offset_and_lowpass_change_only_the_reading() {
    let eff = SensorEffect {
        rotation_deg: 30.0,
        offset_n: [0.5, -0.25],
        lowpass_hz: 0.0,
    };
    let mut cfg = bare();
    cfg.effects.sensor = Some(eff);
    let (p1, t1, r1) = run(cfg, 800, push);
    let (p0, t0, r0) = run(bare(), 800, push);
    // Same motion, same true force, byte for byte: the sensor is not part of the physics.
    assert_eq!(p0, p1);
    assert_eq!(t0, t1);
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    for (a, b) in r0.iter().zip(&r1) {
        // The reading is the ideal one rotated by 30° plus the offset (1e-12 N round-off).
        let ex = [c * a[0] - s * a[1] + 0.5, s * a[0] + c * a[1] - 0.25];
        assert!((b[0] - ex[0]).abs() < 1e-12 && (b[1] - ex[1]).abs() < 1e-12);
    }
    // Low-pass: a constant true force is reached with the first-order time constant:
    // after τ = 1/(2π f) the reading is 1 − e⁻¹ of the step (to one tick's change).
    let f_hz = 20.0;
    let mut cfg = bare();
    cfg.effects.sensor = Some(SensorEffect {
        rotation_deg: 0.0,
        offset_n: [0.0, 0.0],
        lowpass_hz: f_hz,
    });
    let (_, t, r) = run(cfg, 200, |_| [10.0, 0.0]);
    let tau_ticks = (1.0 / (2.0 * PI * f_hz) / TICK_S).round() as usize;
    let ratio = r[tau_ticks - 1][0] / t[tau_ticks - 1].sensor_n[0];
    assert!((ratio - (1.0 - (-1.0f64).exp())).abs() < 0.01, "{ratio}");
}

#[test]
fn actuation_delay_shifts_the_force_by_exactly_n_ticks() {
    let mut cfg = bare();
    cfg.effects.actuation_delay = Some(ActuationDelay { delay_ms: 1.25 });
    let n = 5; // 1.25 ms at 4 kHz
    let (_, t, _) = run(cfg, 400, push);
    for (k, tr) in t.iter().enumerate() {
        let expected = if k >= n {
            push((k - n) as u64)
        } else {
            [0.0, 0.0]
        };
        assert_eq!(tr.motor_n, expected, "tick {k}");
    }
}

#[test]
fn force_ripple_adds_cogging_by_cart_position() {
    // Each axis its own amplitude and phase: a law that swapped the axes or dropped a
    // phase would miss by up to 1.6 N on some tick.
    let r = ForceRipple {
        amplitude_n: [0.8, 0.5],
        pitch_m: 0.03,
        phase_rad: [0.0, 2.0],
    };
    let mut cfg = bare();
    cfg.effects.force_ripple = Some(r);
    let mut rig = SimRig::with_seed(cfg, 7).unwrap();
    let mut max_ripple = 0.0f64;
    for k in 0..4000u64 {
        let x = rig.cart_positions_m();
        rig.write(Tick(k), MotorCommand { force_n: push(k) })
            .unwrap();
        rig.step().unwrap();
        let m = rig.truth().motor_n;
        let cmd = push(k);
        for axis in 0..2 {
            let extra = m[axis] - cmd[axis];
            let law = r.amplitude_n[axis]
                * (std::f64::consts::TAU * x[axis] / r.pitch_m + r.phase_rad[axis]).sin();
            assert_eq!(ripple_force_n(&r, axis, x[axis]), law);
            assert!((extra - law).abs() < 1e-12);
            max_ripple = max_ripple.max(extra.abs());
        }
    }
    // The carts travelled several pitches, so the cogging reached most of its amplitude.
    assert!(max_ripple > 0.7, "{max_ripple}");
}

#[test]
fn extra_handle_mass_is_seen_by_the_sensor_only_through_inertia() {
    let mut cfg = bare();
    cfg.effects.handle_mass = Some(HandleMass { extra_mass_kg: 0.2 });
    let (_, truth, _) = run(cfg, 400, |_| [10.0, -5.0]);
    let mh = 0.35 + 0.2;
    let s = truth[399].sensor_n;
    // 1e-6 N: the joint solver's residual, as for the bare handle.
    assert!((s[0] + mh * 10.0 / (12.0 + mh)).abs() < 1e-6, "{s:?}");
    assert!((s[1] - mh * 5.0 / (4.0 + mh)).abs() < 1e-6, "{s:?}");
}

#[test]
fn grip_compliance_stretches_by_force_over_stiffness() {
    let k = 2000.0;
    let mut cfg = common::arm_config(Grasp::Held);
    cfg.effects.grip_compliance = Some(GripCompliance {
        stiffness_n_per_m: k,
        damping_n_s_per_m: 60.0,
    });
    let mut rig = SimRig::with_seed(cfg, 7).unwrap();
    let q0 = rig.arm_state().unwrap().q;
    // The arm holds its posture stiffly; the carts push with a constant force.
    let f = [3.0, -2.0];
    for tick in 0..24000 {
        let s = rig.arm_state().unwrap();
        let tau = [
            -60.0 * (s.q[0] - q0[0]) - 8.0 * s.qd[0],
            -60.0 * (s.q[1] - q0[1]) - 8.0 * s.qd[1],
        ];
        rig.set_arm_torques(tau).unwrap();
        rig.write(Tick(tick), MotorCommand { force_n: f }).unwrap();
        rig.step().unwrap();
    }
    // Static: handle − hand = F_motor / k (the grip carries the whole motor force).
    let gap = rig.handle_position_m() - rig.hand_position_m().unwrap();
    for axis in 0..2 {
        let ex = f[axis] / k;
        assert!(
            (gap[axis] - ex).abs() < 0.01 * ex.abs(),
            "axis {axis}: gap {} m vs {ex} m",
            gap[axis]
        );
    }
    // With the rigid pin the hand stays on the handle (1 µm: the joint's solver error).
    let mut rig = SimRig::with_seed(common::arm_config(Grasp::Held), 7).unwrap();
    for tick in 0..2000 {
        rig.write(Tick(tick), MotorCommand { force_n: f }).unwrap();
        rig.step().unwrap();
    }
    let gap = rig.handle_position_m() - rig.hand_position_m().unwrap();
    assert!(gap.norm() < 1e-6, "{gap}");
}

#[test]
fn every_effect_is_off_by_default() {
    let e = RigConfig::default().effects;
    assert!(e.rail_friction.is_none() && e.force_ripple.is_none() && e.actuation_delay.is_none());
    assert!(e.sensor.is_none() && e.handle_mass.is_none() && e.grip_compliance.is_none());
    assert!(e.cable_spring.is_none());
}

/// A cable carrier makes each cart a spring-mass oscillator about its rest position:
/// released from 0 with no command, `q(t) = r (1 − cos ωt)`, `ω = √(k/m)` with `m` the
/// mass the axis carries. Over two periods the position follows the closed form to 1 %
/// of the amplitude (semi-implicit Euler at 4 kHz shifts ω by `(ω dt)²/24`, ~1e-7 here;
/// the tolerance covers the 1 µm encoder and the coupled rails' solver residual), and
/// the pull is the law at the start-of-tick position.
#[test]
fn cable_spring_makes_each_cart_a_spring_mass_oscillator() {
    let c = CableSpring {
        stiffness_n_per_m: [300.0, 120.0],
        rest_m: [0.02, -0.015],
    };
    let mut cfg = bare();
    cfg.effects.cable_spring = Some(c);
    let mut rig = SimRig::with_seed(cfg, 7).unwrap();
    let m = rig.carried_mass_kg();
    let omega = [0, 1].map(|a| (c.stiffness_n_per_m[a] / m[a]).sqrt());
    let ticks = (2.0 * std::f64::consts::TAU / omega[1] / TICK_S) as u64;
    for k in 0..ticks {
        let q0 = rig.cart_positions_m();
        rig.write(Tick(k), MotorCommand { force_n: [0.0; 2] })
            .unwrap();
        rig.step().unwrap();
        let t = *rig.truth();
        let q = rig.cart_positions_m();
        for a in 0..2 {
            assert!((t.cable_n[a] - cable_force_n(&c, a, q0[a])).abs() < 1e-12);
            let want = c.rest_m[a] * (1.0 - (omega[a] * (k + 1) as f64 * TICK_S).cos());
            assert!(
                (q[a] - want).abs() < 0.01 * c.rest_m[a].abs(),
                "tick {k} axis {a}: {} vs {want}",
                q[a]
            );
        }
    }
}
