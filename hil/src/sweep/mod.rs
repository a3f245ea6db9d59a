//! Protocol design sweeps: a grid of protocol choices × a population of simulated
//! subjects (× the sizes of a hidden effect × replicates), each run a rehearsed session
//! measured against its simulated truth, run locally on all cores or as shards of a
//! cluster's job array, merged into one table and a report.
//!
//! - [`file`](mod@file): the sweep file and its checks (every grid point's protocol is built
//!   before a run starts).
//! - [`run`]: one run: the subject drawn, the session rehearsed, D and K estimated
//!   against the arm's intrinsic values, the diagnosis asked for the hidden effect.
//! - [`table`]: the results as CSV, shard files (written atomically) and their merge.
//! - [`report`]: `sweep.md` with its figures and the sentences a lab acts on.
//! - [`slurm`]: an sbatch job array and the dependent merge.
//!
//! Contract: the table's bytes depend on the sweep file, the base protocol and the
//! program's version alone. A run's row is a function of its index; [`run_local`] and
//! the [`merge`] of any split into shards, completed in any order, write the same
//! `sweep.csv`.
//!
//! Layout of a sweep folder:
//!
//! ```text
//! <out>/sweep.toml, protocol.toml   the sweep and its base protocol as read (merge reads them)
//! <out>/shards/shard-K-of-N.csv     one per task of a split run
//! <out>/sweep.csv                   every run, in run order
//! <out>/sweep.md, *.png             the report
//! <out>/.work/run-NNNNNNN/          a run's session while it is measured (removed after)
//! <out>/sessions/run-NNNNNNN/S01/   with `keep_sessions`: every run's session, kept
//! ```

pub mod file;
pub mod report;
pub mod run;
pub mod slurm;
pub mod table;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use sha2::{Digest as _, Sha256};

pub use file::{SweepFile, SweepFileError};
pub use run::{Row, Run, RunError};
pub use table::ShardError;

/// Why a sweep failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SweepError {
    /// The sweep file.
    #[error(transparent)]
    File(#[from] SweepFileError),
    /// A run could not be written.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Shards.
    #[error(transparent)]
    Shard(#[from] ShardError),
    /// The folder holds another sweep's results.
    #[error(
        "{0} holds the results of another sweep (its sweep.toml or protocol.toml differs); choose another --out"
    )]
    Another(PathBuf),
    /// The folder already holds a finished sweep.
    #[error("{0} already holds a sweep.csv; choose another --out")]
    Exists(PathBuf),
    /// A file or folder could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The worker threads could not be started.
    #[error("worker threads: {0}")]
    Threads(String),
    /// The report could not be written.
    #[error("report: {0}")]
    Report(String),
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The sweep's identity: sha256 of the program's version, the sweep file and the base
/// protocol. Shards of different identities are never merged.
#[must_use]
pub fn id(sweep: &SweepFile) -> String {
    let mut h = Sha256::new();
    for part in [
        env!("CARGO_PKG_VERSION"),
        "\0",
        &sweep.text,
        "\0",
        &sweep.protocol_text,
    ] {
        h.update(part.as_bytes());
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The folder's shards.
#[must_use]
pub fn shards_dir(out: &Path) -> PathBuf {
    out.join("shards")
}

/// Makes `out` a folder of `sweep`: writes its sweep.toml and protocol.toml, or checks
/// that those there are the same (another task of the same sweep wrote them).
///
/// # Errors
/// [`SweepError::Another`] for a folder of another sweep; I/O errors.
pub fn prepare(sweep: &SweepFile, out: &Path) -> Result<(), SweepError> {
    std::fs::create_dir_all(shards_dir(out)).map_err(io(out))?;
    for (name, text) in [
        ("sweep.toml", &sweep.text),
        ("protocol.toml", &sweep.protocol_text),
    ] {
        let path = out.join(name);
        match std::fs::read_to_string(&path) {
            Ok(there) if there == *text => {}
            Ok(_) => return Err(SweepError::Another(out.to_path_buf())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                table::write_atomic(&path, text)?;
            }
            Err(e) => return Err(io(&path)(e)),
        }
    }
    Ok(())
}

/// Runs `indices` of `sweep` on `jobs` threads (rows in the order of `indices`);
/// `progress(done, total)` after each run. With `keep`, every run's session is moved
/// there ([`run::run_one`]).
///
/// # Errors
/// The first run that could not be written.
pub fn run_runs(
    sweep: &SweepFile,
    indices: &[usize],
    work: &Path,
    keep: Option<&Path>,
    jobs: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<Row>, SweepError> {
    use rayon::prelude::*;
    std::fs::create_dir_all(work).map_err(io(work))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|e| SweepError::Threads(e.to_string()))?;
    let done = AtomicUsize::new(0);
    let total = indices.len();
    let rows = pool.install(|| {
        indices
            .par_iter()
            .map(|&i| {
                let row = run::run_one(sweep, &Run::at(sweep, i), work, keep);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                row
            })
            .collect::<Result<Vec<Row>, RunError>>()
    })?;
    // The scratch folder is empty when every run has cleaned up after itself.
    let _ = std::fs::remove_dir(work);
    Ok(rows)
}

/// What a finished sweep wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// `sweep.csv`.
    pub table: PathBuf,
    /// The report and its figures.
    pub report: Vec<PathBuf>,
    /// Runs in the table.
    pub runs: usize,
}

/// Runs every run of `sweep` on this machine and writes the table and the report into
/// `out` (which must not hold a finished sweep); with `keep_sessions`, every run's
/// session too ([`sessions_dir`]). The table is the same with or without.
///
/// # Errors
/// [`SweepError`].
pub fn run_local(
    sweep: &SweepFile,
    out: &Path,
    jobs: usize,
    keep_sessions: bool,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Written, SweepError> {
    if out.join("sweep.csv").exists() {
        return Err(SweepError::Exists(out.to_path_buf()));
    }
    prepare(sweep, out)?;
    let all: Vec<usize> = (0..sweep.runs()).collect();
    let keep = keep_sessions.then(|| sessions_dir(out));
    let rows = run_runs(
        sweep,
        &all,
        &out.join(".work"),
        keep.as_deref(),
        jobs,
        progress,
    )?;
    finish(sweep, out, &table::records(sweep, &rows))
}

/// What a shard task did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ShardDone {
    /// Ran its runs and wrote its file.
    Written(PathBuf, usize),
    /// Its file was already complete (a requeued or re-run task).
    AlreadyThere(PathBuf),
}

/// Runs shard `k` of `n` (runs `k, k+n, …`) and writes its file atomically into
/// `<out>/shards`; with `keep_sessions`, its runs' sessions into [`sessions_dir`].
///
/// # Errors
/// [`SweepError`].
pub fn run_shard(
    sweep: &SweepFile,
    out: &Path,
    k: usize,
    n: usize,
    jobs: usize,
    keep_sessions: bool,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ShardDone, SweepError> {
    prepare(sweep, out)?;
    let id = id(sweep);
    let path = shards_dir(out).join(table::shard_name(k, n));
    if table::shard_is_complete(&path, &id, k, n) {
        return Ok(ShardDone::AlreadyThere(path));
    }
    let runs: Vec<usize> = table::shard_runs(k, n, sweep.runs()).collect();
    let rows = run_runs(
        sweep,
        &runs,
        &out.join(".work").join(format!("shard-{k}")),
        keep_sessions.then(|| sessions_dir(out)).as_deref(),
        jobs,
        progress,
    )?;
    let text = table::csv_text(&table::records(sweep, &rows))
        .map_err(|e| SweepError::Report(e.to_string()))?;
    let text = format!("{}\n{text}", table::shard_header(&id, k, n, sweep.runs()));
    table::write_atomic(&path, &text)?;
    Ok(ShardDone::Written(path, runs.len()))
}

/// Where a sweep keeps its runs' sessions: `<out>/sessions`, one `run-NNNNNNN/` per run
/// ([`run::run_folder`]), each with the session in `S01/`.
#[must_use]
pub fn sessions_dir(out: &Path) -> PathBuf {
    out.join("sessions")
}

/// Merges the shards of the sweep in `out` and writes its table and report.
///
/// # Errors
/// [`SweepError`]: the folder is not a sweep's, or its shards do not make one whole
/// sweep ([`ShardError`]).
pub fn merge(out: &Path) -> Result<Written, SweepError> {
    let read = |name: &str| {
        let p = out.join(name);
        std::fs::read_to_string(&p).map_err(io(&p))
    };
    let text = read("sweep.toml")?;
    let protocol = read("protocol.toml")?;
    let sweep = SweepFile::with_protocol_text(&text, &out.join("sweep.toml"), &protocol)?;
    let records = table::merge(&shards_dir(out), &id(&sweep), sweep.runs())?;
    finish(&sweep, out, &records)
}

fn finish(sweep: &SweepFile, out: &Path, records: &[Vec<String>]) -> Result<Written, SweepError> {
    let text = table::csv_text(records).map_err(|e| SweepError::Report(e.to_string()))?;
    let path = out.join("sweep.csv");
    table::write_atomic(&path, &text)?;
    let report = report::write(sweep, records, out).map_err(SweepError::Report)?;
    Ok(Written {
        table: path,
        report,
        runs: records.len().saturating_sub(1),
    })
}
