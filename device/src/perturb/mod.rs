//! Perturbations the rig applies: the force pulse of 000_* (added to the admittance
//! input) and the position perturbation of 001_* (added to the rendered reference),
//! their triggers, and the seeded schedules that decide angles and order.
//!
//! Generators are armed from outside the loop (no allocation), fire on their trigger
//! inside `tick`, and report their status and onset tick.

pub mod force_pulse;
pub mod position;
pub mod schedule;

use crate::time::Tick;

/// Where a perturbation generator is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PerturbationStatus {
    /// Nothing armed.
    #[default]
    Idle,
    /// Armed, waiting for its trigger.
    Armed,
    /// Running since `onset`.
    Running {
        /// The tick the trigger fired (the profile's `t = 0`).
        onset: Tick,
    },
    /// Ran to completion.
    Done {
        /// The tick it started.
        onset: Tick,
    },
    /// Cut short by a fault or deactivation.
    Aborted {
        /// The tick it started.
        onset: Tick,
    },
}

impl PerturbationStatus {
    /// True while the perturbation is being applied.
    #[must_use]
    pub fn is_running(self) -> bool {
        matches!(self, PerturbationStatus::Running { .. })
    }

    /// True at the tick the perturbation started: running, with its onset at `now`.
    #[must_use]
    pub fn started_at(self, now: Tick) -> bool {
        self == PerturbationStatus::Running { onset: now }
    }

    /// The onset tick of the running or last perturbation, if any.
    #[must_use]
    pub fn onset(self) -> Option<Tick> {
        match self {
            PerturbationStatus::Running { onset }
            | PerturbationStatus::Done { onset }
            | PerturbationStatus::Aborted { onset } => Some(onset),
            PerturbationStatus::Idle | PerturbationStatus::Armed => None,
        }
    }
}

/// The life of one perturbation generator, shared by the force pulse and the position
/// perturbation: armed with a direction and a trigger of type `T`, running from its
/// onset for a fixed number of ticks, then done (or aborted). Plain data: no
/// allocation, safe inside the tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Lifecycle<T> {
    Idle,
    Armed { dir: [f64; 2], trigger: T },
    Running { dir: [f64; 2], onset: Tick },
    Done { onset: Tick },
    Aborted { onset: Tick },
}

impl<T: Copy> Lifecycle<T> {
    /// Arms along `angle_rad` (rig frame) with `trigger`.
    pub(crate) fn arm(&mut self, angle_rad: f64, trigger: T) -> Result<(), ArmError> {
        if !angle_rad.is_finite() {
            return Err(ArmError::NonFiniteAngle);
        }
        if matches!(self, Lifecycle::Running { .. }) {
            return Err(ArmError::AlreadyRunning);
        }
        let (s, c) = angle_rad.sin_cos();
        *self = Lifecycle::Armed {
            dir: [c, s],
            trigger,
        };
        Ok(())
    }

    /// The armed trigger, if armed.
    pub(crate) fn trigger(&self) -> Option<T> {
        match *self {
            Lifecycle::Armed { trigger, .. } => Some(trigger),
            _ => None,
        }
    }

    /// The armed trigger to change, if armed.
    pub(crate) fn trigger_mut(&mut self) -> Option<&mut T> {
        match self {
            Lifecycle::Armed { trigger, .. } => Some(trigger),
            _ => None,
        }
    }

    /// Disarms, or cuts a running perturbation short.
    pub(crate) fn abort(&mut self) {
        *self = match *self {
            Lifecycle::Running { onset, .. } => Lifecycle::Aborted { onset },
            Lifecycle::Armed { .. } => Lifecycle::Idle,
            s => s,
        };
    }

    /// Status for the recorder.
    pub(crate) fn status(&self) -> PerturbationStatus {
        match *self {
            Lifecycle::Idle => PerturbationStatus::Idle,
            Lifecycle::Armed { .. } => PerturbationStatus::Armed,
            Lifecycle::Running { onset, .. } => PerturbationStatus::Running { onset },
            Lifecycle::Done { onset } => PerturbationStatus::Done { onset },
            Lifecycle::Aborted { onset } => PerturbationStatus::Aborted { onset },
        }
    }

    /// One active tick: fires if armed and `due(trigger)`, then, while running, returns
    /// the ticks since onset and the direction; moves to done after `duration_ticks`.
    pub(crate) fn advance(
        &mut self,
        now: Tick,
        duration_ticks: u64,
        due: impl FnOnce(T) -> bool,
    ) -> Option<(u64, [f64; 2])> {
        if let Lifecycle::Armed { dir, trigger } = *self
            && due(trigger)
        {
            *self = Lifecycle::Running { dir, onset: now };
        }
        if let Lifecycle::Running { dir, onset } = *self {
            let k = now.0.saturating_sub(onset.0);
            if k >= duration_ticks {
                *self = Lifecycle::Done { onset };
                return None;
            }
            return Some((k, dir));
        }
        None
    }
}

/// Which way a line must be crossed to fire a trigger.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Crossing {
    /// From below the line to at-or-above it.
    Rising,
    /// From above the line to at-or-below it.
    Falling,
    /// Either way.
    Either,
}

impl Crossing {
    /// True if going from `before` to `after` crosses `line` this way.
    #[must_use]
    pub fn crossed(self, before: f64, after: f64, line: f64) -> bool {
        let up = before < line && after >= line;
        let down = before > line && after <= line;
        match self {
            Crossing::Rising => up,
            Crossing::Falling => down,
            Crossing::Either => up || down,
        }
    }
}

/// Why a perturbation could not be armed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ArmError {
    /// The direction angle is NaN or infinite.
    #[error("perturbation angle must be finite")]
    NonFiniteAngle,
    /// A line-crossing trigger's line is NaN or infinite.
    #[error("trigger line position must be finite")]
    NonFiniteLine,
    /// A perturbation of this kind is already running.
    #[error("a perturbation of this kind is already running")]
    AlreadyRunning,
    /// The trigger needs the imposed motion, but the virtual-spring law is not selected.
    #[error("zero-acceleration triggers need the virtual-spring law with its imposed motion")]
    NoImposedMotion,
}
