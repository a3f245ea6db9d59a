//! Hardware in the loop across a process boundary: the two ends of the wire
//! (`hil/docs/wire.md`) as runners over the co-simulation step.
//!
//! ```text
//!  rigtwin controller <protocol> --rig udp://HOST:PORT       rigtwin plant serve <protocol> --listen ADDR
//!  ┌──────────────────────────────────────────┐   UDP    ┌───────────────────────────────────────────┐
//!  │ cosim::run on a WallClock (4 kHz)        │ command  │ serve: its own WallClock (4 kHz)          │
//!  │  TrialDriver → Controller::tick(plant)   │ ───────▶ │  poll → zero-order hold (watchdog) →      │
//!  │  plant = RemotePlant(WireRig): read the  │          │  SimPlant: rapier rig + simulated subject │
//!  │  newest frame, write the command         │ ◀─────── │  → sensor frame out, every tick           │
//!  │  recorder → <out>/session.toml (rig view)│  frame   │  recorder → <out>/session.toml (truth)    │
//!  └──────────────────────────────────────────┘          └───────────────────────────────────────────┘
//! ```
//!
//! The controller's side ([`controller`]) is the lock-step rehearsal's loop with a wall
//! clock and a plant that is only a [`rigtwin_wire::WireRig`]: it knows nothing of the
//! simulator, and records the session as a rig records it (encoders, force sensor,
//! commands; no ground truth). The plant's side ([`serve`]) is the rehearsal's
//! [`crate::cosim::SimPlant`] behind a [`rigtwin_wire::PlantEnd`], stepped on its own
//! clock, never skipping physics: a late wake-up steps every tick that came due, as the
//! hardware would have moved on. It records the plant's true state.
//!
//! Both ends read the same protocol and seed: the trial the controller names in its
//! commands (`trial` in the datagrams) tells the plant which trial of the schedule to
//! set up (start, goal, the subject's task and its seeded streams). Either end can be
//! the real thing: a lab's own controller that speaks the wire drives `plant serve`
//! (`hil/examples/pd_client.py`), and `rigtwin controller` drives a rig's I/O bridge.

pub mod controller;
pub mod serve;

use std::time::Duration;

use rigtwin_device::{Rate, Tick};
use rigtwin_wire::{
    FaultCounters, FaultInjector, FaultSpec, Faulty, Transport, TransportError, UdpTransport,
    WireError,
};

use std::path::Path;

use crate::cosim::CoSimError;
use crate::protocol::{Protocol, VirtualSubject};
use crate::rehearse::{self, RehearseError, TrialPlan};
use crate::session::{SessionError, SessionWriter};

/// What both ends run: the protocol, its first subject and the schedule drawn with the
/// session seed (the same on both ends, so that trial `k` is the same trial).
#[derive(Debug, Clone)]
pub struct SessionPlan {
    /// The protocol.
    pub protocol: Protocol,
    /// Subject 1 of the protocol's population with `seed`.
    pub subject: VirtualSubject,
    /// The session seed.
    pub seed: u64,
    /// The trials, in order (the schedule, cut to the first `max_trials`).
    pub plans: Vec<TrialPlan>,
}

impl SessionPlan {
    /// The schedule of subject 1 of `protocol` with `seed`, its first `max_trials` trials.
    ///
    /// # Errors
    /// [`RemoteError::TooManyTrials`] if the schedule has more trials than the wire numbers.
    pub fn new(
        protocol: Protocol,
        seed: u64,
        max_trials: Option<usize>,
    ) -> Result<SessionPlan, RemoteError> {
        let subject = protocol.subjects.draw(seed, 1);
        let mut plans = rehearse::schedule(&protocol, seed, subject.index);
        if let Some(m) = max_trials {
            plans.truncate(m);
        }
        for p in &plans {
            trial_id(p.index, plans.len())?;
        }
        Ok(SessionPlan {
            protocol,
            subject,
            seed,
            plans,
        })
    }

    /// Creates the session folder `out` (refusing one that is not empty) and its writer,
    /// the manifest's model described by `model` from the rehearsal's description.
    ///
    /// # Errors
    /// [`RemoteError`] from the folder or the writer.
    pub fn open_session(
        &self,
        out: &Path,
        model: impl FnOnce(Option<&str>) -> String,
    ) -> Result<SessionWriter, RemoteError> {
        rehearse::prepare_out(out)?;
        let mut manifest = rehearse::manifest(&self.protocol, &self.subject, self.seed);
        if let Some(sim) = manifest.sim.as_mut() {
            sim.model = Some(model(sim.model.as_deref()));
        }
        Ok(SessionWriter::create(out, manifest)?)
    }
}

/// The transport both ends use: UDP with a seeded fault injector on its sending side
/// (`none` injects nothing), on the session's clock.
pub type UdpLink = SessionTicks<Faulty<UdpTransport>>;

/// `transport` with `faults` (seeded by `seed`) on its sending side, at `rate`.
#[must_use]
pub fn with_faults(transport: UdpTransport, faults: FaultSpec, seed: u64, rate: Rate) -> UdpLink {
    SessionTicks {
        inner: Faulty::new(transport, FaultInjector::new(faults, seed, rate)),
        base: 0,
    }
}

/// A transport whose sends are stamped on the session's clock: the controller counts
/// each trial's ticks from 0, but the fault injector's delays and stall window must
/// see one clock that never goes back (a datagram delayed past a trial's end would
/// otherwise wait a whole trial in the injector's queue and block it). The runner moves
/// `base` on by the ticks each trial and hello phase took.
#[derive(Debug)]
pub struct SessionTicks<T: Transport> {
    inner: T,
    base: u64,
}

impl<T: Transport> SessionTicks<T> {
    /// Ticks of the session before the current trial's tick 0.
    pub fn set_base(&mut self, base: u64) {
        self.base = base;
    }

    /// The wrapped transport.
    #[must_use]
    pub fn inner(&self) -> &T {
        &self.inner
    }
}

impl SessionTicks<Faulty<UdpTransport>> {
    /// What the fault injector did.
    #[must_use]
    pub fn faults(&self) -> FaultCounters {
        self.inner.injector().counters()
    }
}

impl<T: Transport> Transport for SessionTicks<T> {
    fn send(&mut self, now: Tick, bytes: &[u8]) -> Result<(), TransportError> {
        self.inner.send(Tick(self.base + now.0), bytes)
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Result<Option<usize>, TransportError> {
        self.inner.try_recv(buf)
    }

    fn accept_peer(&mut self) {
        self.inner.accept_peer();
    }
}

/// Why a run across the wire failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RemoteError {
    /// The wire: a socket error, a refused command.
    #[error("wire: {0}")]
    Wire(#[from] WireError),
    /// The co-simulation step.
    #[error(transparent)]
    CoSim(#[from] CoSimError),
    /// Building a trial from the protocol.
    #[error(transparent)]
    Rehearse(#[from] RehearseError),
    /// Writing the session.
    #[error(transparent)]
    Session(#[from] SessionError),
    /// The plant's simulated rig.
    #[error("plant: {0}")]
    World(#[from] rigtwin_world::WorldError),
    /// No frame of the trial came back in time.
    #[error(
        "no sensor frame of trial {trial} from {peer} within {waited:?}: is `rigtwin plant serve` (or the rig's bridge) running there, on the same protocol?"
    )]
    NoPlant {
        /// The trial id asked for.
        trial: u16,
        /// The plant's address.
        peer: String,
        /// How long the controller waited.
        waited: Duration,
    },
    /// The protocol has more trials than the wire's trial field counts.
    #[error("the protocol has {trials} trials per subject; the wire numbers trials up to {max}")]
    TooManyTrials {
        /// Trials in the schedule.
        trials: usize,
        /// The largest trial id the wire carries.
        max: u16,
    },
    /// The thread writing the session panicked.
    #[error("the session writer's thread panicked")]
    WriterPanicked,
    /// The clock could not be used.
    #[error("clock: {0}")]
    Clock(#[from] crate::cosim::ClockError),
}

/// The wire's id of a trial (1-based), or an error for a schedule too long for the wire.
///
/// # Errors
/// [`RemoteError::TooManyTrials`] past `u16::MAX` trials.
pub fn trial_id(index: u32, trials: usize) -> Result<u16, RemoteError> {
    u16::try_from(index + 1).map_err(|_| RemoteError::TooManyTrials {
        trials,
        max: u16::MAX,
    })
}
