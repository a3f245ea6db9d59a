//! Test data shared by the unit tests of the sample repairs (`glitch.rs`, `hold.rs`,
//! `slip.rs`): a reach as a 1 kHz log records it.

use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// The log's rate, Hz.
pub const RATE_HZ: f64 = 1000.0;
/// A reach's duration, s: 0.25 m in 0.6 s peaks at 0.78 m/s and 4.2 m/s².
pub const DURATION_S: f64 = 0.6;

/// The minimum-jerk position of a reach of `extent_m` started at `start_s`, at `t_s`.
pub fn min_jerk(extent_m: f64, start_s: f64, t_s: f64) -> f64 {
    let tau = ((t_s - start_s) / DURATION_S).clamp(0.0, 1.0);
    extent_m * (10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5))
}

/// The reach of `extent_m` from `start_s` at the times `t_rows` (in rows of the log),
/// each with 0.3 µm of white noise from `rng`: an encoder's fine noise.
pub fn noisy(
    rng: &mut ChaCha8Rng,
    extent_m: f64,
    start_s: f64,
    t_rows: impl Iterator<Item = f64>,
) -> Vec<f64> {
    let noise = Normal::new(0.0, 0.3e-6).unwrap();
    t_rows
        .map(|t| min_jerk(extent_m, start_s, t / RATE_HZ) + noise.sample(rng))
        .collect()
}
