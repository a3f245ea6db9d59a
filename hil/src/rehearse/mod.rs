//! Protocol rehearsal: run a protocol against virtual subjects in lock step, faster
//! than real time, and record one session per subject.
//!
//! Determinism: every trial is simulated independently from seeds derived from
//! (session seed, subject, trial) ([`seed`]); worker threads pick trials up in any
//! order, and the main thread writes them in trial order through the crash-safe
//! [`SessionWriter`] as soon as each next one is ready. The same protocol and seed
//! therefore give byte-identical sessions whatever `--jobs` is. The manifest's
//! `created` is fixed ([`CREATED`]) for the same reason; wall-clock times go to the
//! report only.
//!
//! A [`RehearsalObserver`] passed to [`rehearse_observed`] sees each session start, each
//! trial as soon as it is written (in trial order, with the table in memory and the
//! simulated arm's muscle activations, which the session files do not hold) and each
//! session end, on the writing thread while the workers simulate the next trials: the
//! viewer logs the rehearsal that way, overlapped with the simulation.
//!
//! Layout of a rehearsal folder:
//!
//! ```text
//! <out>/report.md, report.json      the rehearsal report (all subjects)
//! <out>/S01/session.toml, trials/   subject 1's session (recording format v1)
//! <out>/S02/...
//! ```

pub use crate::cosim::record;
/// Seed derivation lives with the protocol, which draws its subjects from it.
pub use crate::protocol::seed;
pub mod cost;
pub mod trial;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rigtwin_arm::muscles::MUSCLES;
use rigtwin_device::config::LawKind;

use crate::cosim::WallClock;
use crate::protocol::{Protocol, ProtocolKind, VirtualSubject};
use crate::session::{
    Amplitude, Axes, Device, FORMAT_VERSION, Manifest, Perturbation, PerturbationKind,
    SessionError, SessionWriter, SimInfo, Source, Subject, Timing, Trial, TrialEntry, TrialKind,
    TrialMeta,
};
use record::{Block, Layout, ch};
pub use trial::{Extremes, OnsetTruth, TrialPlan, TrialTask};

/// The control clock of the simulator, Hz: [`rigtwin_device::Rate::CONTROL`] (000_*
/// section 5.1), as the integer the rehearsal's tick arithmetic uses.
pub const TICK_HZ: u64 = rigtwin_device::Rate::CONTROL.hz() as u64;

/// The `created` stamp of simulated sessions: fixed, so that a session's bytes depend on
/// the protocol and the seed only.
pub const CREATED: &str = "1970-01-01T00:00:00Z";

/// Why a rehearsal failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RehearseError {
    /// The controller refused its configuration.
    #[error("controller: {0}")]
    Controller(#[from] rigtwin_device::ConfigError),
    /// Writing the session failed.
    #[error("session: {0}")]
    Session(#[from] SessionError),
    /// The output folder exists and is not empty.
    #[error("output folder {0} already exists and is not empty; choose another --out")]
    OutputExists(PathBuf),
    /// An I/O error outside the session writer.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The run was cancelled.
    #[error("cancelled")]
    Cancelled,
    /// More subjects than a rehearsal may draw.
    #[error("{0} subjects is more than the {max} a rehearsal may draw", max = crate::protocol::MAX_SUBJECTS)]
    TooManySubjects(u32),
    /// A co-simulation could not be built or a step failed: a lifecycle transition or a
    /// perturbation refused, the arm or the plant refusing its configuration, or the
    /// plant diverging.
    #[error(transparent)]
    CoSim(#[from] crate::cosim::CoSimError),
    /// The real-time clock could not be used.
    #[error("real-time clock: {0}")]
    Clock(String),
}

/// How to run a rehearsal.
#[derive(Debug, Clone)]
pub struct Options {
    /// Number of virtual subjects.
    pub subjects: u32,
    /// Session seed.
    pub seed: u64,
    /// Output folder (must not exist or be empty).
    pub out_dir: PathBuf,
    /// Worker threads.
    pub jobs: usize,
    /// Run at most this many trials per subject (the first ones of the schedule), for
    /// quick checks; `None` runs the protocol as written.
    pub max_trials: Option<usize>,
}

/// How a rehearsal's trials are paced.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Pacing {
    /// As fast as the machine goes, trials in parallel: byte-identical sessions.
    #[default]
    LockStep,
    /// At the control rate on the wall clock, one trial after the other on one thread
    /// ([`crate::cosim::WallClock`]); each session records its timing.
    RealTime(RealTime),
}

/// The real-time settings of a paced rehearsal.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RealTime {
    /// Spin on the clock for this long before each deadline instead of sleeping.
    pub spin: std::time::Duration,
    /// Run the loop's thread under SCHED_FIFO at this priority (1–99).
    pub fifo_priority: Option<u8>,
}

/// Progress, reported after every written trial.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Trials written so far (all subjects).
    pub done: usize,
    /// Trials in the rehearsal.
    pub total: usize,
    /// Simulated time so far, s.
    pub simulated_s: f64,
}

/// Variational truth of one perturbed reach, from its unperturbed twin, per row from
/// the onset row over the estimation window.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TwinTruth {
    /// Row of the onset in the table.
    pub onset_index: usize,
    /// `Δx`, m.
    pub dx_m: Vec<[f64; 2]>,
    /// `Δẋ`, m/s.
    pub dv_m_per_s: Vec<[f64; 2]>,
    /// `Δẍ`, m/s².
    pub da_m_per_s2: Vec<[f64; 2]>,
    /// `Δu_ext`: the change of the force on the arm from the handle, N.
    pub du_ext_n: Vec<[f64; 2]>,
}

/// One position perturbation of a hold trial.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Push {
    /// Onset on the table clock, s.
    pub onset_s: f64,
    /// Direction, degrees.
    pub angle_deg: f64,
    /// Largest |x − anchor| within the estimation window per axis, m.
    pub deviation_m: [f64; 2],
}

/// The outcome of one trial.
#[derive(Debug, Clone)]
pub struct TrialResult {
    /// Trial id (1-based).
    pub id: u32,
    /// What was done.
    pub task: TrialTask,
    /// Trial length, s.
    pub duration_s: f64,
    /// SHA-256 of the written table.
    pub sha256: String,
    /// Extremes over all ticks.
    pub extremes: Extremes,
    /// Force-pulse onset on the table clock, s, as the rig logs it (with a realistic
    /// rig's trigger lag, up to `nuisance.trigger_jitter_ticks` before the pulse).
    pub onset_s: Option<f64>,
    /// Ground truth at the onset.
    pub onset_truth: Option<OnsetTruth>,
    /// Largest |Δx| per axis within the estimation window, from the twin, m.
    pub deviation_m: Option<[f64; 2]>,
    /// Variational truth from the twin.
    pub twin: Option<TwinTruth>,
    /// Position perturbations (hold kinds).
    pub pushes: Vec<Push>,
    /// The table as written, kept for perturbed trials (the estimators read it).
    pub table: Option<Trial>,
}

/// One subject's session.
#[derive(Debug, Clone)]
pub struct SubjectResult {
    /// The subject.
    pub subject: VirtualSubject,
    /// Its session folder.
    pub dir: PathBuf,
    /// Its trials in order.
    pub trials: Vec<TrialResult>,
    /// How the real-time loop kept its clock over the session (real-time pacing only).
    pub timing: Option<Timing>,
}

/// A finished rehearsal.
#[derive(Debug, Clone)]
pub struct Rehearsal {
    /// The protocol run.
    pub protocol: Protocol,
    /// The session seed.
    pub seed: u64,
    /// The rehearsal folder.
    pub out_dir: PathBuf,
    /// Per subject.
    pub subjects: Vec<SubjectResult>,
    /// Simulated time, s (twins included).
    pub simulated_s: f64,
    /// Wall-clock time, s.
    pub wall_s: f64,
    /// Worker threads used.
    pub jobs: usize,
    /// What the real-time set-up could not do (e.g. SCHED_FIFO refused), one line each.
    pub realtime_notes: Vec<String>,
}

/// A trial just written, as a [`RehearsalObserver`] sees it: everything in memory.
#[derive(Debug, Clone, Copy)]
pub struct WrittenTrial<'a> {
    /// The subject.
    pub subject: &'a VirtualSubject,
    /// 0-based position of the trial in its session.
    pub index: usize,
    /// Its entry in the manifest, as written (id, kind, targets, perturbation, digest).
    pub entry: &'a TrialEntry,
    /// The table, exactly as written to the trial file (every value is the double its text
    /// parses to, so a reader of the file gets the same numbers).
    pub table: &'a Trial,
    /// The outcome (extremes, safety trip, ground truth at the onset).
    pub result: &'a TrialResult,
    /// The arm's six muscle activations per table row (N, in the order of
    /// `rigtwin_arm::muscles::MUSCLE_NAMES`; block means like the table's rows), `None`
    /// without an arm (the spring-mass rig). Not part of the session files.
    pub activations_n: Option<&'a [[f64; MUSCLES]]>,
    /// In a real-time rehearsal, the loop's timing per table row: the mean wake-up
    /// latency of the ticks run, µs, and the share of ticks held (missed deadlines);
    /// `None` in lock step. Not part of the session files.
    pub timing: Option<&'a [[f64; 2]]>,
}

/// Sees a rehearsal as it is written, on the writing thread, in order: for each subject
/// [`Self::session_started`], then [`Self::trial_written`] per trial in trial order, then
/// [`Self::session_finished`]. The workers keep simulating meanwhile, so an observer that
/// takes a while delays only the writing, not the simulation. Every method does nothing
/// by default; `()` observes nothing.
pub trait RehearsalObserver {
    /// A subject's session is about to be written: its manifest (no trials yet).
    fn session_started(&mut self, subject: &VirtualSubject, manifest: &Manifest) {
        let _ = (subject, manifest);
    }

    /// A trial has been written.
    fn trial_written(&mut self, trial: &WrittenTrial<'_>) {
        let _ = trial;
    }

    /// The session is complete: `manifest` is the one written to `dir`, with every trial.
    fn session_finished(&mut self, subject: &VirtualSubject, dir: &Path, manifest: &Manifest) {
        let _ = (subject, dir, manifest);
    }
}

impl RehearsalObserver for () {}

/// The trials of one subject, in session order. Reach: `angles × repetitions`
/// perturbed trials at random places among `trials`, angles in random order (000_*
/// section 5.2), from the subject's schedule stream.
#[must_use]
pub fn schedule(protocol: &Protocol, session_seed: u64, subject: u32) -> Vec<TrialPlan> {
    let plans: Vec<TrialTask> = match protocol.kind {
        ProtocolKind::ReachPerturb => {
            let r = protocol.reach();
            let mut rng = ChaCha8Rng::seed_from_u64(seed::schedule_seed(session_seed, subject));
            // Centre-out: the r-th repetition of a direction on the p-th pulse axis to
            // goal (r + p) mod n, the unperturbed reaches to the goals in turn.
            let goals = r.targets_m.len();
            let target = |i: usize| (goals > 0).then(|| i % goals);
            let axes = pulse_axes(&r.angles_deg);
            let mut slots: Vec<(Option<f64>, Option<usize>)> =
                vec![(None, None); r.trials as usize];
            let mut k = 0;
            for rep in 0..r.repetitions as usize {
                for (a, axis) in r.angles_deg.iter().zip(&axes) {
                    if let Some(slot) = slots.get_mut(k) {
                        *slot = (Some(*a), target(rep + axis));
                    }
                    k += 1;
                }
            }
            for (j, slot) in slots.iter_mut().skip(k).enumerate() {
                slot.1 = target(j);
            }
            slots.shuffle(&mut rng);
            slots
                .into_iter()
                .map(|(angle_deg, target)| TrialTask::Reach { angle_deg, target })
                .collect()
        }
        ProtocolKind::HoldSinusoid => protocol
            .hold()
            .conditions
            .iter()
            .map(|c| TrialTask::Hold { condition: *c })
            .collect(),
        ProtocolKind::CalibrationRig => (0..protocol.calibration().repetitions)
            .map(|_| TrialTask::Calibration)
            .collect(),
    };
    plans
        .into_iter()
        .enumerate()
        .map(|(i, task)| TrialPlan {
            index: u32::try_from(i).unwrap_or(u32::MAX),
            task,
        })
        .collect()
}

/// The pulse axis of each direction: the index, in order of first appearance, of the
/// line it lies on (`θ` and `θ + 180°`, in whole degrees, share one). A centre-out
/// schedule sends the `r`-th repetitions of opposite directions to one goal, so that
/// their responses, which the hand balance pairs, are taken in one posture.
fn pulse_axes(angles_deg: &[f64]) -> Vec<usize> {
    let mut lines: Vec<i64> = Vec::new();
    angles_deg
        .iter()
        .map(|a| {
            let line = (a.round() as i64).rem_euclid(180);
            lines.iter().position(|l| *l == line).unwrap_or_else(|| {
                lines.push(line);
                lines.len() - 1
            })
        })
        .collect()
}

/// A fresh folder `base/<name>-<seed>`, or `...-2`, `...-3` if taken.
#[must_use]
pub fn fresh_dir(base: &Path, name: &str, seed: u64) -> PathBuf {
    let first = base.join(format!("{name}-{seed}"));
    if !first.exists() {
        return first;
    }
    (2..)
        .map(|k| base.join(format!("{name}-{seed}-{k}")))
        .find(|p| !p.exists())
        .unwrap_or(first)
}

/// The manifest of `subject`'s session of `protocol` with `session_seed`, before any
/// trial: the device, the subject's geometry and factors, the seed and the model.
#[must_use]
pub fn manifest(protocol: &Protocol, subject: &VirtualSubject, session_seed: u64) -> Manifest {
    let c = &protocol.controller;
    let (kind, mass, damping) = match c.law {
        LawKind::Admittance => (
            "admittance",
            c.admittance.mass_kg,
            c.admittance.damping_n_s_per_m,
        ),
        LawKind::VirtualSpring => (
            "virtual-spring",
            c.virtual_spring.mass_kg,
            c.virtual_spring.damping_n_s_per_m,
        ),
    };
    let mut extra = BTreeMap::new();
    let f = subject.factors;
    for (name, v) in [
        ("factor_muscle_stiffness", f[0]),
        ("factor_co_contraction", f[1]),
        ("factor_upper_arm", f[2]),
        ("factor_forearm", f[3]),
        ("factor_feedback_gain", f[4]),
    ] {
        extra.insert(name.to_owned(), toml::Value::Float(v));
    }
    let calibration = protocol.kind == ProtocolKind::CalibrationRig;
    Manifest {
        source: Source::Sim,
        rate_hz: f64::from(protocol.recording.rate_hz),
        axes: Axes::Both,
        created: CREATED.to_owned(),
        device: Device {
            kind: kind.to_owned(),
            mass_kg: mass,
            damping_n_s_per_m: damping,
            handle_mass_kg: Some(protocol.plant.handle_mass_kg),
            workspace_half_width_m: Some(c.safety.wall_m),
        },
        subject: Subject {
            id: if calibration {
                "spring-mass".to_owned()
            } else {
                subject.id.clone()
            },
            shoulder_m: subject.shoulder_m,
            upper_arm_m: (!calibration).then_some(subject.arm.upper.length_m),
            forearm_m: (!calibration).then_some(subject.arm.fore.length_m),
            body_mass_kg: None,
            extra: if calibration { BTreeMap::new() } else { extra },
        },
        sim: Some(SimInfo {
            seed: Some(session_seed),
            protocol: Some(protocol.name.clone()),
            model: Some(if calibration {
                "spring-mass rig (001_* Appendix B)".to_owned()
            } else {
                "rigtwin_arm six-muscle arm".to_owned()
            }),
            extra: BTreeMap::new(),
        }),
        timing: None,
        trials: Vec::new(),
    }
}

/// What a worker hands back: the table to write plus the result.
struct Done {
    meta: TrialMeta,
    table: Trial,
    result: TrialResult,
    activations_n: Option<Vec<[f64; MUSCLES]>>,
    /// The loop's timing per row (real-time pacing only).
    timing_rows: Option<Vec<[f64; 2]>>,
    simulated_s: f64,
    /// The real-time clock's timing of the session so far (real-time pacing only).
    timing: Option<Timing>,
}

fn run_trial(
    recorded: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    plan: &TrialPlan,
    clock: Option<&mut WallClock>,
) -> Result<Done, RehearseError> {
    // A centre-out reach runs as a reach to its own goal.
    let recorded = &*trial::for_plan(recorded, plan);
    // The trial runs with its nuisances (if the protocol has any); its manifest entry
    // keeps the protocol's task, as a lab's rig logs its targets.
    let (protocol, subject, trigger_lag) =
        crate::protocol::nuisance::realise(recorded, subject, session_seed, plan.index);
    let (protocol, subject) = (&protocol, &subject);
    let rate = f64::from(protocol.recording.rate_hz);
    let div = TICK_HZ / u64::from(protocol.recording.rate_hz);
    let (sim, timing) = match clock {
        Some(clock) => {
            clock.restart();
            let sim = trial::simulate_on(protocol, subject, session_seed, plan, true, clock)?;
            (sim, Some(clock.summary()))
        }
        None => (
            trial::simulate(protocol, subject, session_seed, plan, true)?,
            None,
        ),
    };
    let n_ticks = trial::trial_ticks(protocol);
    let mut simulated_s = n_ticks as f64 / TICK_HZ as f64;
    let layout = Layout {
        truth: protocol.recording.truth_columns,
        position_perturbation: protocol.kind != ProtocolKind::ReachPerturb,
    };
    let table = record::to_trial(&sim.rows, rate, layout);
    let activations_n = sim
        .muscles
        .then(|| sim.rows.iter().map(Block::activations_n).collect());
    let timing_rows = timing.map(|_| sim.rows.iter().map(Block::timing).collect());
    let t_est = protocol.estimate.t_est_s;
    let n_est = (t_est * rate).round() as usize + 1;
    // The pulse's own onset (the simulated truth's reference) and the one the rig logs,
    // `trigger_lag` ticks before it.
    let pulse_onset_s = sim.pulse_onset.map(|k| record::tick_time_s(k, div));
    let onset_s = sim
        .pulse_onset
        .map(|k| record::tick_time_s(k.saturating_sub(trigger_lag), div));
    let mut twin = None;
    let mut deviation = None;
    if let (
        Some(t0),
        TrialTask::Reach {
            angle_deg: Some(_), ..
        },
    ) = (pulse_onset_s, &plan.task)
    {
        let base = trial::simulate(protocol, subject, session_seed, plan, false)?;
        simulated_s += n_ticks as f64 / TICK_HZ as f64;
        let i0 = (t0 * rate).round().max(0.0) as usize;
        let tw = twin_truth(&sim.rows, &base.rows, i0, n_est, rate, &protocol.estimate);
        let mut dev = [0.0_f64; 2];
        for d in &tw.dx_m {
            dev[0] = dev[0].max(d[0].abs());
            dev[1] = dev[1].max(d[1].abs());
        }
        deviation = Some(dev);
        twin = Some(tw);
    }
    let pushes = sim
        .push_onsets
        .iter()
        .map(|&(k, angle_deg)| {
            let t = record::tick_time_s(k, div);
            let i0 = (t * rate).round().max(0.0) as usize;
            let mut dev = [0.0_f64; 2];
            for b in sim.rows.iter().skip(i0).take(n_est) {
                for (a, d) in dev.iter_mut().enumerate() {
                    *d = d.max((b.v[ch::X + a] - b.v[ch::ANCHOR + a]).abs());
                }
            }
            Push {
                onset_s: t,
                angle_deg,
                deviation_m: dev,
            }
        })
        .collect();
    let meta = trial_meta(recorded, plan, onset_s);
    let keep = onset_s.is_some() || !sim.push_onsets.is_empty();
    let result = TrialResult {
        id: plan.index + 1,
        task: plan.task.clone(),
        duration_s: n_ticks as f64 / TICK_HZ as f64,
        sha256: String::new(),
        extremes: sim.extremes,
        onset_s,
        onset_truth: sim.onset_truth,
        deviation_m: deviation,
        twin,
        pushes,
        table: keep.then(|| table.clone()),
    };
    Ok(Done {
        meta,
        table,
        result,
        activations_n,
        timing_rows,
        simulated_s,
        timing,
    })
}

/// The manifest entry of `plan`'s trial: its id, kind, start and goal, and its force
/// pulse where one started (`onset_s` on the table clock).
pub(crate) fn trial_meta(protocol: &Protocol, plan: &TrialPlan, onset_s: Option<f64>) -> TrialMeta {
    let (kind, start_m, goal_m) = match &plan.task {
        TrialTask::Reach { .. } => {
            let r = protocol.reach();
            (TrialKind::Reach, Some(r.start_m), Some(r.goal_m))
        }
        TrialTask::Hold { .. } => (TrialKind::Hold, Some(protocol.hold().hand_m), None),
        TrialTask::Calibration => (
            TrialKind::Other("calibration".to_owned()),
            Some(protocol.hold().hand_m),
            None,
        ),
    };
    let perturbation = match (&plan.task, onset_s) {
        (
            TrialTask::Reach {
                angle_deg: Some(a), ..
            },
            Some(t),
        ) => Some(Perturbation {
            kind: PerturbationKind::ForcePulse,
            onset_s: t,
            duration_s: protocol.controller.force_pulse.duration_s,
            amplitude: Amplitude::ForceN(protocol.controller.force_pulse.amplitude_n),
            angle_deg: *a,
        }),
        _ => None,
    };
    TrialMeta {
        id: plan.index + 1,
        kind,
        start_m,
        goal_m,
        perturbation,
    }
}

/// The variational truth `perturbed − twin`, filtered as 000_* filters its simulated
/// signals before comparing (section 4.2: "the simulated signals are filtered using a
/// fifth order Savitzky-Golay filter with a cut-off frequency of 30 Hz"): `Δx`, `Δẋ`,
/// `Δẍ` are the SG fit of the true handle position difference and its derivatives,
/// `Δu_ext` the SG fit of minus the difference of the true hand force on the handle.
/// Without an SG window for the rate, the raw block means are used.
fn twin_truth(
    pert: &[Block],
    base: &[Block],
    i0: usize,
    n: usize,
    rate_hz: f64,
    est: &crate::protocol::EstimateConfig,
) -> TwinTruth {
    use rigtwin_device::signal::{EdgeMode, savgol_filter, savgol_window_for_cutoff};
    let len = pert.len().min(base.len());
    let diff = |c: usize| -> Vec<f64> { (0..len).map(|i| pert[i].v[c] - base[i].v[c]).collect() };
    let window = savgol_window_for_cutoff(est.savgol_polyorder, est.savgol_cutoff_hz, rate_hz).ok();
    let sg = |y: &[f64], deriv: usize| -> Option<Vec<f64>> {
        let w = window?;
        savgol_filter(
            y,
            w,
            est.savgol_polyorder,
            deriv,
            1.0 / rate_hz,
            EdgeMode::Interp,
        )
        .ok()
    };
    let mut axes: [[Vec<f64>; 4]; 2] = Default::default();
    for (a, out) in axes.iter_mut().enumerate() {
        let x = diff(ch::TRUE_X + a);
        let h: Vec<f64> = diff(ch::HAND + a).iter().map(|v| -v).collect();
        *out = match (sg(&x, 0), sg(&x, 1), sg(&x, 2), sg(&h, 0)) {
            (Some(p), Some(v), Some(acc), Some(f)) => [p, v, acc, f],
            _ => [x, diff(ch::TRUE_V + a), diff(ch::ACC + a), h],
        };
    }
    let pick = |k: usize| -> Vec<[f64; 2]> {
        (i0..(i0 + n).min(len))
            .map(|i| [axes[0][k][i], axes[1][k][i]])
            .collect()
    };
    TwinTruth {
        onset_index: i0,
        dx_m: pick(0),
        dv_m_per_s: pick(1),
        da_m_per_s2: pick(2),
        du_ext_n: pick(3),
    }
}

/// Creates the output folder `dir`, refusing one that exists and is not empty.
///
/// # Errors
/// [`RehearseError::OutputExists`], or the I/O error.
pub fn prepare_out(dir: &Path) -> Result<(), RehearseError> {
    let io = |source| RehearseError::Io {
        path: dir.to_path_buf(),
        source,
    };
    if dir.exists() {
        let mut entries = std::fs::read_dir(dir).map_err(io)?;
        if entries.next().is_some() {
            return Err(RehearseError::OutputExists(dir.to_path_buf()));
        }
    }
    std::fs::create_dir_all(dir).map_err(io)
}

/// Runs the rehearsal and writes its sessions (not the report: see
/// [`crate::report`]). `progress` is called after every written trial; `cancel` stops
/// the run between trials when set.
///
/// # Errors
/// [`RehearseError`] from the output folder, the models or the writer.
pub fn rehearse(
    protocol: &Protocol,
    options: &Options,
    progress: &(dyn Fn(Progress) + Sync),
    cancel: &AtomicBool,
) -> Result<Rehearsal, RehearseError> {
    rehearse_observed(protocol, options, progress, cancel, &mut ())
}

/// [`rehearse`], with `observer` shown each session and each trial as it is written
/// (see [`RehearsalObserver`]).
///
/// # Errors
/// [`RehearseError`] from the output folder, the models or the writer.
pub fn rehearse_observed(
    protocol: &Protocol,
    options: &Options,
    progress: &(dyn Fn(Progress) + Sync),
    cancel: &AtomicBool,
    observer: &mut dyn RehearsalObserver,
) -> Result<Rehearsal, RehearseError> {
    rehearse_paced(
        protocol,
        options,
        Pacing::LockStep,
        progress,
        cancel,
        observer,
    )
}

/// [`rehearse_observed`] with the trials paced by `pacing`. Real time runs one worker
/// (the loop's thread, under SCHED_FIFO if asked) whatever `options.jobs` says; the
/// unperturbed twins that give the report its ground truth run in lock step between
/// trials.
///
/// # Errors
/// [`RehearseError`] from the output folder, the clock, the models or the writer.
pub fn rehearse_paced(
    protocol: &Protocol,
    options: &Options,
    pacing: Pacing,
    progress: &(dyn Fn(Progress) + Sync),
    cancel: &AtomicBool,
    observer: &mut dyn RehearsalObserver,
) -> Result<Rehearsal, RehearseError> {
    let started = Instant::now();
    if options.subjects > crate::protocol::MAX_SUBJECTS {
        return Err(RehearseError::TooManySubjects(options.subjects));
    }
    prepare_out(&options.out_dir)?;
    let realtime = match pacing {
        Pacing::LockStep => None,
        Pacing::RealTime(rt) => Some(rt),
    };
    let jobs = if realtime.is_some() {
        1
    } else {
        options.jobs.max(1)
    };
    let notes = std::sync::Mutex::new(Vec::<String>::new());
    let subjects: Vec<VirtualSubject> = (1..=options.subjects.max(1))
        .map(|i| protocol.subjects.draw(options.seed, i))
        .collect();
    let plans: Vec<Vec<TrialPlan>> = subjects
        .iter()
        .map(|s| {
            let mut p = schedule(protocol, options.seed, s.index);
            if let Some(m) = options.max_trials {
                p.truncate(m);
            }
            p
        })
        .collect();
    let total: usize = plans.iter().map(Vec::len).sum();
    let mut done = 0;
    let mut simulated_s = 0.0;
    let mut out = Vec::with_capacity(subjects.len());
    for (subject, plans) in subjects.iter().zip(&plans) {
        let dir = options.out_dir.join(&subject.id);
        let manifest = manifest(protocol, subject, options.seed);
        observer.session_started(subject, &manifest);
        let mut writer = SessionWriter::create(&dir, manifest)?;
        let mut results = Vec::with_capacity(plans.len());
        let next = AtomicUsize::new(0);
        let mut timing = None;
        let (tx, rx) = mpsc::channel::<(usize, Result<Done, RehearseError>)>();
        let outcome: Result<(), RehearseError> = std::thread::scope(|scope| {
            for _ in 0..jobs.min(plans.len()).max(1) {
                let tx = tx.clone();
                let next = &next;
                let notes = &notes;
                scope.spawn(move || {
                    let mut clock = match realtime.map(|rt| realtime_clock(protocol, rt)) {
                        None => None,
                        Some(Ok((clock, note))) => {
                            if let (Some(n), Ok(mut all)) = (note, notes.lock())
                                && !all.contains(&n)
                            {
                                all.push(n);
                            }
                            Some(clock)
                        }
                        Some(Err(e)) => {
                            let _ = tx.send((0, Err(e)));
                            return;
                        }
                    };
                    loop {
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        if i >= plans.len() || cancel.load(Ordering::SeqCst) {
                            break;
                        }
                        let r =
                            run_trial(protocol, subject, options.seed, &plans[i], clock.as_mut());
                        if tx.send((i, r)).is_err() {
                            break;
                        }
                    }
                });
            }
            drop(tx);
            let mut pending: BTreeMap<usize, Done> = BTreeMap::new();
            let mut want = 0;
            for (i, r) in rx.iter() {
                match r {
                    Ok(d) => {
                        pending.insert(i, d);
                    }
                    Err(e) => {
                        cancel.store(true, Ordering::SeqCst);
                        return Err(e);
                    }
                }
                while let Some(d) = pending.remove(&want) {
                    let Done {
                        meta,
                        table,
                        mut result,
                        activations_n,
                        timing_rows,
                        simulated_s: s,
                        timing: t,
                    } = d;
                    if t.is_some() {
                        timing = t;
                    }
                    let entry = writer.write_trial(meta, &table)?;
                    result.sha256 = entry.sha256.map(|h| h.to_string()).unwrap_or_default();
                    observer.trial_written(&WrittenTrial {
                        subject,
                        index: want,
                        entry,
                        table: &table,
                        result: &result,
                        activations_n: activations_n.as_deref(),
                        timing: timing_rows.as_deref(),
                    });
                    results.push(result);
                    want += 1;
                    done += 1;
                    simulated_s += s;
                    progress(Progress {
                        done,
                        total,
                        simulated_s,
                    });
                }
            }
            if want < plans.len() {
                return Err(RehearseError::Cancelled);
            }
            Ok(())
        });
        outcome?;
        if let Some(t) = timing {
            writer.set_timing(t)?;
        }
        let written = writer.finish()?;
        observer.session_finished(subject, &dir, &written);
        out.push(SubjectResult {
            subject: subject.clone(),
            dir,
            trials: results,
            timing,
        });
    }
    Ok(Rehearsal {
        protocol: protocol.clone(),
        seed: options.seed,
        out_dir: options.out_dir.clone(),
        subjects: out,
        simulated_s,
        wall_s: started.elapsed().as_secs_f64(),
        jobs,
        realtime_notes: notes.into_inner().unwrap_or_default(),
    })
}

/// The wall clock of a real-time worker, on a thread under SCHED_FIFO if asked; the
/// note says what the OS refused (the run goes on without it).
fn realtime_clock(
    protocol: &Protocol,
    rt: RealTime,
) -> Result<(WallClock, Option<String>), RehearseError> {
    let clock = WallClock::new(protocol.control_rate(), rt.spin)
        .map_err(|e| RehearseError::Clock(e.to_string()))?;
    let note = rt
        .fifo_priority
        .and_then(|p| crate::cosim::rt::set_fifo_priority(p).err());
    Ok((clock, note))
}

/// Format version written (for the report).
pub const SESSION_FORMAT_VERSION: i64 = FORMAT_VERSION;

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use rigtwin_device::config::Axis;

    /// A centre-out schedule gives every goal each pulse direction once per `n`
    /// repetitions and the unperturbed reaches in turn, opposite directions to one
    /// goal, and with fewer repetitions than goals pulses to every goal; each goal's
    /// reach fires its pulse at the protocol's fraction of the way (0.4) on the axis it
    /// travels along more; without goals the schedule is the one-goal protocol's, slot
    /// for slot.
    #[test]
    fn centre_out_goals_share_the_pulses_and_the_trigger_fraction() {
        let mut p = Protocol::builtin("reach-perturb").unwrap();
        let one_goal = schedule(&p, 42, 1);
        let goals = vec![[0.1, -0.125], [0.0, 0.075], [-0.06, -0.045]];
        let mut r = p.reach();
        r.targets_m.clone_from(&goals);
        r.trials = 32;
        p.reach = Some(r.clone());
        let plans = schedule(&p, 42, 1);
        assert_eq!(plans.len(), 32);
        let mut seen = BTreeMap::new();
        let mut unperturbed = [0; 3];
        for plan in &plans {
            let TrialTask::Reach { angle_deg, target } = plan.task else {
                panic!("{plan:?}");
            };
            let t = target.unwrap();
            match angle_deg {
                Some(a) => *seen.entry((t, a.round() as i64)).or_insert(0) += 1,
                None => unperturbed[t] += 1,
            }
        }
        // 8 directions × 3 repetitions over 3 goals: each (goal, direction) once.
        assert_eq!(seen.len(), 24);
        assert!(seen.values().all(|n| *n == 1), "{seen:?}");
        assert_eq!(unperturbed, [3, 3, 2]);
        // With one repetition the pulses still reach every goal, and each direction
        // shares its goal with the opposite one (the pair the hand balance takes).
        let mut once = p.clone();
        once.reach.as_mut().unwrap().repetitions = 1;
        let mut goal_of = BTreeMap::new();
        for plan in schedule(&once, 42, 1) {
            if let TrialTask::Reach {
                angle_deg: Some(a),
                target,
            } = plan.task
            {
                goal_of.insert(a.round() as i64, target.unwrap());
            }
        }
        assert_eq!(goal_of.len(), 8);
        for (a, g) in goal_of.range(..180) {
            assert_eq!(goal_of[&(a + 180)], *g, "{goal_of:?}");
        }
        let used: std::collections::BTreeSet<usize> = goal_of.values().copied().collect();
        assert_eq!(used.len(), 3, "{goal_of:?}");
        // The same shuffle: pulses sit in the same slots, at the same angles.
        let angle = |t: &TrialTask| match t {
            TrialTask::Reach { angle_deg, .. } => *angle_deg,
            _ => None,
        };
        let p100 = schedule(&Protocol::builtin("reach-perturb").unwrap(), 42, 1);
        assert_eq!(p100, one_goal);
        assert!(
            one_goal
                .iter()
                .all(|q| matches!(q.task, TrialTask::Reach { target: None, .. }))
        );
        let mut q = p.clone();
        q.reach.as_mut().unwrap().targets_m.clear();
        let without: Vec<_> = schedule(&q, 42, 1).iter().map(|q| angle(&q.task)).collect();
        let with: Vec<_> = plans.iter().map(|q| angle(&q.task)).collect();
        assert_eq!(with, without);
        // The reaches to each goal: the trigger at 0.4 of the way on the longer axis.
        assert!((r.trigger_fraction() - 0.4).abs() < 1e-12);
        let sideways = r.toward(0).unwrap();
        assert_eq!(sideways.goal_m, [0.1, -0.125]);
        assert_eq!(sideways.trigger_axis, Axis::X);
        assert!((sideways.trigger_position_m - 0.04).abs() < 1e-12);
        assert!(sideways.targets_m.is_empty());
        let ahead = r.toward(1).unwrap();
        assert_eq!(ahead.trigger_axis, Axis::Y);
        assert!((ahead.trigger_position_m - (-0.125 + 0.4 * 0.2)).abs() < 1e-12);
        let back_left = r.toward(2).unwrap();
        assert_eq!(back_left.trigger_axis, Axis::Y);
        assert!((back_left.trigger_position_m - (-0.125 + 0.4 * 0.08)).abs() < 1e-12);
        assert!(r.toward(3).is_none());
        // The protocol a trial runs with is the reach to its own goal.
        let plan = plans
            .iter()
            .find(|q| {
                matches!(
                    q.task,
                    TrialTask::Reach {
                        target: Some(0),
                        ..
                    }
                )
            })
            .unwrap();
        assert_eq!(trial::for_plan(&p, plan).reach().goal_m, [0.1, -0.125]);
        assert_eq!(
            trial_meta(&trial::for_plan(&p, plan), plan, None).goal_m,
            Some([0.1, -0.125])
        );
    }
}
