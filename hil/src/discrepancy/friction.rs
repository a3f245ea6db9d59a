//! Candidate `rail-friction`: each cart feels `−(Fc · tanh(v / v_s) + b · v)` from its
//! own rail, the same law on both rails (the catalog's `coulomb_n`,
//! `viscous_n_s_per_m`, `smooth_velocity_m_per_s`). `Fc` and `b` enter linearly; the
//! smoothing velocity `v_s` is searched over a grid.

use super::candidate::{Candidate, nominal_target, push_rows, residual_rows};
use super::error::DiscrepancyError;
use super::gram::Gram;
use super::signals::BalanceSignals;

/// Smoothing velocities tried, m/s: from nearly a sign function to a soft knee at
/// 1 cm/s, which spans what rails and their models use.
pub const SMOOTH_VELOCITIES_M_PER_S: [f64; 7] = [2e-4, 5e-4, 1e-3, 2e-3, 4e-3, 7e-3, 1e-2];

/// The rail-friction candidate.
#[derive(Debug, Clone, Copy, Default)]
pub struct RailFriction;

impl Candidate for RailFriction {
    fn name(&self) -> &'static str {
        "rail-friction"
    }
    fn settings(&self) -> usize {
        SMOOTH_VELOCITIES_M_PER_S.len()
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        (
            "smooth_velocity_m_per_s",
            SMOOTH_VELOCITIES_M_PER_S
                .get(s)
                .copied()
                .unwrap_or(f64::NAN),
        )
    }
    fn columns(&self) -> usize {
        4
    }
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        let (tx, nx) = nominal_target(sig, 0, latency_s);
        let (ty, ny) = nominal_target(sig, 1, latency_s);
        let targets = [tx, ty];
        let norms = [nx, ny];
        let v = [sig.at_rows(&sig.v[0]), sig.at_rows(&sig.v[1])];
        SMOOTH_VELOCITIES_M_PER_S
            .iter()
            .map(|vs| {
                let tanh = |axis: usize| -> Result<Vec<f64>, DiscrepancyError> {
                    let raw: Vec<f64> = sig.v[axis].iter().map(|v| (v / vs).tanh()).collect();
                    Ok(sig.at_rows(&sig.smooth(&raw)?))
                };
                let th = [tanh(0)?, tanh(1)?];
                let mut g = Gram::new(4);
                push_rows(&mut g, sig, &targets, &norms, |axis, r, x| {
                    x[0] = th[axis][r];
                    x[1] = v[axis][r];
                });
                Ok(g)
            })
            .collect()
    }
    fn parameters(&self, s: usize, beta: &[f64], _latency_s: f64) -> Vec<(String, f64)> {
        vec![
            (
                "coulomb_n".to_string(),
                beta.get(2).copied().unwrap_or(f64::NAN),
            ),
            (
                "viscous_n_s_per_m".to_string(),
                beta.get(3).copied().unwrap_or(f64::NAN),
            ),
            ("smooth_velocity_m_per_s".to_string(), self.setting(s).1),
        ]
    }
    fn effect_force(&self, s: usize, beta: &[f64], _axis: usize, _q: f64, v: f64) -> Option<f64> {
        let vs = SMOOTH_VELOCITIES_M_PER_S.get(s)?;
        Some(-(beta.get(2)? * (v / vs).tanh() + beta.get(3)? * v))
    }
    fn residual(
        &self,
        sig: &BalanceSignals,
        s: usize,
        beta: &[f64],
        latency_s: f64,
    ) -> Result<[Vec<f64>; 2], DiscrepancyError> {
        let vs = SMOOTH_VELOCITIES_M_PER_S.get(s).copied().unwrap_or(1e-3);
        let t = [
            nominal_target(sig, 0, latency_s).0,
            nominal_target(sig, 1, latency_s).0,
        ];
        let v = [sig.at_rows(&sig.v[0]), sig.at_rows(&sig.v[1])];
        let tanh = |axis: usize| -> Result<Vec<f64>, DiscrepancyError> {
            let raw: Vec<f64> = sig.v[axis].iter().map(|v| (v / vs).tanh()).collect();
            Ok(sig.at_rows(&sig.smooth(&raw)?))
        };
        let th = [tanh(0)?, tanh(1)?];
        Ok(residual_rows(sig, &t, beta, |axis, r, x| {
            x[0] = th[axis][r];
            x[1] = v[axis][r];
        }))
    }
}
