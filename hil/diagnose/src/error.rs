//! What can go wrong while diagnosing a session.

use std::path::PathBuf;

/// Errors of the discrepancy workflow.
#[derive(Debug, thiserror::Error)]
pub enum DiscrepancyError {
    /// The session has too few trials carrying the channels a judgement needs.
    #[error("{what}: needs at least {needed} trials with columns {columns}, the session has {got}")]
    TooFewTrials {
        /// Which analysis.
        what: &'static str,
        /// Trials needed.
        needed: usize,
        /// Trials usable.
        got: usize,
        /// The columns that were missing or needed.
        columns: &'static str,
    },
    /// A trial is too short for the smoothing window.
    #[error("trial {trial}: {samples} samples, fewer than the {window}-sample smoothing window")]
    TrialTooShort {
        /// Trial id.
        trial: u32,
        /// Samples in the trial.
        samples: usize,
        /// Window length.
        window: usize,
    },
    /// The sampling rate cannot carry the analysis.
    #[error("sampling rate {rate_hz} Hz is too low for the force balance (needs at least 200 Hz)")]
    RateTooLow {
        /// The session's rate, Hz.
        rate_hz: f64,
    },
    /// A signal-processing step failed.
    #[error("signal processing of trial {trial}: {source}")]
    Signal {
        /// Trial id.
        trial: u32,
        /// The cause.
        #[source]
        source: rigtwin_device::signal::SignalError,
    },
    /// The least-squares problem has no unique solution.
    #[error(
        "{what}: the least-squares problem is singular (the regressors are not independent on these trials)"
    )]
    Singular {
        /// Which fit.
        what: String,
    },
    /// The nominal balance of a rig without a force sensor wants a moving mass that is
    /// not positive: the command and the position have opposite signs (a map's scale of the wrong sign, a motor wired
    /// the other way round), and no judgement of the session would mean anything.
    #[error(
        "the fitted moving mass of the {axis} axis is {mass_kg:.3} kg: the motor command pushes against the measured motion, so \
         the command's sign (the import map's scale, the motor's wiring) or the position's is reversed; flip one and diagnose again"
    )]
    NegativeMass {
        /// `x` or `y`.
        axis: &'static str,
        /// The fitted mass, kg.
        mass_kg: f64,
    },
    /// Writing a report or a plot failed.
    #[error("writing {path}: {reason}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A session could not be replayed in simulation.
    #[error("replaying trial {trial}: {reason}")]
    Replay {
        /// Trial id (0 for the whole session).
        trial: u32,
        /// Why.
        reason: String,
    },
    /// A row the decision names is not a catalog effect, or its fitted parameters do not
    /// describe one (a candidate whose parameter names and its [`crate::Effect`] disagree).
    #[error("{name} was to be named a cause, but {why}")]
    NotAnEffect {
        /// The row's name.
        name: String,
        /// Why it is not an effect.
        why: String,
    },
    /// A model file could not be made or read.
    #[error("model file {path}: {reason}")]
    Model {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}
