//! `rigtwin view`: a recorded session, measured or simulated, in the rerun viewer.

use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::session::Session;
use rigtwin::viz::{self, RerunArgs, Target, Viewer};

/// Show a recorded session (measured or simulated) in the rerun viewer: the rig and the arm
/// in 2D, every channel as a time series, perturbation responses and events.
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

/// Runs `rigtwin view`. Without `--rerun` a viewer is spawned.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let target = args.rerun.rerun.clone().unwrap_or(Target::Spawn);
    let session = Session::read(&args.session)
        .with_context(|| format!("reading session {}", args.session.display()))?;
    let recording_id = viz::recording_id(&session)?;
    let mut viewer = Viewer::new(&target, "rigtwin", &recording_id)
        .with_context(|| format!("opening --rerun {target}"))?;
    viewer.set_live_rate_hz(args.live_rate_hz)?;
    let logged = viz::log_session(&mut viewer, &session)?;
    viewer
        .finish()
        .with_context(|| format!("finishing --rerun {target}"))?;

    let manifest = &session.manifest;
    println!(
        "session    {} ({}, {} trials, {} perturbed, {:.0} Hz)",
        manifest.subject.id,
        manifest.source.as_str(),
        logged.trials,
        logged.perturbed,
        manifest.rate_hz
    );
    println!("samples    {}", logged.samples);
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
    println!("arm        {arm}");
    println!("recording  {recording_id}");
    match &target {
        Target::Save(path) => {
            let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            println!(
                "written    {} ({:.1} MB); open it with: rerun {}",
                path.display(),
                size as f64 / 1e6,
                path.display()
            );
        }
        Target::Spawn | Target::Connect(_) => println!("streamed   {target}"),
    }
    Ok(())
}
