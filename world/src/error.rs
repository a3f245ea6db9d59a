//! Errors of the world crate.

use rigtwin_device::{ErrorKind, RigIoError};
use thiserror::Error;

/// Everything that can go wrong when building or driving the plant.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum WorldError {
    /// A configuration key out of its range.
    #[error("invalid config key `{key}`: {reason}")]
    InvalidConfig {
        /// The key, dotted from the root of [`crate::RigConfig`].
        key: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The arm cannot reach the initial handle position, or its parameters are bad.
    #[error("arm: {0}")]
    Arm(#[from] rigtwin_arm::ArmError),
    /// A non-finite number where a finite one is needed (a motor command or a torque).
    #[error("non-finite input `{what}`")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// The physics state became non-finite (the simulation blew up).
    #[error("the simulation diverged at tick {tick}")]
    Diverged {
        /// The tick at which a non-finite state was found.
        tick: u64,
    },
}

impl RigIoError for WorldError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}
