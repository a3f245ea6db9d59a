//! The force pulse of 000_* eq. 22–23.
//!
//! `T_pert` is split into three sections of `T_p = T_pert / 3`. With `s = t / T_p`, the
//! normalized jerk of eq. 22 is
//!
//! ```text
//! f(s) = ½ sin((s + 3/2) π) + ½  = ½ (1 − cos πs)      s ∈ [0, 1]
//!      = sin((s − 1 + ½) π)       = cos π(s − 1)       s ∈ ]1, 2]
//!      = ½ sin((s − 2 + 3/2) π) − ½ = −½ (1 + cos π(s − 2))  s ∈ ]2, 3]
//! ```
//!
//! and the force `u_p` is its integral (eq. 22 is `u̇_p`), in closed form
//!
//! ```text
//! g(s) = s/2 − sin(πs)/(2π)                 s ∈ [0, 1]
//!      = ½ + sin(π(s − 1))/π                s ∈ ]1, 2]
//!      = ½ − (s − 2)/2 − sin(π(s − 2))/(2π)  s ∈ ]2, 3]
//! ```
//!
//! scaled to peak 1: `u_p = g / g_max`, `g_max = g(3/2) = ½ + 1/π`. So `u_p` is zero at
//! both ends, its derivative (the jerk of eq. 22) is zero at both ends, and the peak at
//! `t = T_pert / 2` is 1. Eq. 23: `u_pert = A_pert u_p [cos φ, sin φ]`.
//!
//! The time derivative is `u̇_p(t) = f(t / T_p) / (T_p g_max)` per second.

use core::f64::consts::PI;

use super::{ArmError, Crossing, Lifecycle, PerturbationStatus};
use crate::config::{Axis, ForcePulseConfig};
use crate::time::{Rate, Tick};

/// `g_max = ½ + 1/π`, the peak of the once-integrated eq. 22 in units of `T_p`.
pub const G_MAX: f64 = 0.5 + 1.0 / PI;

/// Eq. 22: the normalized jerk at `s = t / T_p` (zero outside `[0, 3]`).
#[must_use]
pub fn normalized_jerk(s: f64) -> f64 {
    if !(0.0..=3.0).contains(&s) {
        0.0
    } else if s <= 1.0 {
        0.5 * ((s + 1.5) * PI).sin() + 0.5
    } else if s <= 2.0 {
        ((s - 1.0 + 0.5) * PI).sin()
    } else {
        0.5 * ((s - 2.0 + 1.5) * PI).sin() - 0.5
    }
}

/// The normalized force `u_p` (peak 1) at `s = t / T_p` (zero outside `[0, 3]`).
#[must_use]
pub fn normalized_force(s: f64) -> f64 {
    let g = if !(0.0..=3.0).contains(&s) {
        0.0
    } else if s <= 1.0 {
        0.5 * s - (PI * s).sin() / (2.0 * PI)
    } else if s <= 2.0 {
        0.5 + (PI * (s - 1.0)).sin() / PI
    } else {
        let r = s - 2.0;
        0.5 - 0.5 * r - (PI * r).sin() / (2.0 * PI)
    };
    g / G_MAX
}

/// What fires an armed force pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PulseTrigger {
    /// At this tick (or the first active tick after it).
    AtTick(Tick),
    /// When the measured handle position on `axis` crosses `position_m` (000_*: the
    /// hand reaching 0.1 m along the movement, e.g. `y` rising through −0.025 m).
    LineCrossing {
        /// Axis whose position is watched.
        axis: Axis,
        /// The line, m, rig frame.
        position_m: f64,
        /// Which way it must be crossed.
        direction: Crossing,
    },
}

/// The force-pulse generator: arm, trigger, sample.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcePulse {
    duration_ticks: u64,
    section_ticks: f64,
    amplitude_n: f64,
    state: Lifecycle<PulseTrigger>,
}

impl ForcePulse {
    /// From a validated config at the control rate.
    #[must_use]
    pub fn new(config: &ForcePulseConfig, rate: Rate) -> Self {
        let duration_ticks = (config.duration_s * f64::from(rate.hz())).round() as u64;
        ForcePulse {
            duration_ticks,
            section_ticks: duration_ticks as f64 / 3.0,
            amplitude_n: config.amplitude_n,
            state: Lifecycle::Idle,
        }
    }

    /// `T_pert` in ticks.
    #[must_use]
    pub fn duration_ticks(&self) -> u64 {
        self.duration_ticks
    }

    /// `A_pert`, N.
    #[must_use]
    pub fn amplitude_n(&self) -> f64 {
        self.amplitude_n
    }

    /// The force vector `k` ticks after onset for direction `angle_rad`, N (eq. 23).
    #[must_use]
    pub fn force_at(&self, k: u64, angle_rad: f64) -> [f64; 2] {
        let (s, c) = angle_rad.sin_cos();
        self.sample(k, [c, s])
    }

    fn sample(&self, k: u64, dir: [f64; 2]) -> [f64; 2] {
        let u = self.amplitude_n * normalized_force(k as f64 / self.section_ticks);
        [u * dir[0], u * dir[1]]
    }

    /// Arm for the next trigger, direction `angle_rad` from +x toward +y.
    ///
    /// # Errors
    /// [`ArmError`] for a non-finite angle or line, or while a pulse is running.
    pub fn arm(&mut self, angle_rad: f64, trigger: PulseTrigger) -> Result<(), ArmError> {
        if let PulseTrigger::LineCrossing { position_m, .. } = trigger
            && !position_m.is_finite()
        {
            return Err(ArmError::NonFiniteLine);
        }
        self.state.arm(angle_rad, trigger)
    }

    /// Disarm or cut short.
    pub fn abort(&mut self) {
        self.state.abort();
    }

    /// Status for the recorder.
    #[must_use]
    pub fn status(&self) -> PerturbationStatus {
        self.state.status()
    }

    /// One active tick: fire the trigger if due, return the force for this tick, N.
    /// `before_m`/`now_m` are the measured positions at the previous and this tick.
    pub fn update(&mut self, now: Tick, before_m: [f64; 2], now_m: [f64; 2]) -> [f64; 2] {
        let due = |trigger| match trigger {
            PulseTrigger::AtTick(t) => now >= t,
            PulseTrigger::LineCrossing {
                axis,
                position_m,
                direction,
            } => {
                let i = axis.index();
                direction.crossed(before_m[i], now_m[i], position_m)
            }
        };
        match self.state.advance(now, self.duration_ticks, due) {
            Some((k, dir)) => self.sample(k, dir),
            None => [0.0; 2],
        }
    }
}
