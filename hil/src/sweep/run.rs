//! One run of a sweep: one subject of the population, one grid point, one effect size,
//! one replicate, rehearsed as a session and measured.
//!
//! The subject is drawn from the grid point's `[subjects]` with the sweep's seed, so the
//! same subject is at every grid point and replicate (common random numbers: a
//! difference between grid points is the protocol's, not the draw's). The session's
//! noise, nuisances and schedule come from a seed of (sweep seed, subject, replicate),
//! the same at every grid point. A run's row is a function of the sweep and its index
//! alone: which shard, machine or thread runs it does not change a byte.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use rigtwin_diagnose::{DiagnoseOptions, diagnose};

use super::file::{ELEMENTS, SweepFile};
use crate::protocol::seed::mix;
use crate::rehearse::{self, Options, RehearseError};
use crate::report;
use crate::session::Session;

/// Tags that keep the sweep's seeds apart from each other and from the rehearsal's own.
const POPULATION_TAG: u64 = 0x5357_4545_5050_4F50;
const SESSION_TAG: u64 = 0x5357_4545_5053_4553;

/// Where a run sits in its sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Run {
    /// Index in the sweep, 0-based: `((point · sizes + size) · subjects + subject − 1) ·
    /// replicates + replicate − 1`.
    pub index: usize,
    /// Grid point, 0-based.
    pub point: usize,
    /// Effect size, 0-based (0 without an effect).
    pub size: usize,
    /// Subject, 1-based.
    pub subject: u32,
    /// Replicate, 1-based.
    pub replicate: u32,
}

impl Run {
    /// Run `index` of `sweep`.
    #[must_use]
    pub fn at(sweep: &SweepFile, index: usize) -> Run {
        let reps = sweep.replicates as usize;
        let subjects = sweep.population.subjects as usize;
        let sizes = sweep.sizes();
        let replicate = index % reps;
        let subject = (index / reps) % subjects;
        let size = (index / (reps * subjects)) % sizes;
        let point = index / (reps * subjects * sizes);
        Run {
            index,
            point,
            size,
            subject: u32::try_from(subject + 1).unwrap_or(u32::MAX),
            replicate: u32::try_from(replicate + 1).unwrap_or(u32::MAX),
        }
    }

    /// The session seed of this run: the same at every grid point and effect size.
    /// Below 2⁶³, the largest integer a TOML reader must accept (the session records it).
    #[must_use]
    pub fn session_seed(&self, sweep: &SweepFile) -> u64 {
        mix(&[
            sweep.seed,
            SESSION_TAG,
            u64::from(self.subject),
            u64::from(self.replicate),
        ]) >> 1
    }
}

/// What one run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The run.
    pub run: Run,
    /// The session seed.
    pub session_seed: u64,
    /// The hidden effect's size, in its key's unit.
    pub effect_size: Option<f64>,
    /// Why the run has no measures (the simulation refused or diverged).
    pub error: Option<String>,
    /// Trials in the session.
    pub trials: usize,
    /// Perturbed trials (pulses) in the session.
    pub perturbed: usize,
    /// Trial time of the session, s.
    pub session_length_s: f64,
    /// Largest motor command, N.
    pub peak_command_n: f64,
    /// Largest hand speed, m/s.
    pub peak_speed_m_per_s: f64,
    /// Distance to the workspace wall at the closest, m.
    pub wall_margin_m: f64,
    /// Safety trips in the session.
    pub trips: usize,
    /// D and K estimated, in [`ELEMENTS`] order (D in N s/m, K in N/m).
    pub estimate: Option<[f64; 8]>,
    /// The simulated arm's intrinsic D and K at the onsets (mean over the session).
    pub truth: Option<[f64; 8]>,
    /// Jackknife standard errors of the estimate.
    pub std_err: Option<[f64; 8]>,
    /// Why the estimate failed.
    pub estimate_error: Option<String>,
    /// The diagnosis, when measured.
    pub diagnosis: Option<Diagnosed>,
}

/// What the diagnosis said of a run's session.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosed {
    /// The strongest cause, or `none`.
    pub cause: String,
    /// Every named cause, `+`-joined, strongest first (`none` for none).
    pub causes: String,
    /// Whether the hidden effect is among them.
    pub named: bool,
    /// The sweep's parameter as the diagnosis found it (when named).
    pub parameter: Option<f64>,
    /// The held-out gain of the hidden effect's cause (when named).
    pub gain: Option<f64>,
    /// Whether the diagnosis reported structure outside its catalog.
    pub unexplained: bool,
    /// Why the diagnosis failed.
    pub error: Option<String>,
}

/// Why a sweep could not go on.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// A rehearsal failed for a reason that is not the run's own (the disk, the folder).
    #[error("run {run}: {source}")]
    Rehearse {
        /// The run index.
        run: usize,
        /// The rehearsal's error.
        source: Box<RehearseError>,
    },
    /// The run's scratch folder could not be made or removed.
    #[error("run {run}: {path}: {source}")]
    Io {
        /// The run index.
        run: usize,
        /// The folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// The folder of run `index` (in the scratch folder, and where a kept session goes).
#[must_use]
pub fn run_folder(index: usize) -> String {
    format!("run-{index:07}")
}

/// The protocol of `run`: its grid point and size, with the drawn subject as the one
/// subject of the session.
#[must_use]
pub fn protocol_of(sweep: &SweepFile, run: &Run) -> crate::protocol::Protocol {
    let mut p = sweep.protocol_at(run.point, run.size).clone();
    let subject = p
        .subjects
        .draw(mix(&[sweep.seed, POPULATION_TAG]), run.subject);
    p.subjects.arm = subject.arm;
    p.subjects.shoulder_m = subject.shoulder_m;
    p.subjects.co_contraction_level = subject.co_contraction_level;
    p.subjects.first_is_nominal = true;
    p.subjects.count = 1;
    p
}

/// Runs `run` of `sweep` in a scratch folder under `work`, removed afterwards or, with
/// `keep`, moved to `keep/run-NNNNNNN/` once measured (the rehearsal's folder: the
/// session in `S01/` and its report), so that a run's diagnosis can be read again.
///
/// # Errors
/// [`RunError`] when the scratch folder or the session cannot be written or kept. A
/// simulation that refuses its protocol or diverges is the run's result (its row's
/// `error`, nothing kept), not an error of the sweep.
pub fn run_one(
    sweep: &SweepFile,
    run: &Run,
    work: &Path,
    keep: Option<&Path>,
) -> Result<Row, RunError> {
    let protocol = protocol_of(sweep, run);
    let dir = work.join(run_folder(run.index));
    let io = |path: &Path, source| RunError::Io {
        run: run.index,
        path: path.to_path_buf(),
        source,
    };
    if dir.exists() {
        // Left by a task that was killed: its result was never written.
        std::fs::remove_dir_all(&dir).map_err(|e| io(&dir, e))?;
    }
    let session_seed = run.session_seed(sweep);
    let options = Options {
        subjects: 1,
        seed: session_seed,
        out_dir: dir.clone(),
        jobs: 1,
        max_trials: sweep.max_trials,
    };
    let effect_size = sweep.effect.as_ref().map(|e| e.sizes[run.size]);
    let mut row = Row {
        run: *run,
        session_seed,
        effect_size,
        error: None,
        trials: 0,
        perturbed: 0,
        session_length_s: 0.0,
        peak_command_n: 0.0,
        peak_speed_m_per_s: 0.0,
        wall_margin_m: 0.0,
        trips: 0,
        estimate: None,
        truth: None,
        std_err: None,
        estimate_error: None,
        diagnosis: None,
    };
    let rehearsal = match rehearse::rehearse(&protocol, &options, &|_| {}, &AtomicBool::new(false))
    {
        Ok(r) => r,
        Err(e @ (RehearseError::CoSim(_) | RehearseError::Controller(_))) => {
            row.error = Some(e.to_string());
            std::fs::remove_dir_all(&dir).map_err(|e| io(&dir, e))?;
            return Ok(row);
        }
        Err(source) => {
            return Err(RunError::Rehearse {
                run: run.index,
                source: Box::new(source),
            });
        }
    };
    let rep = report::build(&rehearsal);
    row.trials = rep.trials_per_subject;
    row.perturbed = rep.perturbed_per_subject;
    row.session_length_s = rep.session_length_s;
    row.peak_command_n = rep.safety.peak_command_n[0].max(rep.safety.peak_command_n[1]);
    row.peak_speed_m_per_s = rep.safety.peak_speed_m_per_s;
    row.wall_margin_m = rep.workspace.margin_m;
    row.trips = rep.safety.trips.len();
    if sweep.estimate
        && let Some(e) = rep.estimates.first()
    {
        row.truth = Some(flatten(e.truth_d_ns_per_m, e.truth_k_n_per_m));
        match &e.estimate {
            Some(b) => {
                row.estimate = Some(flatten(b.d_ns_per_m, b.k_n_per_m));
                row.std_err = Some(flatten(b.d_std_err_ns_per_m, b.k_std_err_n_per_m));
            }
            None => row.estimate_error = e.error.clone(),
        }
    }
    if sweep.diagnose
        && let Some(s) = rehearsal.subjects.first()
    {
        row.diagnosis = Some(diagnose_session(sweep, &s.dir));
    }
    match keep {
        Some(keep) => {
            let to = keep.join(run_folder(run.index));
            if to.exists() {
                // Kept by an earlier attempt at this run (a requeued task).
                std::fs::remove_dir_all(&to).map_err(|e| io(&to, e))?;
            }
            std::fs::create_dir_all(keep).map_err(|e| io(keep, e))?;
            std::fs::rename(&dir, &to).map_err(|e| io(&to, e))?;
        }
        None => std::fs::remove_dir_all(&dir).map_err(|e| io(&dir, e))?,
    }
    Ok(row)
}

fn diagnose_session(sweep: &SweepFile, dir: &Path) -> Diagnosed {
    let failed = |e: String| Diagnosed {
        cause: String::new(),
        causes: String::new(),
        named: false,
        parameter: None,
        gain: None,
        unexplained: false,
        error: Some(e),
    };
    let session = match Session::read(dir) {
        Ok(s) => s,
        Err(e) => return failed(e.to_string()),
    };
    let options = DiagnoseOptions {
        folds: sweep.folds,
        ..DiagnoseOptions::default()
    };
    let analysis = match diagnose(&session, &options) {
        Ok(a) => a,
        Err(e) => return failed(e.to_string()),
    };
    let d = &analysis.diagnosis;
    let hidden = sweep
        .effect
        .as_ref()
        .and_then(|e| d.causes.iter().find(|c| c.name == e.name).map(|c| (e, c)));
    Diagnosed {
        cause: d.cause.clone(),
        causes: if d.causes.is_empty() {
            "none".to_owned()
        } else {
            d.causes
                .iter()
                .map(|c| c.name.name())
                .collect::<Vec<_>>()
                .join("+")
        },
        named: hidden.is_some(),
        parameter: hidden.and_then(|(e, c)| c.parameters.get(&e.parameter).copied()),
        gain: hidden.map(|(_, c)| c.gain),
        unexplained: d.unexplained_structures().next().is_some(),
        error: None,
    }
}

fn flatten(d: [[f64; 2]; 2], k: [[f64; 2]; 2]) -> [f64; 8] {
    [
        d[0][0], d[0][1], d[1][0], d[1][1], k[0][0], k[0][1], k[1][0], k[1][1],
    ]
}

const _: () = assert!(ELEMENTS.len() == 8);
