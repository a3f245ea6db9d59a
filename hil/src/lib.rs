//! rigtwin — the runtime and command line.

pub mod cosim;
pub mod discrepancy;
pub mod protocol;
pub mod rehearse;
pub mod remote;
pub mod replay;
pub mod report;
pub mod session;

/// Visual debugging in the rerun viewer (`--rerun`).
#[cfg(feature = "rerun")]
pub mod viz;
