//! The position perturbation of 001_*: the rendered reference moves `amplitude_m` along
//! a direction in a transition of `transition_s`, holds, and comes back in a second
//! transition, `duration_s` in all (8 mm, 100 ms + 100 ms hold + 100 ms by default).
//!
//! Each transition follows a polynomial `σ(τ)`, `τ ∈ [0, 1]`, with zero velocity and
//! acceleration at both ends. 001_* specifies "a sixth-order polynomial constrained by
//! zero velocity and zero acceleration at both boundaries and zero end jerk":
//! `σ = 20τ³ − 45τ⁴ + 36τ⁵ − 10τ⁶` ([`TransitionShape::Degree6`], the default). The
//! rest-to-rest minimum-snap polynomial `35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷`, which also has zero
//! jerk at the start, is [`TransitionShape::MinimumSnap7`]. The way back is `1 − σ`.

use super::{ArmError, Lifecycle, PerturbationStatus};
use crate::config::{PositionPerturbationConfig, TransitionShape};
use crate::time::{Rate, Tick};

/// `σ(τ)`, `σ'(τ)`, `σ''(τ)` of a transition shape (derivatives in `τ`).
#[must_use]
pub fn transition(shape: TransitionShape, tau: f64) -> (f64, f64, f64) {
    let t = tau.clamp(0.0, 1.0);
    let (t2, t3) = (t * t, t * t * t);
    match shape {
        TransitionShape::Degree6 => (
            t3 * (20.0 + t * (-45.0 + t * (36.0 - 10.0 * t))),
            t2 * (60.0 + t * (-180.0 + t * (180.0 - 60.0 * t))),
            t * (120.0 + t * (-540.0 + t * (720.0 - 300.0 * t))),
        ),
        TransitionShape::MinimumSnap7 => (
            t2 * t2 * (35.0 + t * (-84.0 + t * (70.0 - 20.0 * t))),
            t3 * (140.0 + t * (-420.0 + t * (420.0 - 140.0 * t))),
            t2 * (420.0 + t * (-1680.0 + t * (2100.0 - 840.0 * t))),
        ),
    }
}

/// Displacement along the direction and its time derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Profile {
    /// m
    pub position_m: f64,
    /// m/s
    pub velocity_m_per_s: f64,
    /// m/s²
    pub acceleration_m_per_s2: f64,
}

/// What fires an armed position perturbation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PositionTrigger {
    /// At this tick (or the first active tick after it).
    AtTick(Tick),
    /// At the next zero-acceleration point of the imposed sinusoid (001_*).
    NextZeroAcceleration,
}

/// The position-perturbation generator.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionPerturbation {
    amplitude_m: f64,
    duration_ticks: u64,
    transition_ticks: u64,
    period_s: f64,
    shape: TransitionShape,
    state: Lifecycle<PositionTrigger>,
}

impl PositionPerturbation {
    /// From a validated config at the control rate.
    #[must_use]
    pub fn new(config: &PositionPerturbationConfig, rate: Rate) -> Self {
        let hz = f64::from(rate.hz());
        PositionPerturbation {
            amplitude_m: config.amplitude_m,
            duration_ticks: (config.duration_s * hz).round() as u64,
            transition_ticks: (config.transition_s * hz).round() as u64,
            period_s: rate.period_s(),
            shape: config.shape,
            state: Lifecycle::Idle,
        }
    }

    /// Total duration in ticks.
    #[must_use]
    pub fn duration_ticks(&self) -> u64 {
        self.duration_ticks
    }

    /// Transition duration in ticks.
    #[must_use]
    pub fn transition_ticks(&self) -> u64 {
        self.transition_ticks
    }

    /// The scalar profile `k` ticks after onset (zero before and after).
    #[must_use]
    pub fn profile(&self, k: u64) -> Profile {
        if k >= self.duration_ticks {
            return Profile::default();
        }
        let tt = self.transition_ticks as f64;
        let ts = tt * self.period_s;
        let a = self.amplitude_m;
        let back_start = self.duration_ticks - self.transition_ticks;
        let (sigma, sign) = if k < self.transition_ticks {
            (transition(self.shape, k as f64 / tt), 1.0)
        } else if k < back_start {
            ((1.0, 0.0, 0.0), 1.0)
        } else {
            let (s, ds, dds) = transition(self.shape, (k - back_start) as f64 / tt);
            ((1.0 - s, ds, dds), -1.0)
        };
        Profile {
            position_m: a * sigma.0,
            velocity_m_per_s: sign * a * sigma.1 / ts,
            acceleration_m_per_s2: sign * a * sigma.2 / (ts * ts),
        }
    }

    /// Arm for the next trigger, direction `angle_rad` from +x toward +y.
    ///
    /// # Errors
    /// [`ArmError`] for a non-finite angle or while one is running.
    pub fn arm(&mut self, angle_rad: f64, trigger: PositionTrigger) -> Result<(), ArmError> {
        self.state.arm(angle_rad, trigger)
    }

    /// The armed trigger, if armed.
    #[must_use]
    pub fn armed_trigger(&self) -> Option<PositionTrigger> {
        self.state.trigger()
    }

    /// Replace the armed trigger (the controller resolves a zero-acceleration trigger to
    /// its tick).
    pub(crate) fn retarget(&mut self, new: PositionTrigger) {
        if let Some(trigger) = self.state.trigger_mut() {
            *trigger = new;
        }
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

    /// One active tick: fire an `AtTick` trigger if due and return this tick's offset
    /// (position, velocity, acceleration per axis).
    pub fn update(&mut self, now: Tick) -> [Profile; 2] {
        let due = |trigger| matches!(trigger, PositionTrigger::AtTick(t) if now >= t);
        let Some((k, dir)) = self.state.advance(now, self.duration_ticks, due) else {
            return [Profile::default(); 2];
        };
        let p = self.profile(k);
        let along = |d: f64| Profile {
            position_m: p.position_m * d,
            velocity_m_per_s: p.velocity_m_per_s * d,
            acceleration_m_per_s2: p.acceleration_m_per_s2 * d,
        };
        [along(dir[0]), along(dir[1])]
    }
}
