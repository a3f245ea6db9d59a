//! # rigtwin-device — the rig's own real-time code
//!
//! Everything in this crate runs on the real manipulandum at 4 kHz and, unchanged,
//! against the simulator. It never depends on the physics engine, the viewer, the arm
//! model or the runtime: the only way in and out is [`io::RigIo`], in rig units.
//!
//! Units are SI throughout (m, s, N, kg) unless a name says otherwise; positions are in
//! the rig frame (origin at the workspace centre, `x` to the subject's right, `y` away
//! from the subject, horizontal plane).

pub mod estimate;
pub mod io;
pub mod signal;
pub mod time;

pub use io::{ErrorKind, MotorCommand, RigIo, RigIoError, SensorFrame};
pub use time::{Rate, Tick};
