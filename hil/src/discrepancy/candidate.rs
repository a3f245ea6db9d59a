//! The force balance of the carts and the interface every candidate model fills in.
//!
//! With the sensor under the handle, the force the sensor reads is the force the handle
//! transmits to the upper cart, handle inertia included. So the carts alone obey, per
//! axis (x: lower cart carrying the upper one; y: upper cart only — the y rail sits on
//! the lower cart and takes every x reaction):
//!
//! ```text
//! m_x · a_x = u_x(t − τ) + F_x + ripple_x(x) − friction_x(v_x)
//! m_y · a_y = u_y(t − τ) + F_y + ripple_y(y) − friction_y(v_y)
//! ```
//!
//! where `u` is the motor command, `F` the sensor reading (rotated back into the rig
//! frame if the sensor is rotated), `m_x = m_lower + m_upper`, `m_y = m_upper`. The
//! admittance law and the position loop do not appear: whatever the controller does,
//! the motor force is `u`, so the balance needs no model of the controller and no
//! simulation. The handle mass does not appear either: it sits above the sensor.
//!
//! The target of every fit is `u + F` (the force the model must account for) and the
//! regressors are the cart accelerations (whose coefficients are the unknown masses)
//! plus each candidate's own terms. Rows of both axes are stacked, so parameters that
//! the catalog shares between the axes (friction, ripple, delay, rotation) are fitted
//! once. The normaliser of the NRMSE is the motor command itself: the error is the
//! error of predicting the force the motor had to make.

use super::error::DiscrepancyError;
use super::gram::Gram;
use super::signals::BalanceSignals;

/// A candidate plant effect: a family of linear least-squares problems, one per
/// setting of its nonlinear parameter (pitch, delay, angle, smoothing velocity).
pub trait Candidate: Sync + Send {
    /// Catalog name (`rail-friction`, ...).
    fn name(&self) -> &'static str;
    /// Number of settings of the nonlinear parameter.
    fn settings(&self) -> usize;
    /// The nonlinear parameter's name (with unit) and its value at setting `s`.
    fn setting(&self, s: usize) -> (&'static str, f64);
    /// Regressors: the two masses first, then the candidate's own.
    fn columns(&self) -> usize;
    /// One trial's Gram for every setting.
    ///
    /// # Errors
    /// A signal-processing error while smoothing a regressor.
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError>;
    /// The catalog parameters (name with unit, value) from setting `s` and the fitted
    /// coefficients `beta` (masses first).
    fn parameters(&self, s: usize, beta: &[f64], latency_s: f64) -> Vec<(String, f64)>;
    /// The force the effect adds to the carts (N) at state `(q, v)` of `axis`, for
    /// plots of the residual against position or velocity; `None` when the effect does
    /// not depend on the state alone.
    fn effect_force(&self, s: usize, beta: &[f64], axis: usize, q: f64, v: f64) -> Option<f64> {
        let _ = (s, beta, axis, q, v);
        None
    }
    /// The residual of the balance (target minus fit, N) on the evaluated rows of each
    /// axis, at setting `s` with coefficients `beta`.
    ///
    /// # Errors
    /// A signal-processing error while smoothing a regressor.
    fn residual(
        &self,
        sig: &BalanceSignals,
        s: usize,
        beta: &[f64],
        latency_s: f64,
    ) -> Result<[Vec<f64>; 2], DiscrepancyError>;
}

/// `y − x·β` on the rows of both axes, with `x = [a·[axis = x], a·[axis = y], extra…]`.
pub fn residual_rows(
    sig: &BalanceSignals,
    targets: &[Vec<f64>; 2],
    beta: &[f64],
    mut extra: impl FnMut(usize, usize, &mut [f64]),
) -> [Vec<f64>; 2] {
    let mut x = vec![0.0; beta.len()];
    [0, 1].map(|axis| {
        let a = sig.at_rows(&sig.a[axis]);
        a.iter()
            .zip(&targets[axis])
            .enumerate()
            .map(|(r, (acc, y))| {
                x.iter_mut().for_each(|v| *v = 0.0);
                x[axis] = *acc;
                if x.len() > 2 {
                    extra(axis, r, &mut x[2..]);
                }
                y - x.iter().zip(beta).map(|(a, b)| a * b).sum::<f64>()
            })
            .collect()
    })
}

/// The nominal balance's target `u(t − latency) + F` on the evaluated rows of `axis`,
/// and the normaliser `u` there.
#[must_use]
pub fn nominal_target(sig: &BalanceSignals, axis: usize, latency_s: f64) -> (Vec<f64>, Vec<f64>) {
    let u = sig.delayed_command(axis, latency_s);
    let f = sig.at_rows(&sig.f[axis]);
    let norm = sig.at_rows(&sig.u[axis]);
    (u.iter().zip(&f).map(|(u, f)| u + f).collect(), norm)
}

/// Adds the rows of both axes to `g`: regressors `[a·[axis = x], a·[axis = y], extra…]`
/// where `extra(axis, row)` writes the candidate's own regressors.
pub fn push_rows(
    g: &mut Gram,
    sig: &BalanceSignals,
    targets: &[Vec<f64>; 2],
    norms: &[Vec<f64>; 2],
    mut extra: impl FnMut(usize, usize, &mut [f64]),
) {
    let mut x = vec![0.0; g.p];
    for axis in 0..2 {
        let a = sig.at_rows(&sig.a[axis]);
        for (r, ((acc, y), n)) in a.iter().zip(&targets[axis]).zip(&norms[axis]).enumerate() {
            x.iter_mut().for_each(|v| *v = 0.0);
            x[axis] = *acc;
            extra(axis, r, &mut x[2..]);
            g.push(&x, *y, *n);
        }
    }
}

/// The baseline: the nominal balance with fitted masses only, at the nominal latency.
#[derive(Debug, Clone, Copy, Default)]
pub struct Baseline;

impl Candidate for Baseline {
    fn name(&self) -> &'static str {
        "baseline"
    }
    fn settings(&self) -> usize {
        1
    }
    fn setting(&self, _s: usize) -> (&'static str, f64) {
        ("none", 0.0)
    }
    fn columns(&self) -> usize {
        2
    }
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        let (tx, nx) = nominal_target(sig, 0, latency_s);
        let (ty, ny) = nominal_target(sig, 1, latency_s);
        let mut g = Gram::new(2);
        push_rows(&mut g, sig, &[tx, ty], &[nx, ny], |_, _, _| {});
        Ok(vec![g])
    }
    fn parameters(&self, _s: usize, beta: &[f64], latency_s: f64) -> Vec<(String, f64)> {
        masses(beta)
            .into_iter()
            .chain([("latency_ms".to_string(), latency_s * 1e3)])
            .collect()
    }
    fn effect_force(
        &self,
        _s: usize,
        _beta: &[f64],
        _axis: usize,
        _q: f64,
        _v: f64,
    ) -> Option<f64> {
        Some(0.0)
    }
    fn residual(
        &self,
        sig: &BalanceSignals,
        _s: usize,
        beta: &[f64],
        latency_s: f64,
    ) -> Result<[Vec<f64>; 2], DiscrepancyError> {
        let t = [
            nominal_target(sig, 0, latency_s).0,
            nominal_target(sig, 1, latency_s).0,
        ];
        Ok(residual_rows(sig, &t, beta, |_, _, _| {}))
    }
}

/// The fitted masses as named parameters: x carries both carts, y the upper cart.
#[must_use]
pub fn masses(beta: &[f64]) -> Vec<(String, f64)> {
    vec![
        (
            "moving_mass_x_kg".to_string(),
            beta.first().copied().unwrap_or(f64::NAN),
        ),
        (
            "moving_mass_y_kg".to_string(),
            beta.get(1).copied().unwrap_or(f64::NAN),
        ),
    ]
}
