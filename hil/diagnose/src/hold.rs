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
//! 0.48. A sensor read faster than every second row is not taken for held. A channel
//! that never moves (an imported single-axis log's zero columns) has no quantum and is
//! not held. The readings are the rows where the value changes (and the first row), so
//! a sensor whose clock is not an exact fraction of the logger's (a reading held for
//! two rows, now and then one or three) is followed as it is.
//!
//! **The fill.** A reading belongs to the row where it first appears. The rows that
//! hold it are filled by the cubic through the readings before and after them (the
//! two on either side, at their rows; fewer at a trial's edge), for the fits only; the
//! files are never changed. A hold longer than [`MAX_HOLD`] rows is a channel at rest,
//! not a slow sensor, and is left as recorded, as are the rows after a trial's last
//! reading (no reading follows them). The glitch rule searches a held channel's
//! readings, not its rows ([`super::glitch::bridge`]): a reading's repeats are not a
//! run of bad samples, and a filled row lies on a smooth curve by construction.
//!
//! **A limit.** A sensor's readings carry nothing above half its reading rate, and a
//! ring near that rate (a loop ringing at 185 Hz read at 500 Hz: 2.7 readings a
//! period) can put one reading on a peak with the readings around it on a line: then the
//! glitch rule can bridge it, as it would a ring near the logger's own half rate.
//!
//! **Measured channels only**, as for glitches ([`super::glitch::SEARCHED`]): the
//! motor command and the perturbation are what the controller sent, and a command held
//! between the controller's ticks is the force the motor made.

use rigtwin_session::{Session, Trial};
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
    /// The median number of rows between readings, over the held trials.
    pub rows_per_reading: f64,
    /// The sensor's reading rate that gives, Hz: the session's rate over
    /// `rows_per_reading`.
    pub reading_rate_hz: f64,
    /// Rows filled between readings, over the session.
    pub filled_rows: usize,
}

/// Whether `x` is held (module docs): `None` when it has fewer than [`MIN_MOVING`]
/// moving rows, else whether at least [`HELD_SHARE`] of them repeat the row before.
#[must_use]
pub fn is_held(x: &[f64]) -> Option<bool> {
    let n = x.len();
    if n < 2 * WINDOW + 2 {
        return None;
    }
    let quantum = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !quantum.is_finite() {
        return None;
    }
    let least = QUANTA_PER_ROW * (2 * WINDOW) as f64 * quantum;
    let (mut moving, mut repeats, mut twice) = (0usize, 0usize, 0usize);
    for j in WINDOW + 2..n - WINDOW {
        let w = &x[j - WINDOW..=j + WINDOW];
        let range = w.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - w.iter().copied().fold(f64::INFINITY, f64::min);
        if range >= least {
            moving += 1;
            repeats += usize::from(x[j] == x[j - 1]);
            twice += usize::from(x[j] != x[j - 1] && x[j - 1] != x[j - 2]);
        }
    }
    let share = |count: usize| count as f64 / moving as f64;
    (moving >= MIN_MOVING)
        .then_some(share(repeats) >= HELD_SHARE && share(twice) <= CHANGED_TWICE_SHARE)
}

/// The rows of `x`'s readings: the first row and every row whose value differs from
/// the row before.
#[must_use]
pub fn readings(x: &[f64]) -> Vec<usize> {
    (0..x.len())
        .filter(|&j| j == 0 || x[j] != x[j - 1])
        .collect()
}

/// The value at row `at` of the polynomial through `(rows[k], v[rows[k]])`.
fn lagrange(v: &[f64], rows: &[usize], at: usize) -> f64 {
    let t = at as f64;
    rows.iter()
        .enumerate()
        .map(|(i, &ri)| {
            let w: f64 = rows
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &rj)| (t - rj as f64) / (ri as f64 - rj as f64))
                .product();
            w * v[ri]
        })
        .sum()
}

/// Fills the rows of `v` that hold a reading, between its `readings` (module docs);
/// returns how many rows were filled.
pub fn fill(v: &mut [f64], readings: &[usize]) -> usize {
    let source = v.to_vec();
    let mut filled = 0;
    for m in 0..readings.len().saturating_sub(1) {
        let (from, to) = (readings[m], readings[m + 1]);
        if to - from < 2 || to - from > MAX_HOLD {
            continue;
        }
        let through: Vec<usize> =
            readings[m.saturating_sub(1)..(m + 3).min(readings.len())].to_vec();
        for (row, value) in v.iter_mut().enumerate().take(to).skip(from + 1) {
            *value = lagrange(&source, &through, row);
            filled += 1;
        }
    }
    filled
}

/// Each trial's held channels, each with the rows of its readings ([`readings`]).
pub type Readings = Vec<Vec<(&'static str, Vec<usize>)>>;

/// The held channels of each trial of `session`, in trial order, each with the rows of
/// its readings (module docs).
#[must_use]
pub fn find(session: &Session) -> Readings {
    session.trials.iter().map(of_trial).collect()
}

/// The held channels of `trial`, each with the rows of its readings (module docs).
#[must_use]
pub fn of_trial(trial: &Trial) -> Vec<(&'static str, Vec<usize>)> {
    glitch::SEARCHED
        .iter()
        .filter_map(|&(channel, _)| {
            let x = trial.column(channel)?;
            (is_held(x) == Some(true)).then(|| (channel, readings(x)))
        })
        .collect()
}

/// `session` with the held rows of every held channel filled (`held` as [`find`]
/// gives, found on the recorded values; `session` may have its glitches bridged),
/// and the held channels; `None` in place of the session when none is held.
#[must_use]
pub fn fill_session(
    recorded: &Session,
    session: &Session,
    held: &Readings,
) -> (Option<Session>, Vec<Held>) {
    let mut copy: Option<Session> = None;
    let mut found: Vec<Held> = Vec::new();
    for (channel, _) in glitch::SEARCHED {
        let judged = recorded
            .trials
            .iter()
            .filter(|t| t.column(channel).and_then(is_held).is_some())
            .count();
        let mut intervals: Vec<f64> = Vec::new();
        let (mut trials, mut filled) = (0, 0);
        for (index, channels) in held.iter().enumerate() {
            let Some((_, rows)) = channels.iter().find(|(c, _)| *c == channel) else {
                continue;
            };
            let mut gaps: Vec<f64> = rows
                .windows(2)
                .map(|w| w[1] - w[0])
                .filter(|g| *g <= MAX_HOLD)
                .map(|g| g as f64)
                .collect();
            intervals.push(upper_median(&mut gaps));
            let work = &mut copy.get_or_insert_with(|| session.clone()).trials[index];
            if let Some(values) = glitch::channel_mut(work, channel) {
                filled += fill(values, rows);
            }
            trials += 1;
        }
        if trials > 0 {
            let rows_per_reading = upper_median(&mut intervals);
            found.push(Held {
                channel,
                trials,
                judged,
                rows_per_reading,
                reading_rate_hz: recorded.manifest.rate_hz / rows_per_reading,
                filled_rows: filled,
            });
        }
    }
    (copy, found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// A reach at 1 kHz (0.25 m in 0.6 s, minimum jerk, from 0.2 s; 0.78 m/s peak)
    /// with 0.3 µm of white noise, written to 1 µm as an encoder would.
    fn reach(seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.3e-6).unwrap();
        (0..1200)
            .map(|i| {
                let tau = ((f64::from(i) * 1e-3 - 0.2) / 0.6).clamp(0.0, 1.0);
                let p = 10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5);
                ((0.25 * p + noise.sample(&mut rng)) * 1e6).round() / 1e6
            })
            .collect()
    }

    /// `x` as a logger writes a sensor read at the rows `read` (ascending, from 0): each
    /// reading repeated until the next.
    fn held_at(x: &[f64], read: &[usize]) -> Vec<f64> {
        let mut out = x.to_vec();
        for (k, &r) in read.iter().enumerate() {
            let end = read.get(k + 1).copied().unwrap_or(x.len());
            for v in &mut out[r..end] {
                *v = x[r];
            }
        }
        out
    }

    #[test]
    fn a_position_read_every_second_or_third_row_is_held_and_filled_to_the_noise() {
        for seed in 0..5 {
            let x = reach(seed);
            // Read at every row, quantised to 1 µm: judged, not held (its repeats are the
            // slow start and end, outside the moving rows).
            assert_eq!(is_held(&x), Some(false), "seed {seed}");
            // A sensor at 500 Hz, and one at 400 Hz whose readings fall two and three
            // rows apart in turn (a clock that is not a fraction of the logger's).
            let every_two: Vec<usize> = (0..x.len()).step_by(2).collect();
            let two_three: Vec<usize> = (0..x.len()).filter(|r| r % 5 == 0 || r % 5 == 2).collect();
            for read in [every_two, two_three] {
                let h = held_at(&x, &read);
                assert_eq!(is_held(&h), Some(true), "seed {seed}");
                let rows = readings(&h);
                let mut f = h.clone();
                let filled = fill(&mut f, &rows);
                assert!(filled > 300, "seed {seed}: {filled}");
                // Filled to 2 µm of the row's own reading while the reach moves: the
                // cubic's error on the reach over three rows is below 0.1 µm, and what is
                // left is its readings' noise and quantum (0.3 µm and 0.5 µm, about 1 µm
                // in the cubic's weights, plus the row's own); held, the rows were a
                // period's travel at peak speed off (0.78 mm) or more. At rest, to 4 µm:
                // there the readings change by a count at most eight rows apart, and the
                // cubic through such uneven points overshoots by a count or two.
                let worst_held = h
                    .iter()
                    .zip(&x)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(worst_held > 0.7e-3, "seed {seed}: {worst_held}");
                // The rows after the last reading are not filled (none follows them).
                let last = *rows.last().unwrap();
                for (k, (a, b)) in f.iter().zip(&x).enumerate().take(last) {
                    let moving = (200..=800).contains(&k);
                    let tolerance = if moving { 2e-6 } else { 4e-6 };
                    assert!(
                        (a - b).abs() < tolerance,
                        "seed {seed} row {k}: {a} against {b}"
                    );
                }
            }
        }
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
            let read: Vec<usize> = (0..f.len()).step_by(2).collect();
            let h = held_at(&f, &read);
            assert_eq!(is_held(&h), Some(true), "{hz} Hz");
            let values: Vec<f64> = readings(&h).iter().map(|&r| h[r]).collect();
            assert!(glitch::find(&values, 1.0).is_empty(), "{hz} Hz");
            assert!(glitch::find(&f, 1.0).is_empty(), "{hz} Hz");
            false_runs += glitch::find(&h, 1.0).len();
        }
        assert!(false_runs >= 2, "{false_runs}");
    }
}
