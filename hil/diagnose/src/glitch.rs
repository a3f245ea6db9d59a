//! One-sample glitches in a recorded channel, found and bridged before the balances
//! are fitted.
//!
//! A rig's log can hold a sample that no physics made: an encoder read torn by
//! interference, a force sensor's converter spiking for one conversion. The balances
//! differentiate the position twice and square their residuals, so one such sample
//! weighs far beyond its share: six 2 mm encoder glitches in 100 000 rows double the
//! cart baseline's NRMSE and take a 1.1 ms actuation delay out of the findings
//! (`hil/docs/notes/2026-12-06-glitches.md`).
//!
//! **The signature.** With `e_i = x_i − (x_{i−1} + x_{i+1})/2`, the sample's departure
//! from its neighbours' midpoint, a spike `s` on sample `i` alone gives `e_i = s` and
//! `e_{i±1} = −s/2`, and leaves `e_{i±2}` alone. A glitch is a sample whose `e_i` is
//! above the threshold below while both neighbours' are of the other sign and
//! 0.25–0.75 of its size, and the samples two away carry less than a quarter of it.
//! A stale sample (a logger repeating the previous frame) during motion at speed `v`
//! has the same signature, of size `v·dt`, and its neighbours' midpoint is what was
//! read. Motion the rig can make has none of this: an acceleration, however sharp, bends
//! neighbouring samples the same way (`e_{i±1}` of the same sign as `e_i`); a step (a
//! missed encoder count, a re-tare) gives `e` of opposite signs on two samples, not
//! one between two halves; a ringing sensor alternates with ratios near 0 (at a
//! quarter of the rate) or 1 (at half of it).
//!
//! **The threshold** is the largest of
//! - [`ROBUST_SIGMAS`] times the channel's robust scale of `e` in the trial
//!   (1.4826 × its median absolute deviation, the standard deviation for Gaussian
//!   noise): a spike of ten sigmas with the exact pattern does not arise from noise;
//! - [`QUANTA`] times the channel's smallest recorded step (its quantum, or a
//!   fraction of it for block means): a count of dither on a coarse encoder is not a
//!   glitch;
//! - the channel's physical floor ([`SEARCHED`]): 20 µm of position, 1 N of force,
//!   20 mm/s of velocity, four times the rig's resolution and below any size that moves
//!   a fit (a balance's error from a spike grows with its square: 20 µm is 10⁻⁴ of the
//!   harm of 2 mm).
//!
//! **The measured channels only:** the encoder's position, the force sensor's force
//! and the drive's velocity. The motor command and the perturbation are computed by
//! the controller and sent as logged, so a one-sample spike in them is a force the
//! motor made: a PID's derivative kick from one encoder count is exactly one (the
//! imported servo axis, `recordings/example-servo-axis`, logs 31 such kicks of about
//! 1 N in its command).
//!
//! **The bridge.** A glitch is replaced by its neighbours' midpoint, for the fits only:
//! the files are never changed, and [`Glitch`] lists each one with the trial's file,
//! the channel and the time so that a person can look. Runs of two or more bad samples,
//! and the first and last two samples of a trial, are left as recorded.

use rigtwin_session::{Session, Trial};
use serde::Serialize;

use super::stats::upper_median;

/// A glitch's departure from its neighbours' midpoint, in robust standard deviations
/// of that departure in its trial, at least.
pub const ROBUST_SIGMAS: f64 = 10.0;
/// A glitch's departure in the channel's smallest recorded steps, at least.
pub const QUANTA: f64 = 10.0;
/// The neighbours' share of the glitch's departure, opposite in sign: a lone spike
/// gives one half to each.
const NEIGHBOUR_SHARE: (f64, f64) = (0.25, 0.75);
/// The samples two away carry less than this share (the spike is alone).
const SECOND_NEIGHBOUR_SHARE: f64 = 0.25;

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
    /// The value the fits used: its neighbours' midpoint.
    pub bridged: f64,
}

/// The searched channels, each with the physical floor of a glitch on it in its unit
/// (module docs): what a sensor measures. Not searched: time, and what the controller
/// computes rather than measures (the motor command and the perturbation).
pub const SEARCHED: [(&str, f64); 6] = [
    ("x_m", 20e-6),
    ("y_m", 20e-6),
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

/// The rows of `x` that carry a one-sample glitch of at least `floor` (module docs).
#[must_use]
pub fn find(x: &[f64], floor: f64) -> Vec<usize> {
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
    // e[k] belongs to row k + 1.
    let at = |row: usize| e[row - 1];
    (2..n - 2)
        .filter(|&row| {
            let s = at(row);
            if s.abs() < threshold {
                return false;
            }
            let share = |r: usize| -at(r) / s;
            let (lo, hi) = NEIGHBOUR_SHARE;
            let neighbours = [row - 1, row + 1]
                .iter()
                .all(|&r| (lo..=hi).contains(&share(r)));
            let alone = [row - 2, row + 2]
                .iter()
                .filter(|&&r| r >= 1 && r < n - 1)
                .all(|&r| at(r).abs() < SECOND_NEIGHBOUR_SHARE * s.abs());
            neighbours && alone
        })
        .collect()
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
fn channel_mut<'a>(trial: &'a mut Trial, name: &str) -> Option<&'a mut Vec<f64>> {
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
/// trial is copied).
#[must_use]
pub fn bridge(session: &Session) -> (Option<Session>, Vec<Glitch>) {
    let mut found = Vec::new();
    let mut copy: Option<Session> = None;
    for (index, (entry, trial)) in session.iter().enumerate() {
        let first = found.len();
        for (channel, floor) in SEARCHED {
            let Some(x) = trial.column(channel) else {
                continue;
            };
            // No two glitches are neighbours (each needs its neighbours' departures
            // at half its own), so each bridge reads recorded values.
            for row in find(x, floor) {
                found.push(Glitch {
                    file: entry.file.clone(),
                    channel,
                    row,
                    t_s: trial.t_s[row],
                    recorded: x[row],
                    bridged: 0.5 * (x[row - 1] + x[row + 1]),
                });
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
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// A reach-like position at 1 kHz (0.25 m in 0.6 s, minimum jerk) with 0.3 µm of
    /// white noise: smooth motion whose peak acceleration, 4.2 m/s², bends the
    /// samples by 2 µm.
    fn reach(seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.3e-6).unwrap();
        (0..2000)
            .map(|i| {
                let tau = (f64::from(i) * 1e-3 / 0.6).clamp(0.0, 1.0);
                let p = 10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5);
                0.25 * p + noise.sample(&mut rng)
            })
            .collect()
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
            assert_eq!(find(&x, 20e-6), vec![300, 1400], "seed {seed}");
            // A stale sample (a logger repeating the previous frame) at the reach's
            // peak speed, 0.78 m/s: `e = −v·dt`, its neighbours `+v·dt/2`, the same
            // signature; its midpoint is what the encoder read.
            let mut x = clean.clone();
            x[300] = x[299];
            assert_eq!(find(&x, 20e-6), vec![300], "seed {seed}");
        }
    }

    #[test]
    fn steps_ringing_dither_and_sharp_motion_are_not_glitches() {
        let n = 400;
        // A step of 1 mm (a missed count burst, a re-tare).
        let step: Vec<f64> = (0..n).map(|i| if i < 200 { 0.0 } else { 1e-3 }).collect();
        assert!(find(&step, 20e-6).is_empty());
        // A sensor ringing at half and at a quarter of the sampling rate, 5 N.
        let half: Vec<f64> = (0..n)
            .map(|i| match i {
                100..110 if i % 2 == 0 => 5.0,
                100..110 => -5.0,
                _ => 0.0,
            })
            .collect();
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
        assert_eq!(find(&f, 1.0), vec![700]);
    }
}
