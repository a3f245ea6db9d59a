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

use super::candidate::{Candidate, Design, Designed, NUISANCE_COLUMNS, gain_bounds, push_rows};
use super::error::DiscrepancyError;
use super::gram::Gram;
use super::signals::BalanceSignals;

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
    fn name(&self) -> &'static str {
        "sensor-rotation"
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
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        // Raw Gram of [a_x·1x, a_y·1y, u, F_own, F_other, u·1x, u·1y] with target 0,
        // built (offsets eliminated) with the generic row pusher by treating all seven
        // as regressors; each angle's Gram is a quadratic form of it: regressors the
        // masses and the force gains, target `u + cos θ F_own + sin θ F_other`.
        let u = [
            sig.delayed_command(0, latency_s),
            sig.delayed_command(1, latency_s),
        ];
        let f = [sig.at_rows(&sig.f[0]), sig.at_rows(&sig.f[1])];
        let norms = [sig.at_rows(&sig.u[0]), sig.at_rows(&sig.u[1])];
        let zeros = [vec![0.0; sig.rows.len()], vec![0.0; sig.rows.len()]];
        const RAW: usize = 5 + NUISANCE_COLUMNS;
        let mut raw = Gram::new(RAW);
        push_rows(&mut raw, sig, &zeros, &norms, &u, |axis, r, x| {
            x[0] = u[axis][r];
            x[1] = f[axis][r];
            // x rows: +F_y; y rows: −F_x.
            x[2] = if axis == 0 { f[1][r] } else { -f[0][r] };
        });
        let at = |i: usize, j: usize| raw.xtx[i * RAW + j];
        let regressors = [0, 1, 5, 6];
        let p = regressors.len();
        Ok((0..self.settings())
            .map(|s| {
                let th = self.angle_deg(s).to_radians();
                let w = [1.0, th.cos(), th.sin()];
                let mut g = Gram::new(p).with_bounds(gain_bounds(p));
                for (i, &ri) in regressors.iter().enumerate() {
                    for (j, &rj) in regressors.iter().enumerate() {
                        g.xtx[i * p + j] = at(ri, rj);
                    }
                    g.xty[i] = (0..3).map(|k| w[k] * at(ri, 2 + k)).sum();
                }
                g.yty = (0..3)
                    .map(|k| (0..3).map(|l| w[k] * w[l] * at(2 + k, 2 + l)).sum::<f64>())
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
