//! Candidate `force-ripple`: motor cogging `A_i · sin(2π q_i / p + φ_i)` added to the
//! motor force of axis `i` at its cart position `q_i` (the catalog's `amplitude_x_n`,
//! `amplitude_y_n`, `phase_x_rad`, `phase_y_rad`, `pitch_m`). Each axis has its own
//! magnet track, so its own amplitude and phase; the two motors share the pitch. With
//! one amplitude and phase shared by the axes, a rig whose two tracks start at different
//! positions has its amplitude found low (the shared sinusoid fits each axis's out of
//! phase), so the law has both per axis.
//!
//! The pitch is searched on a grid uniform in wavenumber `1/p`, with a spacing of
//! `1/(16 L)` for a travel `L`: the nearest grid point is then at most half a step off,
//! which turns the fitted sinusoid by at most π/16 over the travel. That alone would
//! cost under 1 % of amplitude, but the misfit it leaves is not left alone: a position
//! loop that rejects the cogging puts the ripple into the command, so the force gain's
//! column can take up what the sinusoid misses, and the gain–mass ridge of a
//! closed-loop balance carries it further. Half a step of a grid twice as coarse costs
//! about twice the amplitude on a simulated closed-loop trial, and on one centre-out
//! session 10 % where this grid's nearest point costs 1 %
//! (`hil/docs/notes/2026-12-08-ripple-pitch-grid.md`). For each
//! pitch the amplitudes and phases are linear (a
//! `sin`, `cos` column per axis, each zero on the other axis's rows). An axis whose cart
//! barely moves over the session (the x axis of a sagittal reach moves only under the
//! pulses) has its sinusoid nearly constant on each trial, which the per-trial sensor
//! offsets take up: its amplitude is then poorly determined, and its standard error
//! says so.
//!
//! The forces of the balance pass the balance filter, so the cogging in them does too:
//! at a speed `v` a ripple of pitch `p` is a tone of `|v| / p` Hz, which the filter
//! passes at its gain `H(|v| / p)` (real: the filter is symmetric), 0.97 at 5 Hz and
//! 0.76 at 15 Hz (the 41 ms window). Each sinusoid is therefore scaled by the filter's
//! gain at its row's own tone, `H(|v| / p) · sin(2π q / p)` — the filtered sinusoid for
//! a velocity constant over the window — so the fitted amplitudes are the motor's, not
//! the filter's share of them (a 10.6 mm pitch came out 10 % low without it). The
//! law written and drawn (`effect_force`) is the motor's, unfiltered.

use crate::effect::EffectKind;
use std::f64::consts::TAU;

use super::candidate::{Candidate, Design, Designed, NUISANCE_COLUMNS, gain_bounds};
use super::error::DiscrepancyError;
use super::gram::{Gram, Intercepts};
use super::signals::BalanceSignals;

/// Shortest pitch searched, m.
pub const MIN_PITCH_M: f64 = 5e-3;
/// Longest pitch searched, m (also at most half the travel: two periods are needed to
/// tell a ripple from a slow trend).
pub const MAX_PITCH_M: f64 = 0.1;

/// The force-ripple candidate over a wavenumber grid.
#[derive(Debug, Clone, Copy)]
pub struct ForceRipple {
    /// First wavenumber, 1/m.
    pub k0_per_m: f64,
    /// Wavenumber step, 1/m.
    pub dk_per_m: f64,
    /// Number of wavenumbers.
    pub n: usize,
}

impl ForceRipple {
    /// The grid for a largest travel `travel_m` of one axis over the session.
    #[must_use]
    pub fn for_travel(travel_m: f64) -> Self {
        let travel = travel_m.max(4.0 * MIN_PITCH_M);
        let k0 = 1.0 / MAX_PITCH_M.min(0.5 * travel);
        let k1 = 1.0 / MIN_PITCH_M;
        let dk = 1.0 / (16.0 * travel);
        let n = ((k1 - k0) / dk).floor().max(0.0) as usize + 1;
        ForceRipple {
            k0_per_m: k0,
            dk_per_m: dk,
            n,
        }
    }

    /// Pitch of setting `s`, m.
    #[must_use]
    pub fn pitch_m(&self, s: usize) -> f64 {
        1.0 / (self.k0_per_m + s as f64 * self.dk_per_m)
    }
}

/// Own columns of the candidate: `sin`, `cos` of the x axis, then of the y axis.
const OWN: usize = 4;

impl Designed for ForceRipple {
    /// The nominal balance plus `sin`, `cos` of `2π q / p` per axis, each zero on the
    /// other axis's rows.
    fn design(
        &self,
        sig: &BalanceSignals,
        s: usize,
        latency_s: f64,
    ) -> Result<Design, DiscrepancyError> {
        let k = 1.0 / self.pitch_m(s);
        let (speeds, gain) = speeds_and_gain(sig, k);
        let own = |axis: usize| {
            let q = sig.at_rows(&sig.q[axis]);
            let mut cols = vec![vec![0.0; q.len()]; OWN];
            for (r, q) in q.iter().enumerate() {
                let (sn, cs) = (TAU * k * q).sin_cos();
                let g = gain.at(k * speeds[axis][r]);
                cols[2 * axis][r] = g * sn;
                cols[2 * axis + 1][r] = g * cs;
            }
            cols
        };
        Ok(Design::nominal(sig, latency_s).with_own([own(0), own(1)]))
    }
}

/// Amplitude and phase of `axis` from the fitted `sin`, `cos` coefficients: the fit
/// carries the ripple on the target side (`u + F = m a + b_s sin + b_c cos`), so the
/// cogging force is `−(b_s sin θ + b_c cos θ) = A sin(θ + φ)`.
fn amplitude_phase(beta: &[f64], axis: usize) -> (f64, f64) {
    let (bs, bc) = (
        beta.get(2 + 2 * axis).copied().unwrap_or(f64::NAN),
        beta.get(3 + 2 * axis).copied().unwrap_or(f64::NAN),
    );
    (bs.hypot(bc), (-bc).atan2(-bs))
}

/// The balance filter's gain `H(f) = Σ_j h_j cos(2π f (j − c) / rate)` of one trial
/// (`c` the middle tap), tabulated every [`FilterGain::STEP_HZ`] up to the highest tone
/// a row can hold and read by linear interpolation (exact to ~1e-5: `H` bends on the
/// window's scale, ~25 Hz).
struct FilterGain {
    table: Vec<f64>,
}

impl FilterGain {
    const STEP_HZ: f64 = 0.25;

    /// The table up to `max_hz`.
    fn of(sig: &BalanceSignals, max_hz: f64) -> Self {
        let h = &sig.force_taps;
        let c = (h.len() as f64 - 1.0) / 2.0;
        let n = (max_hz / Self::STEP_HZ).ceil().max(0.0) as usize + 2;
        let table = (0..n)
            .map(|i| {
                let w = TAU * i as f64 * Self::STEP_HZ / sig.rate_hz;
                h.iter()
                    .enumerate()
                    .map(|(j, hj)| hj * (w * (j as f64 - c)).cos())
                    .sum()
            })
            .collect();
        FilterGain { table }
    }

    /// The gain at `f_hz` (≥ 0, within the table).
    fn at(&self, f_hz: f64) -> f64 {
        let x = f_hz / Self::STEP_HZ;
        let i = (x.floor() as usize).min(self.table.len() - 2);
        let w = x - i as f64;
        self.table[i] * (1.0 - w) + self.table[i + 1] * w
    }
}

/// Each axis's speed `|v|` at the evaluated rows, and the filter's gain table up to the
/// tone of the wavenumber `k_max_per_m` at the fastest of them: what the sinusoids of
/// every setting up to `k_max_per_m` are scaled by.
fn speeds_and_gain(sig: &BalanceSignals, k_max_per_m: f64) -> ([Vec<f64>; 2], FilterGain) {
    let speeds = [0, 1].map(|axis| sig.at_rows(&sig.v[axis]).iter().map(|v| v.abs()).collect());
    let v_max = speeds.iter().flatten().copied().fold(0.0, f64::max);
    let gain = FilterGain::of(sig, k_max_per_m * v_max);
    (speeds, gain)
}

impl Candidate for ForceRipple {
    fn kind(&self) -> Option<EffectKind> {
        Some(EffectKind::ForceRipple)
    }
    fn settings(&self) -> usize {
        self.n
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("pitch_m", self.pitch_m(s))
    }
    fn columns(&self) -> usize {
        2 + OWN
    }
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        self.grams_given(sig, latency_s, &Design::nominal(sig, latency_s))
    }
    /// All pitches in one pass over the rows: `e^{i 2π k q}` for `k = k0 + j dk` by a
    /// rotation recurrence over `j` (one `sin_cos` per row instead of one per pitch),
    /// with `base`'s target, command and own regressors. Equal to the joined
    /// `Designed::design`'s Gram at every setting (a unit test checks it).
    fn grams_given(
        &self,
        sig: &BalanceSignals,
        _latency_s: f64,
        base: &Design,
    ) -> Result<Vec<Gram>, DiscrepancyError> {
        let kb = base.own[0].len();
        let p = 2 + kb + OWN + NUISANCE_COLUMNS;
        let mut grams = vec![Gram::new(p).with_bounds(gain_bounds(p)); self.n];
        let mut offsets = vec![Intercepts::new(2, p); self.n];
        let mut x = vec![0.0; p];
        if !sig.per_trial_offsets() {
            grams.iter_mut().for_each(|g| g.bounds.clear());
        }
        let k_max = self.k0_per_m + (self.n.max(1) - 1) as f64 * self.dk_per_m;
        let (speeds, gain) = speeds_and_gain(sig, k_max);
        for axis in (0..2).filter(|a| sig.present(*a)) {
            let a = sig.at_rows(&sig.a[axis]);
            let q = sig.at_rows(&sig.q[axis]);
            // This axis's sin, cos columns; the other axis's stay zero.
            let (js, jc) = (2 + kb + 2 * axis, 3 + kb + 2 * axis);
            x.iter_mut().for_each(|v| *v = 0.0);
            for r in 0..q.len() {
                let (s0, c0) = (TAU * self.k0_per_m * q[r]).sin_cos();
                let (sd, cd) = (TAU * self.dk_per_m * q[r]).sin_cos();
                let (mut s, mut c) = (s0, c0);
                x[axis] = a[r];
                for (xi, col) in x[2..2 + kb].iter_mut().zip(&base.own[axis]) {
                    *xi = col[r];
                }
                x[2 + kb + OWN + axis] = sig.nuisance(base.gain[axis][r]);
                let y = base.target[axis][r];
                let mut tone = self.k0_per_m * speeds[axis][r];
                let dtone = self.dk_per_m * speeds[axis][r];
                for (g, ic) in grams.iter_mut().zip(&mut offsets) {
                    let h = gain.at(tone);
                    x[js] = h * s;
                    x[jc] = h * c;
                    g.push(&x, y, base.norm[axis][r]);
                    ic.push(axis, &x, y);
                    (s, c) = (s * cd + c * sd, c * cd - s * sd);
                    tone += dtone;
                }
            }
        }
        if sig.per_trial_offsets() {
            for (g, ic) in grams.iter_mut().zip(&offsets) {
                g.absorb(ic);
            }
        }
        Ok(grams)
    }
    fn parameters(&self, s: usize, beta: &[f64], _latency_s: f64) -> Vec<(String, f64)> {
        let (ax, px) = amplitude_phase(beta, 0);
        let (ay, py) = amplitude_phase(beta, 1);
        vec![
            ("amplitude_x_n".to_string(), ax),
            ("amplitude_y_n".to_string(), ay),
            ("pitch_m".to_string(), self.pitch_m(s)),
            ("phase_x_rad".to_string(), px),
            ("phase_y_rad".to_string(), py),
        ]
    }
    fn effect_force(&self, s: usize, beta: &[f64], axis: usize, q: f64, _v: f64) -> Option<f64> {
        let (bs, bc) = (beta.get(2 + 2 * axis)?, beta.get(3 + 2 * axis)?);
        let ph = TAU * q / self.pitch_m(s);
        Some(-(bs * ph.sin() + bc * ph.cos()))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::candidate::tests::simulate_carts;
    use rigtwin_session::{Trial, TrialEntry};

    const TICK_S: f64 = 2.5e-4;
    const MASS_KG: [f64; 2] = [12.0, 4.0];
    const PITCH_M: f64 = 0.03;
    const AMPLITUDE_N: [f64; 2] = [1.2, 2.0];
    const PHASE_RAD: [f64; 2] = [2.0, -0.7];

    /// Carts of 12 and 4 kg integrated at 4 kHz (semi-implicit Euler, as the plant), each
    /// made to follow a slow swing over 10 (x) and 16 cm (y) by a position loop, with the
    /// world's cogging law added to the motor force but not to the logged command, and a
    /// slow hand force; logged at 1 kHz as 4-tick block means.
    fn cogged_trial() -> (TrialEntry, Trial) {
        simulate_carts(24_000, |k, x, v| {
            let t = k as f64 * TICK_S;
            // A position loop (5 Hz, damping 0.7) along `a (1 − cos ω t)`, with its feed
            // forward: the cogging moves the carts off the plan only by millimetres.
            let cmd: [f64; 2] = std::array::from_fn(|a| {
                let (amp, w) = [(0.05, TAU / 3.0), (0.08, TAU / 4.0)][a];
                let wn = TAU * 5.0;
                let (xd, vd, ad) = (
                    amp * (1.0 - (w * t).cos()),
                    amp * w * (w * t).sin(),
                    amp * w * w * (w * t).cos(),
                );
                MASS_KG[a] * (ad + wn * wn * (xd - x[a]) + 1.4 * wn * (vd - v[a]))
            });
            // A hand pushing on the handle: without it the force constant's column (the
            // command itself) would balance the carts alone.
            let hand = [
                3.0 * (TAU * 0.7 * t + 0.4).sin(),
                2.5 * (TAU * 1.3 * t).cos(),
            ];
            let force = std::array::from_fn(|a| {
                let cog = AMPLITUDE_N[a] * (TAU * x[a] / PITCH_M + PHASE_RAD[a]).sin();
                cmd[a] + hand[a] + cog
            });
            [hand, cmd, force]
        })
    }

    /// The cogged trial's balance signals and the grid for its travel.
    fn cogged_signals() -> (BalanceSignals, ForceRipple) {
        let (entry, trial) = cogged_trial();
        let sig = BalanceSignals::from_trial(&entry, &trial, 1000.0)
            .unwrap()
            .unwrap();
        let grid = ForceRipple::for_travel(sig.travel_m(0).max(sig.travel_m(1)));
        (sig, grid)
    }

    /// The grid's worst case: the true pitch half a step from the nearest point. The
    /// carts' position loop rejects the cogging, so the command carries it and the force
    /// gain's column takes up part of what a sinusoid at the wrong pitch misses (here the
    /// y gain moves by about 1 %). Half a step of this grid must still give each
    /// amplitude within 3 %: measured at most 1.8 % off over both axes and sides. Half a
    /// step of a grid twice as coarse is a whole step here, and costs 4.2 %, beyond the
    /// bound: the test tells the two.
    #[test]
    fn half_a_grid_step_off_costs_little_amplitude() {
        let (sig, grid) = cogged_signals();
        // The worst amplitude error, relative, over both sides of the true pitch.
        let worst = |dk: f64| {
            [-1.0, 1.0]
                .iter()
                .flat_map(|sign| {
                    let off = ForceRipple {
                        k0_per_m: 1.0 / PITCH_M + sign * dk,
                        dk_per_m: 1.0,
                        n: 1,
                    };
                    let beta = off.grams(&sig, 0.0).unwrap()[0].solve().unwrap();
                    [0, 1].map(|axis| {
                        (amplitude_phase(&beta, axis).0 / AMPLITUDE_N[axis] - 1.0).abs()
                    })
                })
                .fold(0.0, f64::max)
        };
        let half = worst(0.5 * grid.dk_per_m);
        assert!(
            half < 0.03,
            "half a step off: amplitude {:.1} % off",
            half * 100.0
        );
        let coarse = worst(grid.dk_per_m);
        assert!(
            coarse > 0.03,
            "half a step of the coarser grid: amplitude only {:.1} % off",
            coarse * 100.0
        );
    }

    /// Two motors whose tracks start at different positions, with different amplitudes:
    /// the best pitch of the grid is the true one within one grid step; at the true pitch
    /// each axis's amplitude (within 0.1 %) and phase (within 0.02 rad) come back, at the
    /// grid's best within 5 % and 0.1 rad, so the model written from them is the law that
    /// made the data. Measured: at the true pitch 0.020 % and 0.021 % low, phases within
    /// 0.00001 rad (with the sinusoids not scaled by the balance filter's gain at their
    /// tone, 0.78 % and 0.996 % low: the filter passes the 3–4 Hz ripple of these swings
    /// at about 99 %); at the grid's best (0.15 mm off) 0.8 % and 1.5 % low, 0.05 and
    /// 0.08 rad. A law with one amplitude and phase shared by the axes could match at
    /// most one of them.
    #[test]
    fn each_axis_has_its_own_amplitude_and_phase() {
        let (sig, ripple) = cogged_signals();
        let grams = ripple.grams(&sig, 0.0).unwrap();
        let (best, beta) = grams
            .iter()
            .enumerate()
            .map(|(s, g)| {
                let beta = g.solve().unwrap();
                (g.sse(&beta), s, beta)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, s, beta)| (s, beta))
            .unwrap();
        let step = ripple.pitch_m(best) * ripple.pitch_m(best) * ripple.dk_per_m;
        assert!(
            (ripple.pitch_m(best) - PITCH_M).abs() <= step,
            "pitch {} (step {step})",
            ripple.pitch_m(best)
        );
        // On the grid the sinusoid drifts by up to half a step over the travel, which
        // costs at most a few percent of amplitude and a tenth of a radian.
        let at_true = ForceRipple {
            k0_per_m: 1.0 / PITCH_M,
            dk_per_m: 1.0,
            n: 1,
        };
        let exact = at_true.grams(&sig, 0.0).unwrap()[0].solve().unwrap();
        for (axis, name) in ["x", "y"].iter().enumerate() {
            for (r, s, b, tol_a, tol_ph) in [
                (&ripple, best, &beta, 0.05, 0.1),
                (&at_true, 0, &exact, 0.001, 0.02),
            ] {
                let p: std::collections::BTreeMap<String, f64> =
                    r.parameters(s, b, 0.0).into_iter().collect();
                let a = p[&format!("amplitude_{name}_n")];
                let ph = p[&format!("phase_{name}_rad")];
                assert!(
                    (a - AMPLITUDE_N[axis]).abs() < tol_a * AMPLITUDE_N[axis],
                    "amplitude {name} {a} at pitch {}",
                    r.pitch_m(s)
                );
                let dph = (ph - PHASE_RAD[axis] + std::f64::consts::PI).rem_euclid(TAU)
                    - std::f64::consts::PI;
                assert!(
                    dph.abs() < tol_ph,
                    "phase {name} {ph} at pitch {}",
                    r.pitch_m(s)
                );
                // The law the plots and the evidence check use is the same force.
                let q = 0.013;
                let law = -r.effect_force(s, b, axis, q, 0.0).unwrap();
                let want = -(a * (TAU * q / r.pitch_m(s) + ph).sin());
                assert!((law - want).abs() < 1e-9, "{law} vs {want}");
            }
        }
    }
}
