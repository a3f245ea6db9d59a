//! Seeded perturbation schedules: which trials are perturbed, at which angle, in which
//! order. Built before a session (they allocate), never inside `tick`. The generator is
//! passed in, so the same seed gives the same schedule on every machine (ChaCha's
//! stream is specified).

use core::f64::consts::FRAC_PI_4;

use rand::Rng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::check::{Checker, ConfigError};

/// The force-pulse protocol of 000_* section 4: every angle repeated, each perturbed
/// movement paired with unperturbed ones, all in random order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ForcePulseScheduleConfig {
    /// Perturbation angles, degrees from +x toward +y (000_*: 30, 60, 120, 150, 210,
    /// 240, 300, 330 — never along an axis).
    pub angles_deg: Vec<f64>,
    /// Repetitions of each angle (10 in 000_*). > 0.
    pub repetitions: u32,
    /// Unperturbed trials per perturbed trial (1 in 000_*: each trial has an
    /// unperturbed and a perturbed version).
    pub unperturbed_per_perturbed: u32,
}

impl Default for ForcePulseScheduleConfig {
    fn default() -> Self {
        ForcePulseScheduleConfig {
            angles_deg: vec![30.0, 60.0, 120.0, 150.0, 210.0, 240.0, 300.0, 330.0],
            repetitions: 10,
            unperturbed_per_perturbed: 1,
        }
    }
}

impl ForcePulseScheduleConfig {
    /// Check every key.
    ///
    /// # Errors
    /// [`ConfigError`] naming each invalid key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let mut c = Checker::default();
        if self.angles_deg.is_empty() {
            c.fail("angles_deg", "must list at least one angle".to_owned());
        }
        for (i, a) in self.angles_deg.iter().enumerate() {
            c.finite(&format!("angles_deg[{i}]"), *a);
        }
        if self.repetitions == 0 {
            c.fail("repetitions", "must be > 0, got 0".to_owned());
        }
        c.finish()
    }
}

/// One trial of a force-pulse schedule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlannedTrial {
    /// 0-based position in the session.
    pub index: u32,
    /// The pulse angle in degrees, or `None` for an unperturbed trial.
    pub angle_deg: Option<f64>,
}

/// Build the shuffled force-pulse schedule.
///
/// # Errors
/// [`ConfigError`] if the config is invalid.
pub fn force_pulse_schedule(
    config: &ForcePulseScheduleConfig,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<PlannedTrial>, ConfigError> {
    config.validate()?;
    let per = 1 + config.unperturbed_per_perturbed as usize;
    let mut trials =
        Vec::with_capacity(config.angles_deg.len() * config.repetitions as usize * per);
    for _ in 0..config.repetitions {
        for a in &config.angles_deg {
            trials.push(Some(*a));
            trials.extend(core::iter::repeat_n(None, per - 1));
        }
    }
    trials.shuffle(rng);
    Ok(trials
        .into_iter()
        .enumerate()
        .map(|(i, angle_deg)| PlannedTrial {
            index: u32::try_from(i).unwrap_or(u32::MAX),
            angle_deg,
        })
        .collect())
}

/// One slot of a position-perturbation schedule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlannedPush {
    /// 0-based zero-acceleration point of the imposed motion.
    pub slot: u32,
    /// `k` of the direction `k π / 4`, in `1..=8` (001_*).
    pub k: u8,
    /// The direction, rad from +x toward +y.
    pub angle_rad: f64,
}

/// 001_*: one perturbation at each of `slots` zero-acceleration points (50 = 25 cycles ×
/// 2), each direction drawn uniformly from `{kπ/4 | k = 1..8}`.
#[must_use]
pub fn position_schedule(slots: u32, rng: &mut ChaCha8Rng) -> Vec<PlannedPush> {
    (0..slots)
        .map(|slot| {
            let k: u8 = rng.random_range(1..=8);
            PlannedPush {
                slot,
                k,
                angle_rad: f64::from(k) * FRAC_PI_4,
            }
        })
        .collect()
}
