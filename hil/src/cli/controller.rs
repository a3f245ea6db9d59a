//! `rigtwin controller`: the rig's controller running a protocol's trials in real time
//! against a plant across the wire, recording the session as the rig records it.

use std::net::{SocketAddr, ToSocketAddrs as _};
use std::time::Duration;

use anyhow::Context as _;
use rigtwin::remote::{self, controller};
use rigtwin_wire::{RigLimits, UdpTransport, WireRig};

use super::link::{LinkArgs, SessionArgs, timing_table};

/// Run the rig's own controller in real time against a plant across the wire (the
/// simulated rig and subject of `rigtwin plant serve`, or a real rig's I/O bridge that
/// speaks the wire protocol, hil/docs/wire.md).
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Examples (two terminals, same protocol and seed on both ends):
  rigtwin plant serve reach-perturb --listen 127.0.0.1:47000 --out out/plant
  rigtwin controller reach-perturb --rig udp://127.0.0.1:47000 --out out/controller --max-trials 4
  rigtwin controller reach-perturb --rig udp://127.0.0.1:47000 --faults drop=0.01,stall=1.5s:50ms

Per trial the controller names the trial in its commands, says hello until the plant's
frames of that trial arrive, then runs the trial at the control rate (4 kHz) on absolute
deadlines. It trips (latched for the trial) on a stale or missing frame after
--stale-ticks, a sequence gap of more than --max-gap frames, the e-stop or a limit.
Output: <out>/session.toml and trials/*.csv (the rig's columns; no ground truth),
<out>/controller.json (per trial: trip, first missed deadline, round trip, tracking
error; the timing), and a timing table (wake-up latency, loop time, missed deadlines)
plus the link's counters.")]
pub struct Args {
    #[command(flatten)]
    pub session: SessionArgs,

    /// The plant: udp://HOST:PORT.
    #[arg(long, value_name = "udp://HOST:PORT")]
    pub rig: String,

    /// How long to wait for the plant's first frame of each trial, s.
    #[arg(long, value_name = "S", default_value_t = 5.0)]
    pub connect_timeout_s: f64,

    /// Most frames lost in one gap before the controller trips.
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub max_gap: u32,

    #[command(flatten)]
    pub link: LinkArgs,
}

/// The plant's address from `udp://HOST:PORT`.
fn parse_rig(rig: &str) -> anyhow::Result<SocketAddr> {
    let Some(rest) = rig.strip_prefix("udp://") else {
        anyhow::bail!("--rig {rig:?}: expected udp://HOST:PORT (e.g. udp://127.0.0.1:47000)");
    };
    rest.to_socket_addrs()
        .with_context(|| format!("--rig {rig:?}: not a HOST:PORT"))?
        .next()
        .with_context(|| format!("--rig {rig:?}: the host has no address"))
}

/// Runs `rigtwin controller`.
///
/// # Errors
/// A bad protocol or argument, an output folder that is not empty, a plant that does
/// not answer, a socket or writer failure.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let (session, out) = args.session.plan("controller", |_| Ok(()))?;
    let protocol = &session.protocol;
    let peer = parse_rig(&args.rig)?;
    if !(args.connect_timeout_s.is_finite() && args.connect_timeout_s > 0.0) {
        anyhow::bail!(
            "--connect-timeout-s {}: must be a positive number of seconds",
            args.connect_timeout_s
        );
    }
    let mut clock = args.link.clock(protocol)?;
    let rate = protocol.control_rate();
    let local: SocketAddr = if peer.is_ipv4() {
        ([0, 0, 0, 0], 0).into()
    } else {
        (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
    };
    let udp = UdpTransport::connect(local, peer)
        .with_context(|| format!("opening a UDP socket to {peer}"))?;
    let transport = remote::with_faults(udp, args.link.faults, args.link.fault_seed, rate);
    let mut rig = WireRig::new(
        transport,
        RigLimits {
            stale_ticks: args.link.stale_ticks,
            max_gap: args.max_gap,
        },
    )?;
    let mut writer =
        session.open_session(&out, |_| format!("controller across the wire to {peer}"))?;
    let bar = super::trial_bar(
        session.plans.len() as u64,
        "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} trials",
    );
    let progress = |done: usize, _total: usize| bar.set_position(done as u64);
    let timeout = Duration::from_secs_f64(args.connect_timeout_s);
    let result = controller::run(
        &session,
        &mut rig,
        &mut clock,
        &mut writer,
        timeout,
        &peer.to_string(),
        &progress,
    );
    bar.finish_and_clear();
    // Whatever happened, keep what was recorded: the timing and the manifest.
    let timing = clock.summary();
    writer.set_timing(timing)?;
    writer.finish()?;
    let run = result.with_context(|| format!("running {} against {peer}", protocol.name))?;
    outln!(
        "trial  trip                                    first missed deadline  round trip  max |x - ref| (x, y)"
    );
    for t in &run.trials {
        let trip = t
            .trip
            .as_ref()
            .map_or_else(|| "-".to_owned(), |(k, why)| format!("tick {k}: {why}"));
        let rt = t
            .round_trip_ticks
            .map_or_else(|| "-".to_owned(), |r| format!("{r} ticks"));
        let miss = t
            .first_miss_tick
            .map_or_else(|| "-".to_owned(), |k| format!("tick {k}"));
        outln!(
            "{:>5}  {:<39} {:>21}  {:>10}  {:.3} / {:.3} mm",
            t.id,
            trip,
            miss,
            rt,
            t.max_tracking_error_m[0] * 1e3,
            t.max_tracking_error_m[1] * 1e3
        );
    }
    let trials: Vec<serde_json::Value> = run
        .trials
        .iter()
        .map(|t| {
            serde_json::json!({
                "id": t.id,
                "trip_tick": t.trip.as_ref().map(|(k, _)| k),
                "trip": t.trip.as_ref().map(|(_, why)| why),
                "first_miss_tick": t.first_miss_tick,
                "round_trip_ticks": t.round_trip_ticks,
                "max_tracking_error_m": t.max_tracking_error_m,
            })
        })
        .collect();
    let json = serde_json::json!({ "trials": trials, "timing": run.timing });
    let path = out.join("controller.json");
    std::fs::write(&path, serde_json::to_string_pretty(&json)? + "\n")
        .with_context(|| format!("writing {}", path.display()))?;
    out!("{}", timing_table("controller", &run.timing));
    outln!("\nlink (controller end): {}", run.link);
    if args.link.faults != rigtwin_wire::FaultSpec::default() {
        outln!(
            "faults injected (controller -> plant): {:?}",
            rig.transport().faults()
        );
    }
    outln!("session: {}", out.display());
    Ok(())
}
