//! Candidate `sensor-rotation`: the force sensor's frame is turned by θ about the
//! handle axis, so it reads `R(θ)·F` (counter-clockwise, the catalog's `angle_deg`).
//! Back in the rig frame the carts feel `R(−θ)·F_read`, which mixes the axes:
//!
//! ```text
//! x: u_x + cos θ · F_x + sin θ · F_y = m_x a_x
//! y: u_y − sin θ · F_x + cos θ · F_y = m_y a_y
//! ```
//!
//! θ is searched over a grid with the masses refitted at each angle; the rotation is
//! kept exact (cos θ is not a free gain, which would also absorb a scale error of the
//! sensor, an effect outside the catalog). Each angle's Gram is a quadratic form of one
//! 5 × 5 Gram of `[a_x, a_y, u, F_own, F_other]` per trial.

use super::candidate::{
    Candidate, Design, Designed, NUISANCE_COLUMNS, Reshape, gain_bounds, push_rows,
};
use super::error::DiscrepancyError;
use super::gram::Gram;
use super::signals::BalanceSignals;
use crate::effect::EffectKind;

/// The sensor-rotation candidate: θ from `−max_deg` to `max_deg` in `step_deg`.
#[derive(Debug, Clone, Copy)]
pub struct SensorRotation {
    /// Largest angle searched, degrees.
    pub max_deg: f64,
    /// Grid step, degrees.
    pub step_deg: f64,
}

impl Default for SensorRotation {
    /// ±45° in 0.05° steps: a sensor mounted a bolt hole off its index is 15–45° off, a
    /// careless alignment a few degrees.
    fn default() -> Self {
        SensorRotation {
            max_deg: 45.0,
            step_deg: 0.05,
        }
    }
}

impl SensorRotation {
    /// Angle of setting `s`, degrees.
    #[must_use]
    pub fn angle_deg(&self, s: usize) -> f64 {
        -self.max_deg + s as f64 * self.step_deg
    }
}

impl Designed for SensorRotation {
    /// The balance with the sensor force turned back by θ into the rig frame.
    fn design(
        &self,
        sig: &BalanceSignals,
        s: usize,
        latency_s: f64,
    ) -> Result<Design, DiscrepancyError> {
        Ok(Design::balance(
            sig,
            latency_s,
            self.angle_deg(s).to_radians(),
        ))
    }
}

impl Candidate for SensorRotation {
    fn kind(&self) -> Option<EffectKind> {
        Some(EffectKind::SensorRotation)
    }
    fn settings(&self) -> usize {
        (2.0 * self.max_deg / self.step_deg).round() as usize + 1
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("angle_deg", self.angle_deg(s))
    }
    fn columns(&self) -> usize {
        2
    }
    fn reshapes(&self) -> Reshape {
        Reshape::Force
    }
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        self.grams_given(sig, latency_s, &Design::nominal(sig, latency_s))
    }
    /// Every angle's Gram as a quadratic form of one raw Gram per trial. `base` must not
    /// turn the sensor force (its force part is the reading itself); its command and
    /// its own regressors are carried along.
    fn grams_given(
        &self,
        sig: &BalanceSignals,
        _latency_s: f64,
        base: &Design,
    ) -> Result<Vec<Gram>, DiscrepancyError> {
        // Raw Gram of [a_x·1x, a_y·1y, base's own…, u, F_own, F_other, u·1x, u·1y] with
        // target 0, built (offsets eliminated) with the generic row pusher by treating
        // all as regressors; each angle's Gram is a quadratic form of it: regressors the
        // masses, base's own and the force gains, target `u + cos θ F_own + sin θ F_other`.
        let u = &base.gain;
        let f = [sig.at_rows(&sig.f[0]), sig.at_rows(&sig.f[1])];
        let zeros = [vec![0.0; sig.rows.len()], vec![0.0; sig.rows.len()]];
        let kb = base.own[0].len();
        let raw_p = 2 + kb + 3 + NUISANCE_COLUMNS;
        let mut raw = Gram::new(raw_p);
        push_rows(&mut raw, sig, &zeros, &base.norm, u, |axis, r, x| {
            for (xi, col) in x.iter_mut().zip(&base.own[axis]) {
                *xi = col[r];
            }
            x[kb] = u[axis][r];
            x[kb + 1] = f[axis][r];
            // x rows: +F_y; y rows: −F_x.
            x[kb + 2] = if axis == 0 { f[1][r] } else { -f[0][r] };
        });
        let at = |i: usize, j: usize| raw.xtx[i * raw_p + j];
        let regressors: Vec<usize> = (0..2 + kb).chain([raw_p - 2, raw_p - 1]).collect();
        let p = regressors.len();
        let t0 = 2 + kb;
        Ok((0..self.settings())
            .map(|s| {
                let th = self.angle_deg(s).to_radians();
                let w = [1.0, th.cos(), th.sin()];
                let mut g = Gram::new(p).with_bounds(gain_bounds(p));
                for (i, &ri) in regressors.iter().enumerate() {
                    for (j, &rj) in regressors.iter().enumerate() {
                        g.xtx[i * p + j] = at(ri, rj);
                    }
                    g.xty[i] = (0..3).map(|k| w[k] * at(ri, t0 + k)).sum();
                }
                g.yty = (0..3)
                    .map(|k| {
                        (0..3)
                            .map(|l| w[k] * w[l] * at(t0 + k, t0 + l))
                            .sum::<f64>()
                    })
                    .sum::<f64>()
                    .max(0.0);
                g.norm_sq = raw.norm_sq;
                g.n = raw.n;
                g
            })
            .collect())
    }
    fn parameters(&self, s: usize, _beta: &[f64], _latency_s: f64) -> Vec<(String, f64)> {
        vec![("angle_deg".to_string(), self.angle_deg(s))]
    }
}
