//! `rigtwin rehearse`: run a protocol against virtual subjects, record their sessions,
//! and print and write the rehearsal report.

use clap::builder::TypedValueParser as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use anyhow::Context as _;
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options, Progress};
use rigtwin::report;
use rigtwin_diagnose::ExtendedModel;

/// Rehearse a protocol before human sessions: simulate it in lock step against virtual
/// subjects, write one session per subject in the recording format, and report session
/// length, peak forces, speeds and deviations, safety margins, workspace, and whether
/// the estimator recovers the simulated arm's impedance (next to the seeds' figures).
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin rehearse hil/protocols/reach-perturb.toml             # seed from the file, out/reach-perturb-<seed>/
  rigtwin rehearse reach-perturb --subjects 5 --seed 7 --jobs 2  # built-in copy of the shipped protocol
  rigtwin rehearse my-protocol.toml --out runs/pilot --json
  rigtwin rehearse hil/protocols/reach-perturb.toml --rerun save=r.rrd   # then: rerun r.rrd
  rigtwin rehearse reach-perturb --model model.toml  # with `rigtwin diagnose --write-model`'s effects
  rigtwin rehearse reach-perturb --realtime --max-trials 4 --rt-priority 80 --lock-memory
  rigtwin rehearse my-protocol.toml --subjects 200 --dry-run  # what it would cost, then stop

Shipped protocols (hil/protocols/, also built in by name): reach-perturb (000_*),
hold-sinusoid (001_*), calibration-rig (001_* Appendix B).
Output: <out>/S01/ (session.toml, trials/*.csv), ..., <out>/report.md, <out>/report.json.
Before it starts, a run says on stderr what it will cost (trials, simulated time, disk,
memory, an estimate of wall time) and refuses past a day simulated or 10 GB written
unless --yes. The same protocol and seed give byte-identical sessions, whatever --jobs is.
--realtime paces every tick to the wall clock at the control rate (4 kHz) on one thread,
skips missed deadlines instead of bursting (the plant moves on under the held command;
`safety.max_consecutive_misses` trips the controller past that many in a row), and
writes the wake-up latency and loop time (p50, p99, p99.9, max, missed deadlines) to the
report and to each session's [timing].")]
pub struct Args {
    /// Protocol file (TOML), or the name of a shipped protocol.
    pub protocol: PathBuf,

    /// Number of virtual subjects, 1 to 10000 (default: the protocol's `subjects.count`).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(rigtwin::protocol::MAX_SUBJECTS)))]
    pub subjects: Option<u32>,

    /// Session seed (default: the protocol's `seed`).
    #[arg(long, value_name = "S", value_parser = clap::value_parser!(u64).range(..=i64::MAX.cast_unsigned()))]
    pub seed: Option<u64>,

    /// Output folder; must not exist or be empty. Default: a fresh
    /// `out/<name>-<seed>[-k]/`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,

    /// Worker threads, 1 to 1024 (trials are simulated in parallel, written in order).
    #[arg(long, value_name = "N", default_value_t = default_jobs(), value_parser = clap::value_parser!(u16).range(1..=1024).map(usize::from))]
    pub jobs: usize,

    /// Run only the first N trials of each subject's schedule (quick checks).
    #[arg(long, value_name = "N")]
    pub max_trials: Option<usize>,

    /// Print the report as JSON instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Run even if the run is past the limits said before it starts (a day simulated,
    /// 10 GB written).
    #[arg(long)]
    pub yes: bool,

    /// Check the protocol and say what the run would cost, then stop (nothing written).
    #[arg(long)]
    pub dry_run: bool,

    /// Pace every tick to the wall clock at the control rate (real time) instead of lock
    /// step; one trial at a time.
    #[arg(long)]
    pub realtime: bool,

    /// With --realtime: run the loop's thread under SCHED_FIFO at this priority (1-99).
    #[arg(long, value_name = "N", requires = "realtime", value_parser = clap::value_parser!(u8).range(1..=99))]
    pub rt_priority: Option<u8>,

    /// With --realtime: lock the process's memory in RAM (mlockall).
    #[arg(long, requires = "realtime")]
    pub lock_memory: bool,

    /// With --realtime: spin on the clock this many microseconds before each deadline
    /// instead of sleeping (removes the kernel's wake-up latency; costs that much CPU).
    #[arg(long, value_name = "US", default_value_t = 0, requires = "realtime")]
    pub spin_us: u64,

    /// Extended model (`rigtwin diagnose --write-model`): its plant effects and stretch
    /// reflex replace the protocol's before rehearsing.
    #[arg(long, value_name = "MODEL.toml")]
    pub model: Option<PathBuf>,

    #[cfg(feature = "rerun")]
    #[command(flatten)]
    pub rerun: rigtwin::viz::RerunArgs,

    /// Highest sample rate sent to a live viewer, Hz (a saved file holds every sample).
    #[cfg(feature = "rerun")]
    #[arg(long, value_name = "HZ", default_value_t = rigtwin::viz::DEFAULT_LIVE_RATE_HZ)]
    pub live_rate_hz: f64,
}

pub(crate) fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
}

/// Runs `rigtwin rehearse`.
///
/// # Errors
/// A bad protocol (naming the key), an output folder that is not empty, a model or
/// writer failure.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let mut protocol = Protocol::load(&args.protocol)?;
    if let Some(path) = &args.model {
        let model = ExtendedModel::read(path)?;
        model.apply_to(
            &mut protocol.plant.effects,
            &mut protocol.subjects.arm.stretch_reflex,
        );
    }
    if args.subjects == Some(0) {
        anyhow::bail!("--subjects must be at least 1");
    }
    if args.jobs == 0 {
        anyhow::bail!("--jobs must be at least 1");
    }
    if args.max_trials == Some(0) {
        anyhow::bail!("--max-trials must be at least 1");
    }
    let seed = args.seed.unwrap_or(protocol.seed);
    let out_dir = match &args.out {
        Some(d) => d.clone(),
        None => rehearse::fresh_dir(std::path::Path::new("out"), &protocol.name, seed),
    };
    let options = Options {
        subjects: args.subjects.unwrap_or(protocol.subjects.count),
        seed,
        out_dir: out_dir.clone(),
        jobs: args.jobs,
        max_trials: args.max_trials,
    };
    let cost = rehearse::cost::Cost::of(
        &protocol,
        options.subjects,
        args.max_trials,
        options.jobs,
        args.realtime,
    );
    if args.dry_run {
        outln!(
            "{}: valid; {cost}{}",
            protocol.name,
            cost.needs_confirmation()
                .map_or_else(String::new, |why| format!("; would need --yes: {why}"))
        );
        return Ok(());
    }
    errln!("rehearsing {}: {cost}", protocol.name);
    if let Some(why) = cost.needs_confirmation()
        && !args.yes
    {
        anyhow::bail!(
            "not started: {why}; add --yes to run it, or fewer --subjects or --max-trials"
        );
    }
    let total = usize::try_from(cost.trials)?;
    let bar = super::trial_bar(
        total as u64,
        "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} trials  {msg}",
    );
    let progress = |p: Progress| {
        bar.set_position(p.done as u64);
        bar.set_message(format!("{:.0} s simulated", p.simulated_s));
    };
    let cancel = AtomicBool::new(false);
    // With --rerun, each trial is logged as soon as it is written, while the next ones are
    // simulated; the ellipses follow the report.
    #[cfg(feature = "rerun")]
    let mut live = match &args.rerun.rerun {
        Some(target) => Some(open_viewer(args, target, &protocol, &options)?),
        None => None,
    };
    #[cfg(feature = "rerun")]
    let mut logger = live
        .as_mut()
        .map(|(viewer, _, _)| rigtwin::viz::RehearsalLogger::new(viewer, &protocol, seed));
    #[cfg(feature = "rerun")]
    let observer: &mut dyn rehearse::RehearsalObserver = match logger.as_mut() {
        Some(l) => l,
        None => &mut (),
    };
    #[cfg(not(feature = "rerun"))]
    let observer: &mut dyn rehearse::RehearsalObserver = &mut ();
    let pacing = if args.realtime {
        if args.lock_memory
            && let Err(note) = rigtwin::cosim::rt::lock_memory()
        {
            errln!("{note}");
        }
        rehearse::Pacing::RealTime(rehearse::RealTime {
            spin: std::time::Duration::from_micros(args.spin_us),
            fifo_priority: args.rt_priority,
        })
    } else {
        rehearse::Pacing::LockStep
    };
    let rehearsal =
        rehearse::rehearse_paced(&protocol, &options, pacing, &progress, &cancel, observer)
            .with_context(|| format!("rehearsing {} into {}", protocol.name, out_dir.display()))?;
    for note in &rehearsal.realtime_notes {
        errln!("{note}");
    }
    bar.finish_and_clear();
    let rep = report::build(&rehearsal);
    report::write(&rep, &out_dir)?;
    #[cfg(feature = "rerun")]
    if let Some(logger) = logger {
        let logged = logger.finish(&rehearsal, &rep);
        if let Some((viewer, target, id)) = live {
            finish_viewer(args, viewer, &target, &id, logged)?;
        }
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&rep)?);
    } else {
        out!("{}", report::summary_text(&rep));
        outln!(
            "\nsessions: {}/S01 ... ; per-trial table: {}",
            out_dir.display(),
            out_dir.join("report.md").display()
        );
    }
    Ok(())
}

/// Opens the viewer for a rehearsal; returns it with its target and recording id.
#[cfg(feature = "rerun")]
fn open_viewer(
    args: &Args,
    target: &rigtwin::viz::Target,
    protocol: &Protocol,
    options: &Options,
) -> anyhow::Result<(rigtwin::viz::Viewer, rigtwin::viz::Target, String)> {
    use rigtwin::viz::{self, Viewer};
    let id = viz::rehearsal_recording_id(protocol, options)?;
    let mut viewer =
        Viewer::new(target, "rigtwin", &id).with_context(|| format!("opening --rerun {target}"))?;
    viewer.set_live_rate_hz(args.live_rate_hz)?;
    Ok((viewer, target.clone(), id))
}

/// Ends the stream (the `.rrd` footer, or the live viewer's last data) and says what was
/// sent.
#[cfg(feature = "rerun")]
fn finish_viewer(
    args: &Args,
    viewer: rigtwin::viz::Viewer,
    target: &rigtwin::viz::Target,
    id: &str,
    logged: Result<rigtwin::viz::RehearsalLogged, rigtwin::viz::VizError>,
) -> anyhow::Result<()> {
    use rigtwin::viz::Target;
    let logged = logged.with_context(|| format!("streaming the rehearsal to --rerun {target}"))?;
    viewer
        .finish()
        .with_context(|| format!("finishing --rerun {target}"))?;
    let samples: usize = logged.sessions.iter().map(|s| s.samples).sum();
    let line = format!(
        "viewer: {} sessions, {samples} samples ({} with muscle activations, {} with loop timing), {} session estimates, {} onset truths, {} windows, {} safety events; recording {id}",
        logged.sessions.len(),
        logged.activation_samples,
        logged.timing_samples,
        logged.borner,
        logged.onset_truths,
        logged.windows,
        logged.safety_events
    );
    // Keep stdout JSON-only under --json.
    if args.json {
        errln!("{line}");
    } else {
        outln!("{line}");
    }
    match target {
        Target::Save(path) => {
            let msg = format!(
                "written {}; open it with: rerun {}",
                path.display(),
                path.display()
            );
            if args.json {
                errln!("{msg}");
            } else {
                outln!("{msg}");
            }
        }
        Target::Spawn | Target::Connect(_) => {}
    }
    Ok(())
}
