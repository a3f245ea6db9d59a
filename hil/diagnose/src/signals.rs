//! The channels of one trial that the cart force balance needs, filtered so that the
//! balance holds term by term.
//!
//! Position, velocity and acceleration come from one Savitzky–Golay fit of the
//! encoder position (cubic, about 41 ms long). The forces (motor command, sensor force,
//! and the nonlinear regressors of friction) go through the **balance filter**: the
//! Savitzky–Golay second-derivative filter divided by the second difference
//! `x[k+1] − 2x[k] + x[k−1]`, an exact polynomial division that leaves a symmetric FIR
//! of `window − 2` taps summing to one ([`balance_filter`]). The carts integrate their
//! forces twice, so the second difference of the positions is (up to the 4 kHz ticks
//! inside a block, below 1 % at 200 Hz) the force over the mass; the acceleration
//! filter applied to the positions is then *exactly* the balance filter applied to the
//! forces, at every frequency, not only in the pass band.
//!
//! Why not the derivative-0 Savitzky–Golay filter for the forces, which agrees with
//! the acceleration filter in the pass band: above it the two leak differently. A rig
//! whose stiff position loop oscillates (an actuation delay of 1–1.5 ms drives a
//! 170–225 Hz limit cycle of tens of newtons in the command) leaks far more of that
//! oscillation into the smoothed command than into the smoothed acceleration, so no
//! delay can balance it. With the balance filter the masses come out within 0.1 % of
//! the plant's and the residual with the right delay falls to the noise floor of an
//! effect-free session. The measurements with the derivative-0 filter:
//! `hil/docs/notes/2026-12-03-cart-balance.md`.
//!
//! The balance is evaluated on every `decim`-th sample, away from the ends by half a
//! window: the filtered signals hold little above ~30 Hz, so samples closer than
//! ~2 ms carry almost no new information and only cost time.

use rigtwin_device::signal::{
    EdgeMode, SignalError, cumulative_trapezoid, savgol_coeffs, savgol_filter,
};

use super::error::DiscrepancyError;
use rigtwin_session::{Axes, Trial, TrialEntry};

/// Largest actuation delay searched, s (the delay candidate's grid ends here, and every
/// block of a trial keeps this much of the command before its rows). Far beyond it the
/// stiff position loop of an admittance rig could not stay stable.
pub const MAX_DELAY_S: f64 = 25e-3;

/// Length of the smoothing window, s. 41 ms with a cubic passes ~30 Hz: enough for the
/// reach (< 5 Hz), the 150 ms perturbation (< 20 Hz) and ripple up to v/p ≈ 30 Hz,
/// while the acceleration taken from a 1 µm encoder stays quiet enough not to bias
/// the fitted masses (errors in a regressor pull its coefficient towards zero; a
/// window of half the length has ~6 times the acceleration noise).
pub const SMOOTHING_WINDOW_S: f64 = 0.041;
/// Polynomial order of the Savitzky–Golay fit.
pub const SMOOTHING_ORDER: usize = 3;
/// Rate at which the balance is evaluated, Hz (see the module docs).
pub const EVALUATION_RATE_HZ: f64 = 500.0;

/// Below this speed (smoothed, on every present axis) a carriage without a force
/// sensor counts as at rest ([`BalanceSignals::on_axes`]), m/s: 2 mm/s, forty times
/// the smoothed velocity's noise on a 1 µm encoder and a hundredth of a bench move's
/// peak speed; between 2 and 20 mm/s the fitted friction of the project's servo axis
/// moves by less than 1 %.
pub const REST_SPEED_M_PER_S: f64 = 2e-3;

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
    /// Motor command through the balance filter, N.
    pub u: [Vec<f64>; 2],
    /// Sensor force (hand on handle, through the sensor) through the balance filter, N.
    pub f: [Vec<f64>; 2],
    /// Encoder position as recorded, m (for [`Self::fast_match`]).
    pub q_raw: [Vec<f64>; 2],
    /// Motor command as recorded, N (for [`Self::with_fast_velocity`]).
    pub u_raw: [Vec<f64>; 2],
    /// Sensor force as recorded, N (for [`Self::with_fast_velocity`]).
    pub f_raw: [Vec<f64>; 2],
    /// The carts' velocity above the smoothing's pass band, m/s: empty until
    /// [`Self::with_fast_velocity`] fills it from the forces and the fitted masses.
    pub v_fast: [Vec<f64>; 2],
    /// The balance filter's taps (`balance_filter`).
    pub force_taps: Vec<f64>,
    /// Evaluated sample indices.
    pub rows: Vec<usize>,
    /// Which axes the rig has (`axes` in the manifest; both unless [`Self::on_axes`]
    /// says otherwise). An absent axis contributes no rows to any balance.
    pub axes: Axes,
    /// Whether the trial has a handle force sensor: some force sample is not zero. A
    /// one-axis stage logs none, and its force columns are zero; then the motor's
    /// force gain cannot be told from the masses (the balance holds only `u`), so its
    /// column is left out and the masses come out in the command's units.
    pub sensed: bool,
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
        let taps = trial_balance_filter(window, dt, entry.id)?;
        let force = |x: &[f64]| filter_force(&taps, x, entry.id);
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
            u: [force(ux)?, force(uy)?],
            f: [force(&trial.fx_n)?, force(&trial.fy_n)?],
            q_raw: [trial.x_m.clone(), trial.y_m.clone()],
            u_raw: [ux.clone(), uy.clone()],
            f_raw: [trial.fx_n.clone(), trial.fy_n.clone()],
            v_fast: [Vec::new(), Vec::new()],
            force_taps: taps,
            rows,
            axes: Axes::Both,
            sensed: trial.fx_n.iter().chain(&trial.fy_n).any(|f| *f != 0.0),
        }))
    }

    /// The same signals on the axes `axes` (a session's `axes`). Without a force sensor
    /// (a servo stage under a position loop), rows within half a smoothing window of a
    /// sample where every present axis moves slower than [`REST_SPEED_M_PER_S`] are
    /// left out: a carriage at rest holds static friction, any force within `±F_s` that
    /// no law of velocity gives, and the loop's command there says nothing about the
    /// masses; the balance filter spreads that force over its window, where it biased
    /// the fitted delay of the project's servo axis by 0.9 ms (0.25 ms without it). A careful identification of such an
    /// axis fits its moving samples alone, as this does. With a sensor the hand keeps
    /// the carts in motion and the still phases stay in (they tell an offset from a
    /// Coulomb friction on one-signed reaches).
    #[must_use]
    pub fn on_axes(mut self, axes: Axes) -> Self {
        self.axes = axes;
        if !self.sensed {
            // Rest samples, and their running count, so that a row is kept only when its
            // window (the balance filter's reach) holds none.
            let v = &self.v;
            let n = v[0].len();
            let mut at_rest = vec![0usize; n + 1];
            for j in 0..n {
                let rest = (0..2).all(|a| !axes.has(a) || v[a][j].abs() < REST_SPEED_M_PER_S);
                at_rest[j + 1] = at_rest[j] + usize::from(rest);
            }
            let half = self.window / 2;
            self.rows.retain(|&i| {
                let (lo, hi) = (i.saturating_sub(half), (i + half + 1).min(n));
                at_rest[hi] == at_rest[lo]
            });
        }
        self
    }

    /// The part of this trial around the evaluated rows `rows` (a subset of
    /// [`Self::rows`], in order), as a trial of its own: every full-rate channel cut to
    /// the rows' span plus a margin of a smoothing window and the longest delay searched
    /// on each side, so that everything evaluated at the rows (smoothed regressors,
    /// delayed commands) has the values it has in the whole trial. A long continuous
    /// log's blocks are cut so: with whole copies, each block's work scaled with the
    /// log's length (a ten-minute log took 8 min to diagnose).
    #[must_use]
    pub fn block(&self, rows: &[usize]) -> BalanceSignals {
        let n = self.q[0].len();
        let margin = self.window + (MAX_DELAY_S * self.rate_hz).ceil() as usize + 2;
        let (first, last) = (
            rows.first().copied().unwrap_or(0),
            rows.last().copied().unwrap_or(0),
        );
        let lo = first.saturating_sub(margin);
        let hi = (last + margin + 1).min(n);
        // A channel already dropped (`drop_recorded`) or not yet filled stays empty.
        let cut = |x: &[Vec<f64>; 2]| {
            [0, 1].map(|a| x[a].get(lo..hi).map_or_else(Vec::new, <[f64]>::to_vec))
        };
        BalanceSignals {
            id: self.id,
            perturbed: self.perturbed,
            rate_hz: self.rate_hz,
            window: self.window,
            decim: self.decim,
            q: cut(&self.q),
            v: cut(&self.v),
            a: cut(&self.a),
            u: cut(&self.u),
            f: cut(&self.f),
            q_raw: cut(&self.q_raw),
            u_raw: cut(&self.u_raw),
            f_raw: cut(&self.f_raw),
            v_fast: cut(&self.v_fast),
            force_taps: self.force_taps.clone(),
            rows: rows.iter().map(|r| r - lo).collect(),
            axes: self.axes,
            sensed: self.sensed,
        }
    }

    /// The same signals with [`Self::v_fast`]: per axis, the velocity the forces give
    /// the carts above the smoothing's pass band, `w − S(w)` with
    /// `w = ∫ (g·u + F) / m dt` (the recorded command and sensor force, the fitted
    /// moving mass `m` and motor force gain `g`) and `S` the position's
    /// Savitzky–Golay smoothing. The smoothed velocity [`Self::v`] passes ~30 Hz; a
    /// stiff position loop with a delay oscillates at ~200 Hz with velocities of a few
    /// mm/s, as large as a rail friction's knee, and the friction force follows the
    /// cart's whole velocity, `v + v_fast`. An axis whose mass is not positive and
    /// finite keeps no fast part (zeros).
    ///
    /// # Errors
    /// A signal-processing error (a non-finite recorded value).
    pub fn with_fast_velocity(
        mut self,
        mass_kg: [f64; 2],
        gain: [f64; 2],
    ) -> Result<Self, DiscrepancyError> {
        let dt = 1.0 / self.rate_hz;
        let n = self.u_raw[0].len();
        for axis in 0..2 {
            let m = mass_kg[axis];
            if !(m.is_finite() && m > 0.0 && gain[axis].is_finite()) {
                self.v_fast[axis] = vec![0.0; n];
                continue;
            }
            let acc: Vec<f64> = self.u_raw[axis]
                .iter()
                .zip(&self.f_raw[axis])
                .map(|(u, f)| (gain[axis] * u + if self.sensed { *f } else { 0.0 }) / m)
                .collect();
            self.v_fast[axis] = self.above_smoothing(&cumulative_trapezoid(&acc, dt))?;
        }
        Ok(self)
    }

    /// `x − S(x)`: the part of a full-rate channel above the position's Savitzky–Golay
    /// smoothing `S` (the smoothing of [`Self::q`]).
    fn above_smoothing(&self, x: &[f64]) -> Result<Vec<f64>, DiscrepancyError> {
        let dt = 1.0 / self.rate_hz;
        let slow = savgol_filter(x, self.window, SMOOTHING_ORDER, 0, dt, EdgeMode::Interp)
            .map_err(|source| DiscrepancyError::Signal {
                trial: self.id,
                source,
            })?;
        Ok(x.iter().zip(&slow).map(|(a, b)| a - b).collect())
    }

    /// How the encoder sees the fast velocity: per axis, `Σ p(t) e(t + l)` for every
    /// lag `l` in `−max_lag..=max_lag` samples, and `Σ e(t)²`, over the evaluated rows,
    /// with `p = q_raw − q` the recorded position's part above the smoothing and
    /// `e = ∫ v_fast − S(∫ v_fast)` the same part of the position [`Self::v_fast`]
    /// gives. The encoder's quantisation is uncorrelated with `e`, so summed over a
    /// session `Σ p e / Σ e²` at the best lag is the factor by which the forces' fast
    /// velocity is off (what the motor's current loop does above its band, and the
    /// fitted mass's error, included) without the quantisation's bias. An axis without
    /// a fast velocity gives no lags and 0.
    ///
    /// # Errors
    /// A signal-processing error.
    pub fn fast_match(&self, max_lag: usize) -> Result<[(Vec<f64>, f64); 2], DiscrepancyError> {
        let dt = 1.0 / self.rate_hz;
        let mut out = [(Vec::new(), 0.0), (Vec::new(), 0.0)];
        for (axis, (nums, den)) in out.iter_mut().enumerate() {
            let (q, fast) = (&self.q_raw[axis], &self.v_fast[axis]);
            if fast.len() != q.len() {
                continue;
            }
            let e = self.above_smoothing(&cumulative_trapezoid(fast, dt))?;
            let n = e.len() as isize;
            *den = self.rows.iter().map(|&i| e[i] * e[i]).sum();
            let p: Vec<f64> = self.rows.iter().map(|&i| q[i] - self.q[axis][i]).collect();
            *nums = (-(max_lag as isize)..=max_lag as isize)
                .map(|l| {
                    self.rows
                        .iter()
                        .zip(&p)
                        .filter_map(|(&i, p)| {
                            let j = i as isize + l;
                            (0..n).contains(&j).then(|| p * e[j as usize])
                        })
                        .sum::<f64>()
                })
                .collect();
        }
        Ok(out)
    }

    /// [`Self::v_fast`] of `axis` replaced by `factor · v_fast(t + lag)`, `lag` in
    /// samples (the ends hold their last value): the best lag of [`Self::fast_match`].
    pub fn match_fast(&mut self, axis: usize, factor: f64, lag: isize) {
        let v = &self.v_fast[axis];
        let n = v.len() as isize;
        if n == 0 {
            return;
        }
        self.v_fast[axis] = (0..n)
            .map(|i| factor * v[(i + lag).clamp(0, n - 1) as usize])
            .collect();
    }

    /// Frees the recorded copies ([`Self::q_raw`], [`Self::u_raw`], [`Self::f_raw`])
    /// once [`Self::v_fast`] is matched: nothing else reads them.
    pub fn drop_recorded(&mut self) {
        for c in [&mut self.q_raw, &mut self.u_raw, &mut self.f_raw] {
            *c = [Vec::new(), Vec::new()];
        }
    }

    /// The cart's whole velocity on `axis` at full rate: the smoothed one plus
    /// [`Self::v_fast`] when it is filled.
    #[must_use]
    pub fn whole_velocity(&self, axis: usize) -> Vec<f64> {
        let fast = &self.v_fast[axis];
        if fast.len() == self.v[axis].len() {
            self.v[axis].iter().zip(fast).map(|(v, f)| v + f).collect()
        } else {
            self.v[axis].clone()
        }
    }

    /// Whether `axis` contributes rows to the balance.
    #[must_use]
    pub fn present(&self, axis: usize) -> bool {
        self.axes.has(axis)
    }

    /// The nuisance column of a row whose command enters the balance as `gain`.
    ///
    /// With a force sensor it is the command itself (the force constant's error `γ`,
    /// bounded) and each trial's offsets are eliminated (a sensor's tare). Without one
    /// the command's scale cannot be told from the masses (the balance holds only `u`),
    /// and a constant force on the carriage (a cable's pull, a tilted rail, an
    /// amplifier's offset) is a property of the axis, not of a trial: the column is a
    /// constant 1, unbounded, one per axis for the whole session, and its coefficient is
    /// that force (the part of the command spent on it, N).
    #[must_use]
    pub fn nuisance(&self, gain: f64) -> f64 {
        if self.sensed { gain } else { 1.0 }
    }

    /// Whether each trial's constant force per axis is eliminated (a sensor's tare):
    /// with a force sensor only (see [`Self::nuisance`]).
    #[must_use]
    pub fn per_trial_offsets(&self) -> bool {
        self.sensed
    }

    /// The balance filter applied to a force column computed from this trial's samples
    /// (a friction regressor), so that it enters the balance like the measured forces.
    ///
    /// # Errors
    /// A signal-processing error (a non-finite value in `x`).
    pub fn smooth(&self, x: &[f64]) -> Result<Vec<f64>, DiscrepancyError> {
        filter_force(&self.force_taps, x, self.id)
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

/// The balance filter for a Savitzky–Golay `window` (cubic) at sample spacing `dt_s`:
/// the taps `h` with `h ∗ [1, −2, 1] = dt² · c₂`, where `c₂` is the second-derivative
/// Savitzky–Golay filter. `c₂` annihilates constants and lines, so `[1, −2, 1]`
/// divides it exactly; the quotient has `window − 2` symmetric taps that sum to one
/// (the filter passes a constant force unchanged, as `c₂` gives a parabola's
/// curvature exactly).
///
/// # Errors
/// A window or spacing that the Savitzky–Golay design refuses.
pub fn balance_filter(window: usize, dt_s: f64) -> Result<Vec<f64>, SignalError> {
    let c2 = savgol_coeffs(window, SMOOTHING_ORDER, 2, dt_s)?;
    let mut h = vec![0.0; window.saturating_sub(2)];
    for k in 0..h.len() {
        let prev = if k >= 1 { h[k - 1] } else { 0.0 };
        let prev2 = if k >= 2 { h[k - 2] } else { 0.0 };
        h[k] = c2[k] * dt_s * dt_s + 2.0 * prev - prev2;
    }
    Ok(h)
}

/// [`balance_filter`] for trial `trial`'s window and spacing; an error names the trial.
///
/// # Errors
/// A window or spacing that the Savitzky–Golay design refuses.
pub fn trial_balance_filter(
    window: usize,
    dt_s: f64,
    trial: u32,
) -> Result<Vec<f64>, DiscrepancyError> {
    balance_filter(window, dt_s).map_err(|source| DiscrepancyError::Signal { trial, source })
}

/// A force column of trial `trial` through the balance filter `taps`.
///
/// # Errors
/// A non-finite value in `x`, naming the trial and the sample.
pub fn filter_force(taps: &[f64], x: &[f64], trial: u32) -> Result<Vec<f64>, DiscrepancyError> {
    fir_clamped(taps, x).map_err(|source| DiscrepancyError::Signal { trial, source })
}

/// `x` through the symmetric FIR `taps` (odd length), centred; samples beyond the ends
/// are the end samples (only the half window at each end, outside the evaluated rows,
/// sees them).
fn fir_clamped(taps: &[f64], x: &[f64]) -> Result<Vec<f64>, SignalError> {
    if let Some((index, value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SignalError::NonFinite {
            index,
            value: *value,
        });
    }
    let n = x.len() as isize;
    let half = (taps.len() / 2) as isize;
    Ok((0..n)
        .map(|i| {
            taps.iter()
                .enumerate()
                .map(|(k, h)| h * x[(i + half - k as isize).clamp(0, n - 1) as usize])
                .sum()
        })
        .collect())
}
