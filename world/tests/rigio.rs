//! SimRig at the RigIo boundary: encoders, noise, e-stop, commands, end-stops,
//! determinism and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigtwin_device::{MotorCommand, RigIo, Tick};
use rigtwin_world::config::{Attachment, Grasp, RigConfig};
use rigtwin_world::{SimRig, TICK_S, WorldError};

/// A reach driven through RigIo by a PD on the encoder counts; returns every reading's bytes.
fn session(seed: u64) -> Vec<u64> {
    let cfg = RigConfig::default(); // noise on: 0.05 N RMS
    let mut rig = SimRig::new(cfg, ChaCha8Rng::seed_from_u64(seed)).unwrap();
    let mut out = Vec::new();
    let mut prev = [0i64; 2];
    for k in 0..4000u64 {
        let frame = rig.read(Tick(k)).unwrap();
        let t = k as f64 * TICK_S;
        let (p, _, _) = common::min_jerk(
            nalgebra::Vector2::new(0.0, -0.125),
            nalgebra::Vector2::new(0.0, 0.125),
            1.0,
            t,
        );
        let x = [
            frame.encoder_counts[0] as f64 * 1e-6,
            frame.encoder_counts[1] as f64 * 1e-6,
        ];
        let v = [
            (frame.encoder_counts[0] - prev[0]) as f64 * 1e-6 / TICK_S,
            (frame.encoder_counts[1] - prev[1]) as f64 * 1e-6 / TICK_S,
        ];
        prev = frame.encoder_counts;
        let f = [
            2.0e4 * (p.x - x[0]) - 300.0 * v[0],
            2.0e4 * (p.y - x[1]) - 300.0 * v[1],
        ];
        rig.write(Tick(k), MotorCommand { force_n: f }).unwrap();
        rig.step().unwrap();
        out.push(frame.force_raw_n[0].to_bits());
        out.push(frame.force_raw_n[1].to_bits());
        out.push(frame.encoder_counts[0] as u64);
        out.push(frame.encoder_counts[1] as u64);
    }
    out
}

#[test]
fn same_seed_gives_byte_identical_sensor_streams() {
    let a = session(11);
    let b = session(11);
    assert_eq!(a, b);
    // And the seed matters: another seed changes the noise.
    let c = session(12);
    assert_ne!(a, c);
}

#[test]
fn encoder_counts_floor_the_position_to_the_micrometre() {
    let cfg = RigConfig {
        attachment: Attachment::None,
        initial_handle_m: [0.0123456789, -0.0987654321],
        ..RigConfig::default()
    };
    let mut rig = SimRig::with_seed(cfg, 1).unwrap();
    for k in 0..200 {
        rig.write(
            Tick(k),
            MotorCommand {
                force_n: [1.0, -0.5],
            },
        )
        .unwrap();
        rig.step().unwrap();
        let c = rig.read(Tick(k + 1)).unwrap().encoder_counts;
        let x = rig.cart_positions_m();
        for axis in 0..2 {
            // floor: count·q ≤ x < (count + 1)·q, q = 1 µm.
            let lo = c[axis] as f64 * 1e-6;
            assert!(
                lo <= x[axis] + 1e-15 && x[axis] < lo + 1e-6 + 1e-15,
                "{} vs {}",
                c[axis],
                x[axis]
            );
        }
    }
}

#[test]
fn force_noise_has_the_configured_rms() {
    let cfg = RigConfig {
        attachment: Attachment::None,
        ..RigConfig::default()
    };
    let mut rig = SimRig::with_seed(cfg, 3).unwrap();
    let mut x = Vec::new();
    for k in 0..20000 {
        rig.step().unwrap();
        x.push(rig.read(Tick(k)).unwrap().force_raw_n[0]);
    }
    // 20 000 samples: the RMS estimate's relative std is 1/sqrt(2N) = 0.5 %; allow 3 %.
    let r = common::rms(&x);
    assert!((r - 0.05).abs() < 0.0015, "{r}");
}

#[test]
fn estop_is_reported_and_commands_are_held_until_rewritten() {
    let mut rig = SimRig::with_seed(RigConfig::default(), 1).unwrap();
    assert!(!rig.read(Tick(0)).unwrap().estop);
    rig.set_estop(true);
    assert!(rig.read(Tick(0)).unwrap().estop);
    rig.write(
        Tick(0),
        MotorCommand {
            force_n: [1.0, 2.0],
        },
    )
    .unwrap();
    for _ in 0..5 {
        rig.step().unwrap();
        assert_eq!(rig.truth().motor_n, [1.0, 2.0]);
    }
}

#[test]
fn end_stops_hold_the_carts_at_the_rail_limits() {
    let cfg = RigConfig {
        attachment: Attachment::None,
        force_noise_rms_n: 0.0,
        initial_handle_m: [0.0, 0.0],
        ..RigConfig::default()
    };
    let mut rig = SimRig::with_seed(cfg, 1).unwrap();
    for k in 0..8000 {
        rig.write(
            Tick(k),
            MotorCommand {
                force_n: [40.0, -20.0],
            },
        )
        .unwrap();
        rig.step().unwrap();
    }
    let x = rig.cart_positions_m();
    // Static on the bumper (k = 2e5 N/m): penetration F/k = 0.2 mm and 0.1 mm beyond the stop.
    assert!((x[0] - (0.16 + 40.0 / 2.0e5)).abs() < 1e-6, "{x:?}");
    assert!((x[1] - (-0.16 - 20.0 / 2.0e5)).abs() < 1e-6, "{x:?}");
    // The stop's reaction does not leak into the sensor: it reads only the handle's
    // inertia, −m_h a (1e-6 N: the joint solver's residual).
    let t = rig.truth();
    for axis in 0..2 {
        let ex = -0.35 * t.handle_acc_m_per_s2[axis];
        assert!((t.sensor_n[axis] - ex).abs() < 1e-6, "{t:?}");
    }
}

#[test]
fn bad_input_is_an_error_naming_it() {
    let mut rig = SimRig::with_seed(RigConfig::default(), 1).unwrap();
    let e = rig.write(
        Tick(0),
        MotorCommand {
            force_n: [f64::NAN, 0.0],
        },
    );
    assert_eq!(
        e,
        Err(WorldError::NonFinite {
            what: "motor command"
        })
    );
    assert!(rig.set_arm_torques([0.0, f64::INFINITY]).is_err());
    let cfg = RigConfig {
        handle_mass_kg: -1.0,
        ..RigConfig::default()
    };
    match SimRig::with_seed(cfg, 1) {
        Err(WorldError::InvalidConfig { key, .. }) => assert_eq!(key, "handle_mass_kg"),
        other => panic!("{other:?}"),
    }
    // A handle the arm cannot reach.
    let mut cfg = common::arm_config(Grasp::Held);
    cfg.initial_handle_m = [0.0, 0.15];
    if let Attachment::Arm { shoulder_m, .. } = &mut cfg.attachment {
        *shoulder_m = [0.0, -0.6];
    }
    assert!(matches!(SimRig::with_seed(cfg, 1), Err(WorldError::Arm(_))));
}

/// rapier's joint impulses against the momentum-balance reading under a push, for 1 and
/// 4 substeps: pins the rapier 0.36 trap. The impulse is the last substep's, so
/// impulse/(dt/substeps) is the sensor force with one substep (always) or at rest, but
/// not while the load changes within a tick split into substeps.
#[test]
fn rapier_joint_impulses_are_per_substep_and_match_the_reading_only_with_one_substep_or_at_rest() {
    for substeps in [1usize, 4] {
        let mut cfg = common::arm_config(Grasp::Held);
        cfg.solver.substeps = substeps;
        let mut rig = SimRig::with_seed(cfg, 1).unwrap();
        let q0 = rig.arm_state().unwrap().q;
        let h = TICK_S / substeps as f64;
        let mut worst_moving = 0.0f64;
        for k in 0..16000u64 {
            let s = rig.arm_state().unwrap();
            let tau = [
                -30.0 * (s.q[0] - q0[0]) - 3.0 * s.qd[0],
                -30.0 * (s.q[1] - q0[1]) - 3.0 * s.qd[1],
            ];
            rig.set_arm_torques(tau).unwrap();
            rig.write(
                Tick(k),
                MotorCommand {
                    force_n: [4.0, -3.0],
                },
            )
            .unwrap();
            rig.step().unwrap();
            let imp = rig.sensor_joint_impulses_n_s();
            let f = rig.truth().sensor_n;
            if k < 400 {
                worst_moving = worst_moving.max((imp[0] / h - f[0]).abs());
            }
        }
        let imp = rig.sensor_joint_impulses_n_s();
        let f = rig.truth().sensor_n;
        println!(
            "substeps {substeps}: at rest impulse/(dt/substeps) = [{:.4}, {:.4}] N vs reading [{:.4}, {:.4}] N; while moving up to {worst_moving:.3} N apart",
            imp[0] / h,
            imp[1] / h,
            f[0],
            f[1]
        );
        // At rest both equal the motor force in magnitude (the sign is rapier's joint-frame
        // convention); 1 % because the impulse is one substep's solve.
        for axis in 0..2 {
            assert!(
                ((imp[axis] / h).abs() - f[axis].abs()).abs() < 0.01 * f[axis].abs().max(1.0),
                "{imp:?} {f:?}"
            );
        }
    }
}
