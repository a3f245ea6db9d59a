//! Visual debugging in the rerun viewer: the rig and the arm in 2D, time series of every
//! recorded channel, perturbation responses, impedance ellipses and safety events.
//!
//! The viewer is an output, never the archive (`.rrd` has no compatibility promise): the
//! session files stay the record and every `.rrd` can be made again from them.
//!
//! The API takes plain slices and arrays, so the runtime, the session reader and the
//! estimators call it without sharing types with it:
//!
//! ```no_run
//! # fn main() -> Result<(), rigtwin::viz::VizError> {
//! use rigtwin::viz::{RigGeometry, Target, TrialColumns, TrialMeta, Viewer};
//! let target: Target = "save=run.rrd".parse()?;
//! let mut viewer = Viewer::new(&target, "rigtwin", "session-0001")?;
//! viewer.log_rig_geometry(&RigGeometry::with_workspace(0.15))?;
//! let t = [0.0, 0.001, 0.002];
//! let z = [0.0; 3];
//! let columns = TrialColumns::required(&t, &z, &z, &z, &z, &z, &z);
//! let span = viewer.log_trial(&TrialMeta::new(0, 1000.0), &columns)?;
//! viewer.log_ellipse("stiffness", Some(span.stamp(0.002)), [0.0, 0.0],
//!     [[300.0, 0.0], [0.0, 150.0]], 1e-4, "K")?;
//! viewer.finish()?;
//! # Ok(()) }
//! ```
//!
//! Timelines: `tick` (4 kHz control ticks since the start of the session, trials back to
//! back), `time` (seconds on the same axis) and `trial` (the trial's index). Nothing is
//! stamped with the wall clock, chunk and row ids come from a counter and the recording id is
//! given by the caller, so a saved file is the same bytes every time (see [`crate::viz::Viewer`]).

mod blueprint;
mod columns;
mod geometry;
mod ids;
pub mod impedance;
mod overlay;
pub mod paths;
mod rehearsal;
mod session;
mod sink;
mod target;
mod viewer;

pub use columns::{
    ArmColumns, ArmTrajectory, EventLevel, PerturbationMeta, PerturbationSize, RigGeometry, Stamp,
    TrialColumns, TrialMeta, TrialSpan,
};
pub use geometry::{
    Elbow, EllipseAxes, RESPONSE_WINDOW_S, Response, ellipse_axes, ellipse_outline,
    two_link_inverse, variational_response,
};
pub use impedance::{
    EstimatesLogged, Impedance, Which, log_borner, log_impedance, log_piovesan,
    log_session_estimates,
};
pub use overlay::{Overlaid, OverlayError, log_diagnosis_overlay, log_replay_overlay};
pub use rehearsal::{RehearsalLogged, RehearsalLogger, rehearsal_recording_id};
pub use session::{ARM_ANGLE_COLUMNS, Logged, log_session, log_session_at, recording_id};
pub use target::{RerunArgs, Target, TargetParseError};
pub use viewer::{DEFAULT_LIVE_RATE_HZ, Viewer};

/// The rate of the `tick` timeline: the 4 kHz control clock, [`rigtwin_device::Rate::CONTROL`].
pub const TICK_HZ: f64 = rigtwin_device::Rate::CONTROL.hz() as f64;

/// What can go wrong while streaming to the viewer or writing an `.rrd`.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    /// The `--rerun` value did not parse.
    #[error(transparent)]
    Target(#[from] TargetParseError),
    /// Columns of one trial have different lengths.
    #[error("column `{column}` has {len} samples but `t_s` has {expected}")]
    ColumnLength {
        /// The offending column.
        column: &'static str,
        /// Its length.
        len: usize,
        /// The length of `t_s`.
        expected: usize,
    },
    /// A value that must be finite and positive is not (a rate, a display scale).
    #[error("`{what}` must be finite and positive, got {value}")]
    NotPositive {
        /// The parameter.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// The application or recording id is not usable by rerun.
    #[error("invalid rerun id `{id}`: {reason}")]
    InvalidId {
        /// The id as given.
        id: String,
        /// Why rerun refused it.
        reason: String,
    },
    /// A chunk could not be built from the columns (a bug, or a malformed input rerun refused).
    #[error("building rerun data for `{entity}`: {source}")]
    Chunk {
        /// The entity being logged.
        entity: String,
        /// rerun's error.
        source: rerun::log::ChunkError,
    },
    /// A component batch could not be serialised.
    #[error("serialising `{entity}`: {source}")]
    Serialize {
        /// The entity being logged.
        entity: String,
        /// rerun's error.
        source: rerun::SerializationError,
    },
    /// Creating or writing the `.rrd` file failed.
    #[error("writing {path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// rerun's encoder refused a message.
    #[error("encoding the .rrd stream: {0}")]
    Encode(#[from] rerun::external::re_log_encoding::EncodeError),
    /// Starting or connecting to a viewer failed.
    #[error("rerun viewer: {0}")]
    Stream(#[from] rerun::RecordingStreamError),
    /// Flushing a live stream failed.
    #[error("flushing the live stream: {0}")]
    Flush(String),
    /// No viewer accepted a connection at the address within 3 s (`CONNECT_TIMEOUT`).
    #[error("no rerun viewer answers at {url} within {} s ({reason}); start one with `rerun`, or use --rerun spawn or save=FILE.rrd", viewer::CONNECT_TIMEOUT.as_secs())]
    NoViewer {
        /// The viewer's URL.
        url: String,
        /// What the connection attempt said.
        reason: String,
    },
    /// The protocol could not be serialised to derive a rehearsal's recording id.
    #[error("describing the protocol for the recording id: {0}")]
    ProtocolId(serde_json::Error),
    /// A rehearsal's sessions and trials reached the logger out of order (a bug).
    #[error("logging the rehearsal: {0}")]
    Order(String),
    /// A session to be streamed did not read.
    #[error("reading the session to stream it: {0}")]
    Session(#[from] crate::session::SessionError),
}
