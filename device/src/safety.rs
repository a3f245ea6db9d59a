//! The safety layer. It is always on, in every mode: it clamps motor force, pushes the
//! virtual dynamics back from soft workspace walls, and trips a latched fault on an
//! e-stop, an I/O error, a non-finite or frozen force sensor, an encoder jump, a speed
//! or position beyond its limit, a stalled encoder, a non-finite motor command, more
//! missed ticks in a row than allowed, or too many late ticks in a short window. A trip
//! is recorded as a typed [`SafetyEvent`] in a fixed-capacity [`EventLog`] (no
//! allocation), and the command written at the tripping tick, and every tick after it
//! until reset, is zero.
//!
//! ## The model
//!
//! Every check is on what the tick already has: the sensor frame, the converted
//! position, step and velocity, the command written at the previous tick and the tick
//! numbers the loop passes in. Nothing reads a clock or allocates. The limits are
//! symmetric: a force, speed, position or step counts by its magnitude, on either axis.
//!
//! - **Limits** ([`SafetyMonitor::check`]): encoder step `|Δx| > encoder_jump_m`,
//!   position `|x| > wall_m + position_trip_margin_m`, filtered velocity
//!   `|v| > velocity_limit_m_per_s`, per axis.
//! - **Force sensor** ([`SafetyMonitor::observe_force`]): `nonfinite_force_ticks`
//!   non-finite readings in a row (the last finite one is held meanwhile), or
//!   `stale_force_ticks` bit-identical ones (a frozen ADC or bus).
//! - **Encoder stall** ([`SafetyMonitor::observe_encoders`]): an axis commanded at least
//!   `encoder_stall_force_n` at the previous tick whose count did not change, for
//!   `encoder_stall_ticks` readings in a row. The contract: under that force a working
//!   encoder on a free or hand-held cart moves within that time; whatever holds it to
//!   one count that long (a dead encoder, an end stop, a clamp, a hand steadier than a
//!   hand is) is a stall.
//! - **Loop deadline** ([`SafetyMonitor::observe_clock`]): while active, a tick that
//!   comes after one or more skipped ticks is late; more than `max_deadline_overruns`
//!   late ticks within the last `deadline_window_ticks` trip. (How long one gap may be
//!   is `max_consecutive_misses`, judged by the controller as a clock skip.)
//! - **Command** ([`SafetyMonitor::nonfinite_command`], [`SafetyMonitor::clamp`]): a
//!   NaN or infinite command trips and zero is written (never the limit: an infinite
//!   command says the law's state is broken, not that it wants the most force); a
//!   finite one is clamped to `±force_limit_n`.

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
    /// An axis was commanded at least `safety.encoder_stall_force_n` for `ticks`
    /// readings in a row while its encoder count did not change.
    EncoderStall {
        /// 0 = x, 1 = y.
        axis: usize,
        /// The command written at the tick before the trip on that axis, N.
        command_n: f64,
        /// Consecutive readings stalled.
        ticks: u32,
    },
    /// More than `safety.max_deadline_overruns` active ticks came late (after skipped
    /// ticks) within the last `safety.deadline_window_ticks`.
    DeadlineOverrun {
        /// Late ticks in the window, this one included.
        overruns: u32,
        /// The window, ticks.
        window_ticks: u32,
    },
    /// The motor command computed for an axis was NaN or infinite; zero was written.
    NonFiniteCommand {
        /// 0 = x, 1 = y.
        axis: usize,
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

/// The monitor's per-tick state: counters of consecutive bad readings, the last
/// encoder counts and command, and the history of late ticks.
#[derive(Debug, Clone, PartialEq)]
pub struct SafetyMonitor {
    config: SafetyConfig,
    nonfinite_ticks: u32,
    same_force_ticks: u32,
    last_raw_force: Option<[u64; 2]>,
    last_counts: Option<[i64; 2]>,
    last_command_n: [f64; 2],
    stall_ticks: [u32; 2],
    /// Bit `k` set: the tick `k` ticks before the newest one was a late active tick.
    late: u64,
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
            last_counts: None,
            last_command_n: [0.0; 2],
            stall_ticks: [0; 2],
            late: 0,
        }
    }

    /// Forget the counters (on reset).
    pub fn reset(&mut self) {
        let fresh = SafetyMonitor::new(&self.config);
        *self = fresh;
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

    /// Count this frame's encoder counts against the previous reading's under the
    /// command written in between ([`SafetyMonitor::observe_command`]): an axis
    /// commanded at least `encoder_stall_force_n` whose count did not change is one
    /// reading further into a stall; anything else ends it.
    pub fn observe_encoders(&mut self, frame: &SensorFrame) {
        let threshold = self.config.encoder_stall_force_n;
        for axis in 0..2 {
            let still = self
                .last_counts
                .is_some_and(|c| c[axis] == frame.encoder_counts[axis]);
            let pushed = self.last_command_n[axis].abs() >= threshold;
            self.stall_ticks[axis] = if still && pushed {
                self.stall_ticks[axis].saturating_add(1)
            } else {
                0
            };
        }
        self.last_counts = Some(frame.encoder_counts);
    }

    /// Record the command written at this tick (the force the motor holds until the
    /// next reading).
    pub fn observe_command(&mut self, command_n: [f64; 2]) {
        self.last_command_n = command_n;
    }

    /// Record the tick `now` that the loop runs, after `last` (the previous tick run, if
    /// any). While `active`, a tick after one or more skipped ones is late; inactive
    /// ticks command nothing, so their gaps are forgotten.
    pub fn observe_clock(&mut self, now: Tick, last: Option<Tick>, active: bool) {
        if !active {
            self.late = 0;
            return;
        }
        let Some(last) = last else { return };
        if now <= last {
            // Time did not advance: a clock skip, judged by the controller.
            return;
        }
        let gap = now.0 - last.0;
        self.late = if gap >= 64 { 0 } else { self.late << gap };
        if gap > 1 {
            self.late |= 1;
        }
    }

    /// Late active ticks within the last `deadline_window_ticks` (0 when the watchdog
    /// is off).
    #[must_use]
    pub fn deadline_overruns(&self) -> u32 {
        let w = self.config.deadline_window_ticks;
        let mask = if w >= 64 { u64::MAX } else { (1u64 << w) - 1 };
        (self.late & mask).count_ones()
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
        if c.stale_force_ticks > 0 && self.same_force_ticks >= c.stale_force_ticks {
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
        if c.encoder_stall_ticks > 0
            && let Some(axis) = (0..2).find(|&i| self.stall_ticks[i] >= c.encoder_stall_ticks)
        {
            return Some(TripReason::EncoderStall {
                axis,
                command_n: self.last_command_n[axis],
                ticks: self.stall_ticks[axis],
            });
        }
        if c.deadline_window_ticks > 0 {
            let overruns = self.deadline_overruns();
            if overruns > c.max_deadline_overruns {
                return Some(TripReason::DeadlineOverrun {
                    overruns,
                    window_ticks: c.deadline_window_ticks,
                });
            }
        }
        None
    }

    /// The trip for a computed motor command with a NaN or infinite axis, if any.
    #[must_use]
    pub fn nonfinite_command(force_n: [f64; 2]) -> Option<TripReason> {
        force_n
            .iter()
            .position(|f| !f.is_finite())
            .map(|axis| TripReason::NonFiniteCommand { axis })
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
    /// A non-finite axis (NaN, ±inf) becomes 0, flagged: it is never sent, and never
    /// turned into the limit. (The controller trips on it before it gets here:
    /// [`SafetyMonitor::nonfinite_command`].)
    #[must_use]
    pub fn clamp(&self, force_n: [f64; 2]) -> ([f64; 2], [bool; 2]) {
        let l = self.config.force_limit_n;
        let c = |i: usize| {
            let f = force_n[i];
            if f.is_finite() {
                (f.clamp(-l[i], l[i]), f.abs() > l[i])
            } else {
                (0.0, true)
            }
        };
        let (a, b) = (c(0), c(1));
        ([a.0, b.0], [a.1, b.1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_ticks_age_out_of_the_window_and_a_long_gap_clears_it() {
        // Window 8, budget 1: the history is a shift register of the last ticks run.
        let config = SafetyConfig {
            deadline_window_ticks: 8,
            max_deadline_overruns: 1,
            ..SafetyConfig::default()
        };
        let mut m = SafetyMonitor::new(&config);
        let mut last = Tick(0);
        let mut run = |m: &mut SafetyMonitor, n: u64| {
            m.observe_clock(Tick(n), Some(last), true);
            last = Tick(n);
            m.deadline_overruns()
        };
        // Late at 2 and 4 (one skipped tick before each): two in the window.
        assert_eq!(run(&mut m, 2), 1);
        assert_eq!(run(&mut m, 4), 2);
        // Tick 9's window is ticks 2..=9: both still in; tick 10's is 3..=10: tick 2 out.
        for n in 5..=9 {
            assert_eq!(run(&mut m, n), 2, "tick {n}");
        }
        assert_eq!(run(&mut m, 10), 1);
        assert_eq!(run(&mut m, 12), 1, "tick 4 out, tick 12 in");
        // A gap of 64 or more shifts everything out: only the late tick itself is left.
        assert_eq!(run(&mut m, 200), 1);
        // Inactive ticks forget the history.
        m.observe_clock(Tick(202), Some(Tick(200)), false);
        assert_eq!(m.deadline_overruns(), 0);
        // A tick that does not advance leaves it alone (the controller trips a clock skip).
        assert_eq!(run(&mut m, 204), 1);
        m.observe_clock(Tick(204), Some(Tick(204)), true);
        assert_eq!(m.deadline_overruns(), 1);
    }

    #[test]
    fn a_stall_needs_both_the_force_and_the_still_count_on_the_same_axis() {
        // 50 N and 80 readings by default. x still under 60 N counts; y still under 40 N
        // does not; a reading where x moves by one count starts x over.
        let mut m = SafetyMonitor::new(&SafetyConfig::default());
        let frame = |x: i64| SensorFrame {
            encoder_counts: [x, 7],
            ..SensorFrame::default()
        };
        m.observe_encoders(&frame(0));
        m.observe_command([60.0, -40.0]);
        for _ in 0..79 {
            m.observe_encoders(&frame(0));
        }
        let check = |m: &SafetyMonitor| m.check(&frame(0), [0.0; 2], [0.0; 2], [0.0; 2]);
        assert_eq!(check(&m), None, "79 still readings");
        m.observe_encoders(&frame(1));
        for _ in 0..79 {
            m.observe_encoders(&frame(1));
        }
        assert_eq!(check(&m), None, "started over at the move");
        m.observe_encoders(&frame(1));
        assert_eq!(
            check(&m),
            Some(TripReason::EncoderStall {
                axis: 0,
                command_n: 60.0,
                ticks: 80
            })
        );
        m.reset();
        assert_eq!(check(&m), None);
    }
}
