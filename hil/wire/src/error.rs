//! The error of both ends of the link, with the hardware-error class the controller's
//! safety layer reacts to ([`RigIoError::kind`]).
//!
//! | error            | kind           | when                                                  |
//! |------------------|----------------|-------------------------------------------------------|
//! | `NoFrameYet`     | `Disconnected` | the controller read before any sensor frame arrived   |
//! | `Stale`          | `Timeout`      | no new sensor frame for `stale_ticks` controller ticks |
//! | `GapTooLarge`    | `Other`        | more than `max_gap` consecutive frames were lost      |
//! | `Encode`         | `Other`        | a motor command with a non-finite force (not sent)    |
//! | `Transport`      | per error      | the socket failed ([`TransportError::kind`])          |
//! | `BadLimit`       | `Other`        | a limit given to `new` is out of range                |

use rigtwin_device::{ErrorKind, RigIoError};

use crate::datagram::EncodeError;
use crate::transport::TransportError;

/// Why an end of the link could not read or write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum WireError {
    /// No sensor frame has arrived yet: the plant is not there (or not started).
    #[error("no sensor frame has arrived yet")]
    NoFrameYet,
    /// No new sensor frame for `ticks` controller ticks, at or beyond the limit.
    #[error("no new sensor frame for {ticks} ticks (limit {limit})")]
    Stale {
        /// Controller ticks since the newest frame arrived.
        ticks: u64,
        /// The configured `stale_ticks`.
        limit: u32,
    },
    /// A gap of `missing` consecutive sensor frames, more than the limit.
    #[error("{missing} consecutive sensor frames lost (limit {limit})")]
    GapTooLarge {
        /// Sequence numbers skipped.
        missing: u32,
        /// The configured `max_gap`.
        limit: u32,
    },
    /// The command could not be encoded (non-finite force); nothing was sent.
    #[error(transparent)]
    Encode(#[from] EncodeError),
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// A limit is out of range.
    #[error("{name} must be at least {min}")]
    BadLimit {
        /// The limit's name.
        name: &'static str,
        /// Its smallest allowed value.
        min: u32,
    },
}

impl RigIoError for WireError {
    fn kind(&self) -> ErrorKind {
        match self {
            WireError::NoFrameYet => ErrorKind::Disconnected,
            WireError::Stale { .. } => ErrorKind::Timeout,
            WireError::Transport(e) => e.kind(),
            WireError::GapTooLarge { .. } | WireError::Encode(_) | WireError::BadLimit { .. } => {
                ErrorKind::Other
            }
        }
    }
}
