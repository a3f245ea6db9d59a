//! The `rigtwin` command line: one subcommand per module, each with an `Args` struct
//! (clap derive, `after_help` examples) and a `run(&Args) -> anyhow::Result<()>`.
//!
//! To add a subcommand: write `cli/<name>.rs` with `pub struct Args` and `pub fn run`,
//! declare the module below, add a variant to [`Command`] and an arm to [`run`].

use clap::{Parser, Subcommand};

#[macro_use]
pub mod out;
pub mod compare;
pub mod controller;
pub mod diagnose;
pub mod estimate;
pub mod import;
pub mod inspect;
pub mod link;
pub mod plant;
pub mod rehearse;
pub mod sweep;
#[cfg(feature = "rerun")]
pub mod view;

/// rigtwin: a hardware-in-the-loop co-simulation of a planar haptic manipulandum and
/// the human arm that holds it.
#[derive(Debug, Parser)]
#[command(name = "rigtwin", version, about, propagate_version = true)]
#[command(after_help = "\
Examples:
  rigtwin inspect ../shared/recordings/example-none
  rigtwin inspect session/ --json
  rigtwin import log.mat --map map.toml --out session/
  rigtwin rehearse hil/protocols/reach-perturb.toml
  rigtwin estimate ../shared/recordings/example-none
  rigtwin sweep hil/sweeps/pulses.toml
  rigtwin plant serve reach-perturb --listen 127.0.0.1:47000
  rigtwin controller reach-perturb --rig udp://127.0.0.1:47000 --max-trials 4
  rigtwin help inspect")]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Summarise a recorded session: manifest, channels, one line per trial.
    Inspect(inspect::Args),
    /// Turn a lab's measured logs (.mat, CSV/TSV) into a session through a map file.
    Import(import::Args),
    /// Rehearse a protocol against virtual subjects: sessions plus a report.
    Rehearse(rehearse::Args),
    /// Estimate impedance from a session's perturbed trials (measured or simulated).
    Estimate(estimate::Args),
    /// Name the plant or human effect the nominal model misses in a measured session.
    Diagnose(diagnose::Args),
    /// Replay a session in simulation: the fitted subject, error per channel, phase and band,
    /// D and K measured vs simulated.
    ///
    /// Replays every trial of a session in simulation with the session's own inputs (device
    /// admittance, handle mass, subject geometry, start and goal, perturbation angle) and
    /// shows what the simulation gets wrong.
    ///
    /// First the baseline subject is fitted to the session: muscle stiffness, co-contraction
    /// and feedback gain factors (Nelder-Mead on noise-free replays of 8 perturbed trials,
    /// minimising the RMS of the NRMSEs of x, y over the reach and x, y, fx, fy over the
    /// 150 ms response) and the reach timing (read from the measured 5 % and 95 % travel
    /// times). Then every trial is
    /// replayed with the fitted subject and the model's seeded motor and sensor noise, and
    /// the report gives, per channel: RMSE and NRMSE over the whole reach and over the
    /// 150 ms perturbation response; band RMS of measured, simulated and their difference in
    /// 0-2, 2-8 and 8-30 Hz (Welch); and the Börner estimate of D and K on the measured and
    /// on the simulated trials. With --model, the subject fitted to the baseline is kept and
    /// the model's plant and human-side effects are added, so the two runs differ by the
    /// model alone.
    Compare(compare::Args),
    /// Sweep a protocol's choices over a population of simulated subjects, locally, as a
    /// shard of a job array, or as a Slurm job array (`--emit slurm`); `sweep merge`.
    Sweep(sweep::Args),
    /// Run the rig's controller in real time against a plant across the wire (UDP).
    Controller(controller::Args),
    /// The simulated rig and subject as a plant across the wire: `plant serve`.
    Plant(plant::Args),
    /// Show a recorded session in the rerun viewer (live, or saved to an .rrd).
    #[cfg(feature = "rerun")]
    View(view::Args),
}

/// A progress bar of `len` trials on stderr with `template`, hidden when stderr is not
/// a terminal (a log file gets no bar).
pub fn trial_bar(len: u64, template: &str) -> indicatif::ProgressBar {
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    use std::io::IsTerminal as _;
    let bar = ProgressBar::new(len);
    if std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template(template) {
            bar.set_style(style);
        }
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar
}

/// Runs the parsed command line.
///
/// # Errors
/// Whatever the subcommand reports; `main` prints it with its causes.
pub fn run(cli: &Cli) -> anyhow::Result<()> {
    match &cli.command {
        Command::Inspect(args) => inspect::run(args),
        Command::Import(args) => import::run(args),
        Command::Rehearse(args) => rehearse::run(args),
        Command::Estimate(args) => estimate::run(args),
        Command::Diagnose(args) => diagnose::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::Controller(args) => controller::run(args),
        Command::Plant(args) => plant::run(args),
        #[cfg(feature = "rerun")]
        Command::View(args) => view::run(args),
    }
}

/// Says on stdout that nothing of command `what` applies to `session` (a rig of one
/// axis), why (`reason`), and succeeds: the session is valid, and a script looping over
/// a lab's sessions must not stop on it. With `json`, `{"applicable": false, ...}`.
///
/// # Errors
/// Standard output cannot be written.
pub fn not_applicable(
    path: &std::path::Path,
    session: &rigtwin::session::Session,
    json: bool,
    what: &str,
    reason: &str,
) -> anyhow::Result<()> {
    use anyhow::Context as _;
    use std::io::Write as _;
    let axes = session.manifest.axes.names();
    let text = if json {
        serde_json::to_string_pretty(&serde_json::json!({
            "session": path.display().to_string(),
            "axes": axes,
            "applicable": false,
            "reason": reason,
        }))
        .context("formatting the answer as JSON")?
    } else {
        format!(
            "session {}: one axis ({}); nothing to {what}: {reason}",
            path.display(),
            axes.join("")
        )
    };
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}").context("writing to standard output")
}

/// Wall time per second of recording, s: `diagnose` (measured 4.9 s for the 112 s of
/// `example-none` and 44 s for a ten-minute servo log, beside another build) and `compare`
/// (13.6 s for `example-none`), rounded up so the estimate errs long.
pub const DIAGNOSE_S_PER_RECORDED_S: f64 = 0.1;
/// See [`DIAGNOSE_S_PER_RECORDED_S`].
pub const COMPARE_S_PER_RECORDED_S: f64 = 0.15;

/// Past this estimated wall time, `diagnose` and `compare` ask for `--yes`, s (an hour).
pub const CONFIRM_WALL_S: f64 = 3600.0;

/// Says on stderr what `what` will cost on `session` (trials, recorded time, samples and
/// an estimate of wall time at `s_per_recorded_s`), and refuses past [`CONFIRM_WALL_S`]
/// unless `yes`.
///
/// # Errors
/// The run is past the limit and not confirmed; stderr cannot be written.
pub fn preflight(
    what: &str,
    session: &rigtwin::session::Session,
    s_per_recorded_s: f64,
    yes: bool,
) -> anyhow::Result<()> {
    let recorded_s: f64 = session
        .trials
        .iter()
        .map(rigtwin::session::Trial::end_s)
        .sum();
    let samples: usize = session
        .trials
        .iter()
        .map(rigtwin::session::Trial::len)
        .sum();
    let wall_s = recorded_s * s_per_recorded_s;
    errln!(
        "{what}: {} trials, {} recorded ({samples} samples); about {}",
        session.trials.len(),
        rigtwin::rehearse::cost::duration(recorded_s),
        rigtwin::rehearse::cost::duration(wall_s)
    );
    if wall_s > CONFIRM_WALL_S && !yes {
        anyhow::bail!(
            "not started: {what} would take about {}, more than the {} a run may take unconfirmed; add --yes to run it",
            rigtwin::rehearse::cost::duration(wall_s),
            rigtwin::rehearse::cost::duration(CONFIRM_WALL_S)
        );
    }
    Ok(())
}
