//! `rigtwin plant serve`: the simulated rig and subject as a plant across the wire.

use super::out;
use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::rehearse::TICK_HZ;
use rigtwin::remote::{self, serve};
use rigtwin_diagnose::ExtendedModel;
use rigtwin_wire::{PlantEnd, PlantLimits, UdpTransport};

use super::link::{LinkArgs, SessionArgs, timing_table};

/// The plant side of hardware in the loop.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub command: PlantCommand,
}

/// The plant's subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum PlantCommand {
    /// Serve the simulated rig and subject over the wire protocol (hil/docs/wire.md).
    Serve(ServeArgs),
}

/// Serve the protocol's simulated rig and subject (world + arm, the protocol's plant,
/// subject and effects) over UDP, stepping at the control rate (4 kHz) on the plant's
/// own clock: a sensor frame out every tick, the newest command applied.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin plant serve reach-perturb --listen 127.0.0.1:47000 --out out/plant
  rigtwin plant serve reach-perturb --listen 127.0.0.1:0          # any free port; printed
  rigtwin plant serve my-protocol.toml --listen 0.0.0.0:47000 --model model.toml
  python3 hil/examples/pd_client.py --plant 127.0.0.1:47000 --seconds 5   # a lab's own controller

The plant learns its controller from the first valid command and sets up the trial the
commands name (the `trial` field; 1 = the schedule's first). It zeroes the motor force
after --stale-ticks ticks without a command (flag in every frame) and applies force only
while the controller is active. It stops when every trial of the schedule is recorded,
or after --idle-timeout-s without a command (0: never).
Output: <out>/session.toml and trials/*.csv with the plant's true state (true handle
position and velocity, the hand's force, the applied motor force), and a timing table.")]
pub struct ServeArgs {
    #[command(flatten)]
    pub session: SessionArgs,

    /// Address to listen on, HOST:PORT (port 0: any free port, printed at start).
    #[arg(long, value_name = "HOST:PORT")]
    pub listen: SocketAddr,

    /// Stop after this long without a command, s (0: never).
    #[arg(long, value_name = "S", default_value_t = 30.0)]
    pub idle_timeout_s: f64,

    /// Press the simulated e-stop this long into every trial, s (rehearses the safety
    /// chain; the e-stop latency is reported).
    #[arg(long, value_name = "S")]
    pub estop_at_s: Option<f64>,

    /// Extended model (`rigtwin diagnose --write-model`): its plant effects and stretch
    /// reflex replace the protocol's.
    #[arg(long, value_name = "MODEL.toml")]
    pub model: Option<PathBuf>,

    #[command(flatten)]
    pub link: LinkArgs,
}

/// Runs `rigtwin plant ...`.
///
/// # Errors
/// As [`serve_run`].
pub fn run(args: &Args) -> anyhow::Result<()> {
    match &args.command {
        PlantCommand::Serve(a) => serve_run(a),
    }
}

fn seconds_to_ticks(flag: &str, s: f64) -> anyhow::Result<u64> {
    if !(0.0..=86_400.0).contains(&s) {
        anyhow::bail!("{flag} {s}: must be between 0 and 86400 s");
    }
    Ok((s * TICK_HZ as f64).round() as u64)
}

/// Runs `rigtwin plant serve`.
///
/// # Errors
/// A bad protocol, model or argument, an output folder that is not empty, a socket that
/// cannot be bound, a plant that diverges or a writer failure.
pub fn serve_run(args: &ServeArgs) -> anyhow::Result<()> {
    let (session, out) = args.session.plan("plant", |protocol| {
        if let Some(path) = &args.model {
            let model = ExtendedModel::read(path)?;
            model.apply_to(
                &mut protocol.plant.effects,
                &mut protocol.subjects.arm.stretch_reflex,
            );
        }
        Ok(())
    })?;
    let protocol = &session.protocol;
    let seed = session.seed;
    let idle = seconds_to_ticks("--idle-timeout-s", args.idle_timeout_s)?;
    let estop_at_tick = args
        .estop_at_s
        .map(|s| seconds_to_ticks("--estop-at-s", s))
        .transpose()?;
    let udp = UdpTransport::listen(args.listen)
        .with_context(|| format!("listening on {}", args.listen))?;
    let bound = udp.local_addr()?;
    let mut clock = args.link.clock(protocol)?;
    let rate = protocol.control_rate();
    let transport = remote::with_faults(udp, args.link.faults, args.link.fault_seed, rate);
    let mut end = PlantEnd::new(
        transport,
        PlantLimits {
            stale_ticks: args.link.stale_ticks,
        },
    )?;
    let mut writer = session.open_session(&out, |model| {
        format!(
            "{} behind the wire (plant serve): the plant's true state",
            model.unwrap_or("rigtwin plant")
        )
    })?;
    // The address first, on its own line, so a script that asked for port 0 can read it.
    errln!("listening on {bound}");
    errln!(
        "serving {} trials of {} (seed {seed}); waiting for a controller",
        session.plans.len(),
        protocol.name
    );
    // A trial's line that cannot be written must not stop the loop mid-trial: the first
    // failure is kept and returned once the session is closed.
    let mut lost_line = None;
    let mut on_trial = |id: u32| {
        use std::io::Write as _;
        if let Err(e) = out::checked("error", writeln!(std::io::stderr().lock(), "trial {id}")) {
            lost_line.get_or_insert(e);
        }
    };
    let result = serve::serve(
        &session,
        &mut end,
        &mut clock,
        &mut writer,
        serve::ServeOptions {
            idle_ticks: (idle > 0).then_some(idle),
            estop_at_tick,
        },
        &mut on_trial,
    );
    let timing = clock.summary();
    writer.set_timing(timing)?;
    writer.finish()?;
    let report = result.with_context(|| format!("serving {} on {bound}", protocol.name))?;
    if let Some(e) = lost_line {
        return Err(e.into());
    }
    let why = match report.end {
        serve::ServeEnd::AllTrials => "every trial recorded",
        serve::ServeEnd::Idle => "no command for the idle time",
    };
    outln!(
        "plant: {} trials recorded ({why}); {} ticks, {} with the command watchdog zeroing the force",
        report.recorded.len(),
        report.ticks,
        report.watchdog_ticks
    );
    for (id, tick) in &report.first_stall {
        outln!(
            "trial {id}: first stall ({} or more ticks without a fresh command) at tick {tick} ({:.3} s)",
            serve::STALL_TICKS,
            *tick as f64 / TICK_HZ as f64
        );
    }
    if !report.cut_short.is_empty() {
        outln!("cut short by the controller: trials {:?}", report.cut_short);
    }
    if report.unknown_trial_commands > 0 {
        outln!(
            "commands naming a trial the schedule does not have: {}",
            report.unknown_trial_commands
        );
    }
    if !report.estop_latency_ticks.is_empty() {
        let mut l = report.estop_latency_ticks.clone();
        l.sort_unstable();
        let q = |p: f64| l[((l.len() - 1) as f64 * p).round() as usize];
        outln!(
            "e-stop to zero force at the plant, over {} presses: p50 {} / p99 {} / max {} ticks ({:.2} / {:.2} / {:.2} ms)",
            l.len(),
            q(0.5),
            q(0.99),
            q(1.0),
            q(0.5) as f64 * 1e3 / TICK_HZ as f64,
            q(0.99) as f64 * 1e3 / TICK_HZ as f64,
            q(1.0) as f64 * 1e3 / TICK_HZ as f64
        );
    }
    out!("{}", timing_table("plant", &timing));
    outln!("\nlink (plant end): {}", report.link);
    if args.link.faults != rigtwin_wire::FaultSpec::default() {
        outln!(
            "faults injected (plant -> controller): {:?}",
            end.transport().faults()
        );
    }
    outln!("session: {}", out.display());
    Ok(())
}
