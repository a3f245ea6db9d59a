//! The clock a co-simulation loop runs on: lock step (as fast as the machine goes, for
//! rehearsals and CI) or the wall clock (real time, for hardware in the loop).
//!
//! A loop asks the clock for the tick `n` it means to run next; the clock returns the
//! tick that is due. Lock step returns `n`. The wall clock sleeps until tick `n`'s
//! absolute deadline (`start + n · period` on `CLOCK_MONOTONIC`, `clock_nanosleep` with
//! `TIMER_ABSTIME`, so sleeping never accumulates drift) and, if it woke up after the
//! deadline of tick `n + 1` or later, returns the latest tick that is due: the loop skips
//! ahead instead of running the missed ticks in a burst, and the misses are counted. The
//! controller sees the gap and trips when it is longer than its
//! `safety.max_consecutive_misses`, as a rig's real-time layer would.
//!
//! The wall clock records, for every tick it returns, the wake-up latency (now − the
//! returned tick's deadline) and the loop time (from one wake-up to the next request) in
//! HDR histograms of 3 significant digits from 1 ns to 10 s, which do not allocate once
//! built.

use std::time::Duration;

use hdrhistogram::Histogram;
use nix::time::{ClockId, ClockNanosleepFlags, clock_gettime, clock_nanosleep};
use rigtwin_device::{Rate, Tick};

use crate::session::{Percentiles, Timing};

/// What paces a co-simulation loop.
pub trait Clock {
    /// Waits for tick `next` (the loop's next tick) and returns the tick that is due:
    /// `next`, or a later one up to `last` (the run's final tick) if deadlines were
    /// missed.
    fn wait(&mut self, next: Tick, last: Tick) -> Tick;

    /// Counts the deadlines from the next [`Clock::wait`] on, as if that moment were the
    /// next tick's deadline: time spent outside the loop (building a trial) is neither
    /// a missed deadline nor a reason to catch up. Nothing for a clock without
    /// deadlines.
    fn resync(&mut self) {}

    /// The wake-up latency of the tick the last [`Clock::wait`] returned, ns; `None` for
    /// a clock without deadlines.
    fn last_wake_latency_ns(&self) -> Option<u64> {
        None
    }
}

/// Lock step: every tick is due at once. Nothing is measured.
#[derive(Debug, Clone, Copy, Default)]
pub struct LockStep;

impl Clock for LockStep {
    fn wait(&mut self, next: Tick, _last: Tick) -> Tick {
        next
    }
}

/// Why the wall clock could not be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ClockError {
    /// The monotonic clock could not be read.
    #[error("reading CLOCK_MONOTONIC: {0}")]
    Monotonic(nix::Error),
    /// The histograms could not be built (never for the fixed bounds used here).
    #[error("timing histogram: {0}")]
    Histogram(String),
}

/// Real time: ticks at absolute deadlines of the monotonic clock.
#[derive(Debug)]
pub struct WallClock {
    period_ns: u64,
    /// Nanoseconds before a deadline at which sleeping stops and spinning starts.
    spin_ns: u64,
    start_ns: Option<u64>,
    last_wake_ns: Option<u64>,
    wake: Histogram<u64>,
    loop_time: Histogram<u64>,
    missed: u64,
    run_of_misses: u64,
    longest_run: u64,
    ticks: u64,
    first_miss: Option<Tick>,
    last_latency_ns: Option<u64>,
}

/// Largest value the histograms hold, ns (10 s): anything longer is recorded as 10 s.
const HIST_MAX_NS: u64 = 10_000_000_000;

fn now_ns() -> Result<u64, ClockError> {
    let t = clock_gettime(ClockId::CLOCK_MONOTONIC).map_err(ClockError::Monotonic)?;
    Ok(t.tv_sec() as u64 * 1_000_000_000 + t.tv_nsec() as u64)
}

impl WallClock {
    /// A clock ticking at `rate`. `spin`: how long before each deadline to stop sleeping
    /// and spin on the clock instead (zero: sleep only; a spin of tens of microseconds
    /// removes the kernel's wake-up latency at the cost of that much CPU per tick).
    /// The first deadline is the moment of the first [`Clock::wait`].
    ///
    /// # Errors
    /// [`ClockError`] if the monotonic clock cannot be read.
    pub fn new(rate: Rate, spin: Duration) -> Result<WallClock, ClockError> {
        now_ns()?;
        let hist = || {
            Histogram::<u64>::new_with_bounds(1, HIST_MAX_NS, 3)
                .map_err(|e| ClockError::Histogram(e.to_string()))
        };
        Ok(WallClock {
            period_ns: 1_000_000_000 / u64::from(rate.hz()),
            spin_ns: u64::try_from(spin.as_nanos()).unwrap_or(u64::MAX),
            start_ns: None,
            last_wake_ns: None,
            wake: hist()?,
            loop_time: hist()?,
            missed: 0,
            run_of_misses: 0,
            longest_run: 0,
            ticks: 0,
            first_miss: None,
            last_latency_ns: None,
        })
    }

    fn sleep_until(&self, deadline_ns: u64) {
        let sleep_to = deadline_ns.saturating_sub(self.spin_ns);
        let ts = nix::sys::time::TimeSpec::from(Duration::from_nanos(sleep_to));
        // EINTR: sleep again to the same absolute deadline.
        while let Err(nix::Error::EINTR) = clock_nanosleep(
            ClockId::CLOCK_MONOTONIC,
            ClockNanosleepFlags::TIMER_ABSTIME,
            &ts,
        ) {}
        if self.spin_ns > 0 {
            while now_ns().is_ok_and(|t| t < deadline_ns) {
                std::hint::spin_loop();
            }
        }
    }

    /// Starts a new run (a new trial, whose ticks count from 0 again): the next
    /// [`Clock::wait`] sets the first deadline. The histograms and counts go on, so one
    /// clock measures a whole session; the pause between runs is not a loop time. The
    /// run's first miss is forgotten.
    pub fn restart(&mut self) {
        self.start_ns = None;
        self.last_wake_ns = None;
        self.run_of_misses = 0;
        self.first_miss = None;
    }

    /// The period between deadlines.
    #[must_use]
    pub fn period(&self) -> Duration {
        Duration::from_nanos(self.period_ns)
    }

    /// The first tick of this run whose deadline was missed (skipped), if any: up to it
    /// the run was paced exactly.
    #[must_use]
    pub fn first_miss(&self) -> Option<Tick> {
        self.first_miss
    }

    /// The timing so far.
    #[must_use]
    pub fn summary(&self) -> Timing {
        Timing {
            period_us: self.period_ns as f64 / 1000.0,
            ticks: self.ticks,
            missed_deadlines: self.missed,
            max_consecutive_misses: self.longest_run,
            wake_latency: percentiles(&self.wake),
            loop_time: percentiles(&self.loop_time),
        }
    }
}

impl Clock for WallClock {
    fn resync(&mut self) {
        self.restart();
    }

    fn last_wake_latency_ns(&self) -> Option<u64> {
        self.last_latency_ns
    }

    fn wait(&mut self, next: Tick, last: Tick) -> Tick {
        let Ok(t) = now_ns() else {
            // CLOCK_MONOTONIC was readable in `new`; it does not go away. Should it, run
            // the tick unpaced rather than stop a loop that holds a subject.
            return next;
        };
        if let Some(w) = self.last_wake_ns {
            self.loop_time.saturating_record(t.saturating_sub(w).max(1));
        }
        let start = *self
            .start_ns
            .get_or_insert(t.saturating_sub(next.0 * self.period_ns));
        let deadline = start + next.0 * self.period_ns;
        if t < deadline {
            self.sleep_until(deadline);
        }
        let woke = now_ns().unwrap_or(deadline);
        // The latest tick whose deadline has passed.
        let due = next.0.max(((woke - start) / self.period_ns).min(last.0));
        let skipped = due - next.0;
        self.missed += skipped;
        if skipped > 0 {
            self.first_miss.get_or_insert(next);
            self.run_of_misses += skipped;
            self.longest_run = self.longest_run.max(self.run_of_misses);
        } else {
            self.run_of_misses = 0;
        }
        let latency = woke.saturating_sub(start + due * self.period_ns);
        self.wake.saturating_record(latency.max(1));
        self.last_latency_ns = Some(latency);
        self.last_wake_ns = Some(woke);
        self.ticks += 1;
        Tick(due)
    }
}

fn percentiles(h: &Histogram<u64>) -> Percentiles {
    let us = |ns: u64| ns as f64 / 1000.0;
    if h.is_empty() {
        return Percentiles::default();
    }
    Percentiles {
        p50_us: us(h.value_at_quantile(0.5)),
        p99_us: us(h.value_at_quantile(0.99)),
        p999_us: us(h.value_at_quantile(0.999)),
        max_us: us(h.max()),
    }
}
