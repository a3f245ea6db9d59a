//! Helpers shared by the world's integration tests: minimum-jerk references, a simple
//! cart PD, and configs.
#![allow(dead_code)]

use std::f64::consts::PI;

use nalgebra::Vector2;
use rigtwin_world::TICK_S;
use rigtwin_world::config::{Attachment, Grasp, RigConfig};

/// Minimum-jerk position, velocity and acceleration from `a` to `b` over `d_s` at `t_s`.
pub fn min_jerk(
    a: Vector2<f64>,
    b: Vector2<f64>,
    d_s: f64,
    t_s: f64,
) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    let s = (t_s / d_s).clamp(0.0, 1.0);
    let p = 10.0 * s.powi(3) - 15.0 * s.powi(4) + 6.0 * s.powi(5);
    let (pd, pdd) = if (0.0..1.0).contains(&s) && t_s >= 0.0 {
        (
            (30.0 * s.powi(2) - 60.0 * s.powi(3) + 30.0 * s.powi(4)) / d_s,
            (60.0 * s - 180.0 * s.powi(2) + 120.0 * s.powi(3)) / (d_s * d_s),
        )
    } else {
        (0.0, 0.0)
    };
    let d = b - a;
    (a + d * p, d * pd, d * pdd)
}

/// A config with the arm attached by `grasp`, no sensor noise.
pub fn arm_config(grasp: Grasp) -> RigConfig {
    let mut c = RigConfig {
        force_noise_rms_n: 0.0,
        ..RigConfig::default()
    };
    if let Attachment::Arm { grasp: g, .. } = &mut c.attachment {
        *g = grasp;
    }
    c
}

/// RMS of a slice.
pub fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// The bare handle at the origin, no sensor noise.
pub fn bare() -> RigConfig {
    RigConfig {
        attachment: Attachment::None,
        force_noise_rms_n: 0.0,
        initial_handle_m: [0.0, 0.0],
        ..RigConfig::default()
    }
}

/// A smooth two-axis motor command at tick `k`, N.
pub fn push(k: u64) -> [f64; 2] {
    [
        6.0 * (2.0 * PI * k as f64 * TICK_S).sin(),
        4.0 * (3.0 * PI * k as f64 * TICK_S).cos(),
    ]
}
