//! The rig's nuisances (sensor offset, motor gain tolerance, current-loop noise) act by
//! their laws, and a rig without them is the rig it was before.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::f64::consts::PI;

use common::{bare, push};
use rigtwin_device::{MotorCommand, RigIo, Tick};
use rigtwin_world::config::{Attachment, RigConfig, RigNuisance};
use rigtwin_world::{SimRig, StepTruth, TICK_S};

fn run(cfg: RigConfig, ticks: u64) -> (Vec<StepTruth>, Vec<[f64; 2]>) {
    let mut rig = SimRig::with_seed(cfg, 7).unwrap();
    let (mut t, mut r) = (Vec::new(), Vec::new());
    for k in 0..ticks {
        rig.write(Tick(k), MotorCommand { force_n: push(k) })
            .unwrap();
        rig.step().unwrap();
        t.push(*rig.truth());
        r.push(rig.read(Tick(k + 1)).unwrap().force_raw_n);
    }
    (t, r)
}

/// The motor force is the command times the axis's gain (to 1e-12 N: one product), and
/// the reading carries the offset on top of the true force (to 1e-12 N).
#[test]
fn gain_scales_the_motor_and_offset_shifts_the_reading() {
    let mut cfg = bare();
    cfg.nuisance = RigNuisance {
        sensor_offset_n: [0.2, -0.15],
        motor_gain: [1.01, 0.99],
        ..RigNuisance::default()
    };
    let (truth, reading) = run(cfg, 400);
    for (k, (t, r)) in truth.iter().zip(&reading).enumerate() {
        let c = push(k as u64);
        assert!((t.motor_n[0] - 1.01 * c[0]).abs() < 1e-12, "{k}: {t:?}");
        assert!((t.motor_n[1] - 0.99 * c[1]).abs() < 1e-12, "{k}: {t:?}");
        assert!((r[0] - t.sensor_n[0] - 0.2).abs() < 1e-12, "{k}");
        assert!((r[1] - t.sensor_n[1] + 0.15).abs() < 1e-12, "{k}");
    }
}

/// The current-loop noise has the configured RMS and a first-order spectrum: over
/// 200 000 ticks (50 s) the RMS is within 5 % of 0.25 N (the estimate's relative error
/// for a correlation time of 0.8 ms is about 0.6 %), and the lag-one correlation is
/// `1 − α` of the discrete low-pass at 200 Hz to 0.01.
#[test]
fn motor_noise_has_its_rms_and_bandwidth() {
    let mut cfg = bare();
    cfg.nuisance.motor_noise_rms_n = 0.25;
    cfg.nuisance.motor_noise_bw_hz = 200.0;
    let mut rig = SimRig::with_seed(cfg, 11).unwrap();
    let n = 200_000;
    let mut e = Vec::with_capacity(n);
    for k in 0..n as u64 {
        rig.write(Tick(k), MotorCommand { force_n: [0.0; 2] })
            .unwrap();
        rig.step().unwrap();
        e.push(rig.truth().motor_n);
    }
    let alpha = 1.0 - (-2.0 * PI * 200.0 * TICK_S).exp();
    for axis in 0..2 {
        let x: Vec<f64> = e.iter().map(|m| m[axis]).collect();
        let var = x.iter().map(|v| v * v).sum::<f64>() / n as f64;
        let rms = var.sqrt();
        assert!((rms - 0.25).abs() < 0.05 * 0.25, "axis {axis}: rms {rms}");
        let r1 = x.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / (n - 1) as f64 / var;
        assert!((r1 - (1.0 - alpha)).abs() < 0.01, "axis {axis}: ρ₁ {r1}");
    }
}

/// A default nuisance changes nothing: the same seed gives the same readings, bit for
/// bit, as a rig built without the field (the motor noise draws nothing when off).
#[test]
fn no_nuisance_is_the_rig_as_before() {
    let noisy = RigConfig {
        attachment: Attachment::None,
        initial_handle_m: [0.0, 0.0],
        ..RigConfig::default()
    };
    let mut other = noisy.clone();
    other.nuisance = RigNuisance {
        motor_noise_bw_hz: 50.0,
        ..RigNuisance::default()
    };
    let (_, a) = run(noisy, 200);
    let (_, b) = run(other, 200);
    assert_eq!(a, b);
}

/// A zero gain or a negative noise is refused with the key named.
#[test]
fn bad_nuisance_names_its_key() {
    let mut cfg = bare();
    cfg.nuisance.motor_gain = [1.0, 0.0];
    let e = SimRig::with_seed(cfg, 1).unwrap_err().to_string();
    assert!(e.contains("nuisance.motor_gain"), "{e}");
    let mut cfg = bare();
    cfg.nuisance.motor_noise_rms_n = -0.1;
    let e = SimRig::with_seed(cfg, 1).unwrap_err().to_string();
    assert!(e.contains("nuisance.motor_noise_rms_n"), "{e}");
}
