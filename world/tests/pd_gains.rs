//! The position-rendering PD gains this crate recommends for the device controller, on
//! its assumed cart masses: tracking of a 0.25 m minimum-jerk reach with the arm held
//! and passive, the motor command held for two ticks (2 kHz), position from the encoder.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use nalgebra::Vector2;
use rigtwin_device::{MotorCommand, RigIo, Tick};
use rigtwin_world::config::Grasp;
use rigtwin_world::{SimRig, TICK_S};

/// Recommended gains: a 30 Hz critically damped loop on the mass each axis moves
/// (x: 12.35 kg of carts and handle + ≈1.5 kg of arm; y: 4.35 + ≈1.5 kg):
/// Kp = M ω², Kd = 2 M ω, ω = 2π·30 rad/s, rounded.
const KP_N_PER_M: [f64; 2] = [4.5e5, 2.0e5];
const KD_N_S_PER_M: [f64; 2] = [5.0e3, 2.0e3];

#[test]
fn recommended_pd_gains_track_a_quarter_metre_reach_within_half_a_millimetre() {
    for duration_s in [1.0, 3.0] {
        let mut rig = SimRig::with_seed(common::arm_config(Grasp::Held), 9).unwrap();
        let (a, b) = (Vector2::new(0.0, -0.125), Vector2::new(0.0, 0.125));
        let ticks = ((duration_s + 0.5) / TICK_S) as u64;
        let mut max_err = 0.0f64;
        let mut sq = 0.0;
        let mut cmd = [0.0; 2];
        for k in 0..ticks {
            let frame = rig.read(Tick(k)).unwrap();
            let (p, v, _) = common::min_jerk(a, b, duration_s, k as f64 * TICK_S);
            let x = [
                frame.encoder_counts[0] as f64 * 1e-6,
                frame.encoder_counts[1] as f64 * 1e-6,
            ];
            let xd = rig.handle_velocity_m_per_s();
            if k % 2 == 0 {
                cmd = [
                    KP_N_PER_M[0] * (p.x - x[0]) + KD_N_S_PER_M[0] * (v.x - xd.x),
                    KP_N_PER_M[1] * (p.y - x[1]) + KD_N_S_PER_M[1] * (v.y - xd.y),
                ];
                rig.write(Tick(k), MotorCommand { force_n: cmd }).unwrap();
            }
            rig.step().unwrap();
            let e = (rig.handle_position_m()
                - common::min_jerk(a, b, duration_s, (k + 1) as f64 * TICK_S).0)
                .norm();
            max_err = max_err.max(e);
            sq += e * e;
        }
        let rms = (sq / ticks as f64).sqrt();
        println!(
            "PD Kp {KP_N_PER_M:?} N/m, Kd {KD_N_S_PER_M:?} N s/m, 0.25 m reach in {duration_s} s: max error {:.3} mm, RMS {:.3} mm (last command {cmd:.1?} N)",
            max_err * 1e3,
            rms * 1e3
        );
        // 0.5 mm: a tenth of the 6 mm deviations the perturbation experiments measure.
        assert!(max_err < 5e-4, "{max_err}");
    }
}
