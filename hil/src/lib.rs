//! rigtwin — the runtime and command line.
