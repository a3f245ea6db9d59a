//! # rigtwin-wire — the wire between the rig's controller and a rig
//!
//! A versioned binary protocol over UDP, in the spirit of the 1 kHz UDP interfaces of
//! industrial arms (Franka FCI, KUKA FRI), that lets the rig's own controller
//! (`rigtwin_device::Controller`) drive a plant in another process or on another machine,
//! simulated or real, through the same [`RigIo`](rigtwin_device::RigIo) boundary. It
//! knows nothing of the simulator, files, protocols or the viewer. The byte-level spec
//! for implementers in other languages is `hil/docs/wire.md`.
//!
//! ## The model
//!
//! ```text
//!   plant (clock master)                                   controller
//!   ────────────────────                                   ──────────
//!   tick n: poll_command(n) ◀─ motor command (seq, tick c, force, mode, answers n') ─┐
//!           applied_force(n): newest command, held; zero if stale/not Active         │
//!           step physics                                                              │
//!           send_frame(n) ── sensor frame (seq, tick n, counts, force, e-stop, ─▶ read(c)
//!                             flags, echo c') ──────────────────────────────▶ Controller::tick
//!                                                                             write(c) ┘
//! ```
//!
//! - **Who is clock master.** The plant sends one [`SensorDatagram`] every plant tick;
//!   the controller answers each frame it reads with one [`CommandDatagram`]. Each side
//!   stamps datagrams with its own tick; the clocks are not assumed synchronised.
//! - **Zero-order hold.** The plant applies the newest valid command until a newer one
//!   arrives; the controller reads the newest valid frame. Both drop datagrams older
//!   than the newest they accepted (sequence numbers with wrap-around, [`link`]).
//! - **Watchdogs on both ends.** The plant zeroes the force when no new command arrived
//!   for `stale_ticks` plant ticks (default 4 = 1 ms at 4 kHz) and says so in the frame's
//!   flags ([`PlantEnd`]). The controller's [`WireRig::read`](rigtwin_device::RigIo::read)
//!   fails with `ErrorKind::Timeout` when no new frame arrived for `stale_ticks`
//!   controller ticks (default 4), and with `ErrorKind::Other` on a gap of more than
//!   `max_gap` lost frames (default 3); the controller's safety layer then trips and
//!   latches.
//! - **A NaN never reaches a motor.** A command with a non-finite force can neither be
//!   encoded nor decoded ([`datagram`]).
//! - **Faults are reproducible.** [`Faulty`] wraps the sending side of any
//!   [`Transport`] with a seeded [`FaultInjector`] (drop, delay, duplicate, reorder,
//!   stall), configured by a [`FaultSpec`] string.
//!
//! ## Example: lock step in one process
//!
//! ```
//! use rigtwin_device::{Mode, MotorCommand, RigIo, SensorFrame, Tick};
//! use rigtwin_wire::{PlantEnd, PlantLimits, RigLimits, WireRig, channel_pair};
//!
//! let (controller_side, plant_side) = channel_pair(16);
//! let mut rig = WireRig::new(controller_side, RigLimits::default())?;
//! let mut plant = PlantEnd::new(plant_side, PlantLimits::default())?;
//! rig.set_mode(Mode::Active);
//! for n in 0..10 {
//!     let now = Tick(n);
//!     plant.poll_command(now)?;
//!     let force_n = plant.applied_force(now); // onto the motors; step the physics
//!     plant.send_frame(now, SensorFrame { encoder_counts: [n as i64, 0], ..SensorFrame::default() })?;
//!     let frame = rig.read(now)?; // the controller's tick reads ...
//!     assert_eq!(frame.encoder_counts[0], n as i64);
//!     rig.write(now, MotorCommand { force_n: [1.0, -1.0] })?; // ... and writes
//!     assert_eq!(force_n, if n == 0 { [0.0; 2] } else { [1.0, -1.0] });
//! }
//! assert_eq!(rig.round_trip_ticks(), Some(1));
//! # Ok::<(), rigtwin_wire::WireError>(())
//! ```
//!
//! ## Real time
//!
//! [`WireRig::read`](rigtwin_device::RigIo::read), `write`, and the [`PlantEnd`]'s
//! per-tick calls allocate nothing: buffers, queues and the injector's ring are sized at
//! construction (a counting-allocator test proves it). None of them blocks.

pub mod datagram;
pub mod error;
pub mod faults;
pub mod link;
pub mod plant;
pub mod rig;
pub mod transport;

pub use datagram::{
    COMMAND_LEN, CommandDatagram, Datagram, DecodeError, EncodeError, SENSOR_LEN, SensorDatagram,
    VERSION, decode,
};
pub use error::WireError;
pub use faults::{FaultCounters, FaultInjector, FaultSpec, FaultSpecError, MAX_DATAGRAM};
pub use link::{Arrival, LinkCounters, SequenceTracker};
pub use plant::{PlantEnd, PlantLimits};
pub use rig::{RigLimits, WireRig};
pub use transport::{ChannelEnd, Faulty, Transport, TransportError, UdpTransport, channel_pair};
