//! `rigtwin compare`: replay a session in simulation and say, per channel and phase,
//! how far the simulation is from the measurement.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::discrepancy::{ExtendedModel, compare};
use rigtwin::session::Session;

/// Replay every trial of a session in simulation with the session's own inputs (device
/// admittance, handle mass, subject geometry, start and goal, perturbation angle), with
/// the plant effects of an extended model if --model is given, and report the error of
/// x, y, fx, fy over the whole reach and over the 150 ms perturbation response.
#[derive(Debug, Clone, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin compare ../shared/recordings/example-none
  rigtwin diagnose ../shared/recordings/example-friction --write-model model.toml
  rigtwin compare ../shared/recordings/example-friction --model model.toml --json")]
pub struct Args {
    /// Session directory (with session.toml).
    pub session: PathBuf,
    /// Extended model written by `rigtwin diagnose --write-model`.
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `rigtwin compare`.
///
/// # Errors
/// A session or model that cannot be read, a replay that fails.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let session = Session::read(&args.session)
        .with_context(|| format!("reading session {}", args.session.display()))?;
    let model = args.model.as_deref().map(ExtendedModel::read).transpose()?;
    let c = compare(&session, model.as_ref().map(|m| &m.effects))
        .with_context(|| format!("replaying {}", args.session.display()))?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
        return Ok(());
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "session {}  ({} trials replayed{})\n",
        c.session,
        c.trials,
        model
            .as_ref()
            .map_or(String::new(), |m| format!(", with model: {}", m.cause))
    );
    let _ = writeln!(
        out,
        "{:<8} {:<9} {:>12} {:>8} {:>9}",
        "channel", "phase", "RMSE", "NRMSE", "samples"
    );
    for e in &c.channels {
        let _ = writeln!(
            out,
            "{:<8} {:<9} {:>12.4e} {:>8.3} {:>9}",
            e.channel, e.phase, e.rmse, e.nrmse, e.samples
        );
    }
    for n in &c.notes {
        let _ = writeln!(out, "note: {n}");
    }
    print!("{out}");
    Ok(())
}
