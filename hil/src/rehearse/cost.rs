//! What a rehearsal will cost, said before it starts: trials, simulated time, samples,
//! disk, memory and an estimate of wall time, and the limits past which a run is refused
//! unless the user confirms it (`rigtwin rehearse --yes`).
//!
//! The wall-time estimate uses [`SIM_S_PER_WALL_S_PER_JOB`], measured on this project's
//! CI machine class: `rigtwin rehearse reach-perturb --max-trials 8 --jobs 1` simulates
//! 28 s in 0.77 s (36× real time) with another build on the second core; 30 is taken so
//! the estimate errs long. A real-time run takes its simulated time.

use std::fmt;

use crate::protocol::Protocol;

/// Simulated seconds per wall-clock second per worker in lock step (see the module doc).
pub const SIM_S_PER_WALL_S_PER_JOB: f64 = 30.0;

/// Bytes per recorded field in a trial table (`0.0123456,` and the like): measured 7.7 on
/// `reach-perturb`'s tables (131 bytes a row of 17 columns).
pub const BYTES_PER_FIELD: f64 = 8.0;

/// Runs that simulate more than this are refused unless confirmed, s (a day).
pub const CONFIRM_SIMULATED_S: f64 = 86_400.0;

/// Runs that would write more than this are refused unless confirmed, bytes (10 GB).
pub const CONFIRM_DISK_BYTES: f64 = 10.0e9;

/// Columns of a rehearsed table: the format's 13 and, with `truth_columns`, 4 more.
fn columns(protocol: &Protocol) -> f64 {
    if protocol.recording.truth_columns {
        17.0
    } else {
        13.0
    }
}

/// The cost of one rehearsal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cost {
    /// Trials over all subjects.
    pub trials: u64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Control ticks simulated.
    pub ticks: f64,
    /// Rows written.
    pub rows: f64,
    /// Bytes of trial tables written (estimate).
    pub disk_bytes: f64,
    /// Memory the trials in flight hold (one trial's rows per worker), bytes (estimate).
    pub memory_bytes: f64,
    /// Wall time, s (estimate).
    pub wall_s: f64,
}

impl Cost {
    /// The cost of rehearsing `protocol` for `subjects` subjects, at most `max_trials`
    /// trials each, on `jobs` workers (`realtime`: one trial at a time on the wall clock).
    #[must_use]
    pub fn of(
        protocol: &Protocol,
        subjects: u32,
        max_trials: Option<usize>,
        jobs: usize,
        realtime: bool,
    ) -> Cost {
        let per_subject = max_trials.map_or(protocol.trials_per_subject(), |m| {
            m.min(protocol.trials_per_subject())
        }) as u64;
        let trials = per_subject * u64::from(subjects.max(1));
        let (trial_s, _) = protocol.trial_s();
        let simulated_s = trials as f64 * trial_s;
        let rows = simulated_s * f64::from(protocol.recording.rate_hz);
        let row_bytes = columns(protocol) * BYTES_PER_FIELD;
        let jobs = if realtime { 1.0 } else { jobs.max(1) as f64 };
        let in_flight = jobs.min(trials as f64);
        Cost {
            trials,
            simulated_s,
            ticks: simulated_s * f64::from(rigtwin_device::Rate::CONTROL.hz()),
            rows,
            disk_bytes: rows * row_bytes,
            // A trial's rows as f64 columns, twice (the record and its table text).
            memory_bytes: in_flight
                * trial_s
                * f64::from(protocol.recording.rate_hz)
                * columns(protocol)
                * 8.0
                * 2.0,
            wall_s: if realtime {
                simulated_s
            } else {
                simulated_s / (SIM_S_PER_WALL_S_PER_JOB * jobs)
            },
        }
    }

    /// Why this run needs a confirmation, if it does.
    #[must_use]
    pub fn needs_confirmation(&self) -> Option<String> {
        if self.simulated_s > CONFIRM_SIMULATED_S {
            Some(format!(
                "it simulates {}, more than the {} a run may simulate unconfirmed",
                duration(self.simulated_s),
                duration(CONFIRM_SIMULATED_S)
            ))
        } else if self.disk_bytes > CONFIRM_DISK_BYTES {
            Some(format!(
                "it writes about {}, more than the {} a run may write unconfirmed",
                bytes(self.disk_bytes),
                bytes(CONFIRM_DISK_BYTES)
            ))
        } else {
            None
        }
    }
}

impl fmt::Display for Cost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} trials, {} simulated ({:.2e} ticks), about {} on disk and {} in memory, about {} of wall time",
            self.trials,
            duration(self.simulated_s),
            self.ticks,
            bytes(self.disk_bytes),
            bytes(self.memory_bytes),
            duration(self.wall_s)
        )
    }
}

/// `42 s`, `12.5 min`, `3.2 h`, `4.0 days`.
#[must_use]
pub fn duration(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else if s < 172_800.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} days", s / 86_400.0)
    }
}

/// `512 kB`, `46 MB`, `1.2 GB` (decimal units).
#[must_use]
pub fn bytes(b: f64) -> String {
    if b < 1e6 {
        format!("{:.0} kB", b / 1e3)
    } else if b < 1e9 {
        format!("{:.0} MB", b / 1e6)
    } else {
        format!("{:.1} GB", b / 1e9)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// The shipped reach protocol: 100 trials of 3.5 s at 1 kHz with 17 columns.
    #[test]
    fn the_shipped_reach_costs_what_its_keys_say() {
        let p = Protocol::builtin("reach-perturb").unwrap();
        let c = Cost::of(&p, 1, None, 2, false);
        assert_eq!(c.trials, 100);
        assert!((c.simulated_s - 350.0).abs() < 1e-9, "{}", c.simulated_s);
        assert!((c.ticks - 1.4e6).abs() < 1e-3);
        assert!((c.rows - 350_000.0).abs() < 1e-6);
        // 350 000 rows of 17 fields of 8 bytes.
        assert!((c.disk_bytes - 47.6e6).abs() < 1.0);
        // 350 s over two workers at 30× real time.
        assert!((c.wall_s - 350.0 / 60.0).abs() < 1e-9);
        assert_eq!(c.needs_confirmation(), None);
        let many = Cost::of(&p, 300, None, 2, false);
        // 300 subjects × 350 s = 105 000 s, past a day.
        assert!(
            many.needs_confirmation()
                .unwrap()
                .contains("simulates 29.2 h")
        );
        let rt = Cost::of(&p, 1, Some(4), 8, true);
        assert!(
            (rt.wall_s - 14.0).abs() < 1e-9,
            "real time takes its simulated time"
        );
    }
}
