//! rigtwin — the runtime and command line.

/// `rigtwin compare`: a measured session re-simulated, and how far the simulation is.
pub mod compare;
pub mod cosim;
pub mod protocol;
pub mod rehearse;
pub mod remote;
pub mod report;
pub mod sweep;

/// The diagnosis of a measured session (its own crate, `rigtwin-diagnose`).
pub use rigtwin_diagnose as diagnose;
/// The recording format (its own crate, `rigtwin-session`).
pub use rigtwin_session as session;
/// A recorded session as a rig (`rigtwin_session::replay`).
pub use rigtwin_session::replay;

/// Visual debugging in the rerun viewer (`--rerun`).
#[cfg(feature = "rerun")]
pub mod viz;
