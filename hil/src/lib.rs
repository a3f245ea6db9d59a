//! rigtwin — the runtime and command line.

pub mod cosim;
pub mod discrepancy;
pub mod protocol;
pub mod rehearse;
pub mod remote;
pub mod report;

/// The recording format (its own crate, `rigtwin-session`).
pub use rigtwin_session as session;
/// A recorded session as a rig (`rigtwin_session::replay`).
pub use rigtwin_session::replay;

/// Visual debugging in the rerun viewer (`--rerun`).
#[cfg(feature = "rerun")]
pub mod viz;
