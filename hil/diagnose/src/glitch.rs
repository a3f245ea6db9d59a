//! Glitches in a recorded channel, runs of one to [`MAX_RUN`] samples that no physics
//! made and stale runs of up to [`MAX_STALE`] rows, found and bridged before the
//! balances are fitted.
//!
//! A rig's log can hold samples that no physics made: an encoder read torn by
//! interference, a force sensor's converter spiking for a conversion or two, a logger
//! repeating a frame it missed. The balances differentiate the position twice and
//! square their residuals, so one such sample weighs far beyond its share: six 2 mm
//! encoder glitches in 100 000 rows double the cart baseline's NRMSE and take a 1.1 ms
//! actuation delay out of the findings, and two-sample ones make the faulty-unit rule
//! set aside three good trials (`hil/docs/notes/2026-12-06-glitches.md`).
//!
//! **The signature.** A run of `L` samples, rows `i … i+L−1`, bounded by rows
//! `a = i−1` and `b = i+L`. Each run sample's departure `r_k` is its distance from the
//! straight line between the bounding samples. The run is a glitch when
//! - every `r_k` is above the threshold below, all of one sign;
//! - with the run replaced by that line, the path through it is smooth: at the bounding
//!   samples and the ones beyond them, the departure from the neighbours' midpoint,
//!   `e_j = x_j − (x_{j−1} + x_{j+1})/2`, is below a quarter of the run's smallest
//!   `|r_k|`.
//!
//! For one sample this is the lone spike's pattern: with `e_i = s`, its neighbours
//! carry `−s/2` each, within `s/4`, and the samples two away less than `s/4`.
//! A run of a constant offset (a stuck bit, a torn word) leaves the line exactly; a
//! stale run (a logger repeating the last frame `L` times) during motion at speed `v`
//! departs by `v·dt … L·v·dt`, and the line is what was read. Motion the rig can make
//! has none of this: an acceleration, however sharp, bends the path outside the run as
//! well as in it; a step (a missed encoder count burst, a re-tare) leaves the path bent
//! at the bounding samples by half the run's smallest departure or more; a ringing
//! sensor bends it at every sample. Each run is searched at the shortest length that
//! explains it, and a run of constant offset fits no other length.
//!
//! **At a trial's first or last sample** a run has one bound. Its line is the one
//! through that bound and the sample beyond it, extrapolated, and the path is checked
//! at the three samples beyond the bound, against an eighth of the run's smallest
//! departure (a glitch on the sample beyond the bound lends the run a departure four
//! times the bend it leaves, so a quarter could not tell the two apart). A logger that
//! opens a trial's file with the previous trial's last frame leaves such a run: 0.25 m
//! from where the trial starts, it took the cart baseline's NRMSE from 0.039 to 0.505.
//!
//! **The threshold** is the largest of
//! - [`ROBUST_SIGMAS`] times the channel's robust scale of `e` in the trial
//!   (1.4826 × its median absolute deviation, the standard deviation for Gaussian
//!   noise): a departure of ten sigmas with the exact pattern does not arise from noise;
//! - [`QUANTA`] times the channel's smallest recorded step (its quantum, or a
//!   fraction of it for block means): a count of dither on a coarse encoder is not a
//!   glitch;
//! - the channel's physical floor ([`SEARCHED`]): 20 µm of position, 1 N of force,
//!   20 mm/s of velocity, four times the rig's resolution and below any size that moves
//!   a fit (a balance's error from a spike grows with its square: 20 µm is 10⁻⁴ of the
//!   harm of 2 mm).
//!
//! **Runs of at most [`MAX_RUN`] samples.** A lost frame or a torn read spoils one to
//! a few samples. Longer runs are left as recorded: at 4 kHz four samples are a
//! millisecond, the time scale of a real impact on the handle, and a real force that
//! the carts followed must stay in the balance. What a run of three may still be, on
//! the force channels at 1 kHz, is a knock on the handle of 3 ms with a flat top; each
//! bridged sample is listed so that a person can look.
//!
//! **The measured channels only:** the encoder's position, the force sensor's force
//! and the drive's velocity. The motor command and the perturbation are computed by
//! the controller and sent as logged, so a one-sample spike in them is a force the
//! motor made: a PID's derivative kick from one encoder count is exactly one (the
//! imported servo axis, `recordings/example-servo-axis`, logs 31 such kicks of about
//! 1 N in its command).
//!
//! **The bridge.** A glitch's samples are replaced by the line between its bounding
//! samples, for the fits only: the files are never changed, and [`Glitch`] lists each
//! sample with the trial's file, the channel and the time so that a person can look.
//! Runs longer than [`MAX_RUN`] are left as recorded, but for stale frames.
//!
//! **Stale frames.** A bus that stops delivering frames for a few milliseconds (a lost
//! burst of EtherCAT or UDP frames) leaves the logger writing the last value it had,
//! for as many rows, and then the fresh value: a run of rows `i … i+L−1` equal exactly
//! to row `i − 1`, and a jump out of it. In a position channel (either axis that
//! passes), while the handle moves along it, the jump is the path's travel over the run, `(L + 1)` times its step:
//! that is the stale run's signature, `MAX_RUN < L ≤` [`MAX_STALE`], with the steps
//! into row `i − 1` and out of row `i + L` both at least the 20 µm floor, the same way,
//! and the jump within [`STALE_TOLERANCE`] of `(L + 1)` times their mean (a velocity
//! linear in time makes it exact). Motion does not make it: a handle turning back holds
//! its encoder count for a few rows, but its steps either side run opposite ways; a
//! logger writing a frame again every row it lacks a new one (a frame written twice,
//! `super::slip`) jumps by one step, not `L + 1`. Every measured channel that holds row
//! `i − 1`'s value through the run is bridged by the cubic through the two samples on
//! either side at their times (the run's rows were read, unlike a logger's lost rows,
//! so no time moves). Five such runs of five rows at peak speed, in 8 of 32 trials,
//! took a 1.575 ms delay's held-out gain to 0.04, and of eight rows took the delay out
//! of the findings with three trials set aside (`hil/docs/notes/2026-12-06-lost-runs.md`).
//! A trial with a held position channel (`super::hold`, each reading held for rows by
//! design) is not searched.

use std::borrow::Cow;

use rigtwin_session::{Session, Trial};
use serde::Serialize;

use super::stats::upper_median;

/// A glitch's departure from its neighbours' midpoint, in robust standard deviations
/// of that departure in its trial, at least.
pub const ROBUST_SIGMAS: f64 = 10.0;
/// A glitch's departure in the channel's smallest recorded steps, at least.
pub const QUANTA: f64 = 10.0;
/// The longest run of bad samples bridged (module docs).
pub const MAX_RUN: usize = 3;
/// The longest stale run bridged, rows (module docs): 20 ms at 1 kHz, a bus's longest
/// dropout a rig's watchdog lets pass before it stops the motors.
pub const MAX_STALE: usize = 20;
/// How far a stale run's jump may be from `L + 1` times the neighbours' mean step, as
/// a share of `L + 1`: the velocity's change over the run bends it by its curvature
/// only, and the noise little above the 20 µm floor.
pub const STALE_TOLERANCE: f64 = 0.1;
/// With the run bridged, the path's departure from the neighbours' midpoint at the
/// bounding samples and the ones beyond them stays below this share of the run's
/// smallest departure (the path is smooth through it).
const SMOOTH_SHARE: f64 = 0.25;
/// The same at a trial's first or last sample, where the run has one bound: a glitch on
/// the sample beyond that bound bends the path there by exactly [`SMOOTH_SHARE`] of the
/// departure it lends the run through the extrapolated line, so the edge asks for half.
const EDGE_SMOOTH_SHARE: f64 = 0.125;

/// A sample bridged before the fits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Glitch {
    /// The trial's file, as the manifest names it.
    pub file: String,
    /// The channel (the column's name, unit in it).
    pub channel: &'static str,
    /// The sample's row in the table (0 for the first after the header).
    pub row: usize,
    /// The sample's time in its trial, s.
    pub t_s: f64,
    /// The recorded value.
    pub recorded: f64,
    /// The value the fits used: on the line between the samples that bound its run,
    /// or for a stale run ([`find_stale`]) on the cubic through two samples either side.
    pub bridged: f64,
    /// The number of samples in its run (1 for a lone spike; 4 to [`MAX_STALE`] for a
    /// stale run).
    pub run: usize,
}

/// The floor of a glitch on a position channel, m (module docs); `super::slip` holds a
/// lost sample's extra step to it too.
pub const POSITION_FLOOR_M: f64 = 20e-6;

/// The searched channels, each with the physical floor of a glitch on it in its unit
/// (module docs): what a sensor measures. Not searched: time, and what the controller
/// computes rather than measures (the motor command and the perturbation).
pub const SEARCHED: [(&str, f64); 6] = [
    ("x_m", POSITION_FLOOR_M),
    ("y_m", POSITION_FLOOR_M),
    ("fx_n", 1.0),
    ("fy_n", 1.0),
    ("vx_m_per_s", 0.02),
    ("vy_m_per_s", 0.02),
];

/// The unit of a searched channel, as its name spells it (`m`, `N`, `m/s`).
#[must_use]
pub fn unit_of(channel: &str) -> &'static str {
    if channel.ends_with("_m_per_s") {
        "m/s"
    } else if channel.ends_with("_n") {
        "N"
    } else {
        "m"
    }
}

/// The glitches of `x` of at least `floor`: runs of one to [`MAX_RUN`] samples, each as
/// its first row and its length, in row order (module docs).
#[must_use]
pub fn find(x: &[f64], floor: f64) -> Vec<(usize, usize)> {
    let n = x.len();
    if n < 5 {
        return Vec::new();
    }
    let e: Vec<f64> = (1..n - 1)
        .map(|i| x[i] - 0.5 * (x[i - 1] + x[i + 1]))
        .collect();
    let threshold = (ROBUST_SIGMAS * robust_sigma(&e))
        .max(QUANTA * smallest_step(x))
        .max(floor);
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for len in 1..=MAX_RUN {
        // A run at a trial's edge needs three samples beyond its one bound: the two its
        // line runs through and one more to check the path's bend.
        if n < len + 4 {
            continue;
        }
        for i in 0..=n - len {
            let overlaps = runs.iter().any(|&(j, l)| i < j + l + 2 && j < i + len + 2);
            if !overlaps && is_glitch(x, i, len, threshold) {
                runs.push((i, len));
            }
        }
    }
    runs.sort_unstable();
    runs
}

/// The line a run of `len` rows from `start` is bridged by, as a function of the row:
/// through the samples that bound it; at a trial's first or last sample, where it has
/// one bound, through that bound and the sample beyond it (extrapolated).
fn line(x: &[f64], start: usize, len: usize) -> impl Fn(usize) -> f64 + '_ {
    let (anchor, slope) = if start == 0 {
        (len, x[len] - x[len + 1])
    } else if start + len == x.len() {
        (start - 1, x[start - 1] - x[start - 2])
    } else {
        (
            start - 1,
            (x[start + len] - x[start - 1]) / (len + 1) as f64,
        )
    };
    // Rows count away from the anchor: forward, or backward at the first sample.
    let ahead = start != 0;
    move |k: usize| {
        let d = if ahead { k - anchor } else { anchor - k };
        x[anchor] + slope * d as f64
    }
}

/// Whether rows `i..i + len` of `x` are a glitch at `threshold` (module docs); `x` has
/// at least `len + 4` samples.
fn is_glitch(x: &[f64], i: usize, len: usize, threshold: f64) -> bool {
    let n = x.len();
    let b = i + len;
    let line = line(x, i, len);
    let mut smallest = f64::INFINITY;
    let mut sign = 0.0;
    for (k, value) in x.iter().enumerate().take(b).skip(i) {
        let r = value - line(k);
        if r.abs() < threshold || (sign != 0.0 && r.signum() != sign) {
            return false;
        }
        sign = r.signum();
        smallest = smallest.min(r.abs());
    }
    // The path with the run bridged: at the bounding samples and the ones beyond; at a
    // trial's edge, the three beyond its one bound (the first is on the line).
    let bridged = |k: usize| if (i..b).contains(&k) { line(k) } else { x[k] };
    let bend = |j: usize| bridged(j) - 0.5 * (bridged(j - 1) + bridged(j + 1));
    let (rows, share): (Vec<usize>, f64) = if i == 0 {
        ((b..b + 3).collect(), EDGE_SMOOTH_SHARE)
    } else if b == n {
        ((i.saturating_sub(3)..i).collect(), EDGE_SMOOTH_SHARE)
    } else {
        (
            (i.saturating_sub(2)..i).chain(b..b + 2).collect(),
            SMOOTH_SHARE,
        )
    };
    rows.into_iter()
        .filter(|&j| j >= 1 && j + 1 < n)
        .all(|j| bend(j).abs() < share * smallest)
}

/// The stale runs `(i, L)` of a trial's position channels `x, y`: rows `i … i+L−1`
/// that repeat row `i − 1` exactly in either position channel while the handle moves
/// through them (module docs), `MAX_RUN < L ≤ MAX_STALE`, in row order.
#[must_use]
pub fn find_stale(x: &[f64], y: &[f64]) -> Vec<(usize, usize)> {
    let n = x.len().min(y.len());
    let mut runs = Vec::new();
    let mut i = 2;
    while i + 1 < n {
        // The run's length, counted to one beyond the longest searched.
        let stale = |p: &[f64]| {
            let mut end = i;
            while end < n && end - i <= MAX_STALE && p[end] == p[i - 1] {
                end += 1;
            }
            end - i
        };
        let (lx, ly) = (stale(x), stale(y));
        let mut found = None;
        for (p, len) in [(x, lx), (y, ly)] {
            if len <= MAX_RUN || len > MAX_STALE || i + len + 1 >= n {
                continue;
            }
            let (a, b) = (p[i - 1] - p[i - 2], p[i + len + 1] - p[i + len]);
            let mean = 0.5 * (a + b);
            let jump = p[i + len] - p[i - 1];
            let moving = moves_through(a, b);
            let ratio = jump / (mean * (len + 1) as f64);
            if moving && (ratio - 1.0).abs() < STALE_TOLERANCE {
                found = Some(len);
            }
        }
        match found {
            Some(len) => {
                runs.push((i, len));
                i += len + 1;
            }
            None => i += 1,
        }
    }
    runs
}

/// Whether the handle moves through a run of a position channel: the steps into it
/// (`a`) and out of it (`b`) each at least [`POSITION_FLOOR_M`], and the same way (a
/// handle turning back steps either side opposite ways).
pub(crate) fn moves_through(a: f64, b: f64) -> bool {
    a.abs() >= POSITION_FLOOR_M && b.abs() >= POSITION_FLOOR_M && a.signum() == b.signum()
}

/// The values at rows `1 … gap` after `before[1]` of the cubic through `before`
/// (rows `−1, 0`) and `after` (rows `gap + 1, gap + 2`), Lagrange's form: a run of
/// `gap` rows bridged at its rows' times.
pub(crate) fn gap_cubic(
    before: [f64; 2],
    after: [f64; 2],
    gap: usize,
) -> impl Iterator<Item = f64> {
    let m = gap as f64;
    let nodes = [-1.0, 0.0, m + 1.0, m + 2.0];
    let values = [before[0], before[1], after[0], after[1]];
    (1..=gap).map(move |j| {
        let t = j as f64;
        (0..4)
            .map(|a| {
                let w: f64 = (0..4)
                    .filter(|&b| b != a)
                    .map(|b| (t - nodes[b]) / (nodes[a] - nodes[b]))
                    .product();
                w * values[a]
            })
            .sum::<f64>()
    })
}

/// 1.4826 × the median absolute deviation of `e` from its median.
fn robust_sigma(e: &[f64]) -> f64 {
    let mut v = e.to_vec();
    let m = upper_median(&mut v);
    let mut dev: Vec<f64> = e.iter().map(|x| (x - m).abs()).collect();
    1.4826 * upper_median(&mut dev)
}

/// The smallest nonzero step between consecutive samples of `x` (0 when it never
/// moves): its quantum, or a fraction of it where block means are recorded.
fn smallest_step(x: &[f64]) -> f64 {
    let s = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if s.is_finite() { s } else { 0.0 }
}

/// The searched channel `name` of `trial`, mutable (`None` when the trial lacks it).
pub(crate) fn channel_mut<'a>(trial: &'a mut Trial, name: &str) -> Option<&'a mut Vec<f64>> {
    match name {
        "x_m" => Some(&mut trial.x_m),
        "y_m" => Some(&mut trial.y_m),
        "fx_n" => Some(&mut trial.fx_n),
        "fy_n" => Some(&mut trial.fy_n),
        "vx_m_per_s" => trial.vx_m_per_s.as_mut(),
        "vy_m_per_s" => trial.vy_m_per_s.as_mut(),
        _ => None,
    }
}

/// The session with every glitch bridged, and the glitches, in trial and row order;
/// `None` in place of the session when it has none (the caller keeps its own, and no
/// trial is copied). `held` gives, for a trial's index and a channel, the rows of its
/// readings if it is held there (`hold::find`): on those the readings are searched, not
/// the rows, a run counts readings, and every row that holds a bridged reading is
/// bridged with it.
#[must_use]
pub fn bridge<'a>(
    session: &Session,
    held: impl Fn(usize, &'static str) -> Option<&'a [usize]>,
) -> (Option<Session>, Vec<Glitch>) {
    let mut found = Vec::new();
    let mut copy: Option<Session> = None;
    for (index, (entry, trial)) in session.iter().enumerate() {
        let first = found.len();
        let position_held = held(index, "x_m").is_some() || held(index, "y_m").is_some();
        let stale = if position_held {
            Vec::new()
        } else {
            find_stale(&trial.x_m, &trial.y_m)
        };
        for (channel, floor) in SEARCHED {
            let Some(recorded) = trial.column(channel) else {
                continue;
            };
            // Stale runs first: each channel that holds the run's first value through
            // it is bridged by the cubic, and the runs of one to three are searched on
            // what that leaves.
            let mut x = Cow::Borrowed(recorded);
            for &(i, len) in &stale {
                if recorded[i..i + len].iter().any(|v| *v != recorded[i - 1]) {
                    continue;
                }
                let fill = gap_cubic(
                    [recorded[i - 2], recorded[i - 1]],
                    [recorded[i + len], recorded[i + len + 1]],
                    len,
                );
                for (k, value) in (i..i + len).zip(fill) {
                    found.push(Glitch {
                        file: entry.file.clone(),
                        channel,
                        row: k,
                        t_s: trial.t_s[k],
                        recorded: recorded[k],
                        bridged: value,
                        run: len,
                    });
                    x.to_mut()[k] = value;
                }
            }
            let x: &[f64] = &x;
            // A held channel's readings and the rows each holds (every row otherwise).
            let readings = held(index, channel);
            let values: Cow<[f64]> = readings.map_or(Cow::Borrowed(x), |rows| {
                Cow::Owned(rows.iter().map(|&r| x[r]).collect())
            });
            // The rows reading `k` holds.
            let held_by = |k: usize| match readings {
                Some(rows) => rows[k]..rows.get(k + 1).copied().unwrap_or(x.len()),
                None => k..k + 1,
            };
            // No two runs come within two readings of each other (`find`), so each
            // bridge reads recorded values.
            for (start, run) in find(&values, floor) {
                let line = line(&values, start, run);
                for k in start..start + run {
                    for row in held_by(k) {
                        found.push(Glitch {
                            file: entry.file.clone(),
                            channel,
                            row,
                            t_s: trial.t_s[row],
                            recorded: x[row],
                            bridged: line(k),
                            run,
                        });
                    }
                }
            }
        }
        if found.len() > first {
            let work = &mut copy.get_or_insert_with(|| session.clone()).trials[index];
            for g in &found[first..] {
                if let Some(values) = channel_mut(work, g.channel) {
                    values[g.row] = g.bridged;
                }
            }
        }
    }
    (copy, found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reaches;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// A reach-like position at 1 kHz (0.25 m in 0.6 s, minimum jerk) with 0.3 µm of
    /// white noise: smooth motion whose peak acceleration, 4.2 m/s², bends the
    /// samples by 2 µm.
    fn reach(seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        reaches::noisy(&mut rng, 0.25, 0.0, (0..2000).map(f64::from))
    }

    /// `x` with white noise of `sd` added: a recorded channel's fine noise, which keeps
    /// the smallest recorded step and the robust scale small, so that the threshold is
    /// the floor and a pattern is judged by its shape alone.
    fn with_noise(mut x: Vec<f64>, sd: f64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let noise = Normal::new(0.0, sd).unwrap();
        for v in &mut x {
            *v += noise.sample(&mut rng);
        }
        x
    }

    #[test]
    fn a_lone_spike_is_found_and_nothing_else() {
        // Checked on ten noise draws: the 2 mm spike and the 50 µm one are the only
        // rows found; the clean reach has none.
        for seed in 0..10 {
            let clean = reach(seed);
            assert!(find(&clean, 20e-6).is_empty(), "seed {seed}");
            let mut x = clean.clone();
            x[300] += 2e-3;
            x[1400] -= 50e-6;
            assert_eq!(find(&x, 20e-6), vec![(300, 1), (1400, 1)], "seed {seed}");
            // A stale sample (a logger repeating the previous frame) at the reach's
            // peak speed, 0.78 m/s: `e = −v·dt`, its neighbours `+v·dt/2`, the same
            // signature; its midpoint is what the encoder read.
            let mut x = clean.clone();
            x[300] = x[299];
            assert_eq!(find(&x, 20e-6), vec![(300, 1)], "seed {seed}");
        }
    }

    #[test]
    fn runs_of_two_and_three_are_found_at_their_length() {
        // Checked on ten noise draws: offset runs of 2 and 3 samples (a torn word held
        // for a frame or two), and a stale run of three at the reach's peak speed (the
        // logger repeating a frame), each found once, at its own start and length.
        for seed in 0..10 {
            let clean = reach(seed);
            let mut x = clean.clone();
            x[200..202].iter_mut().for_each(|v| *v += 2e-3);
            x[900..903].iter_mut().for_each(|v| *v -= 60e-6);
            let held = x[299];
            x[300..303].iter_mut().for_each(|v| *v = held);
            assert_eq!(
                find(&x, 20e-6),
                vec![(200, 2), (300, 3), (900, 3)],
                "seed {seed}"
            );
        }
    }

    #[test]
    fn runs_at_a_trials_first_or_last_sample_are_found() {
        // A logger that opens a trial with the previous trial's last frame (0.25 m
        // away), one that does so for two frames, and a last sample read as zero; on
        // ten noise draws each is found at its edge and bridged onto the line the two
        // samples beyond it continue.
        for seed in 0..10 {
            let clean = reach(seed);
            let n = clean.len();
            let mut x = clean.clone();
            x[0] = -0.25;
            x[n - 1] = 0.0;
            assert_eq!(find(&x, 20e-6), vec![(0, 1), (n - 1, 1)], "seed {seed}");
            let line = line(&x, 0, 1);
            assert!(
                (line(0) - clean[0]).abs() < 5e-6,
                "seed {seed}: {}",
                line(0)
            );
            let mut x = clean.clone();
            x[..2].iter_mut().for_each(|v| *v = -0.25);
            assert_eq!(find(&x, 20e-6), vec![(0, 2)], "seed {seed}");
        }
        // A spike on the second sample is bridged from the first and the third.
        let mut x = reach(1);
        x[1] += 1e-3;
        assert_eq!(find(&x, 20e-6), vec![(1, 1)]);
        // A trial that starts in motion at 0.78 m/s (no glitch: the path is straight
        // at its edge) has none.
        let moving: Vec<f64> = reach(2)[300..].to_vec();
        assert!(find(&moving, 20e-6).is_empty());
    }

    #[test]
    fn gap_cubic_is_exact_on_a_cubic() {
        // v(t) = 2 − t + 0.5 t² − 0.1 t³ sampled at −1, 0 and after a gap of `gap`
        // rows is put back exactly at the gap's rows, to rounding.
        let cubic = |t: f64| 2.0 - t + 0.5 * t * t - 0.1 * t * t * t;
        for gap in [1, 2, 3, 8, MAX_STALE] {
            let m = gap as f64;
            let got: Vec<f64> = gap_cubic(
                [cubic(-1.0), cubic(0.0)],
                [cubic(m + 1.0), cubic(m + 2.0)],
                gap,
            )
            .collect();
            assert_eq!(got.len(), gap);
            for (j, g) in got.iter().enumerate() {
                let want = cubic((j + 1) as f64);
                assert!(
                    (g - want).abs() < 1e-9 * want.abs().max(1.0),
                    "gap {gap}, row {j}"
                );
            }
        }
    }

    #[test]
    fn stale_runs_while_moving_are_found_and_bridged_to_the_noise() {
        // A reach on both axes (0.25 m along y, 0.1 m along x) whose logger wrote the
        // last frame again for 4, 8 and 20 rows (runs at 0.15, 0.3 and 0.45 s, where the
        // handle moves at 0.35–0.78 m/s), on ten noise draws: each run found at its row
        // and length, and the cubic over it within 3, 4.5 and 9 µm of the clean samples.
        // The bounds are five standard deviations of the fill's noise less the clean
        // sample's (the cubic's weights from two samples either side amplify the
        // 0.3 µm noise 1.6, 2.6 and 5.5 times in the run's middle) and the cubic's error
        // on the reach, 0.4 µm at most (20 rows). Left stale, the rows are off by up to
        // the run's travel, 3–16 mm.
        for seed in 0..10 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let rows = || (0..2000).map(f64::from);
            let x = reaches::noisy(&mut rng, 0.1, 0.0, rows());
            let y = reaches::noisy(&mut rng, 0.25, 0.0, rows());
            let (mut xs, mut ys) = (x.clone(), y.clone());
            let runs = [(150, 4, 3e-6), (300, 8, 4.5e-6), (450, 20, 9e-6)];
            for &(i, len, _) in &runs {
                for k in i..i + len {
                    xs[k] = xs[i - 1];
                    ys[k] = ys[i - 1];
                }
            }
            let found = find_stale(&xs, &ys);
            assert_eq!(found, vec![(150, 4), (300, 8), (450, 20)], "seed {seed}");
            for &(i, len, bound) in &runs {
                for (v, clean) in [(&xs, &x), (&ys, &y)] {
                    let fill = gap_cubic([v[i - 2], v[i - 1]], [v[i + len], v[i + len + 1]], len);
                    for (k, value) in (i..).zip(fill) {
                        assert!((value - clean[k]).abs() < bound, "seed {seed} row {k}");
                    }
                }
            }
            assert!(find_stale(&x, &y).is_empty(), "seed {seed}");
        }
    }

    #[test]
    fn a_turning_handle_a_frame_written_again_and_rest_are_not_stale() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let rows = || (0..2000).map(f64::from);
        // Out and back (0.1 m out in 0.6 s, back from 0.6 s) at 1 µm resolution: at
        // the turn the count holds for a few rows, with the steps either side opposite.
        let out: Vec<f64> = reaches::noisy(&mut rng, 0.1, 0.0, rows())
            .into_iter()
            .zip(reaches::noisy(&mut rng, -0.1, 0.6, rows()))
            .map(|(a, b)| ((a + b) * 1e6).round() * 1e-6)
            .collect();
        let held = out.windows(5).any(|w| w.iter().all(|v| *v == w[0]));
        assert!(held, "the turn holds the count for five rows");
        let still = vec![0.0; 2000];
        assert!(find_stale(&still, &out).is_empty());
        // A frame written again for five rows (inserted, the later rows late: a jump
        // of one step out of the run) is the repeated frames' rule, not a stale run.
        let y = reaches::noisy(&mut rng, 0.25, 0.0, rows());
        let mut again = y.clone();
        for _ in 0..5 {
            again.insert(300, y[299]);
        }
        assert!(find_stale(&still, &again).is_empty());
        // At rest (before the reach) every row repeats: nothing moves, nothing is stale.
        let mut rest = y.clone();
        rest[..20].iter_mut().for_each(|v| *v = 0.0);
        assert!(find_stale(&still, &rest).is_empty());
    }

    #[test]
    fn a_run_longer_than_three_or_a_bump_in_the_path_is_left() {
        let clean = reach(1);
        // Four samples off: a millisecond at 4 kHz, the time scale of a real impact.
        let mut x = clean.clone();
        x[200..204].iter_mut().for_each(|v| *v += 2e-3);
        assert!(find(&x, 20e-6).is_empty());
        // A force that rises over three samples and decays over five: the path bends
        // beyond any three-sample run.
        let mut f = vec![0.0; 400];
        for (k, v) in [10.0, 20.0, 30.0, 25.0, 20.0, 15.0, 10.0, 5.0]
            .iter()
            .enumerate()
        {
            f[200 + k] = *v;
        }
        let f = with_noise(f, 1e-3);
        assert!(find(&f, 1.0).is_empty());
        // The same force with its peak alone 10 N high is a one-sample glitch on it.
        let mut g = f.clone();
        g[202] += 10.0;
        assert_eq!(find(&g, 1.0), vec![(202, 1)]);
    }

    #[test]
    fn steps_ringing_dither_and_sharp_motion_are_not_glitches() {
        let n = 400;
        // A step of 1 mm (a missed count burst, a re-tare).
        // Each signal carries fine noise (`with_noise`), so that the threshold is the
        // floor and only the shape keeps it from being a glitch.
        let step: Vec<f64> = (0..n).map(|i| if i < 200 { 0.0 } else { 1e-3 }).collect();
        let step = with_noise(step, 1e-7);
        assert!(find(&step, 20e-6).is_empty());
        // A sensor ringing at half and at a quarter of the sampling rate, 5 N.
        let half: Vec<f64> = (0..n)
            .map(|i| match i {
                100..110 if i % 2 == 0 => 5.0,
                100..110 => -5.0,
                _ => 0.0,
            })
            .collect();
        let half = with_noise(half, 1e-3);
        assert!(find(&half, 1.0).is_empty());
        let quarter: Vec<f64> = (0..n)
            .map(|i| {
                if (100..120).contains(&i) {
                    5.0 * (std::f64::consts::FRAC_PI_2 * f64::from(u32::try_from(i).unwrap())).cos()
                } else {
                    0.0
                }
            })
            .collect();
        let quarter = with_noise(quarter, 1e-3);
        assert!(find(&quarter, 1.0).is_empty());
        // A coarse encoder (0.1 mm counts) dithering by one count at rest.
        let dither: Vec<f64> = (0..n)
            .map(|i| if i % 37 == 5 { 1e-4 } else { 0.0 })
            .collect();
        assert!(find(&dither, 20e-6).is_empty());
        // An impact: 2000 m/s² for one sample at 1 kHz, a step of 2 m/s in the
        // velocity. It bends the path at one sample and its neighbours not at all.
        let mut v = 0.0;
        let mut x = 0.0;
        let impact: Vec<f64> = (0..n)
            .map(|i| {
                let a = if i == 200 { 2000.0 } else { 0.0 };
                v += a * 1e-3;
                x += v * 1e-3;
                x
            })
            .collect();
        let impact = with_noise(impact, 1e-7);
        assert!(find(&impact, 20e-6).is_empty());
    }

    #[test]
    fn a_spike_below_the_floor_or_the_noise_is_left() {
        // 0.5 N on a force with 0.1 N of noise: below the 1 N floor.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let noise = Normal::new(0.0, 0.1).unwrap();
        let mut f: Vec<f64> = (0..1000).map(|_| noise.sample(&mut rng)).collect();
        f[500] += 0.5;
        assert!(find(&f, 1.0).is_empty());
        // 2 N on a force with 0.5 N of noise: above the floor, below ten sigmas.
        let noise = Normal::new(0.0, 0.5).unwrap();
        let mut f: Vec<f64> = (0..1000).map(|_| noise.sample(&mut rng)).collect();
        f[500] += 2.0;
        assert!(find(&f, 1.0).is_empty());
        // 40 N on the same: found.
        f[700] += 40.0;
        assert_eq!(find(&f, 1.0), vec![(700, 1)]);
    }
}
