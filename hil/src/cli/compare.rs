//! `rigtwin compare`: fit the baseline subject to a session, replay the session in
//! simulation and say, per channel, phase and frequency band, how far the simulation is
//! from the measurement, and how the estimator's D and K differ.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::compare::{CompareOptions, Comparison, compare};
use rigtwin::session::Session;
use rigtwin_diagnose::ExtendedModel;

/// The arguments of `rigtwin compare` (the help text is on the subcommand).
#[derive(Debug, Clone, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin compare ../shared/recordings/example-none
  rigtwin compare ../shared/recordings/example-friction --json > compare.json
  rigtwin diagnose ../shared/recordings/example-friction --write-model model.toml
  rigtwin compare ../shared/recordings/example-friction --model model.toml
  rigtwin compare session/ --fit-trials 16 --fit-evaluations 90   (slower, closer fit)
  rigtwin compare ../shared/recordings/example-none --rerun save=compare.rrd
      (measured/ and simulated/ channels of every trial in one plot each; rerun compare.rrd)")]
pub struct Args {
    /// Session directory (with session.toml).
    pub session: PathBuf,
    /// Extended model written by `rigtwin diagnose --write-model`.
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Run even if the run is estimated to take more than an hour.
    #[arg(long)]
    pub yes: bool,
    /// Trials replayed by each evaluation of the subject fit.
    #[arg(long, value_name = "N", default_value_t = 8)]
    pub fit_trials: usize,
    /// Evaluations of the subject fit at most.
    #[arg(long, value_name = "N", default_value_t = 45)]
    pub fit_evaluations: usize,
    /// Also send every trial's measured channels (`measured/…`) and its simulated replay's
    /// (`simulated/…`) to the rerun viewer, on the same timelines.
    #[cfg(feature = "rerun")]
    #[command(flatten)]
    pub rerun: rigtwin::viz::RerunArgs,
}

fn mat(m: &[[f64; 2]; 2]) -> String {
    format!(
        "[[{:8.2}, {:8.2}], [{:8.2}, {:8.2}]]",
        m[0][0], m[0][1], m[1][0], m[1][1]
    )
}

/// The table a person reads.
#[must_use]
pub fn table(c: &Comparison, cause: Option<&str>) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "session {}  ({} trials replayed{})\n",
        c.session,
        c.trials,
        cause.map_or(String::new(), |m| format!(", with model: {m}"))
    );
    let f = &c.subject;
    let _ = writeln!(
        out,
        "subject fit (baseline model{}; trials {:?}, {} evaluations{})",
        if c.with_model {
            ", kept for the model run"
        } else {
            ""
        },
        f.fit_trials,
        f.evaluations,
        if f.failed_evaluations > 0 {
            format!(", {} failed", f.failed_evaluations)
        } else {
            String::new()
        }
    );
    let _ = writeln!(
        out,
        "  factors      muscle stiffness {:.3}, co-contraction {:.3}, feedback gain {:.3}; upper arm {:.3}, forearm {:.3} (manifest)",
        f.muscle_stiffness, f.co_contraction, f.feedback_gain, f.upper_arm_factor, f.forearm_factor
    );
    if !f.at_bound.is_empty() {
        let _ = writeln!(
            out,
            "  at bound     {} (not identified within [1/4, 4])",
            f.at_bound.join(", ")
        );
    }
    let _ = writeln!(
        out,
        "  timing       start {:.4} s, duration {:.4} s (plan: {:.2} s, {:.2} s); measured 5 %/95 % travel at {:.4}/{:.4} s over {} trials",
        f.timing.start_s,
        f.timing.duration_s,
        f.nominal_timing.start_s,
        f.nominal_timing.duration_s,
        f.measured_travel_s[0],
        f.measured_travel_s[1],
        f.timing_trials
    );
    let _ = writeln!(
        out,
        "  discrepancy  {:.4} nominal -> {:.4} fitted (RMS of NRMSE: x, y reach; x, y, fx, fy response; noise-free replays)",
        f.discrepancy_nominal, f.discrepancy_fitted
    );
    let _ = writeln!(
        out,
        "  {:<9} {:<9} {:>8} {:>8}",
        "channel", "phase", "nominal", "fitted"
    );
    for r in &f.residuals {
        let _ = writeln!(
            out,
            "  {:<9} {:<9} {:>8.3} {:>8.3}{}",
            r.channel,
            r.phase,
            r.nrmse_nominal,
            r.nrmse_fitted,
            if r.in_objective { "" } else { "  (not fitted)" }
        );
    }
    let _ = writeln!(
        out,
        "\nreplay with the fitted subject\n{:<8} {:<9} {:>12} {:>8} {:>9}",
        "channel", "phase", "RMSE", "NRMSE", "samples"
    );
    for e in &c.channels {
        let _ = writeln!(
            out,
            "{:<8} {:<9} {:>12.4e} {:>8.3} {:>9}",
            e.channel, e.phase, e.rmse, e.nrmse, e.samples
        );
    }
    let _ = writeln!(
        out,
        "\nfrequency content (Welch, band RMS; ratio = simulated/measured band power)\n{:<8} {:>9} {:>12} {:>12} {:>8} {:>12}",
        "channel", "band Hz", "measured", "simulated", "ratio", "diff RMS"
    );
    for b in &c.frequency {
        let _ = writeln!(
            out,
            "{:<8} {:>9} {:>12.4e} {:>12.4e} {:>8.3} {:>12.4e}",
            b.channel,
            format!("{}-{}", b.band_hz[0], b.band_hz[1]),
            b.measured_rms,
            b.simulated_rms,
            b.power_ratio,
            b.diff_rms
        );
    }
    if let Some(i) = &c.impedance {
        let _ = writeln!(
            out,
            "\nestimator (Börner, as `rigtwin estimate`; {} measured, {} simulated force-pulse trials)",
            i.measured.trials, i.simulated.trials
        );
        let _ = writeln!(out, "  D measured  {} N s/m", mat(&i.measured.d_ns_per_m));
        let _ = writeln!(out, "  D simulated {} N s/m", mat(&i.simulated.d_ns_per_m));
        let _ = writeln!(out, "  D sim-meas  {} N s/m", mat(&i.d_diff_ns_per_m));
        let _ = writeln!(out, "  K measured  {} N/m", mat(&i.measured.k_n_per_m));
        let _ = writeln!(out, "  K simulated {} N/m", mat(&i.simulated.k_n_per_m));
        let _ = writeln!(out, "  K sim-meas  {} N/m", mat(&i.k_diff_n_per_m));
    }
    out.push('\n');
    for n in &c.notes {
        let _ = writeln!(out, "note: {n}");
    }
    out
}

/// Runs `rigtwin compare`.
///
/// # Errors
/// A session or model that cannot be read, a replay that fails.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.fit_trials == 0 {
        anyhow::bail!("--fit-trials must be >= 1, got 0");
    }
    let session = Session::read(&args.session)
        .with_context(|| format!("reading session {}", args.session.display()))?;
    if session.manifest.axes != rigtwin::session::Axes::Both {
        return super::not_applicable(
            &args.session,
            &session,
            args.json,
            "compare",
            "compare re-simulates the planar rig with a subject's arm fitted to the session; a rig of one axis has no subject to fit. What applies to it is `rigtwin diagnose`, which judges the axis's own force balance with held-out gains and writes the model it finds",
        );
    }
    let model = args.model.as_deref().map(ExtendedModel::read).transpose()?;
    super::preflight(
        "compare",
        &session,
        super::COMPARE_S_PER_RECORDED_S,
        args.yes,
    )?;
    let mut options = CompareOptions::default();
    options.fit.max_trials = args.fit_trials;
    options.fit.max_evaluations = args.fit_evaluations;
    #[cfg(feature = "rerun")]
    {
        options.keep_simulated = args.rerun.rerun.is_some();
    }
    let c = compare(&session, model.as_ref(), &options)
        .with_context(|| format!("replaying {}", args.session.display()))?;
    #[cfg(feature = "rerun")]
    if let Some(target) = &args.rerun.rerun {
        let id = format!(
            "{}-compare{}",
            rigtwin::viz::recording_id(&session)?,
            if model.is_some() { "-model" } else { "" }
        );
        let mut viewer = rigtwin::viz::Viewer::new(target, "rigtwin", &id)
            .with_context(|| format!("opening --rerun {target}"))?;
        let sent = rigtwin::viz::log_replay_overlay(&mut viewer, &session, &c.simulated)?;
        viewer
            .finish()
            .with_context(|| format!("finishing --rerun {target}"))?;
        errln!(
            "rerun: {} trials, {} measured and {} simulated samples sent to {target} (recording {id})",
            sent.trials,
            sent.measured_samples,
            sent.simulated_samples
        );
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&c)?);
        return Ok(());
    }
    out!("{}", table(&c, model.as_ref().map(|m| m.cause.as_str())));
    Ok(())
}
