//! Samples a logger lost while it kept its clock, found from the position and put
//! back before the balances are fitted.
//!
//! A logger that numbers its rows itself (`t_s = row / rate_hz`) and drops a frame, a
//! stream's lost datagram, a buffer overrun, writes every later row one period early:
//! every channel slips by one sample at once, and the format's uniform clock cannot
//! show it. The balances differentiate the position twice, so the slip's jump of
//! `v·dt` becomes an acceleration doublet of `±v/dt`: seven slips at peak speed in a
//! session of 32 trials made the faulty-unit rule set aside two good trials and cut a
//! delay's held-out gain from 0.34 to 0.22 (`hil/docs/notes/2026-12-06-glitches.md`).
//!
//! **The signature.** A lost sample between rows `i − 1` and `i` doubles the position's
//! step there: with `d_k = x_k − x_{k−1}`, `d_i ≈ 2 v dt` while its neighbours carry
//! `v dt`, so `d` has a lone spike the size of its neighbours' mean. A slip is a row
//! where, in the faster of the two position channels, `d` has a lone spike (the
//! [`super::glitch`] rule on `d`: above ten robust sigmas and the 20 µm floor, its
//! neighbours' departures opposite at 0.25–0.75 of it, the samples two away under a
//! quarter) of [`RATIO`] times the neighbours' mean step, and the other channel's step
//! there is its neighbours' mean doubled too, within a quarter of the faster one's.
//! A glitch is not a slip: it leaves `d` a dipole (`+s`, then `−s`), and a stale frame
//! a dipole the other way (`0`, then `2 v dt`). A slip below 20 µm (`v < 20 mm/s` at
//! 1 kHz, 80 mm/s at 4 kHz) is left: its doublet moves no fit.
//!
//! **The repair.** The lost sample is put back in every column at the midpoint of its
//! neighbours in time, by the cubic through the two recorded samples on either side
//! (true times `−2, −1, +1, +2` periods from it: weights `−1/6, 2/3, 2/3, −1/6`), and
//! the time column is renumbered. The files are never changed; [`Slip`] lists each one
//! with its trial's file and the recorded row after which the sample was lost. Rows in
//! [`super::glitch::Glitch`] are the file's, and found before the repair.

use rigtwin_session::{Session, Trial};
use serde::Serialize;

use super::glitch;

/// The lost sample's step over its neighbours' mean step: one (the step doubles).
pub const RATIO: f64 = 1.0;
/// How far the ratio may be from [`RATIO`]: the path's curvature over three samples
/// and the noise move it little above the 20 µm floor.
pub const RATIO_TOLERANCE: f64 = 0.25;

/// A sample lost by the logger, put back before the fits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Slip {
    /// The trial's file, as the manifest names it.
    pub file: String,
    /// The recorded row after which the sample was lost (0 for the first after the
    /// header).
    pub after_row: usize,
    /// That row's time in its trial as recorded, s.
    pub t_s: f64,
    /// The position's extra step there (the faster channel's), m.
    pub step_m: f64,
}

/// The recorded rows `i` of a trial such that a sample was lost between `i − 1` and
/// `i`, with the extra step (module docs).
#[must_use]
pub fn find(x: &[f64], y: &[f64]) -> Vec<(usize, f64)> {
    let n = x.len().min(y.len());
    if n < 8 {
        return Vec::new();
    }
    let step = |p: &[f64]| -> Vec<f64> { p[..n].windows(2).map(|w| w[1] - w[0]).collect() };
    let (dx, dy) = (step(x), step(y));
    // d[k] is the step into row k + 1.
    // Lone spikes in the step, inside the trial (the glitch rule's runs of one).
    let spikes = |d: &[f64]| -> Vec<usize> {
        glitch::find(d, glitch::POSITION_FLOOR_M)
            .into_iter()
            .filter(|&(k, len)| len == 1 && k >= 1 && k + 1 < d.len())
            .map(|(k, _)| k)
            .collect()
    };
    let mut rows: Vec<(usize, f64)> = Vec::new();
    for (fast, slow) in [(&dx, &dy), (&dy, &dx)] {
        for k in spikes(fast) {
            let mean = |d: &[f64]| 0.5 * (d[k - 1] + d[k + 1]);
            let (mf, ms) = (mean(fast), mean(slow));
            if mf.abs() < ms.abs() {
                continue;
            }
            let extra = fast[k] - mf;
            let doubled = (extra / mf - RATIO).abs() < RATIO_TOLERANCE;
            let other = (slow[k] - 2.0 * ms).abs() < RATIO_TOLERANCE * mf.abs();
            if doubled && other && !rows.iter().any(|r| r.0 == k + 1) {
                rows.push((k + 1, extra.abs()));
            }
        }
    }
    rows.sort_by_key(|r| r.0);
    rows
}

/// The value of the sample lost between `v[i − 1]` and `v[i]`: the cubic through
/// rows `i − 2 … i + 1` at their true times `−2, −1, +1, +2` (module docs). [`find`]
/// gives rows `2 ≤ i ≤ len − 2` only (its spikes in the step have both neighbours).
fn lost_value(v: &[f64], i: usize) -> f64 {
    (-v[i - 2] + 4.0 * v[i - 1] + 4.0 * v[i] - v[i + 1]) / 6.0
}

/// `trial` with a sample put back before each recorded row of `rows` (ascending), and
/// its time renumbered at `period_s`.
fn repaired(trial: &Trial, rows: &[usize], period_s: f64) -> Trial {
    let fill = |v: &[f64]| -> Vec<f64> {
        let mut out = Vec::with_capacity(v.len() + rows.len());
        let mut next = rows.iter().peekable();
        for (k, &value) in v.iter().enumerate() {
            if next.peek() == Some(&&k) {
                out.push(lost_value(v, k));
                next.next();
            }
            out.push(value);
        }
        out
    };
    let fill_opt = |v: &Option<Vec<f64>>| v.as_deref().map(fill);
    let mut t = Trial {
        t_s: Vec::new(),
        x_m: fill(&trial.x_m),
        y_m: fill(&trial.y_m),
        fx_n: fill(&trial.fx_n),
        fy_n: fill(&trial.fy_n),
        pert_fx_n: fill(&trial.pert_fx_n),
        pert_fy_n: fill(&trial.pert_fy_n),
        vx_m_per_s: fill_opt(&trial.vx_m_per_s),
        vy_m_per_s: fill_opt(&trial.vy_m_per_s),
        ref_x_m: fill_opt(&trial.ref_x_m),
        ref_y_m: fill_opt(&trial.ref_y_m),
        cmd_fx_n: fill_opt(&trial.cmd_fx_n),
        cmd_fy_n: fill_opt(&trial.cmd_fy_n),
        extra: trial
            .extra
            .iter()
            .map(|c| rigtwin_session::Column {
                name: c.name.clone(),
                values: fill(&c.values),
            })
            .collect(),
    };
    t.t_s = (0..t.x_m.len()).map(|k| k as f64 * period_s).collect();
    t
}

/// The session with every lost sample put back, and the slips, in trial and row
/// order; `None` in place of the session when it has none (the caller keeps its own).
#[must_use]
pub fn repair(session: &Session) -> (Option<Session>, Vec<Slip>) {
    let period_s = 1.0 / session.manifest.rate_hz;
    let mut found = Vec::new();
    let mut copy: Option<Session> = None;
    for (index, (entry, trial)) in session.iter().enumerate() {
        let rows = find(&trial.x_m, &trial.y_m);
        if rows.is_empty() {
            continue;
        }
        for &(row, step_m) in &rows {
            found.push(Slip {
                file: entry.file.clone(),
                after_row: row - 1,
                t_s: trial.t_s[row - 1],
                step_m,
            });
        }
        let at: Vec<usize> = rows.iter().map(|r| r.0).collect();
        copy.get_or_insert_with(|| session.clone()).trials[index] = repaired(trial, &at, period_s);
    }
    (copy, found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// A reach at 1 kHz on both axes (0.25 m along y, 0.1 m along x, in 0.6 s, minimum
    /// jerk; 1.3 m/s peak speed along y) with 0.3 µm of white noise, `len` samples.
    fn reach(seed: u64, len: usize) -> (Vec<f64>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.3e-6).unwrap();
        let p = |i: usize| {
            let tau = (i as f64 * 1e-3 / 0.6).clamp(0.0, 1.0);
            10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5)
        };
        let x = (0..len)
            .map(|i| 0.1 * p(i) + noise.sample(&mut rng))
            .collect();
        let y = (0..len)
            .map(|i| 0.25 * p(i) + noise.sample(&mut rng))
            .collect();
        (x, y)
    }

    /// Drops row `k` of both channels: what a logger that lost it writes.
    fn drop_row(v: &[f64], k: usize) -> Vec<f64> {
        v.iter()
            .enumerate()
            .filter(|&(i, _)| i != k)
            .map(|(_, &x)| x)
            .collect()
    }

    #[test]
    fn a_lost_sample_is_found_and_put_back_to_the_noise() {
        // On ten noise draws, samples lost at 0.3 s (peak speed), at 0.15 s and at
        // 0.5 s are each found after the row before them; put back, the trial is the
        // clean one within 2 µm: five standard deviations of the difference between the
        // cubic's noise (0.97 × 0.3 µm) and the clean sample's own (0.3 µm); the cubic's
        // error on the reach itself is below 0.1 µm. Left lost, the row would be off by
        // a period's travel, 0.65 mm at peak speed.
        for seed in 0..10 {
            let (x, y) = reach(seed, 2000);
            let (mut xs, mut ys) = (x.clone(), y.clone());
            for k in [500, 300, 150] {
                xs = drop_row(&xs, k);
                ys = drop_row(&ys, k);
            }
            let rows = find(&xs, &ys);
            let at: Vec<usize> = rows.iter().map(|r| r.0).collect();
            assert_eq!(at, vec![150, 299, 498], "seed {seed}");
            let trial = Trial {
                x_m: xs.clone(),
                y_m: ys.clone(),
                ..Trial::default()
            };
            let t = repaired(&trial, &at, 1e-3);
            assert_eq!(t.y_m.len(), 2000);
            for k in [150, 300, 500] {
                assert!((t.y_m[k] - y[k]).abs() < 2e-6, "seed {seed} row {k}");
                assert!((t.x_m[k] - x[k]).abs() < 2e-6, "seed {seed} row {k}");
            }
            assert!((t.t_s[1999] - 1.999).abs() < 1e-12);
        }
    }

    #[test]
    fn glitches_stale_frames_and_slow_slips_are_not_slips() {
        let (x, y) = reach(4, 2000);
        assert!(find(&x, &y).is_empty());
        // A spike of 1 mm and a stale frame at peak speed: dipoles in the step.
        let mut g = y.clone();
        g[300] += 1e-3;
        g[700] = g[699];
        assert!(find(&x, &g).is_empty());
        // A lost sample at rest (before the reach): nothing to see, nothing to mend.
        let (xs, ys) = (drop_row(&x, 20), drop_row(&y, 20));
        assert!(find(&xs, &ys).is_empty());
        // One channel alone doubling its step (a glitch shaped like a slip on y only,
        // x not following) is not a slip.
        let mut one = y.clone();
        for v in &mut one[301..] {
            *v += y[300] - y[299];
        }
        assert!(find(&x, &one).is_empty());
    }
}
