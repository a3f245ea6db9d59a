//! Candidate `force-ripple`: motor cogging `A · sin(2π q / p + φ)` added to each axis's
//! motor force at its cart position `q` (the catalog's `amplitude_n`, `pitch_m`; the
//! phase is fitted too because a foreign rig's magnets need not start at `q = 0`).
//!
//! The pitch is searched on a grid uniform in wavenumber `1/p`, with a spacing of
//! `1/(8 L)` for a travel `L`: a pitch error of one step then turns the fitted sinusoid
//! by at most π/8 over the travel, so the true pitch never falls between two grid
//! points that both miss it. For each pitch the amplitude and phase are linear
//! (`sin`, `cos` columns), shared by both axes as in the catalog law. The sinusoids are
//! evaluated on the smoothed position without smoothing them again: at the speeds of a
//! reach (mostly < 0.15 m/s) and pitches above 5 mm the ripple stays below ~30 Hz,
//! where the smoothing passes it.

use std::f64::consts::TAU;

use super::candidate::{Candidate, Design, Designed, NUISANCE_COLUMNS};
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
        let dk = 1.0 / (8.0 * travel);
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

impl Designed for ForceRipple {
    /// The nominal balance plus `sin`, `cos` of `2π q / p` per axis.
    fn design(
        &self,
        sig: &BalanceSignals,
        s: usize,
        latency_s: f64,
    ) -> Result<Design, DiscrepancyError> {
        let k = 1.0 / self.pitch_m(s);
        let own = |axis: usize| {
            let (sn, cs): (Vec<f64>, Vec<f64>) = sig
                .at_rows(&sig.q[axis])
                .iter()
                .map(|q| (TAU * k * q).sin_cos())
                .unzip();
            vec![sn, cs]
        };
        Ok(Design::nominal(sig, latency_s).with_own([own(0), own(1)]))
    }
}

impl Candidate for ForceRipple {
    fn name(&self) -> &'static str {
        "force-ripple"
    }
    fn settings(&self) -> usize {
        self.n
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("pitch_m", self.pitch_m(s))
    }
    fn columns(&self) -> usize {
        4
    }
    /// All pitches in one pass over the rows: `e^{i 2π k q}` for `k = k0 + j dk` by a
    /// rotation recurrence over `j` (one `sin_cos` per row instead of one per pitch).
    /// Equal to `Designed::design`'s Gram at every setting (a unit test checks it).
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        let nominal = Design::nominal(sig, latency_s);
        const P: usize = 4 + NUISANCE_COLUMNS;
        let mut grams = vec![Gram::new(P); self.n];
        let mut offsets = vec![Intercepts::new(2, P); self.n];
        let mut x = [0.0; P];
        for axis in 0..2 {
            let a = sig.at_rows(&sig.a[axis]);
            let q = sig.at_rows(&sig.q[axis]);
            for r in 0..q.len() {
                let (s0, c0) = (TAU * self.k0_per_m * q[r]).sin_cos();
                let (sd, cd) = (TAU * self.dk_per_m * q[r]).sin_cos();
                let (mut s, mut c) = (s0, c0);
                x[0] = if axis == 0 { a[r] } else { 0.0 };
                x[1] = if axis == 1 { a[r] } else { 0.0 };
                x[4] = if axis == 0 { nominal.gain[0][r] } else { 0.0 };
                x[5] = if axis == 1 { nominal.gain[1][r] } else { 0.0 };
                let y = nominal.target[axis][r];
                for (g, ic) in grams.iter_mut().zip(&mut offsets) {
                    x[2] = s;
                    x[3] = c;
                    g.push(&x, y, nominal.norm[axis][r]);
                    ic.push(axis, &x, y);
                    (s, c) = (s * cd + c * sd, c * cd - s * sd);
                }
            }
        }
        for (g, ic) in grams.iter_mut().zip(&offsets) {
            g.absorb(ic);
        }
        Ok(grams)
    }
    fn parameters(&self, s: usize, beta: &[f64], _latency_s: f64) -> Vec<(String, f64)> {
        let (bs, bc) = (
            beta.get(2).copied().unwrap_or(f64::NAN),
            beta.get(3).copied().unwrap_or(f64::NAN),
        );
        vec![
            ("amplitude_n".to_string(), bs.hypot(bc)),
            ("pitch_m".to_string(), self.pitch_m(s)),
            ("phase_rad".to_string(), (-bc).atan2(-bs)),
        ]
    }
    fn effect_force(&self, s: usize, beta: &[f64], _axis: usize, q: f64, _v: f64) -> Option<f64> {
        let (bs, bc) = (beta.get(2)?, beta.get(3)?);
        let ph = TAU * q / self.pitch_m(s);
        Some(-(bs * ph.sin() + bc * ph.cos()))
    }
}
