//! `rigtwin diagnose`: name the physical cause of what the nominal model gets wrong
//! about a measured session, from the cart force balance.

use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::session::Session;
use rigtwin_diagnose::{DiagnoseOptions, ExtendedModel, diagnose, table, write_report};

/// Name the effect, of the plant or of the human, that the nominal model misses in a
/// measured session. Fits the plant-side catalog effects (rail-friction, force-ripple,
/// actuation-delay, sensor-rotation) to the force balance of the carts,
/// m·a = u(t − τ) + F + effect (needs cmd_fx_n, cmd_fy_n), and the human-side ones
/// (grip-compliance, handle-mass, stretch-reflex) to the hand balance of the force-pulse
/// responses (needs ≥ 8 perturbed and 2 unperturbed trials), on training folds; judges
/// each on held-out folds against its balance's nominal model, and names every cause
/// whose gain is beyond chance (fold t-test) and at least --min-gain, whose parameters
/// are material in physical units and inside their search range, and whose binned
/// evidence follows its law; on each balance effects are selected forward, each judged
/// given those named before it, and what the catalog lacks is reported as unexplained.
/// Writes diagnosis.md with PNG figures into <session>/diagnosis (or --report-dir).
#[derive(Debug, Clone, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin diagnose ../shared/recordings/example-friction
  rigtwin diagnose ../shared/recordings/example-none --json --write-model model.toml
  rigtwin diagnose session/ --report-dir /tmp/diag --folds 4
  rigtwin diagnose ../shared/recordings/example-friction --rerun save=diagnose.rrd
      (the session, and on every held-out trial the motor command predicted by the
       baseline and each candidate under predicted/plots/command; rerun diagnose.rrd)")]
pub struct Args {
    /// Session directory (with session.toml).
    pub session: PathBuf,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Run even if the run is estimated to take more than an hour.
    #[arg(long)]
    pub yes: bool,
    /// Write the extended model (the cause's effect, world keys) to this TOML file.
    #[arg(long, value_name = "FILE")]
    pub write_model: Option<PathBuf>,
    /// Where diagnosis.md and its figures go (default: <session>/diagnosis).
    #[arg(long, value_name = "DIR")]
    pub report_dir: Option<PathBuf>,
    /// Do not write diagnosis.md and figures.
    #[arg(long)]
    pub no_report: bool,
    /// Cross-validation folds (whole trials; the hand balance on opposite pulse pairs
    /// leaves one pair, and for its test one repetition, out instead).
    #[arg(long, default_value_t = 8)]
    pub folds: usize,
    /// Family-wise false-alarm level of the fold t-test.
    #[arg(long, default_value_t = 0.05)]
    pub alpha: f64,
    /// Smallest held-out gain that names a cause (fraction).
    #[arg(long, default_value_t = 0.03)]
    pub min_gain: f64,
    /// Also send the session, and for every trial the motor command the balance predicts
    /// with the baseline and each candidate fitted without it (`predicted/…`), to the rerun
    /// viewer.
    #[cfg(feature = "rerun")]
    #[command(flatten)]
    pub rerun: rigtwin::viz::RerunArgs,
}

/// Runs `rigtwin diagnose`.
///
/// # Errors
/// A session that cannot be read, a fit that cannot be made, a file that cannot be
/// written.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.folds < 2 {
        anyhow::bail!("--folds must be at least 2, got {}", args.folds);
    }
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        anyhow::bail!("--alpha must be in (0, 1), got {}", args.alpha);
    }
    let session = Session::read(&args.session)
        .with_context(|| format!("reading session {}", args.session.display()))?;
    super::preflight(
        "diagnose",
        &session,
        super::DIAGNOSE_S_PER_RECORDED_S,
        args.yes,
    )?;
    let opts = DiagnoseOptions {
        folds: args.folds,
        alpha: args.alpha,
        min_gain: args.min_gain,
    };
    let analysis = diagnose(&session, &opts)
        .with_context(|| format!("diagnosing {}", args.session.display()))?;
    let d = &analysis.diagnosis;
    #[cfg(feature = "rerun")]
    if let Some(target) = &args.rerun.rerun {
        let id = format!("{}-diagnose", rigtwin::viz::recording_id(&session)?);
        let mut viewer = rigtwin::viz::Viewer::new(target, "rigtwin", &id)
            .with_context(|| format!("opening --rerun {target}"))?;
        rigtwin::viz::log_session(&mut viewer, &session)?;
        let sent = rigtwin::viz::log_diagnosis_overlay(&mut viewer, &session, &analysis)?;
        viewer
            .finish()
            .with_context(|| format!("finishing --rerun {target}"))?;
        errln!(
            "rerun: session and {} held-out trials ({} rows of the command, {} predicted) sent to {target} (recording {id})",
            sent.trials,
            sent.measured_samples,
            sent.simulated_samples
        );
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(d)?);
    } else {
        out!("{}", table(d));
    }
    if let Some(path) = &args.write_model {
        ExtendedModel::from_diagnosis(d).write(path)?;
        if !args.json {
            outln!("model written to {}", path.display());
        }
    }
    if !args.no_report {
        let dir = args
            .report_dir
            .clone()
            .unwrap_or_else(|| args.session.join("diagnosis"));
        let files = write_report(&analysis, &dir)?;
        if let (false, Some(md)) = (args.json, files.first()) {
            outln!("report written to {}", md.display());
        }
    }
    Ok(())
}
