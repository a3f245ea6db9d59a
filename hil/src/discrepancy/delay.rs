//! Candidate `actuation-delay`: the motor force lags its command, `u(t − τ)`.
//!
//! Every rig has some latency between the logged command and the force (compute tick,
//! zero-order hold of the 2 kHz motor update, the logging convention). The baseline
//! therefore fits its own latency within [`NOMINAL_LATENCY_MAX_S`] (two control ticks),
//! and this candidate reports the delay **beyond** the baseline's. When a hidden delay
//! is present the baseline's latency sits at that bound, so the report is the lag in
//! excess of a two-tick nominal rig; a rig whose own latency is shorter (the shared
//! emulated rig: 0.33 ms) gets its delay underestimated by the difference (≤ 0.5 ms).
//! The search is over a grid of lags at a tenth of a 4 kHz tick; between samples the
//! command is interpolated linearly.

use super::candidate::{Candidate, push_rows, residual_rows};
use super::error::DiscrepancyError;
use super::gram::Gram;
use super::signals::BalanceSignals;

/// Largest latency a nominal rig may have, s: two 4 kHz ticks — the command computed at
/// tick k acts from tick k + 1, and the 2 kHz zero-order hold adds half a motor period
/// (one tick) on average.
pub const NOMINAL_LATENCY_MAX_S: f64 = 0.5e-3;
/// Largest actuation delay searched, s. Far beyond it the stiff position loop of an
/// admittance rig could not stay stable.
pub const MAX_DELAY_S: f64 = 25e-3;

/// A delay search over `[0, max_s]` in steps of `step_s`.
#[derive(Debug, Clone, Copy)]
pub struct ActuationDelay {
    /// Largest lag, s.
    pub max_s: f64,
    /// Grid step, s.
    pub step_s: f64,
}

impl ActuationDelay {
    /// The catalog candidate: 0–25 ms in 25 µs steps (the nominal grid is a subset, so the baseline is nested).
    #[must_use]
    pub fn candidate() -> Self {
        ActuationDelay {
            max_s: MAX_DELAY_S,
            step_s: 25e-6,
        }
    }

    /// The nominal latency search of the baseline: 0–0.5 ms in 25 µs steps.
    #[must_use]
    pub fn nominal() -> Self {
        ActuationDelay {
            max_s: NOMINAL_LATENCY_MAX_S,
            step_s: 25e-6,
        }
    }

    /// Lag of setting `s`, s.
    #[must_use]
    pub fn lag_s(&self, s: usize) -> f64 {
        s as f64 * self.step_s
    }
}

impl Candidate for ActuationDelay {
    fn name(&self) -> &'static str {
        "actuation-delay"
    }
    fn settings(&self) -> usize {
        (self.max_s / self.step_s).round() as usize + 1
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("lag_ms", self.lag_s(s) * 1e3)
    }
    fn columns(&self) -> usize {
        2
    }
    fn grams(&self, sig: &BalanceSignals, _latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        let f = [sig.at_rows(&sig.f[0]), sig.at_rows(&sig.f[1])];
        let norms = [sig.at_rows(&sig.u[0]), sig.at_rows(&sig.u[1])];
        Ok((0..self.settings())
            .map(|s| {
                let lag = self.lag_s(s);
                let targets = [0, 1].map(|axis| {
                    sig.delayed_command(axis, lag)
                        .iter()
                        .zip(&f[axis])
                        .map(|(u, f)| u + f)
                        .collect::<Vec<_>>()
                });
                let mut g = Gram::new(2);
                push_rows(&mut g, sig, &targets, &norms, |_, _, _| {});
                g
            })
            .collect())
    }
    fn parameters(&self, s: usize, _beta: &[f64], latency_s: f64) -> Vec<(String, f64)> {
        vec![("delay_ms".to_string(), (self.lag_s(s) - latency_s) * 1e3)]
    }
    fn residual(
        &self,
        sig: &BalanceSignals,
        s: usize,
        beta: &[f64],
        _latency_s: f64,
    ) -> Result<[Vec<f64>; 2], DiscrepancyError> {
        let lag = self.lag_s(s);
        let t = [0, 1].map(|axis| {
            let f = sig.at_rows(&sig.f[axis]);
            sig.delayed_command(axis, lag)
                .iter()
                .zip(&f)
                .map(|(u, f)| u + f)
                .collect::<Vec<_>>()
        });
        Ok(residual_rows(sig, &t, beta, |_, _, _| {}))
    }
}
