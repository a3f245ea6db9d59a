//! The simulated plant behind the wire, in one process: the controller's [`WireRig`]
//! and the plant's [`PlantEnd`] on two ends of a [`Transport`], with a [`SimPlant`]
//! behind the plant's end. Every sensor frame and every motor command is encoded,
//! sent, received and decoded as across a real link (with the transport's faults, if
//! it injects any), while the loop stays in lock step.
//!
//! Over a fault-free in-process channel this plant is exactly the [`SimPlant`]: frames
//! and commands cross bit for bit, the plant applies the command of the same tick, so a
//! rehearsal gives the bytes of the lock-step one (a test asserts it). With faults, it
//! shows what the controller's safety layer and the plant's watchdog do when the link
//! misbehaves.

use rigtwin_device::{
    ErrorKind, Mode, MotorCommand, RigIo, RigIoError, SensorFrame, Tick, TickReport,
};
use rigtwin_wire::{PlantEnd, Transport, WireError, WireRig};
use rigtwin_world::WorldError;

use super::{CoSimError, Plant, PlantSample, SimPlant};

/// Why the wired plant's I/O failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WiredError {
    /// The wire (either end).
    #[error("wire: {0}")]
    Wire(#[from] WireError),
    /// The simulated plant.
    #[error("plant: {0}")]
    World(#[from] WorldError),
}

impl RigIoError for WiredError {
    fn kind(&self) -> ErrorKind {
        match self {
            WiredError::Wire(e) => e.kind(),
            WiredError::World(e) => e.kind(),
        }
    }
}

/// A [`SimPlant`] reached only through the wire.
#[derive(Debug)]
pub struct WiredPlant<C: Transport, P: Transport> {
    rig: WireRig<C>,
    end: PlantEnd<P>,
    sim: SimPlant,
}

impl<C: Transport, P: Transport> WiredPlant<C, P> {
    /// The controller's end `rig`, the plant's end `end` (the two ends of one link, each
    /// with its own sending side, which may inject faults) and
    /// the plant behind it.
    #[must_use]
    pub fn new(rig: WireRig<C>, end: PlantEnd<P>, sim: SimPlant) -> WiredPlant<C, P> {
        WiredPlant { rig, end, sim }
    }

    /// The controller's end.
    #[must_use]
    pub fn rig(&self) -> &WireRig<C> {
        &self.rig
    }

    /// The plant's end.
    #[must_use]
    pub fn end(&self) -> &PlantEnd<P> {
        &self.end
    }

    /// The simulated plant.
    #[must_use]
    pub fn sim(&self) -> &SimPlant {
        &self.sim
    }

    /// The simulated plant, e.g. to press its e-stop.
    pub fn sim_mut(&mut self) -> &mut SimPlant {
        &mut self.sim
    }
}

impl<C: Transport, P: Transport> RigIo for WiredPlant<C, P> {
    type Error = WiredError;

    /// The plant sends the frame of its state at `now`; the controller's end reads the
    /// newest frame that arrived.
    fn read(&mut self, now: Tick) -> Result<SensorFrame, WiredError> {
        let frame = self.sim.read(now)?;
        self.end.send_frame(now, frame)?;
        Ok(self.rig.read(now)?)
    }

    /// The controller's end sends the command; the plant takes the newest command that
    /// arrived (zero when stale or not active) onto its motors.
    fn write(&mut self, now: Tick, command: MotorCommand) -> Result<(), WiredError> {
        self.rig.write(now, command)?;
        self.end.poll_command(now)?;
        let force_n = self.end.applied_force(now);
        self.sim.write(now, MotorCommand { force_n })?;
        Ok(())
    }
}

impl<C: Transport, P: Transport> Plant for WiredPlant<C, P> {
    fn before_tick(&mut self, mode: Mode) {
        self.rig.set_mode(mode);
    }

    fn advance(
        &mut self,
        now: Tick,
        report: &TickReport,
    ) -> Result<Option<PlantSample>, CoSimError> {
        self.sim.advance(now, report)
    }

    fn has_muscles(&self) -> bool {
        self.sim.has_muscles()
    }
}
