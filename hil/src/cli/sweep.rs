//! `rigtwin sweep`: a protocol design sweep over a population of simulated subjects, on
//! this machine's cores, as one shard of a cluster's job array, or written out as a
//! Slurm job array; `rigtwin sweep merge` combines the shards.

use clap::builder::TypedValueParser as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use rigtwin::sweep::{self, Run, ShardDone, SweepFile, slurm};

/// Sweep a protocol's choices over a population of simulated subjects: every grid point
/// (any protocol key) × every subject × every size of a hidden effect × replicates, each
/// run a rehearsed session measured against its simulated truth (bias and spread of D
/// and K per element, session length, safety margins, and whether the diagnosis names
/// the hidden effect and how well it sizes it). Writes <out>/sweep.csv (one row per
/// run), <out>/sweep.md with precision.png and detection.png, and the sentences a lab
/// acts on ("with 24 pulses K22 is known to ±X N/m; ±Y needs Z pulses").
#[derive(Debug, clap::Args)]
#[command(
    args_conflicts_with_subcommands = true,
    after_help = "\
Examples:
  rigtwin sweep hil/sweeps/pulses.toml                      # all cores, progress bar, out: pulses-sweep/
  rigtwin sweep hil/sweeps/pulses.toml --out runs/pulses --jobs 8
  rigtwin sweep hil/sweeps/pulses.toml --dry-run            # check it and say what it costs
  rigtwin sweep hil/sweeps/pulses.toml --shard 3/16         # one task of a job array
  rigtwin sweep merge runs/pulses                           # the shards -> sweep.csv, sweep.md
  rigtwin sweep hil/sweeps/grip-compliance.toml --out g --keep-sessions
  rigtwin diagnose g/sessions/run-0000003/S01               # read run 3's diagnosis again
  rigtwin sweep hil/sweeps/pulses.toml --emit slurm --tasks 16 --max-running 8 --out /scratch/pulses
      (measures one run, writes <out>/slurm/{array,merge}.sbatch and submit.sh; then
       bash /scratch/pulses/slurm/submit.sh)

The sweep file (TOML): name, protocol (a shipped name or a file next to it), seed,
replicates, max_trials; [grid] any dotted protocol key = [values]; [population] subjects,
first_is_nominal, spread = {muscle_stiffness, co_contraction, segment_length,
feedback_gain, reflex_gain}, reflex = {delay_ms, gain_n_s_per_m}; [effect] name (a catalog
effect), key (the protocol key of its size), sizes, parameter (the diagnosis's), fixed =
{other keys}; [measure] estimate, diagnose, folds; [report] targets = {K22 = 20.0}.
Every grid point is checked before a run starts; an error names the file, line and key.
The table's bytes depend on the sweep file, the protocol and the program's version only:
a local run and the merge of any number of shards, finished in any order, are identical."
)]
pub struct Args {
    /// `merge`: combine the shards of a sweep folder.
    #[command(subcommand)]
    pub command: Option<Command>,

    /// The sweep file (TOML).
    pub sweep: Option<PathBuf>,

    /// The sweep's folder (default: `<name>-sweep` here). A local run refuses one that
    /// already holds a sweep.csv; shards of one sweep share it.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,

    /// Worker threads: runs in parallel, 1 to 1024 (default: every core).
    #[arg(long, value_name = "N", default_value_t = super::rehearse::default_jobs(), value_parser = clap::value_parser!(u16).range(1..=1024).map(usize::from))]
    pub jobs: usize,

    /// Run shard K of N only (runs K, K+N, K+2N, ...) and write <out>/shards/shard-K-of-N.csv.
    #[arg(long, value_name = "K/N", value_parser = parse_shard, conflicts_with = "emit")]
    pub shard: Option<(usize, usize)>,

    /// Write a job array for this scheduler instead of running (after measuring one run).
    #[arg(long, value_enum)]
    pub emit: Option<Emit>,

    /// --emit slurm: array tasks (shards).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=100_000).map(|v| v as usize))]
    pub tasks: usize,

    /// --emit slurm: at most this many tasks at once (the array's %LIMIT).
    #[arg(long, value_name = "N")]
    pub max_running: Option<usize>,

    /// --emit slurm: CPUs per task (each task's --jobs).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=1024).map(usize::from))]
    pub cpus_per_task: usize,

    /// --emit slurm: the partition to submit to.
    #[arg(long, value_parser = slurm_name)]
    pub partition: Option<String>,

    /// --emit slurm: the account to charge.
    #[arg(long, value_parser = slurm_name)]
    pub account: Option<String>,

    /// --emit slurm: take this wall time per simulated second of a run instead of
    /// measuring one run (s/s).
    #[arg(long, value_name = "S_PER_S")]
    pub wall_per_simulated_s: Option<f64>,

    /// Keep every run's session in <out>/sessions/run-NNNNNNN/S01 (about 2 MB for 32
    /// trials), to diagnose or view a run again; the table is the same without it.
    #[arg(long, conflicts_with = "emit")]
    pub keep_sessions: bool,

    /// Check the sweep, say what it would cost, and stop.
    #[arg(long)]
    pub dry_run: bool,

    /// Run even if the sweep is estimated to take more than a day on this machine.
    #[arg(long)]
    pub yes: bool,
}

/// The scheduler an `--emit` writes for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Emit {
    /// An sbatch job array and a merge job after it.
    Slurm,
}

/// `rigtwin sweep merge`.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// Combine the shards of a sweep folder into sweep.csv and sweep.md; refuses missing,
    /// duplicate or mismatched shards.
    Merge {
        /// The sweep's folder (with sweep.toml and shards/).
        dir: PathBuf,
    },
}

/// A partition or account name as it goes into an `#SBATCH` line: letters, digits and
/// `_ - . ,` only, so nothing else can be written into the script.
fn slurm_name(v: &str) -> Result<String, String> {
    if !v.is_empty()
        && v.len() <= 128
        && v.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | ','))
    {
        Ok(v.to_owned())
    } else {
        Err(format!(
            "{v:?}: want a Slurm name of letters, digits, _ - . and , (at most 128)"
        ))
    }
}

fn parse_shard(v: &str) -> Result<(usize, usize), String> {
    let (k, n) = v
        .split_once('/')
        .ok_or_else(|| format!("{v:?}: want K/N, e.g. 3/16"))?;
    let k: usize = k.trim().parse().map_err(|e| format!("K in {v:?}: {e}"))?;
    let n: usize = n.trim().parse().map_err(|e| format!("N in {v:?}: {e}"))?;
    if n == 0 || k >= n {
        return Err(format!(
            "{v:?}: want 0 <= K < N (tasks count from 0, as Slurm's array ids)"
        ));
    }
    Ok((k, n))
}

/// Past this estimated wall time on this machine, a local sweep asks for --yes, s.
const CONFIRM_WALL_S: f64 = 86_400.0;

/// Runs `rigtwin sweep`.
///
/// # Errors
/// A bad sweep file (naming file, line and key), a run that cannot be written, shards
/// that do not make a whole sweep.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if let Some(Command::Merge { dir }) = &args.command {
        let w = sweep::merge(dir).with_context(|| format!("merging {}", dir.display()))?;
        outln!(
            "merged {} runs into {}; report {}",
            w.runs,
            w.table.display(),
            w.report
                .first()
                .map_or(String::new(), |p| p.display().to_string())
        );
        return Ok(());
    }
    let Some(path) = &args.sweep else {
        anyhow::bail!(
            "give a sweep file (rigtwin sweep <sweep.toml>) or `rigtwin sweep merge <dir>`"
        );
    };
    let s = SweepFile::load(path)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}-sweep", s.name)));
    let runs = s.runs();
    let simulated: f64 = (0..runs)
        .map(|i| slurm::simulated_s(&s, &Run::at(&s, i)))
        .sum();
    let per_sim = rigtwin::rehearse::cost::SIM_S_PER_WALL_S_PER_JOB;
    let diag = if s.diagnose {
        // The diagnosis reads what the session recorded (no twins): about a third.
        simulated / 3.0 * super::DIAGNOSE_S_PER_RECORDED_S
    } else {
        0.0
    };
    let wall = (simulated / per_sim + diag) / args.jobs.max(1) as f64;
    errln!(
        "sweep {}: {runs} runs ({} grid point(s) x {} effect size(s) x {} subjects x {} replicate(s)), {} simulated; about {} on {} worker(s)",
        s.name,
        s.points(),
        s.sizes(),
        s.population.subjects,
        s.replicates,
        rigtwin::rehearse::cost::duration(simulated),
        rigtwin::rehearse::cost::duration(wall),
        args.jobs
    );
    if args.dry_run {
        return Ok(());
    }
    if let Some(Emit::Slurm) = args.emit {
        return emit_slurm(args, &s, path, &out);
    }
    if let Some((k, n)) = args.shard {
        let mine = sweep::table::shard_runs(k, n, runs).count();
        let bar = super::trial_bar(
            mine as u64,
            "{elapsed_precise} [{bar:40}] {pos}/{len} runs, {eta} left",
        );
        // A task's log (no terminal) gets a line per run instead of the bar.
        let log = !std::io::IsTerminal::is_terminal(&std::io::stderr());
        let done = sweep::run_shard(
            &s,
            &out,
            k,
            n,
            args.jobs,
            args.keep_sessions,
            &|d, total| {
                bar.set_position(d as u64);
                if log {
                    let _ = writeln!(
                        std::io::stderr().lock(),
                        "shard {k}/{n}: {d}/{total} runs done"
                    );
                }
            },
        )?;
        bar.finish_and_clear();
        match done {
            ShardDone::Written(p, runs) => {
                outln!("shard {k}/{n}: {runs} runs written to {}", p.display());
            }
            ShardDone::AlreadyThere(p) => outln!(
                "shard {k}/{n} is already complete in {}; nothing to do",
                p.display()
            ),
        }
        return Ok(());
    }
    if wall > CONFIRM_WALL_S && !args.yes {
        anyhow::bail!(
            "not started: about {} on this machine; split it with --shard or --emit slurm, or add --yes",
            rigtwin::rehearse::cost::duration(wall)
        );
    }
    let bar = super::trial_bar(
        runs as u64,
        "{elapsed_precise} [{bar:40}] {pos}/{len} runs, {eta} left",
    );
    let started = Instant::now();
    let w = sweep::run_local(&s, &out, args.jobs, args.keep_sessions, &|d, _| {
        bar.set_position(d as u64);
    })?;
    bar.finish_and_clear();
    outln!(
        "{} runs in {} on {} worker(s): {}; report {}",
        w.runs,
        rigtwin::rehearse::cost::duration(started.elapsed().as_secs_f64()),
        args.jobs,
        w.table.display(),
        w.report
            .first()
            .map_or(String::new(), |p| p.display().to_string())
    );
    if let Some(md) = w.report.first()
        && let Ok(text) = std::fs::read_to_string(md)
    {
        for line in text.lines().filter(|l| l.starts_with("- With ")) {
            outln!("{}", line.trim_start_matches("- "));
        }
    }
    Ok(())
}

fn absolute(p: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(p).with_context(|| format!("{}: cannot make it absolute", p.display()))
}

/// Peak resident memory of this process so far, bytes.
fn peak_rss_bytes() -> f64 {
    nix::sys::resource::getrusage(nix::sys::resource::UsageWho::RUSAGE_SELF)
        .map_or(0.0, |u| u.max_rss() as f64 * 1024.0)
}

fn emit_slurm(args: &Args, s: &SweepFile, path: &Path, out: &Path) -> anyhow::Result<()> {
    if args.tasks > s.runs() {
        anyhow::bail!(
            "--tasks {} is more than the sweep's {} runs; a task would have nothing to do",
            args.tasks,
            s.runs()
        );
    }
    if args.max_running == Some(0) {
        anyhow::bail!("--max-running must be > 0");
    }
    sweep::prepare(s, out)?;
    let wall_per_simulated_s = match args.wall_per_simulated_s {
        Some(v) if v.is_finite() && v > 0.0 => v,
        Some(v) => anyhow::bail!("--wall-per-simulated-s must be > 0, got {v}"),
        None => {
            let run = Run::at(s, 0);
            errln!("measuring run 0 for the requests ...");
            let started = Instant::now();
            sweep::run::run_one(s, &run, &out.join(".work").join("measure"), None)?;
            let _ = std::fs::remove_dir_all(out.join(".work"));
            let wall = started.elapsed().as_secs_f64();
            let sim = slurm::simulated_s(s, &run);
            errln!(
                "run 0: {} simulated in {} ({:.3} s per simulated s), {:.0} MB peak",
                rigtwin::rehearse::cost::duration(sim),
                rigtwin::rehearse::cost::duration(wall),
                wall / sim,
                peak_rss_bytes() / 1e6
            );
            wall / sim
        }
    };
    let plan = slurm::SlurmPlan {
        tasks: args.tasks,
        max_running: args.max_running,
        cpus_per_task: args.cpus_per_task,
        partition: args.partition.clone(),
        account: args.account.clone(),
        binary: std::env::current_exe().context("finding the rigtwin binary")?,
        sweep: absolute(path)?,
        out: absolute(out)?,
        wall_per_simulated_s,
        peak_bytes: peak_rss_bytes().max(64.0e6),
    };
    let files = slurm::write(s, &plan).map_err(anyhow::Error::msg)?;
    for f in &files {
        outln!("wrote {}", f.display());
    }
    outln!(
        "slowest task: about {}; submit with: bash {}",
        rigtwin::rehearse::cost::duration(slurm::task_wall_s(s, &plan)),
        files
            .last()
            .map_or(String::new(), |p| p.display().to_string())
    );
    Ok(())
}
