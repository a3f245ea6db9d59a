//! The rig's controller running a protocol's trials in real time against a plant across
//! the wire, and recording the session as the rig records it.
//!
//! Per trial: the controller's end names the trial and sends hellos (zero commands,
//! mode `configured`) on the wall clock until the plant's first frame of that trial
//! arrives ([`await_plant`], bounded by a time-out); then the trial's controller,
//! driver and recorder ([`crate::rehearse::trial::controller_parts`]) run as
//! [`crate::cosim::run`] over a [`RemotePlant`] for the protocol's trial length, and the
//! recorded rows are written as the session's trial. The plant's ground truth never
//! crosses the wire, so the session has the rig's columns only (encoders, calibrated
//! force, perturbation, velocity, reference, command).
//!
//! A trip (a stale or missing frame, a sequence gap, the e-stop, a force or wall limit)
//! latches the controller in fault for the rest of that trial, as on the rig; the next
//! trial starts with a new controller, as a rig's experiment script resets it.

use std::time::Duration;

use rigtwin_device::{MotorCommand, RigIo, SensorFrame, Tick, TickReport};
use rigtwin_wire::{LinkCounters, Transport, WireError, WireRig};

use super::{RemoteError, SessionPlan, SessionTicks, trial_id};
use crate::cosim::{self, Clock, CoSim, CoSimError, Plant, PlantSample, WallClock};
use crate::protocol::ProtocolKind;
use crate::rehearse::record::{self, Layout};
use crate::rehearse::{TICK_HZ, trial, trial_meta};
use crate::session::{SessionWriter, Timing};

/// A plant across the wire, as the co-simulation loop sees it: the controller's end of
/// the link, which moves on by itself and reports no ground truth.
#[derive(Debug)]
pub struct RemotePlant<'a, T: Transport> {
    rig: &'a mut WireRig<T>,
}

impl<'a, T: Transport> RemotePlant<'a, T> {
    /// The plant behind `rig`.
    pub fn new(rig: &'a mut WireRig<T>) -> RemotePlant<'a, T> {
        RemotePlant { rig }
    }
}

impl<T: Transport> RigIo for RemotePlant<'_, T> {
    type Error = WireError;

    fn read(&mut self, now: Tick) -> Result<SensorFrame, WireError> {
        self.rig.read(now)
    }

    fn write(&mut self, now: Tick, command: MotorCommand) -> Result<(), WireError> {
        self.rig.write(now, command)
    }
}

impl<T: Transport> Plant for RemotePlant<'_, T> {
    fn before_tick(&mut self, mode: rigtwin_device::Mode) {
        self.rig.set_mode(mode);
    }

    fn advance(
        &mut self,
        _now: Tick,
        _report: &TickReport,
    ) -> Result<Option<PlantSample>, CoSimError> {
        Ok(None)
    }
}

/// Sends hellos for trial `trial` on `clock` until the plant's first frame of it
/// arrives, for at most `timeout`; returns the ticks it took. `peer` names the plant in
/// the error.
///
/// # Errors
/// [`RemoteError::NoPlant`] when nothing of the trial came back in time.
pub fn await_plant<T: Transport>(
    rig: &mut WireRig<T>,
    trial: u16,
    clock: &mut WallClock,
    timeout: Duration,
    peer: &str,
) -> Result<u64, RemoteError> {
    rig.begin_trial(trial);
    rig.set_mode(rigtwin_device::Mode::Configured);
    clock.restart();
    let last = u64::try_from(timeout.as_nanos() / clock.period().as_nanos().max(1))
        .unwrap_or(u64::MAX)
        .max(1);
    let mut n = 0;
    while n <= last {
        let now = clock.wait(Tick(n), Tick(last));
        // A refused port (no plant yet) is an error of the send or the receive; keep
        // saying hello until the time-out.
        let _ = rig.write(now, MotorCommand::ZERO);
        if rig.read(now).is_ok() {
            return Ok(now.0 + 1);
        }
        n = now.0 + 1;
    }
    Err(RemoteError::NoPlant {
        trial,
        peer: peer.to_owned(),
        waited: timeout,
    })
}

/// What happened in one trial across the wire.
#[derive(Debug, Clone, PartialEq)]
pub struct RemoteTrial {
    /// Trial id.
    pub id: u32,
    /// The trip that latched the controller, with its tick, if any.
    pub trip: Option<(u64, String)>,
    /// Round trip at the trial's end, controller ticks (frame read → command applied →
    /// next frame read), if the plant echoed a command.
    pub round_trip_ticks: Option<u64>,
    /// The first tick whose deadline the controller's loop missed (the plant then moved
    /// on under a held command), if any: up to it, the trial ran as in lock step but
    /// for the wire's delay.
    pub first_miss_tick: Option<u64>,
    /// Largest distance between the handle (encoders) and the admittance's reference
    /// over the trial, per axis, m: how well the rig followed the controller.
    pub max_tracking_error_m: [f64; 2],
}

/// The controller's run of a session across the wire.
#[derive(Debug, Clone, PartialEq)]
pub struct RemoteRun {
    /// One entry per trial, in order.
    pub trials: Vec<RemoteTrial>,
    /// The wall clock's timing over the whole session (hellos included).
    pub timing: Timing,
    /// The controller end's link counters.
    pub link: LinkCounters,
}

/// Runs the trials of `session` against the plant behind `rig`, paced by `clock`, and
/// writes each trial to `writer` as it ends. `progress(done, total)` is called after
/// every written trial.
///
/// # Errors
/// [`RemoteError`] if the plant does not answer a trial within `timeout`, the protocol
/// refuses a trial, or the session cannot be written.
#[allow(clippy::too_many_arguments)]
pub fn run<T: Transport>(
    session: &SessionPlan,
    rig: &mut WireRig<SessionTicks<T>>,
    clock: &mut WallClock,
    writer: &mut SessionWriter,
    timeout: Duration,
    peer: &str,
    progress: &dyn Fn(usize, usize),
) -> Result<RemoteRun, RemoteError> {
    let (protocol, subject, plans) = (&session.protocol, &session.subject, &session.plans);
    let session_seed = session.seed;
    let rate = f64::from(protocol.recording.rate_hz);
    let layout = Layout {
        truth: false,
        position_perturbation: protocol.kind != ProtocolKind::ReachPerturb,
    };
    let div = TICK_HZ / u64::from(protocol.recording.rate_hz);
    let n_ticks = trial::trial_ticks(protocol);
    let mut trials = Vec::with_capacity(plans.len());
    let mut session_tick = 0;
    for (k, plan) in plans.iter().enumerate() {
        let id = trial_id(plan.index, plans.len())?;
        // A centre-out reach runs as a reach to its own goal.
        let protocol = &*trial::for_plan(protocol, plan);
        // Built before the hand-over, so that the trial's tick 0 follows the plant's
        // first frame of it by no more than the loop's own latency.
        let parts = trial::controller_parts(protocol, subject, session_seed, plan, true)?;
        rig.transport_mut().set_base(session_tick);
        session_tick += await_plant(rig, id, clock, timeout, peer)?;
        rig.transport_mut().set_base(session_tick);
        session_tick += n_ticks;
        rig.restart_clock();
        clock.restart();
        let mut cosim = CoSim::new(
            parts.controller,
            parts.driver,
            RemotePlant::new(rig),
            parts.recorder,
        );
        cosim::run(&mut cosim, clock, n_ticks)?;
        let sim = cosim.finish();
        let round_trip_ticks = rig.round_trip_ticks();
        let mut err = [0.0_f64; 2];
        for b in &sim.rows {
            for (a, e) in err.iter_mut().enumerate() {
                *e = e.max((b.v[record::ch::X + a] - b.v[record::ch::REF + a]).abs());
            }
        }
        let onset_s = sim.pulse_onset.map(|t| record::tick_time_s(t, div));
        let table = record::to_trial(&sim.rows, rate, layout);
        writer.write_trial(trial_meta(protocol, plan, onset_s), &table)?;
        trials.push(RemoteTrial {
            id: plan.index + 1,
            trip: sim.extremes.trip.clone(),
            round_trip_ticks,
            first_miss_tick: clock.first_miss().map(|t| t.0),
            max_tracking_error_m: err,
        });
        progress(k + 1, plans.len());
    }
    Ok(RemoteRun {
        trials,
        timing: clock.summary(),
        link: rig.counters(),
    })
}
