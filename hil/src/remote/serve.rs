//! The simulated rig and subject as a plant across the wire: `rigtwin plant serve`.
//!
//! The plant is the clock master. Every tick of its own clock it
//! 1. sets up the trial the newest command names, if it is not the one running (the
//!    trial of the protocol's schedule with that id: the rig at its start, the subject
//!    given its task, both seeded as in a rehearsal, the trial clock at 0);
//! 2. samples the sensors of the trial's state and sends the frame;
//! 3. takes every pending command and applies the newest one's force (zero-order hold;
//!    zero when its mode is not `active` or the command watchdog has fired);
//! 4. lets the subject answer and steps physics by one tick, and records the true state.
//!
//! A late wake-up runs every tick that came due, one after the other: physics never
//! skips (the hardware would have moved on), and the controller sees only the newest
//! frame. A trial ends after the protocol's trial length; the handle then stays where
//! it is, frames of that trial keep going out (so the controller's last ticks read
//! them), and the next trial starts when a command names it. The run ends when every
//! trial of the schedule is recorded, or after `idle` without a new command.
//!
//! Recorded per trial (`<out>/session.toml`, `trials/NNNN.csv`): the true handle
//! position and velocity (`x_m`, `vx_m_per_s`, and `true_x_m`), the true force of the
//! hand on the handle (`fx_n`, `hand_fx_n`) and the force the motors applied
//! (`cmd_fx_n`): what the plant is, not what a rig measures.

use std::collections::BTreeSet;
use std::sync::mpsc;

use rigtwin_device::{MotorCommand, RigIo, SensorFrame, Tick, TickReport};
use rigtwin_wire::{LinkCounters, PlantEnd, Transport};

use super::{RemoteError, SessionPlan};
use crate::cosim::record::{Block, Layout, Recorder};
use crate::cosim::{Clock, SimPlant};
use crate::rehearse::record::to_trial;
use crate::rehearse::{TICK_HZ, trial, trial_meta};
use crate::session::{SessionWriter, TrialMeta};

/// How a serve run ends and what it presses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServeOptions {
    /// Plant ticks without a new command after which the server stops (from its start,
    /// before the first command); `None`: never.
    pub idle_ticks: Option<u64>,
    /// Press the simulated e-stop at this trial tick of every trial (to rehearse and
    /// measure the safety chain); `None`: never.
    pub estop_at_tick: Option<u64>,
}

/// Why the server stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServeEnd {
    /// Every trial of the schedule was recorded.
    AllTrials,
    /// No new command came for the idle time.
    Idle,
}

/// What the server did.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeReport {
    /// Why it stopped.
    pub end: ServeEnd,
    /// Ids of the trials recorded, in order.
    pub recorded: Vec<u32>,
    /// Trials the controller left before their end (recorded up to there).
    pub cut_short: Vec<u32>,
    /// Plant ticks run.
    pub ticks: u64,
    /// Plant ticks at which the command watchdog had zeroed the force during a trial.
    pub watchdog_ticks: u64,
    /// Per recorded trial that had one, `(trial id, trial tick)`: the first tick of the
    /// trial's first stall, a run of at least [`STALL_TICKS`] ticks without a fresh
    /// command after the trial's first, under which the plant held the previous one (late
    /// datagrams, or a late wake-up of either end). Single late datagrams on a loaded
    /// machine are common (on loopback, every few tens of milliseconds) and hold a command
    /// for a tick; a stall holds one long enough to move the handle off the lock-step
    /// trial.
    pub first_stall: Vec<(u32, u64)>,
    /// Commands that named a trial the schedule does not have (ignored).
    pub unknown_trial_commands: u64,
    /// Per pressed e-stop: plant ticks from the press to the first tick whose newest
    /// command answers a frame sent at or after the press and comes from a controller
    /// no longer active, so that its force is no longer applied (the safety chain's
    /// latency over the wire: frame out, controller trips, command back).
    pub estop_latency_ticks: Vec<u64>,
    /// The plant end's link counters.
    pub link: LinkCounters,
}

/// Consecutive ticks without a fresh command that make a stall (0.5 ms at 4 kHz). A
/// single late datagram holds a command for one tick, a delay of two ticks instead of
/// the wire's one for that command; two in a row is where, on a loaded machine's
/// loopback, the trial was seen to leave its lock-step twin (0.23 mm with runs of 2–3
/// held ticks, where runs of one stayed within 10 µm).
pub const STALL_TICKS: u64 = 2;

/// Ticks without a command after the last trial at which the server stops (0.1 s at
/// 4 kHz: far more than a round trip, far less than a human notices).
const LINGER_TICKS: u64 = 400;

struct Running {
    plan: usize,
    sim: SimPlant,
    recorder: Recorder,
    tick: u64,
    estop_pressed_at: Option<u64>,
    /// Whether a command has arrived in this trial, the ticks since the last fresh one,
    /// and the first trial tick of the first stall.
    commanded: bool,
    held_run: u64,
    first_stall: Option<u64>,
}

/// Serves the trials of `session` through `end` on `clock`, writing each trial's true
/// plant state to `writer` as it ends. `on_trial(id)` is called when a trial is set up.
/// The session is written on a thread of its own, so that no file is created, written
/// or synced inside the loop.
///
/// # Errors
/// [`RemoteError`] if a trial cannot be built, the plant diverges, the socket fails or
/// the session cannot be written.
pub fn serve<T: Transport, C: Clock>(
    session: &SessionPlan,
    end: &mut PlantEnd<T>,
    clock: &mut C,
    writer: &mut SessionWriter,
    options: ServeOptions,
    on_trial: &mut dyn FnMut(u32),
) -> Result<ServeReport, RemoteError> {
    let rate = f64::from(session.protocol.recording.rate_hz);
    let layout = Layout {
        truth: true,
        position_perturbation: false,
    };
    let (tx, rx) = mpsc::channel::<(TrialMeta, Vec<Block>)>();
    std::thread::scope(|scope| {
        let written = scope.spawn(move || -> Result<(), RemoteError> {
            for (meta, rows) in rx {
                writer.write_trial(meta, &to_trial(&rows, rate, layout))?;
            }
            Ok(())
        });
        let served = serve_loop(session, end, clock, &tx, options, on_trial);
        drop(tx);
        let written = written.join().unwrap_or(Err(RemoteError::WriterPanicked));
        // A writer error is the cause of anything the loop saw after it.
        written?;
        served
    })
}

fn serve_loop<T: Transport, C: Clock>(
    session: &SessionPlan,
    end: &mut PlantEnd<T>,
    clock: &mut C,
    tx: &mpsc::Sender<(TrialMeta, Vec<Block>)>,
    options: ServeOptions,
    on_trial: &mut dyn FnMut(u32),
) -> Result<ServeReport, RemoteError> {
    let (protocol, subject, plans) = (&session.protocol, &session.subject, &session.plans);
    let session_seed = session.seed;
    let div = TICK_HZ / u64::from(protocol.recording.rate_hz);
    let n_ticks = trial::trial_ticks(protocol);
    let mut report = ServeReport {
        end: ServeEnd::Idle,
        recorded: Vec::with_capacity(plans.len()),
        cut_short: Vec::new(),
        ticks: 0,
        watchdog_ticks: 0,
        first_stall: Vec::with_capacity(plans.len()),
        unknown_trial_commands: 0,
        estop_latency_ticks: Vec::new(),
        link: end.counters(),
    };
    let mut done = BTreeSet::new();
    let mut running: Option<Running> = None;
    let mut held_frame: Option<SensorFrame> = None;
    let mut last_command_at = 0_u64;
    let mut s = 0_u64;
    // Hands a trial to the writer thread; if that thread has stopped, its error is
    // what `serve` returns.
    let finish = |r: Running, report: &mut ServeReport| {
        let plan = &plans[r.plan];
        let rows = r.recorder.finish();
        if rows.is_empty() {
            return;
        }
        let _ = tx.send((
            trial_meta(&trial::for_plan(protocol, plan), plan, None),
            rows,
        ));
        report.recorded.push(plan.index + 1);
        if let Some(t) = r.first_stall {
            report.first_stall.push((plan.index + 1, t));
        }
        if r.tick < n_ticks {
            report.cut_short.push(plan.index + 1);
        }
    };
    loop {
        let due = clock.wait(Tick(s), Tick(u64::MAX - 1)).0.max(s);
        let mut ran = 0;
        for k in s..=due {
            let now = Tick(k);
            ran += 1;
            // 1. The trial the controller names, read from each fresh command (the held
            // one asks nothing new).
            let (asked, fresh) = match end.poll_command(now)? {
                Some(c) => {
                    last_command_at = k;
                    (c.trial, true)
                }
                None => (0, false),
            };
            if asked != 0 && asked != end.trial() {
                match plans.iter().position(|p| p.index + 1 == u32::from(asked)) {
                    Some(i) => {
                        if let Some(r) = running.take() {
                            finish(r, &mut report);
                        }
                        let plan = &plans[i];
                        running = Some(Running {
                            plan: i,
                            sim: trial::plant(
                                &trial::for_plan(protocol, plan),
                                subject,
                                session_seed,
                                plan,
                            )?,
                            recorder: Recorder::new(div, n_ticks),
                            tick: 0,
                            estop_pressed_at: None,
                            commanded: false,
                            held_run: 0,
                            first_stall: None,
                        });
                        done.remove(&plan.index);
                        end.set_trial(asked);
                        on_trial(plan.index + 1);
                        // Building the trial took wall time that belongs to no trial:
                        // the trial starts now, on deadlines counted from here, instead
                        // of catching up on ticks that would run before the controller
                        // has seen a frame.
                        clock.resync();
                        break;
                    }
                    None => report.unknown_trial_commands += 1,
                }
            }
            let Some(r) = running.as_mut() else {
                // Between trials: the last frame again, so the controller's last ticks
                // read the handle where it stopped.
                if let Some(f) = held_frame {
                    end.send_frame(now, f)?;
                }
                continue;
            };
            let t = Tick(r.tick);
            if fresh {
                r.commanded = true;
                r.held_run = 0;
            } else if r.commanded {
                r.held_run += 1;
                if r.held_run == STALL_TICKS && r.first_stall.is_none() {
                    r.first_stall = Some(r.tick + 1 - STALL_TICKS);
                }
            }
            if options.estop_at_tick == Some(r.tick) {
                r.sim.rig_mut().set_estop(true);
                r.estop_pressed_at = Some(k);
            }
            // 2. Sensors of the state at t.
            let frame = r.sim.read(t)?;
            end.send_frame(now, frame)?;
            // 3. The newest command, held.
            let force_n = end.applied_force(now);
            if end.watchdog_zeroed(now) {
                report.watchdog_ticks += 1;
            }
            if let (Some(p), Some(c)) = (r.estop_pressed_at, end.latest_command())
                && c.mode != rigtwin_device::Mode::Active
                && c.answers_tick.is_some_and(|a| a.0 >= p)
            {
                report.estop_latency_ticks.push(k - p);
                r.estop_pressed_at = None;
            }
            r.sim.write(t, MotorCommand { force_n })?;
            // 4. Subject and physics, t → t + 1.
            let sample = r.sim.advance_with(t, false)?;
            let tick_report = TickReport {
                tick: t,
                position_m: sample.position_m,
                velocity_m_per_s: sample.velocity_m_per_s,
                force_n: sample.hand_n,
                command_n: force_n,
                ..TickReport::default()
            };
            r.recorder.push(&tick_report, &sample);
            r.tick += 1;
            if r.tick >= n_ticks
                && let Some(r) = running.take()
            {
                done.insert(plans[r.plan].index);
                held_frame = Some(frame);
                finish(r, &mut report);
            }
        }
        report.ticks += ran;
        s += ran;
        // Every trial is recorded: linger while the controller still sends (its trial
        // started a round trip after the plant's, so its last ticks read the held frame),
        // and stop once it has been quiet for `LINGER_TICKS`.
        if running.is_none()
            && done.len() == plans.len()
            && s.saturating_sub(last_command_at) > LINGER_TICKS
        {
            report.end = ServeEnd::AllTrials;
            break;
        }
        if options
            .idle_ticks
            .is_some_and(|idle| s.saturating_sub(last_command_at) > idle)
        {
            report.end = ServeEnd::Idle;
            if let Some(r) = running.take() {
                finish(r, &mut report);
            }
            break;
        }
    }
    report.link = end.counters();
    Ok(report)
}
