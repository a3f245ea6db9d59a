//! Minimum-jerk hand plans (Flash & Hogan 1985) on the integer tick clock.

use nalgebra::Vector2;

use crate::error::ArmError;
use crate::time::TICK_HZ;

/// Planned hand position \[m\], velocity \[m/s\] and acceleration \[m/s²\] in one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandRef {
    /// Position \[m\].
    pub pos_m: Vector2<f64>,
    /// Velocity \[m/s\].
    pub vel_m_s: Vector2<f64>,
    /// Acceleration \[m/s²\].
    pub acc_m_s2: Vector2<f64>,
}

/// A straight minimum-jerk movement from `start_m` to `goal_m`, beginning at
/// `start_tick` and lasting `duration_ticks`; at rest at `start_m` before and at
/// `goal_m` after.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MinJerk {
    start_m: Vector2<f64>,
    goal_m: Vector2<f64>,
    start_tick: u64,
    duration_ticks: u64,
}

impl MinJerk {
    /// A plan; errors on a zero duration or non-finite points.
    pub fn new(
        start_m: Vector2<f64>,
        goal_m: Vector2<f64>,
        start_tick: u64,
        duration_ticks: u64,
    ) -> Result<MinJerk, ArmError> {
        if duration_ticks == 0 {
            return Err(ArmError::InvalidParameter {
                key: "duration_ticks",
                reason: "must be > 0".into(),
            });
        }
        if !(start_m.iter().chain(goal_m.iter()).all(|x| x.is_finite())) {
            return Err(ArmError::NonFinite {
                what: "reach start/goal",
            });
        }
        Ok(MinJerk {
            start_m,
            goal_m,
            start_tick,
            duration_ticks,
        })
    }

    /// Start point \[m\].
    pub fn start_m(&self) -> Vector2<f64> {
        self.start_m
    }

    /// Goal point \[m\].
    pub fn goal_m(&self) -> Vector2<f64> {
        self.goal_m
    }

    /// Duration \[s\].
    pub fn duration_s(&self) -> f64 {
        self.duration_ticks as f64 / TICK_HZ as f64
    }

    /// The plan at a tick: x = x₀ + Δ(10s³ − 15s⁴ + 6s⁵), s = (t − t₀)/T clamped to \[0, 1\].
    pub fn at(&self, tick: u64) -> HandRef {
        let elapsed = tick
            .saturating_sub(self.start_tick)
            .min(self.duration_ticks);
        let s = elapsed as f64 / self.duration_ticks as f64;
        let t = self.duration_s();
        let d = self.goal_m - self.start_m;
        let (s2, s3) = (s * s, s * s * s);
        let pos = 10.0 * s3 - 15.0 * s3 * s + 6.0 * s3 * s2;
        let vel = (30.0 * s2 - 60.0 * s3 + 30.0 * s2 * s2) / t;
        let acc = (60.0 * s - 180.0 * s2 + 120.0 * s3) / (t * t);
        HandRef {
            pos_m: self.start_m + d * pos,
            vel_m_s: d * vel,
            acc_m_s2: d * acc,
        }
    }
}

/// A reach's plan: the way out, and the way back when the trial returns to its start
/// (a centre-out task that logs the return). The way back begins where it is due;
/// before that the plan is the way out's (at rest at its goal after it ends).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachPlan {
    /// From the start to the goal.
    pub out: MinJerk,
    /// From the goal back to the start, beginning after the way out ends.
    pub back: Option<MinJerk>,
}

impl ReachPlan {
    /// The reach from `start_m` to `goal_m` beginning at `start_tick` and lasting
    /// `duration_ticks`, and with `back_after_ticks` the way back: from the goal to the
    /// start in the same duration, beginning that many ticks after the way out ends
    /// (the way out mirrored in time). Errors as [`MinJerk::new`].
    pub fn new(
        start_m: Vector2<f64>,
        goal_m: Vector2<f64>,
        start_tick: u64,
        duration_ticks: u64,
        back_after_ticks: Option<u64>,
    ) -> Result<ReachPlan, ArmError> {
        let out = MinJerk::new(start_m, goal_m, start_tick, duration_ticks)?;
        let back = back_after_ticks
            .map(|dwell| {
                let back_tick = start_tick
                    .saturating_add(duration_ticks)
                    .saturating_add(dwell);
                MinJerk::new(goal_m, start_m, back_tick, duration_ticks)
            })
            .transpose()?;
        Ok(ReachPlan { out, back })
    }

    /// The plan at a tick.
    pub fn at(&self, tick: u64) -> HandRef {
        match &self.back {
            Some(b) if tick >= b.start_tick => b.at(tick),
            _ => self.out.at(tick),
        }
    }
}
