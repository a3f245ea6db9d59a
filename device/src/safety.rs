//! The safety layer. It is always on, in every mode: it clamps motor force, pushes the
//! virtual dynamics back from soft workspace walls, and trips a latched fault on an
//! e-stop, an I/O error, a non-finite or frozen force sensor, an encoder jump, a speed
//! or position beyond its limit, or more missed ticks in a row than allowed. A trip is recorded as a typed
//! [`SafetyEvent`] in a fixed-capacity [`EventLog`] (no allocation), and the command
//! written at the tripping tick, and every tick after it until reset, is zero.

use crate::config::SafetyConfig;
use crate::io::{ErrorKind, SensorFrame};
use crate::time::Tick;

/// Which half of the I/O cycle failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IoStage {
    /// `RigIo::read`.
    Read,
    /// `RigIo::write`.
    Write,
}

/// Why the safety layer tripped.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum TripReason {
    /// The e-stop input was pressed.
    EStop,
    /// The hardware reported an error.
    Io {
        /// Read or write.
        stage: IoStage,
        /// The error's class.
        kind: ErrorKind,
    },
    /// The force reading was non-finite for `ticks` consecutive ticks.
    NonFiniteForce {
        /// Consecutive non-finite readings.
        ticks: u32,
    },
    /// The raw force reading was bit-identical for `ticks` consecutive ticks.
    StaleForce {
        /// Consecutive identical readings.
        ticks: u32,
    },
    /// An encoder moved further in one tick than the configured jump limit.
    EncoderJump {
        /// 0 = x, 1 = y.
        axis: usize,
        /// The step, m.
        step_m: f64,
    },
    /// The filtered encoder velocity exceeded the limit.
    VelocityLimit {
        /// 0 = x, 1 = y.
        axis: usize,
        /// The velocity, m/s.
        velocity_m_per_s: f64,
    },
    /// The measured position went beyond the wall plus margin.
    PositionLimit {
        /// 0 = x, 1 = y.
        axis: usize,
        /// The position, m.
        position_m: f64,
    },
    /// An active tick came after more skipped ticks than
    /// `safety.max_consecutive_misses` allows (or did not come after the previous one).
    ClockSkip {
        /// The tick that was due.
        expected: Tick,
        /// The tick that came.
        got: Tick,
    },
}

/// One trip: when and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SafetyEvent {
    /// The tick at which the trip was detected (the command written at it is zero).
    pub tick: Tick,
    /// Why.
    pub reason: TripReason,
}

/// Capacity of the [`EventLog`].
pub const EVENT_CAPACITY: usize = 64;

/// The latest [`EVENT_CAPACITY`] safety events in a fixed array; older ones are
/// overwritten and counted.
#[derive(Debug, Clone, PartialEq)]
pub struct EventLog {
    slots: [Option<SafetyEvent>; EVENT_CAPACITY],
    total: u64,
}

impl Default for EventLog {
    fn default() -> Self {
        EventLog {
            slots: [None; EVENT_CAPACITY],
            total: 0,
        }
    }
}

impl EventLog {
    /// Record an event (never allocates).
    pub fn push(&mut self, event: SafetyEvent) {
        let i = (self.total % EVENT_CAPACITY as u64) as usize;
        self.slots[i] = Some(event);
        self.total += 1;
    }

    /// Events ever recorded, including overwritten ones.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Events held (at most [`EVENT_CAPACITY`]).
    #[must_use]
    pub fn len(&self) -> usize {
        self.total.min(EVENT_CAPACITY as u64) as usize
    }

    /// True if no event was ever recorded.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.total == 0
    }

    /// The held events, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = SafetyEvent> + '_ {
        let n = self.len() as u64;
        let first = self.total - n;
        (first..self.total).filter_map(move |k| self.slots[(k % EVENT_CAPACITY as u64) as usize])
    }

    /// The newest event.
    #[must_use]
    pub fn last(&self) -> Option<SafetyEvent> {
        if self.total == 0 {
            None
        } else {
            self.slots[((self.total - 1) % EVENT_CAPACITY as u64) as usize]
        }
    }
}

/// The monitor's per-tick state (counters of consecutive bad readings).
#[derive(Debug, Clone, PartialEq)]
pub struct SafetyMonitor {
    config: SafetyConfig,
    nonfinite_ticks: u32,
    same_force_ticks: u32,
    last_raw_force: Option<[u64; 2]>,
}

impl SafetyMonitor {
    /// From a validated config.
    #[must_use]
    pub fn new(config: &SafetyConfig) -> Self {
        SafetyMonitor {
            config: config.clone(),
            nonfinite_ticks: 0,
            same_force_ticks: 0,
            last_raw_force: None,
        }
    }

    /// Forget the counters (on reset).
    pub fn reset(&mut self) {
        self.nonfinite_ticks = 0;
        self.same_force_ticks = 0;
        self.last_raw_force = None;
    }

    /// Count this frame's force reading; true if it is finite and may be used.
    pub fn observe_force(&mut self, frame: &SensorFrame) -> bool {
        let finite = frame.force_raw_n.iter().all(|f| f.is_finite());
        self.nonfinite_ticks = if finite {
            0
        } else {
            self.nonfinite_ticks.saturating_add(1)
        };
        let bits = [
            frame.force_raw_n[0].to_bits(),
            frame.force_raw_n[1].to_bits(),
        ];
        self.same_force_ticks = match self.last_raw_force {
            Some(last) if last == bits => self.same_force_ticks.saturating_add(1),
            _ => 1,
        };
        self.last_raw_force = Some(bits);
        finite
    }

    /// The first trip condition present this tick, if any. `step_m` is the encoder
    /// position change since the previous tick (zero on the first).
    #[must_use]
    pub fn check(
        &self,
        frame: &SensorFrame,
        position_m: [f64; 2],
        step_m: [f64; 2],
        velocity_m_per_s: [f64; 2],
    ) -> Option<TripReason> {
        let c = &self.config;
        if frame.estop {
            return Some(TripReason::EStop);
        }
        if self.nonfinite_ticks >= c.nonfinite_force_ticks {
            return Some(TripReason::NonFiniteForce {
                ticks: self.nonfinite_ticks,
            });
        }
        if let Some(n) = c.stale_force_ticks
            && self.same_force_ticks >= n
        {
            return Some(TripReason::StaleForce {
                ticks: self.same_force_ticks,
            });
        }
        if let Some((axis, &step_m)) = step_m
            .iter()
            .enumerate()
            .find(|(_, s)| s.abs() > c.encoder_jump_m)
        {
            return Some(TripReason::EncoderJump { axis, step_m });
        }
        let limit = c.wall_m + c.position_trip_margin_m;
        if let Some((axis, &position_m)) =
            position_m.iter().enumerate().find(|(_, x)| x.abs() > limit)
        {
            return Some(TripReason::PositionLimit { axis, position_m });
        }
        let vmax = c.velocity_limit_m_per_s;
        if let Some((axis, &velocity_m_per_s)) = velocity_m_per_s
            .iter()
            .enumerate()
            .find(|(_, v)| v.abs() > vmax)
        {
            return Some(TripReason::VelocityLimit {
                axis,
                velocity_m_per_s,
            });
        }
        None
    }

    /// Force of the soft walls on a virtual state beyond `±wall_m`, N: a spring plus a
    /// damper that only ever pushes back toward the workspace.
    #[must_use]
    pub fn wall_force(&self, position_m: [f64; 2], velocity_m_per_s: [f64; 2]) -> [f64; 2] {
        let c = &self.config;
        let f = |i: usize| {
            let (x, v) = (position_m[i], velocity_m_per_s[i]);
            if x > c.wall_m {
                (-c.wall_stiffness_n_per_m * (x - c.wall_m) - c.wall_damping_n_s_per_m * v).min(0.0)
            } else if x < -c.wall_m {
                (-c.wall_stiffness_n_per_m * (x + c.wall_m) - c.wall_damping_n_s_per_m * v).max(0.0)
            } else {
                0.0
            }
        };
        [f(0), f(1)]
    }

    /// Clamp a motor command to the force limit; the flags say which axes saturated.
    #[must_use]
    pub fn clamp(&self, force_n: [f64; 2]) -> ([f64; 2], [bool; 2]) {
        let l = self.config.force_limit_n;
        let c = |i: usize| {
            let f = force_n[i];
            // A non-finite command is never sent: NaN becomes 0 and counts as saturated.
            if f.is_nan() {
                (0.0, true)
            } else {
                (f.clamp(-l[i], l[i]), f.abs() > l[i])
            }
        };
        let (a, b) = (c(0), c(1));
        ([a.0, b.0], [a.1, b.1])
    }
}
