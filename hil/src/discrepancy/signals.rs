//! The channels of one trial that the cart force balance needs, smoothed alike.
//!
//! Position, velocity and acceleration come from one Savitzky–Golay fit of the
//! encoder position (cubic, about 41 ms long); the motor command and the sensor force
//! go through the same smoothing (derivative 0), so that every term of the balance
//! `m·a = u + F + effects` has passed the same filter and the filter's own lag and
//! roll-off cancel out of the comparison. Regressors that are nonlinear in the state
//! (friction, ripple) are evaluated sample by sample and smoothed by the same filter
//! before use ([`BalanceSignals::smooth`]).
//!
//! The balance is evaluated on every `decim`-th sample, away from the ends by half a
//! window: the smoothed signals hold little above ~30 Hz, so samples closer than
//! ~2 ms carry almost no new information and only cost time.

use rigtwin_device::signal::{EdgeMode, savgol_filter};

use super::error::DiscrepancyError;
use crate::session::{Trial, TrialEntry};

/// Length of the smoothing window, s. 41 ms with a cubic passes ~30 Hz: enough for the
/// reach (< 5 Hz), the 150 ms perturbation (< 20 Hz) and ripple up to v/p ≈ 30 Hz. A
/// 21 ms window doubled the nominal balance's residual on the project's plant (the
/// position loop's jitter and the encoder quantum pass into the acceleration), an 81 ms
/// one starts to bias the fitted masses (12.9 instead of 12.3 kg).
pub const SMOOTHING_WINDOW_S: f64 = 0.041;
/// Polynomial order of the Savitzky–Golay fit.
pub const SMOOTHING_ORDER: usize = 3;
/// Rate at which the balance is evaluated, Hz (see the module docs).
pub const EVALUATION_RATE_HZ: f64 = 500.0;

/// One trial's smoothed channels at the recording rate, per axis `[x, y]`.
#[derive(Debug, Clone)]
pub struct BalanceSignals {
    /// Trial id.
    pub id: u32,
    /// Whether the trial was perturbed.
    pub perturbed: bool,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Smoothing window, samples (odd).
    pub window: usize,
    /// Step between evaluated samples.
    pub decim: usize,
    /// Cart position, m.
    pub q: [Vec<f64>; 2],
    /// Cart velocity, m/s.
    pub v: [Vec<f64>; 2],
    /// Cart acceleration, m/s².
    pub a: [Vec<f64>; 2],
    /// Motor command, N.
    pub u: [Vec<f64>; 2],
    /// Sensor force (hand on handle, through the sensor), N.
    pub f: [Vec<f64>; 2],
    /// Evaluated sample indices.
    pub rows: Vec<usize>,
}

/// The smoothing window in samples for a rate: odd, at least 5.
#[must_use]
pub fn window_for_rate(rate_hz: f64) -> usize {
    let n = (SMOOTHING_WINDOW_S * rate_hz).round().max(5.0) as usize;
    if n.is_multiple_of(2) { n + 1 } else { n }
}

impl BalanceSignals {
    /// Smooths a trial's channels. `None` when the trial has no motor command
    /// columns (the balance cannot be written without them).
    ///
    /// # Errors
    /// [`DiscrepancyError::RateTooLow`], [`DiscrepancyError::TrialTooShort`] or a
    /// signal-processing error.
    pub fn from_trial(
        entry: &TrialEntry,
        trial: &Trial,
        rate_hz: f64,
    ) -> Result<Option<Self>, DiscrepancyError> {
        let (Some(ux), Some(uy)) = (&trial.cmd_fx_n, &trial.cmd_fy_n) else {
            return Ok(None);
        };
        if !(rate_hz.is_finite() && rate_hz >= 200.0) {
            return Err(DiscrepancyError::RateTooLow { rate_hz });
        }
        let window = window_for_rate(rate_hz);
        let n = trial.len();
        if n < 2 * window + 2 {
            return Err(DiscrepancyError::TrialTooShort {
                trial: entry.id,
                samples: n,
                window: 2 * window + 2,
            });
        }
        let dt = 1.0 / rate_hz;
        let sg = |x: &[f64], deriv: usize| {
            savgol_filter(x, window, SMOOTHING_ORDER, deriv, dt, EdgeMode::Interp).map_err(
                |source| DiscrepancyError::Signal {
                    trial: entry.id,
                    source,
                },
            )
        };
        let decim = ((rate_hz / EVALUATION_RATE_HZ).round() as usize).max(1);
        let half = window / 2;
        let rows = (half..n - half).step_by(decim).collect();
        Ok(Some(BalanceSignals {
            id: entry.id,
            perturbed: entry.perturbation.is_some(),
            rate_hz,
            window,
            decim,
            q: [sg(&trial.x_m, 0)?, sg(&trial.y_m, 0)?],
            v: [sg(&trial.x_m, 1)?, sg(&trial.y_m, 1)?],
            a: [sg(&trial.x_m, 2)?, sg(&trial.y_m, 2)?],
            u: [sg(ux, 0)?, sg(uy, 0)?],
            f: [sg(&trial.fx_n, 0)?, sg(&trial.fy_n, 0)?],
            rows,
        }))
    }

    /// The same smoothing applied to a column computed from this trial's samples.
    ///
    /// # Errors
    /// A signal-processing error (a non-finite value in `x`).
    pub fn smooth(&self, x: &[f64]) -> Result<Vec<f64>, DiscrepancyError> {
        savgol_filter(
            x,
            self.window,
            SMOOTHING_ORDER,
            0,
            1.0 / self.rate_hz,
            EdgeMode::Interp,
        )
        .map_err(|source| DiscrepancyError::Signal {
            trial: self.id,
            source,
        })
    }

    /// The motor command of `axis` delayed by `delay_s` (`u(t − delay)`), at the
    /// evaluated rows; linear interpolation between samples, the first sample before
    /// the start.
    #[must_use]
    pub fn delayed_command(&self, axis: usize, delay_s: f64) -> Vec<f64> {
        let u = &self.u[axis];
        let lag = delay_s * self.rate_hz;
        self.rows
            .iter()
            .map(|&i| {
                let t = i as f64 - lag;
                if t <= 0.0 {
                    return u[0];
                }
                let k = t.floor() as usize;
                let w = t - k as f64;
                match (u.get(k), u.get(k + 1)) {
                    (Some(a), Some(b)) => a + w * (b - a),
                    (Some(a), None) => *a,
                    _ => u[u.len() - 1],
                }
            })
            .collect()
    }

    /// Values of a full-rate column at the evaluated rows.
    #[must_use]
    pub fn at_rows(&self, x: &[f64]) -> Vec<f64> {
        self.rows
            .iter()
            .map(|&i| x.get(i).copied().unwrap_or(0.0))
            .collect()
    }

    /// Travel of `axis` over the trial, m.
    #[must_use]
    pub fn travel_m(&self, axis: usize) -> f64 {
        let q = &self.q[axis];
        let lo = q.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = q.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (hi - lo).max(0.0)
    }
}
