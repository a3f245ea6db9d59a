//! rigtwin — the runtime and command line.

pub mod replay;
pub mod session;
