//! What both ends of the wire take on the command line: the session (protocol, seed,
//! trials, output), the link's faults and watchdog, the real-time requests, and the way
//! a run's clock is printed.

use std::path::PathBuf;
use std::time::Duration;

use rigtwin::cosim::WallClock;
use rigtwin::protocol::Protocol;
use rigtwin::rehearse;
use rigtwin::remote::SessionPlan;
use rigtwin::report::{SubjectTiming, timing_text};
use rigtwin::session::Timing;
use rigtwin_wire::FaultSpec;

/// What both ends run: the protocol, its seed, the trials and where the session goes.
#[derive(Debug, Clone, clap::Args)]
pub struct SessionArgs {
    /// Protocol file (TOML), or the name of a shipped protocol.
    pub protocol: PathBuf,

    /// Session seed (default: the protocol's `seed`); the same on both ends.
    #[arg(long, value_name = "S", value_parser = clap::value_parser!(u64).range(..=i64::MAX.cast_unsigned()))]
    pub seed: Option<u64>,

    /// Output session folder; must not exist or be empty. Default: a fresh
    /// `out/<name>-<controller|plant>-<seed>[-k]/`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,

    /// Run only the first N trials of the schedule.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_trials: Option<u32>,
}

impl SessionArgs {
    /// The protocol (`edit` applies a model to it), the session plan, and the output
    /// folder of this end (`role`: "controller" or "plant").
    pub fn plan(
        &self,
        role: &str,
        edit: impl FnOnce(&mut Protocol) -> anyhow::Result<()>,
    ) -> anyhow::Result<(SessionPlan, PathBuf)> {
        let mut protocol = Protocol::load(&self.protocol)?;
        edit(&mut protocol)?;
        let seed = self.seed.unwrap_or(protocol.seed);
        let out = match &self.out {
            Some(d) => d.clone(),
            None => rehearse::fresh_dir(
                std::path::Path::new("out"),
                &format!("{}-{role}", protocol.name),
                seed,
            ),
        };
        let plan = SessionPlan::new(protocol, seed, self.max_trials.map(|m| m as usize))?;
        Ok((plan, out))
    }
}

/// The link and the loop's real-time requests.
#[derive(Debug, Clone, clap::Args)]
pub struct LinkArgs {
    /// Faults injected on this end's sending side, seeded (hil/docs/wire.md):
    /// e.g. drop=0.01,delay_ticks=2,duplicate=0.001,reorder=0.001,stall=1.5s:50ms
    #[arg(long, value_name = "SPEC", default_value = "none")]
    pub faults: FaultSpec,

    /// Seed of the fault injector.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub fault_seed: u64,

    /// Watchdog: ticks without a fresh datagram from the other end at which this end
    /// reacts (the plant zeroes the force, the controller trips). 4 ticks = 1 ms.
    #[arg(long, value_name = "TICKS", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    pub stale_ticks: u32,

    /// Run the loop's thread under SCHED_FIFO at this priority (1-99).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(1..=99))]
    pub rt_priority: Option<u8>,

    /// Lock the process's memory in RAM (mlockall).
    #[arg(long)]
    pub lock_memory: bool,

    /// Spin on the clock this many microseconds before each deadline instead of
    /// sleeping (removes the kernel's wake-up latency; costs that much CPU).
    #[arg(long, value_name = "US", default_value_t = 0)]
    pub spin_us: u64,
}

impl LinkArgs {
    /// The wall clock at the protocol's control rate, with the OS requests made (each
    /// refusal is one line on stderr; the run goes on without it).
    pub fn clock(&self, protocol: &Protocol) -> anyhow::Result<WallClock> {
        if self.lock_memory
            && let Err(note) = rigtwin::cosim::rt::lock_memory()
        {
            errln!("{note}");
        }
        if let Some(p) = self.rt_priority
            && let Err(note) = rigtwin::cosim::rt::set_fifo_priority(p)
        {
            errln!("{note}");
        }
        Ok(WallClock::new(
            protocol.control_rate(),
            Duration::from_micros(self.spin_us),
        )?)
    }
}

/// The timing table of one loop (`who`: "controller" or "plant").
pub fn timing_table(who: &str, timing: &Timing) -> String {
    timing_text(&[SubjectTiming {
        subject: who.to_owned(),
        timing: *timing,
    }])
}
