//! The boundary between the rig's code and its hardware, in rig units.
//!
//! One trait, [`RigIo`], with (at least) three implementations: the simulator
//! (`rigtwin-world`'s `SimRig`), a replay of a recorded session, and mocks in tests.
//! The controller is generic over it and never knows which one it drives.
//!
//! This signature is the contract the other rooms build against: extend it, do not
//! change it.

use crate::time::Tick;

/// What the hardware reports at one tick, in the units the hardware speaks.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SensorFrame {
    /// Encoder counts of the lower (x) and upper (y) cart; one count is the encoder
    /// quantum (1 µm on the Börner rig). Count 0 is the rig-frame origin.
    pub encoder_counts: [i64; 2],
    /// The handle force sensor's raw reading in the sensor's own frame, N, before the
    /// calibration (rotation and offset) that the controller applies.
    pub force_raw_n: [f64; 2],
    /// The emergency-stop input: `true` while the button is pressed.
    pub estop: bool,
}

/// Motor force commands per axis, N, in the rig frame: `force_n[0]` drives the lower
/// (x) cart, `force_n[1]` the upper (y) cart.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotorCommand {
    /// Force per axis, N.
    pub force_n: [f64; 2],
}

impl MotorCommand {
    /// No force on either axis.
    pub const ZERO: MotorCommand = MotorCommand {
        force_n: [0.0, 0.0],
    };
}

/// The broad class of a hardware error, so the controller can react without knowing
/// the implementation's error type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The device is not there (cable, bus, process ended).
    Disconnected,
    /// A read or write did not complete within its tick.
    Timeout,
    /// The source has no more data (end of a replayed session).
    EndOfData,
    /// Anything else.
    Other,
}

/// An error from a [`RigIo`] implementation.
pub trait RigIoError: core::fmt::Debug {
    /// The class of this error.
    fn kind(&self) -> ErrorKind;
}

impl RigIoError for core::convert::Infallible {
    fn kind(&self) -> ErrorKind {
        match *self {}
    }
}

/// The rig's hardware as the controller sees it: read sensors, write motor commands.
///
/// The control loop calls `read` then `write` once per tick, in that order, with the
/// same `now`. Implementations must not block beyond the tick.
pub trait RigIo {
    /// The implementation's error type.
    type Error: RigIoError;

    /// Sample the sensors at tick `now`.
    fn read(&mut self, now: Tick) -> Result<SensorFrame, Self::Error>;

    /// Apply motor force commands from tick `now` on (held until the next write).
    fn write(&mut self, now: Tick, command: MotorCommand) -> Result<(), Self::Error>;
}
