//! `rigtwin view`: a recorded session, measured or simulated, in the rerun viewer.

use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::protocol::EstimateConfig;
use rigtwin::session::Session;
use rigtwin::viz::{self, RerunArgs, Target, Viewer};

/// Show a recorded session (measured or simulated) in the rerun viewer: the rig and the arm
/// in 2D, every channel as a time series, perturbation responses, events, and the impedance
/// ellipses of the estimator `rigtwin estimate` runs on it (estimate only: a recorded session
/// has no ground truth).
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin view recordings/example-friction                      # spawns a viewer
  rigtwin view recordings/example-friction --rerun save=f.rrd   # then: rerun f.rrd
  rigtwin view runs/sim-001 --rerun connect=127.0.0.1:9876

Timelines: tick (4 kHz ticks, trials back to back), time (s), trial (index).
Without arm angles in the trials, the arm is solved from the handle path and the
subject's shoulder and segment lengths (right arm, elbow to the right).")]
pub struct Args {
    /// Session directory (holds session.toml and trials/).
    pub session: PathBuf,

    #[command(flatten)]
    pub rerun: RerunArgs,

    /// Highest sample rate sent to a live viewer, Hz (a saved file holds every sample).
    #[arg(long, value_name = "HZ", default_value_t = viz::DEFAULT_LIVE_RATE_HZ)]
    pub live_rate_hz: f64,
}

/// What [`stream_session`] sent.
pub struct Streamed {
    /// The trials and samples.
    pub logged: viz::Logged,
    /// The estimates drawn.
    pub estimates: viz::EstimatesLogged,
    /// The recording id.
    pub recording_id: String,
}

/// Streams a session to `target`: its samples ([`viz::log_session`]) and the impedance
/// ellipses of the estimator `rigtwin estimate` runs on it, with `config` (Börner) or
/// `m_hat_kg` (windowed regression). Shared by `view`, `inspect` and `estimate`.
pub fn stream_session(
    target: &Target,
    session: &Session,
    live_rate_hz: f64,
    config: &EstimateConfig,
    m_hat_kg: Option<f64>,
) -> anyhow::Result<Streamed> {
    let recording_id = viz::recording_id(session)?;
    let mut viewer = Viewer::new(target, "rigtwin", &recording_id)
        .with_context(|| format!("opening --rerun {target}"))?;
    viewer.set_live_rate_hz(live_rate_hz)?;
    let logged = viz::log_session(&mut viewer, session)?;
    let estimates =
        viz::log_session_estimates(&mut viewer, session, &logged.spans, config, m_hat_kg)?;
    viewer
        .finish()
        .with_context(|| format!("finishing --rerun {target}"))?;
    Ok(Streamed {
        logged,
        estimates,
        recording_id,
    })
}

/// One line saying where the viewer data went.
/// Says what went to the viewer: on stdout, or on stderr under `--json` (stdout stays
/// JSON-only).
///
/// # Errors
/// A failed write to the stream, named.
pub fn report_streamed(
    streamed: &Streamed,
    target: &Target,
    json: bool,
) -> Result<(), super::out::OutputError> {
    let line = format!(
        "viewer: {} samples, recording {}\n{}",
        streamed.logged.samples,
        streamed.recording_id,
        target_line(target)
    );
    if json {
        errln!("{line}");
    } else {
        outln!("{line}");
    }
    Ok(())
}

/// What `--rerun` will have produced, in one line.
pub fn target_line(target: &Target) -> String {
    match target {
        Target::Save(path) => {
            let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            format!(
                "written    {} ({:.1} MB); open it with: rerun {}",
                path.display(),
                size as f64 / 1e6,
                path.display()
            )
        }
        Target::Spawn | Target::Connect(_) => format!("streamed   {target}"),
    }
}

/// Runs `rigtwin view`. Without `--rerun` a viewer is spawned.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let target = args.rerun.rerun.clone().unwrap_or(Target::Spawn);
    let session = Session::read(&args.session)
        .with_context(|| format!("reading session {}", args.session.display()))?;
    let Streamed {
        logged,
        estimates,
        recording_id,
    } = stream_session(
        &target,
        &session,
        args.live_rate_hz,
        &EstimateConfig::default(),
        None,
    )?;

    let manifest = &session.manifest;
    outln!(
        "session    {} ({}, {} trials, {} perturbed, {:.0} Hz)",
        manifest.subject.id,
        manifest.source.as_str(),
        logged.trials,
        logged.perturbed,
        manifest.rate_hz
    );
    outln!("samples    {}", logged.samples);
    let arm = if !logged.arm {
        "not drawn (no segment lengths in the manifest)".to_owned()
    } else if logged.out_of_reach > 0 {
        format!(
            "drawn; {} samples out of reach, shown stretched",
            logged.out_of_reach
        )
    } else {
        "drawn".to_owned()
    };
    outln!("arm        {arm}");
    let ellipses = match (estimates.borner, estimates.windows) {
        (0, 0) => "none (nothing to estimate; see the event log)".to_owned(),
        (0, w) => format!("{w} windowed-regression windows (001_*)"),
        (_, _) => "Börner session estimate (000_*)".to_owned(),
    };
    outln!("ellipses   {ellipses}");
    outln!("recording  {recording_id}");
    outln!("{}", target_line(&target));
    Ok(())
}
