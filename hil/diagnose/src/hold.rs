//! Channels a logger wrote faster than their sensor read them: each reading held for
//! several rows, found, and the held rows filled between the readings before the
//! balances are fitted.
//!
//! A rig's logger often runs faster than one of its sensors: a force sensor read over
//! a bus at 500 Hz into a 1 kHz log, an encoder latched by a slower loop, a logger at
//! twice the control rate. Each reading then repeats, exactly, for the rows until the
//! next one. The balances differentiate the position twice, so a held position is a
//! staircase whose steps are accelerations of `±v/dt`: on a session hiding nothing,
//! its position held for two rows made the diagnosis report `unexplained` structure,
//! and a 1.6 ms actuation delay came out at 2.3 ms. On the force, the glitch rule took
//! the flat tops of a fast oscillation read at 500 Hz for runs of two bad samples and
//! bridged 264 real samples (`hil/docs/notes/2026-12-06-held-samples.md`).
//!
//! **The signature.** Where a channel moves by at least [`QUANTA_PER_ROW`] of its
//! smallest recorded step per row (measured over the [`WINDOW`] rows either side), a
//! channel read at every row changes at nearly every row; one held for `k` rows repeats
//! at `(k − 1)/k` of them, half or more, and never changes at two rows in a row. A
//! channel is held in a trial when at least [`MIN_MOVING`] such rows exist, at least
//! [`HELD_SHARE`] of them repeat the row before exactly, and at most
//! [`CHANGED_TWICE_SHARE`] change at both it and the row before. Measured: repeats at 0
//! to 0.12 on every channel of 114 of the generator's realistic sessions and of the
//! independent rig's; 0.5 to 0.75 held for two to four rows, with no row changing
//! twice. The second test is for a quiet channel: on the generator's noise-free rig, the
//! drive velocity of an axis the reach does not use rests at exactly zero between
//! bursts of change, repeating at 0.44 of its moving rows, but changes twice in a row at
//! 0.48.
//!
//! A sensor read faster than every second row (a clock of period `P` between one and
//! two rows, each reading shown for one row or two) repeats at only `1 − 1/P` of the
//! rows, and changes twice in a row often. It is held when its repeats on **fast
//! rows** (where it moves by at least [`FAST_QUANTA_PER_ROW`] of its smallest step per
//! row, at the row and the two either side) lie on a clock: such a clock falls behind the rows once every `P/(P − 1)` rows,
//! and its repeats land there, so the spacings between them take the two whole numbers
//! around that; at least [`ON_CLOCK_SHARE`] of at least [`MIN_WRAPS`] spacings lie
//! within a row of their mean. A channel read at every row does not repeat on its fast
//! rows at all, or at random: pooled over a session, at most 0.17 of its spacings
//! within a row of their mean on 114 realistic sessions, the shared ones and three
//! quiet ones. The same test holds a sensor read every second row or slower, so the two
//! rules overlap. A channel is one sensor through a session, so its spacings are
//! judged pooled over the session's trials ([`find`]): a clock so near the logger's
//! rate that fewer than [`MIN_WRAPS`] spacings fall on one trial's fast rows (at 980
//! Hz, the slower axis of many of the generator's trials) is found on all of them
//! together, and every trial whose own spacings agree with the pooled mean, or that
//! has none, is held. A channel that never moves (an
//! imported single-axis log's zero columns) has no quantum and is not held. The
//! readings are the rows where the value changes (and the first row); the clock's
//! period is the least-squares slope of their rows on their count over the fast rows
//! of every trial it is held in, where no reading can equal the one before unseen.
//!
//! **One sensor, several channels.** A sensor reads its channels together: an encoder
//! interface both axes, a force sensor both forces, a drive both velocities
//! ([`SENSORS`]). A reach along one axis moves the other by little, and a clock near
//! the logger's rate (990 Hz: one repeated row in a hundred) shows on the moving
//! channel's repeats and not on the slow one's, which is then judged read at every row
//! while its partner is filled: the two axes a varying part of a row apart took the
//! delay's seed 1001 from 1.30 ms to 1.725 ms and its held-out gain from 0.38 to 0.06.
//! So each pair is judged again as one sensor ([`look_sensor`]): a row repeats when
//! every channel repeats, and is moving or fast when any channel is, each by its own
//! quantum, so the rules above apply unchanged. Where the pair's joint repeats lie on a
//! clock (pooled over the session as above), both channels are held in those trials
//! on the sensor's readings, the rows where either channel changes, and the pair's
//! period. The joint readings also show a reading one channel alone hides (equal to
//! the one before where it moves slowly). A channel read at every row rarely repeats
//! where its partner does (both at random), so a pair of channels each read at every
//! row shows no clock, and one whose partner is on another clock neither; each then
//! keeps what it shows alone.
//!
//! **The fill.** A reading taken at time `t` appears at row `ceil(t)`. Where the
//! sensor's clock is not an exact fraction of the logger's (a reading held for one row
//! or two, or two or three, in turn), what part of a row each reading is late varies
//! from reading to reading, by up to a row (at peak speed, 0.8 mm of a reach); where it is (500 Hz into 1 kHz),
//! by nothing. So each reading is put at its time on the sensor's clock
//! ([`reading_times`]): each reading's time from the rows of its neighbours and the
//! clock's period, to within `1/(2q)` of a row for a
//! period of `p/q` rows (a tenth at 625 Hz into 1 kHz). A clock at exactly a whole
//! multiple of the logger's period (500 Hz into 1 kHz) leaves the part of a row
//! unknown, the same for every reading, and each reading keeps the row it shows on. Every row from a reading to the next, the
//! reading's own row too, is then the cubic through the two readings on either side,
//! at their times, for the fits only; the files are never changed. A hold longer than
//! [`MAX_HOLD`] rows is a channel at rest, not a slow sensor, and is left as recorded,
//! as are the rows after a trial's last reading (no reading follows them). The glitch
//! rule searches a held channel's readings, not its rows ([`super::glitch::bridge`]): a
//! reading's repeats are not a run of bad samples, and a filled row lies on a smooth
//! curve by construction.
//!
//! **A limit.** A sensor's readings carry nothing above half its reading rate, and a
//! ring near that rate (a loop ringing at 185 Hz read at 500 Hz: 2.7 readings a
//! period) can put one reading on a peak with the readings around it on a line: then the
//! glitch rule can bridge it, as it would a ring near the logger's own half rate.
//!
//! **Measured channels only**, as for glitches ([`super::glitch::SEARCHED`]): the
//! motor command and the perturbation are what the controller sent, and a command held
//! between the controller's ticks is the force the motor made.

use rigtwin_session::Session;
use serde::Serialize;

use super::glitch;
use super::stats::upper_median;

/// The rows either side over which a channel's movement is measured.
pub const WINDOW: usize = 8;
/// A row is moving when the channel's range over the window is at least this many of
/// its smallest recorded steps per row: a channel read at every row then changes at
/// nearly every row (its quantum is far below its step).
pub const QUANTA_PER_ROW: f64 = 4.0;
/// The fewest moving rows on which a trial's channel is judged.
pub const MIN_MOVING: usize = 100;
/// The share of moving rows that repeat the row before exactly, at least, for a held
/// channel: a reading held for two rows gives one half; channels read at every row
/// gave at most 0.15.
pub const HELD_SHARE: f64 = 0.4;
/// The share of moving rows that change twice in a row, at most, for a held channel:
/// readings at least two rows apart never do (but where two clocks jitter); a quiet
/// channel resting at exactly one value between bursts of change does at about half.
pub const CHANGED_TWICE_SHARE: f64 = 0.1;
/// A row is fast when the channel changes by at least twice this many of its smallest
/// recorded steps over two rows, at it and at the two rows either side: a fresh reading
/// then never equals the one before, even where a reach turns (a window's range says
/// nothing of that). Measured: the positions of the delay's realistic seed 1001 repeat
/// on their fast rows 23 times in 32 trials, at random, and a quiet rig's channels not
/// at all.
pub const FAST_QUANTA_PER_ROW: f64 = 16.0;
/// The fewest spacings between repeats on fast rows by which a sensor's clock is judged.
pub const MIN_WRAPS: usize = 10;
/// The share of spacings between repeats on fast rows within a row of their mean, at
/// least, for a sensor's clock: a clock's are all (its repeats land where its readings
/// fall behind the rows, every `P/(P − 1)` rows); a channel read at every row whose
/// count stands still now and then spaces them at random: at most 0.17 within a row of
/// their mean, pooled over a session, on 114 realistic sessions, the shared ones and
/// three quiet ones.
pub const ON_CLOCK_SHARE: f64 = 0.9;
/// The longest hold filled, rows: longer, the channel is at rest.
pub const MAX_HOLD: usize = 8;

/// A channel held in some trials, and what was filled.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Held {
    /// The channel (the column's name, unit in it).
    pub channel: &'static str,
    /// The trials in which it is held.
    pub trials: usize,
    /// The trials in which it was judged (at least [`MIN_MOVING`] moving rows).
    pub judged: usize,
    /// The rows between readings, the sensor clock's period ([`reading_times`]); the
    /// median over the held trials.
    pub rows_per_reading: f64,
    /// The sensor's reading rate that gives, Hz: the session's rate over
    /// `rows_per_reading`.
    pub reading_rate_hz: f64,
    /// Rows filled between readings, over the session.
    pub filled_rows: usize,
    /// Whether the clock is a whole multiple of the logger's period, two or more (500 Hz
    /// into 1 kHz, to a thousandth of a row): each reading then keeps the row it shows on, and when
    /// within the row before it the reading was taken, up to one row earlier, the log
    /// cannot show ([`reading_times`]). A position read so may be that much older than
    /// its row, and a named actuation delay takes it up: up to one row long.
    pub reading_time_unknown: bool,
}

impl Held {
    /// For a position read on a clock at a whole multiple of the log's period
    /// ([`Self::reading_time_unknown`]), what that leaves unknown, in words; `None`
    /// otherwise. Not for a force: one read up to a row late moved the delay by at most
    /// 0.075 ms (the baseline's latency takes it up;
    /// `hil/docs/notes/2026-12-07-one-sensor-two-channels.md`).
    #[must_use]
    pub fn timing_caveat(&self) -> Option<String> {
        (self.reading_time_unknown && self.channel.ends_with("_m")).then(|| {
            format!(
                "a whole multiple of the log's period: when within the row before its row \
                 each reading was taken the log cannot show, so the position may be up to \
                 a row, {:.2} ms, older than it shows, and a named actuation delay up to \
                 that much long",
                1e3 / (self.reading_rate_hz * self.rows_per_reading)
            )
        })
    }
}

/// What [`judge`] finds a channel to be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Judged {
    /// Read at every row.
    EveryRow,
    /// Held between the readings of a sensor whose clock's period is `period` rows.
    Held {
        /// The clock's period, rows: the least-squares slope of the readings' rows on
        /// their count over runs of fast rows (moving rows if too few are fast).
        period: f64,
    },
}

/// What one trial's channel shows ([`look`]): what [`judge`] and [`find`] decide on.
#[derive(Debug, Clone, PartialEq)]
pub struct Look {
    /// Whether its moving rows repeat as a reading held for two rows or more does
    /// ([`HELD_SHARE`], [`CHANGED_TWICE_SHARE`]).
    pub held_rows: bool,
    /// The spacings between its repeats on fast rows with only fast rows between, rows.
    pub spacings: Vec<f64>,
    /// The rows of its readings ([`readings`]).
    pub rows: Vec<usize>,
    /// The least-squares sums of its readings' rows on their count, over runs of
    /// readings on fast rows and over runs on moving rows (their ratio, pooled, is the clock's period).
    pub sums: [(f64, f64); 2],
}

/// What `x` shows (module docs); `None` when it has fewer than [`MIN_MOVING`] moving
/// rows (or never moves).
#[must_use]
pub fn look(x: &[f64]) -> Option<Look> {
    look_sensor(&[x])
}

/// What the channels of one sensor show together (module docs, "One sensor, several
/// channels"): a row repeats when every channel repeats, and is moving or fast when
/// some channel is, each by its own quantum; `None` when fewer than [`MIN_MOVING`]
/// rows are moving (or no channel moves). For one channel, [`look`].
#[must_use]
pub fn look_sensor(channels: &[&[f64]]) -> Option<Look> {
    let n = channels.iter().map(|x| x.len()).min()?;
    if n < 2 * WINDOW + 2 {
        return None;
    }
    let mut moving = vec![false; n];
    let mut fast = vec![false; n];
    let mut any = false;
    for x in channels {
        let x = &x[..n];
        let quantum = x
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min);
        if !quantum.is_finite() {
            continue;
        }
        any = true;
        let least = QUANTA_PER_ROW * (2 * WINDOW) as f64 * quantum;
        // Fast: the change over two rows, at the row and the two either side, at least
        // twice FAST_QUANTA_PER_ROW quanta.
        let across: Vec<f64> = (0..n)
            .map(|k| {
                if k == 0 || k + 1 == n {
                    0.0
                } else {
                    (x[k + 1] - x[k - 1]).abs()
                }
            })
            .collect();
        for j in 3..n.saturating_sub(3) {
            fast[j] |= across[j - 2..=j + 2]
                .iter()
                .all(|&d| d >= 2.0 * FAST_QUANTA_PER_ROW * quantum);
        }
        for j in WINDOW + 2..n - WINDOW {
            let w = &x[j - WINDOW..=j + WINDOW];
            let range = w.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - w.iter().copied().fold(f64::INFINITY, f64::min);
            moving[j] |= range >= least;
        }
    }
    if !any {
        return None;
    }
    let same = |j: usize| channels.iter().all(|x| x[j] == x[j - 1]);
    let (mut count, mut repeats, mut twice) = (0usize, 0usize, 0usize);
    for (j, _) in moving
        .iter()
        .enumerate()
        .take(n - WINDOW)
        .skip(WINDOW + 2)
        .filter(|(_, m)| **m)
    {
        count += 1;
        repeats += usize::from(same(j));
        twice += usize::from(!same(j) && !same(j - 1));
    }
    if count < MIN_MOVING {
        return None;
    }
    let share = |c: usize| c as f64 / count as f64;
    // The spacings between repeats on fast rows, only fast rows between.
    let mut slow_before = Vec::with_capacity(n + 1);
    slow_before.push(0usize);
    for &f in &fast {
        slow_before.push(slow_before.last().copied().unwrap_or(0) + usize::from(!f));
    }
    let fast_repeats: Vec<usize> = (1..n).filter(|&j| fast[j] && same(j)).collect();
    let spacings = fast_repeats
        .windows(2)
        .filter(|w| slow_before[w[1] + 1] == slow_before[w[0]])
        .map(|w| (w[1] - w[0]) as f64)
        .collect();
    let rows: Vec<usize> = (0..n).filter(|&j| j == 0 || !same(j)).collect();
    let sums = [clock_sums(&rows, &fast), clock_sums(&rows, &moving)];
    Some(Look {
        held_rows: share(repeats) >= HELD_SHARE && share(twice) <= CHANGED_TWICE_SHARE,
        spacings,
        rows,
        sums,
    })
}

/// What `x` is, judged on its own (module docs): `None` when it has fewer than
/// [`MIN_MOVING`] moving rows; else held when its moving rows repeat as a reading held
/// for two rows or more does, or when its repeats on fast rows lie on a sensor's clock
/// ([`on_clock`]). [`find`] judges a session's channel on all its trials at once.
#[must_use]
pub fn judge(x: &[f64]) -> Option<Judged> {
    let looks = [Some(look(x)?)];
    Some(match held_trials(&looks) {
        Some((held, period)) if held[0] => Judged::Held { period },
        _ => Judged::EveryRow,
    })
}

/// Which of one channel's trials (their looks, `None` where not judged) are held, and
/// the clock's period over those; `None` when none is (module docs): a trial is held
/// when its moving rows repeat as a reading held for two rows or more does, or when the
/// spacings pooled over the trials lie on a clock and its own agree with their mean.
fn held_trials(looks: &[Option<Look>]) -> Option<(Vec<bool>, f64)> {
    let pooled: Vec<f64> = looks
        .iter()
        .flatten()
        .flat_map(|l| l.spacings.iter().copied())
        .collect();
    let clock = on_clock(&pooled, None).then(|| pooled.iter().sum::<f64>() / pooled.len() as f64);
    let held: Vec<bool> = looks
        .iter()
        .map(|l| {
            l.as_ref().is_some_and(|l| {
                l.held_rows || clock.is_some_and(|m| on_clock(&l.spacings, Some(m)))
            })
        })
        .collect();
    let members: Vec<&Look> = looks
        .iter()
        .zip(&held)
        .filter_map(|(l, &h)| l.as_ref().filter(|_| h))
        .collect();
    (!members.is_empty()).then(|| (held, period(&members)))
}

/// Whether `x` is held ([`judge`]).
#[must_use]
pub fn is_held(x: &[f64]) -> Option<bool> {
    judge(x).map(|j| j != Judged::EveryRow)
}

/// Whether `spacings` between repeats on fast rows are a sensor's clock's: at least
/// [`MIN_WRAPS`] of them, and at least [`ON_CLOCK_SHARE`] within a row of their mean;
/// or, given the `mean` of a clock found on other trials, at least that share within
/// a row of it (however few). A clock of period `P` falls behind the rows once every
/// `P/(P − 1)` rows, and its repeats land there, so their spacings take the two whole
/// numbers around it.
#[must_use]
pub fn on_clock(spacings: &[f64], mean: Option<f64>) -> bool {
    if spacings.len() < MIN_WRAPS && mean.is_none() {
        return false;
    }
    let own = spacings.iter().sum::<f64>() / spacings.len().max(1) as f64;
    let mean = mean.unwrap_or(own);
    let on = spacings.iter().filter(|d| (*d - mean).abs() < 1.0).count();
    on as f64 >= ON_CLOCK_SHARE * spacings.len() as f64
}

/// The clock's period, rows, from the least-squares sums of its readings' rows on
/// their count over runs on fast rows in `looks` (where none can equal the one before
/// unseen); over runs on moving rows if none is fast; else one row.
fn period(looks: &[&Look]) -> f64 {
    for which in 0..2 {
        let (sxy, sxx) = looks.iter().fold((0.0, 0.0), |(a, b), l| {
            (a + l.sums[which].0, b + l.sums[which].1)
        });
        if sxx > 0.0 {
            return sxy / sxx;
        }
    }
    1.0
}

/// The least-squares sums `(Σ (k − k̄)(ρ − ρ̄), Σ (k − k̄)²)` of the readings' rows `ρ`
/// on their count `k` over runs of at least three consecutive readings all on rows
/// where `on` holds: their ratio is the clock's period.
fn clock_sums(rows: &[usize], on: &[bool]) -> (f64, f64) {
    let (mut sxy, mut sxx) = (0.0, 0.0);
    let mut start = 0;
    for k in 0..=rows.len() {
        if k < rows.len() && on[rows[k]] {
            continue;
        }
        let run = &rows[start..k];
        if run.len() >= 3 {
            let mid_k = (run.len() - 1) as f64 / 2.0;
            let mid_row = run.iter().sum::<usize>() as f64 / run.len() as f64;
            for (i, &row) in run.iter().enumerate() {
                sxy += (i as f64 - mid_k) * (row as f64 - mid_row);
                sxx += (i as f64 - mid_k).powi(2);
            }
        }
        start = k + 1;
    }
    (sxy, sxx)
}

/// The rows of `x`'s readings: the first row and every row whose value differs from
/// the row before.
#[must_use]
pub fn readings(x: &[f64]) -> Vec<usize> {
    (0..x.len())
        .filter(|&j| j == 0 || x[j] != x[j - 1])
        .collect()
}

/// The fewest readings either side of one whose time is found on the sensor's clock;
/// more for a clock near a whole multiple of the logger's period ([`reading_times`]).
pub const CLOCK_REACH: usize = 10;
/// A reading's time is the middle of what its neighbours allow when they narrow it to
/// less than this part of a row; otherwise it is placed as a reading off the clock
/// ([`reading_times`]).
pub const NARROWED: f64 = 0.75;

/// The times of the readings at `rows`, in rows, on the clock of period `period` rows
/// that took them ([`Judged::Held`]; module docs, "The fill").
///
/// A reading taken at `t` appears at row `ceil(t)`. The steps between a moving
/// channel's readings take the two whole numbers around the period, and each run of
/// such steps is one stretch of the clock's readings, one period apart. Each reading's
/// time is the middle of the times `t` that put it and the readings either side in its
/// run ([`CLOCK_REACH`], or enough for their lags behind the rows to go once round a
/// row: `1/(2d)` for a period `d` off a whole number of rows) on their rows (`ρ_j − 1 < t + (j −
/// k)·P ≤ ρ_j`), when they narrow it to less than [`NARROWED`] of a row: within
/// `1/(2q)` of a row of its time for a period of `p/q` rows, `q ≥ 2` (a quarter of a row
/// at 400 Hz in a 1 kHz log, a tenth at 625 Hz). A clock at a whole multiple of the
/// logger's period (500 Hz into 1 kHz; to a thousandth of a row) puts every reading the
/// same unknown part of a row before the row it shows on; each keeps its row, as the
/// log shows it (a logger at twice a control loop's rate shows each reading on the tick
/// it was taken). A reading
/// whose neighbours admit no such time (a reading that equalled the one before, unseen,
/// where the channel moves slowly), or that has fewer than two neighbours in its run,
/// is put half a row before its row: the middle of its own span, and at least half a
/// row from the times of the readings on either side, so that no cubic is drawn
/// through two readings at nearly one time.
#[must_use]
pub fn reading_times(rows: &[usize], period: f64) -> Vec<f64> {
    // On a clock at a whole multiple every reading keeps its row; off the clock, a
    // reading is put at the middle of its row's span, as far from its neighbours'
    // times as their rows allow.
    let off_whole = (period - period.round()).abs();
    let whole = off_whole < 1e-3;
    // Enough neighbours for the lags behind the rows to go once round a whole row: a
    // clock `d` periods off a whole number of rows goes round every `1/d` readings.
    let reach = CLOCK_REACH.max((0.5 / off_whole).ceil() as usize + 1);
    if whole {
        return rows.iter().map(|&r| r as f64).collect();
    }
    let mut times: Vec<f64> = rows.iter().map(|&r| r as f64 - 0.5).collect();
    // Runs of readings one period apart: steps of the two whole numbers around it.
    let m = ((period + 1e-9).floor() as usize).max(1);
    let mut runs: Vec<std::ops::Range<usize>> = Vec::new();
    let mut start = 0;
    for k in 1..=rows.len() {
        if k == rows.len() || !(m..=m + 1).contains(&(rows[k] - rows[k - 1])) {
            if k - start >= 3 {
                runs.push(start..k);
            }
            start = k;
        }
    }
    for r in &runs {
        for k in r.clone() {
            let near = k.saturating_sub(reach).max(r.start)..(k + reach + 1).min(r.end);
            if near.len() < 3 {
                continue;
            }
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            for j in near {
                let shift = (j as f64 - k as f64) * period;
                lo = lo.max(rows[j] as f64 - 1.0 - shift);
                hi = hi.min(rows[j] as f64 - shift);
            }
            // Neighbours that leave most of a row open (a run too short for their lags
            // to go round a row) say little; the reading is placed as one off the clock.
            if lo <= hi && hi - lo < NARROWED {
                times[k] = 0.5 * (lo + hi);
            }
        }
    }
    times
}

/// The value at `at` of the polynomial through the points `(t[i], v[i])`.
pub(crate) fn lagrange(t: &[f64], v: &[f64], at: f64) -> f64 {
    (0..t.len())
        .map(|i| {
            let w: f64 = (0..t.len())
                .filter(|&j| j != i)
                .map(|j| (at - t[j]) / (t[i] - t[j]))
                .product();
            w * v[i]
        })
        .sum()
}

/// Fills `v`, a channel whose readings are at `readings`, at every row from a reading
/// to the next one at most [`MAX_HOLD`] rows later, by the cubic through the two
/// readings on either side at their `times` on the sensor's clock of period `period`
/// rows ([`reading_times`]); returns how many rows that held a reading were filled.
/// A step of more than one and a half periods in time (readings unseen, or a channel
/// near rest) is filled by the line between its two readings, and no cubic reaches
/// across it or a hold longer than [`MAX_HOLD`]: a cubic through readings that uneven
/// overshoots them.
pub fn fill(v: &mut [f64], readings: &[usize], times: &[f64], period: f64) -> usize {
    let values: Vec<f64> = readings.iter().map(|&r| v[r]).collect();
    let n = readings.len();
    // Whether the step into reading `k` breaks the clock's run.
    let breaks = |k: usize| {
        readings[k] - readings[k - 1] > MAX_HOLD || times[k] - times[k - 1] > 1.5 * period
    };
    let mut filled = 0;
    for m in 0..n.saturating_sub(1) {
        let (from, to) = (readings[m], readings[m + 1]);
        if to - from > MAX_HOLD {
            continue;
        }
        // A reading's time lies within its row's span, so the rows from `from` to `to`
        // lie between readings `m` and `m + 1` on the clock.
        let nodes = if breaks(m + 1) {
            m..m + 2
        } else {
            let lo = if m >= 1 && !breaks(m) { m - 1 } else { m };
            let hi = if m + 2 < n && !breaks(m + 2) {
                m + 3
            } else {
                m + 2
            };
            lo..hi
        };
        for (row, value) in v.iter_mut().enumerate().take(to).skip(from) {
            *value = lagrange(&times[nodes.clone()], &values[nodes.clone()], row as f64);
            filled += usize::from(row != from);
        }
    }
    filled
}

/// A channel held in one trial.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldChannel {
    /// The channel (the column's name).
    pub channel: &'static str,
    /// The rows of its readings ([`readings`]).
    pub rows: Vec<usize>,
    /// Its sensor clock's period, rows ([`Judged::Held`]).
    pub period: f64,
}

/// What [`find`] judged of a session.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Readings {
    /// Each trial's held channels, in trial order.
    pub held: Vec<Vec<HeldChannel>>,
    /// For each searched channel ([`glitch::SEARCHED`]), the trials in which it was
    /// judged (at least [`MIN_MOVING`] moving rows).
    pub judged: Vec<(&'static str, usize)>,
}

impl Readings {
    /// The rows of `channel`'s readings in trial `index`, if it is held there.
    #[must_use]
    pub fn rows(&self, index: usize, channel: &str) -> Option<&[usize]> {
        self.held
            .get(index)?
            .iter()
            .find(|h| h.channel == channel)
            .map(|h| h.rows.as_slice())
    }

    /// Whether any channel of trial `index` is held.
    #[must_use]
    pub fn any_held(&self, index: usize) -> bool {
        self.held.get(index).is_some_and(|h| !h.is_empty())
    }
}

/// The held channels of each trial of `session`, each with the rows of its readings
/// and its clock's period, and how many trials each channel was judged in (module
/// docs). A channel is one sensor through the session: its repeats on fast rows are
/// judged pooled over the trials ([`on_clock`]), a trial whose own spacings agree with
/// the pooled mean (or that has none) is held with the others, and the period is the
/// pooled one. Each pair of one sensor's channels ([`SENSORS`]) is then judged as one
/// ([`look_sensor`]): where it is held, both channels are, on the pair's readings and
/// period, in place of what each showed alone.
#[must_use]
pub fn find(session: &Session) -> Readings {
    let mut held: Vec<Vec<HeldChannel>> = vec![Vec::new(); session.trials.len()];
    let mut judged: Vec<(&'static str, usize)> = Vec::new();
    for &(channel, _) in &glitch::SEARCHED {
        let looks: Vec<Option<Look>> = session
            .trials
            .iter()
            .map(|t| t.column(channel).and_then(look))
            .collect();
        judged.push((channel, looks.iter().flatten().count()));
        let Some((is_held, period)) = held_trials(&looks) else {
            continue;
        };
        for ((index, l), h) in looks.into_iter().enumerate().zip(is_held) {
            if let (Some(l), true) = (l, h) {
                held[index].push(HeldChannel {
                    channel,
                    rows: l.rows,
                    period,
                });
            }
        }
    }
    // One sensor's channels together: where its clock shows on their joint readings,
    // both are held on them (they show readings either channel alone hides).
    for pair in SENSORS {
        let looks: Vec<Option<Look>> = session
            .trials
            .iter()
            .map(|t| look_sensor(&[t.column(pair[0])?, t.column(pair[1])?]))
            .collect();
        let Some((is_held, period)) = held_trials(&looks) else {
            continue;
        };
        for ((index, l), h) in looks.into_iter().enumerate().zip(is_held) {
            let (Some(l), true) = (l, h) else {
                continue;
            };
            for channel in pair {
                held[index].retain(|c| c.channel != channel);
                held[index].push(HeldChannel {
                    channel,
                    rows: l.rows.clone(),
                    period,
                });
            }
        }
    }
    Readings { held, judged }
}

/// The channels one sensor reads together, judged together too ([`look_sensor`]).
pub const SENSORS: [[&str; 2]; 3] = [
    ["x_m", "y_m"],
    ["fx_n", "fy_n"],
    ["vx_m_per_s", "vy_m_per_s"],
];

/// `session` with the held rows of every held channel filled (`found` as [`find`]
/// gives, judged on the recorded values; `session` may have its glitches bridged),
/// and the held channels; `None` in place of the session when none is held.
#[must_use]
pub fn fill_session(session: &Session, found: &Readings) -> (Option<Session>, Vec<Held>) {
    let mut copy: Option<Session> = None;
    let mut reported: Vec<Held> = Vec::new();
    for &(channel, judged) in &found.judged {
        let mut periods: Vec<f64> = Vec::new();
        let (mut trials, mut filled) = (0, 0);
        for (index, channels) in found.held.iter().enumerate() {
            let Some(held) = channels.iter().find(|h| h.channel == channel) else {
                continue;
            };
            periods.push(held.period);
            let times = reading_times(&held.rows, held.period);
            let work = &mut copy.get_or_insert_with(|| session.clone()).trials[index];
            if let Some(values) = glitch::channel_mut(work, channel) {
                filled += fill(values, &held.rows, &times, held.period);
            }
            trials += 1;
        }
        if trials > 0 {
            let rows_per_reading = upper_median(&mut periods);
            reported.push(Held {
                channel,
                trials,
                judged,
                rows_per_reading,
                reading_rate_hz: session.manifest.rate_hz / rows_per_reading,
                filled_rows: filled,
                reading_time_unknown: rows_per_reading.round() >= 2.0
                    && (rows_per_reading - rows_per_reading.round()).abs() < 1e-3,
            });
        }
    }
    (copy, reported)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reaches;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// The reach (0.25 m from 0.2 s) at `t` rows.
    fn reach_at(t: f64) -> f64 {
        reaches::min_jerk(0.25, 0.2, t / reaches::RATE_HZ)
    }

    /// The reach read at the times `t` (rows), with an encoder's noise, written to 1 µm
    /// as an encoder would.
    fn encoder(seed: u64, t: impl Iterator<Item = f64>) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        reaches::noisy(&mut rng, 0.25, 0.2, t)
            .into_iter()
            .map(|v| (v * 1e6).round() / 1e6)
            .collect()
    }

    /// The reach read at every one of 1200 rows.
    fn reach(seed: u64) -> Vec<f64> {
        encoder(seed, (0..1200).map(f64::from))
    }

    /// The reach as a 1 kHz logger writes a sensor whose reading `k` is taken at
    /// `phase + k·period` rows and shown from the first row at or after it until the
    /// next; and the times the readings were taken.
    fn read_every(seed: u64, period: f64, phase: f64) -> (Vec<f64>, Vec<f64>) {
        let count = ((1200.0 - phase) / period).ceil() as usize;
        let taken: Vec<f64> = (0..count).map(|k| phase + k as f64 * period).collect();
        let values = encoder(seed, taken.iter().copied());
        let mut out = vec![0.0; 1200];
        let mut k = 0;
        for (row, v) in out.iter_mut().enumerate() {
            while k + 1 < count && taken[k + 1] <= row as f64 {
                k += 1;
            }
            *v = values[k];
        }
        (out, taken)
    }

    #[test]
    fn a_position_read_on_a_slower_clock_is_held_and_filled_to_the_noise() {
        for seed in 0..4 {
            // Read at every row, quantised to 1 µm: judged, not held (its repeats are the
            // slow start and end, outside the moving rows).
            assert_eq!(is_held(&reach(seed)), Some(false), "seed {seed}");
            // Sensors at 500 and 400 Hz (readings two rows apart, and two or three in
            // turn), and at 800, 625 and 952 Hz (one or two), their periods `p/q` rows
            // with `q` 1, 2, 4, 5 and 20: clocks that are not a fraction of the
            // logger's show their readings a varying part of a row late.
            for (period, q) in [
                (2.0, 1.0),
                (2.5, 2.0),
                (1.25, 4.0),
                (1.6, 5.0),
                (1.05, 20.0),
            ] {
                let (h, taken) = read_every(seed, period, 0.37);
                let Some(Judged::Held { period: found }) = judge(&h) else {
                    panic!("seed {seed}, {period} rows: {:?}", judge(&h));
                };
                assert!((found - period).abs() < 1e-3, "{period} rows: {found}");
                let rows = readings(&h);
                let times = reading_times(&rows, found);
                // Each moving reading's time is found within half a `1/q` of a row (its
                // neighbours' rows tell no finer), and by the same error for all, to a
                // thousandth of a row (the period found is 3e-5 of a row off).
                let errors: Vec<f64> = rows
                    .iter()
                    .zip(&times)
                    .filter(|&(&r, _)| (250..=750).contains(&r))
                    .map(|(&r, &t)| {
                        let k = taken.partition_point(|&tk| tk <= r as f64) - 1;
                        t - taken[k]
                    })
                    .collect();
                // (At a whole multiple, `q` 1, the readings keep their rows: late by
                // what part of a row the reading was taken before.)
                let error = errors[0];
                let within = if q == 1.0 {
                    0.0..1.0
                } else {
                    -0.5 / q..0.5 / q
                };
                assert!(within.contains(&error), "{period} rows: {error}");
                let spread = errors.iter().map(|e| (e - error).abs()).fold(0.0, f64::max);
                assert!(spread < 1e-3, "{period} rows: {spread}");
                let mut f = h.clone();
                let filled = fill(&mut f, &rows, &times, found);
                // Every repeat while the reach moves is filled: `1 − 1/P` of its 600
                // rows, and more at its slow ends.
                let repeats = (1.0 - 1.0 / period) * 600.0;
                assert!(
                    filled as f64 > repeats,
                    "seed {seed}, {period} rows: {filled} for {repeats}"
                );
                // Against the reach late by that error: held, the rows were up to a
                // row's travel at peak speed off (0.78 mm), at least 0.3 mm; filled,
                // within 2 µm while the reach moves. The cubic's error on the reach over
                // four readings is below 0.2 µm, and what is left is its readings' noise
                // and quantum (0.3 µm and 0.5 µm, about 1 µm in the cubic's weights).
                // Slower, to 4 µm plus a row's travel: there the readings change by a
                // count at most eight rows apart, and the cubic through such uneven
                // points overshoots by a count or two; and a reading at the edge of a run
                // (a step the clock's two cannot make) keeps its row, up to a row late.
                let truth: Vec<f64> = (0..1200).map(|j| reach_at(f64::from(j) - error)).collect();
                let worst_held = h
                    .iter()
                    .zip(&truth)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(
                    worst_held > 0.3e-3,
                    "seed {seed}, {period} rows: {worst_held}"
                );
                // The rows after the last reading are not filled (none follows them).
                let last = *rows.last().unwrap();
                for (k, (a, b)) in f.iter().zip(&truth).enumerate().take(last) {
                    let tolerance = if (250..=750).contains(&k) {
                        2e-6
                    } else {
                        4e-6 + (truth[k + 1] - truth[k]).abs()
                    };
                    assert!(
                        (a - b).abs() < tolerance,
                        "seed {seed}, {period} rows, row {k}: {a} against {b}"
                    );
                }
            }
        }
    }

    /// Two channels of one sensor whose reading `k` is taken at `phase + k·period` rows,
    /// each shown from the first row at or after it until the next, 1200 rows: a reach
    /// of 0.25 m on `y` and of `x_extent_m` on `x`, each to 1 µm; and the times taken.
    fn sensor_pair(seed: u64, x_extent_m: f64, period: f64, phase: f64) -> [Vec<f64>; 3] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let count = ((1200.0 - phase) / period).ceil() as usize;
        let taken: Vec<f64> = (0..count).map(|k| phase + k as f64 * period).collect();
        let micron =
            |v: Vec<f64>| -> Vec<f64> { v.iter().map(|v| (v * 1e6).round() / 1e6).collect() };
        let xs = micron(reaches::noisy(
            &mut rng,
            x_extent_m,
            0.2,
            taken.iter().copied(),
        ));
        let ys = micron(reaches::noisy(&mut rng, 0.25, 0.2, taken.iter().copied()));
        let (mut x, mut y) = (vec![0.0; 1200], vec![0.0; 1200]);
        let mut k = 0;
        for row in 0..1200 {
            while k + 1 < count && taken[k + 1] <= row as f64 {
                k += 1;
            }
            (x[row], y[row]) = (xs[k], ys[k]);
        }
        [x, y, taken]
    }

    #[test]
    fn the_channels_of_one_sensor_are_held_on_its_readings() {
        // A position sensor at 990 Hz (a reading every 1.01 rows, one repeated row in
        // a hundred), four trials: `y` reaches 0.25 m, `x` 4 mm (at most 12.5 µm a row,
        // never a fast row of its own). Alone, `x` repeats too seldom and too slowly to
        // show the clock, and is judged read at every row; with `y` its repeats are the
        // sensor's, and both are held on the joint readings.
        let period = 1.01;
        let trials: Vec<[Vec<f64>; 3]> = (0..4)
            .map(|s| sensor_pair(s, 0.004, period, 0.13 + 0.2 * s as f64))
            .collect();
        let alone: Vec<Option<Look>> = trials.iter().map(|t| look(&t[0])).collect();
        assert!(held_trials(&alone).is_none(), "x alone held");
        let joint: Vec<Option<Look>> = trials
            .iter()
            .map(|t| look_sensor(&[&t[0], &t[1]]))
            .collect();
        let Some((held, found)) = held_trials(&joint) else {
            panic!("the pair is not held");
        };
        assert!(held.iter().all(|h| *h), "{held:?}");
        assert!((found - period).abs() < 1e-3, "{found}");
        for (t, l) in trials.iter().zip(&joint) {
            let rows = &l.as_ref().unwrap().rows;
            let times = reading_times(rows, found);
            let mut x = t[0].clone();
            fill(&mut x, rows, &times, found);
            // The truth at each row: the reach where the clock's error puts it (the
            // readings' times are found to within 1/(2q) of a row, q = 100, all off by
            // the same amount), checked while the reach moves.
            let taken = &t[2];
            let k = taken.partition_point(|&tk| tk <= 500.0) - 1;
            let error = times[rows.partition_point(|&r| r < 500)] - taken[k];
            let truth =
                |j: usize| reaches::min_jerk(0.004, 0.2, (j as f64 - error) / reaches::RATE_HZ);
            let (mut worst_held, mut worst_filled) = (0.0_f64, 0.0_f64);
            for j in 300..=700 {
                worst_held = worst_held.max((t[0][j] - truth(j)).abs());
                worst_filled = worst_filled.max((x[j] - truth(j)).abs());
            }
            // Held, a row late at the repeats: up to a row's travel (12.5 µm) off;
            // filled, within the readings' noise and quantum in the cubic's weights
            // (0.3 µm and 0.5 µm: 2 µm).
            assert!(worst_held > 8e-6, "{worst_held}");
            assert!(worst_filled < 2e-6, "{worst_filled}");
        }
    }

    #[test]
    fn repeats_off_any_clock_are_not_a_held_channel() {
        // The reach read at every row, with a fifth of its rows, drawn at random,
        // repeating the row before (as many as a sensor at 800 Hz repeats, but on no
        // clock): not held, so the glitch rule judges them one by one.
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut x = reach(11);
        for j in 1..x.len() {
            if rand::Rng::random_bool(&mut rng, 0.2) {
                x[j] = x[j - 1];
            }
        }
        assert_eq!(is_held(&x), Some(false));
    }

    #[test]
    fn channels_that_never_move_or_rest_are_not_judged() {
        // A column of zeros (an imported single-axis log's second axis) has no quantum.
        assert_eq!(is_held(&[0.0; 500]), None);
        // A channel at rest, moving by a count now and then: too few moving rows.
        let rest: Vec<f64> = (0..2000).map(|i| f64::from(i / 300) * 1e-6).collect();
        assert_eq!(is_held(&rest), None);
        // A quiet channel resting at exactly zero between bursts of change, each row of
        // a burst new (the noise-free rig's drive velocity on an axis the reach does not
        // use): it repeats at about half of its moving rows, but is read at every row.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let noise = Normal::new(0.0, 4e-4).unwrap();
        let quiet: Vec<f64> = (0..3000)
            .map(|i| {
                if i % 20 < 10 {
                    (noise.sample(&mut rng) * 1e6_f64).round() / 1e6
                } else {
                    0.0
                }
            })
            .collect();
        let repeats = quiet.windows(2).filter(|w| w[0] == w[1]).count();
        assert!(repeats > 1300, "{repeats}");
        assert_eq!(is_held(&quiet), Some(false));
    }

    #[test]
    fn a_held_force_is_searched_for_glitches_by_its_readings() {
        // A force sensor read at 500 Hz into a 1 kHz log, on a rig that rings for 0.1 s
        // at 192 or 196 Hz with 8 N (an admittance loop with a delay), 0.05 N of noise
        // elsewhere: some readings fall on the ring's peaks, one per period, and their
        // two repeated rows with the path around them straight look like a run of two
        // bad samples. The readings themselves, and the rows read at every row, do not.
        // (At 185 Hz a reading on a peak can pass the rule on the readings too: the
        // module docs' limit near the sensor's Nyquist rate.)
        let mut false_runs = 0;
        for hz in [192.0, 196.0] {
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            let noise = Normal::new(0.0, 0.05).unwrap();
            let f: Vec<f64> = (0..3000)
                .map(|i| {
                    let t = f64::from(i) * 1e-3;
                    let ring = if (0.1..0.2).contains(&t) { 8.0 } else { 0.0 };
                    ring * (2.0 * std::f64::consts::PI * hz * t).sin() + noise.sample(&mut rng)
                })
                .collect();
            let h: Vec<f64> = (0..f.len()).map(|j| f[j - j % 2]).collect();
            assert_eq!(is_held(&h), Some(true), "{hz} Hz");
            let values: Vec<f64> = readings(&h).iter().map(|&r| h[r]).collect();
            assert!(glitch::find(&values, 1.0).is_empty(), "{hz} Hz");
            assert!(glitch::find(&f, 1.0).is_empty(), "{hz} Hz");
            false_runs += glitch::find(&h, 1.0).len();
        }
        assert!(false_runs >= 2, "{false_runs}");
    }
}
