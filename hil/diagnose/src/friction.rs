//! Candidate `rail-friction`: each cart feels `−(Fc · tanh(v / v_s) + b · v)` from its
//! own rail, the same law on both rails (the catalog's `coulomb_n`,
//! `viscous_n_s_per_m`, `smooth_velocity_m_per_s`). `Fc` and `b` enter linearly; the
//! smoothing velocity `v_s` is searched over a grid.

use super::candidate::{Candidate, Design, Designed};
use super::error::DiscrepancyError;
use super::signals::BalanceSignals;
use crate::effect::EffectKind;

/// Number of smoothing velocities tried: from nearly a sign function (0.2 mm/s) to a
/// soft knee at 1 cm/s, which spans what rails and their models use, 20 to a decade
/// (the R20 series, a factor `10^(1/20) ≈ 1.12` a step, through 1 mm/s exactly;
/// [`smooth_velocity_m_per_s`]). The held-out fit is sensitive to the knee: on the
/// shared friction session a knee 10 % off (1.1 mm/s for its 1 mm/s) left three times
/// the residual of the true one (gain 0.979 for 0.994); the former factor-2 grid
/// could be off by 41 %.
pub const SMOOTH_VELOCITY_STEPS: usize = 35;

/// Smoothing velocity of setting `s`, m/s: `1 mm/s · 10^((s − 14)/20)`.
#[must_use]
pub fn smooth_velocity_m_per_s(s: usize) -> f64 {
    1e-3 * 10f64.powf((s as f64 - 14.0) / 20.0)
}

/// The rail-friction candidate.
#[derive(Debug, Clone, Copy, Default)]
pub struct RailFriction;

impl Designed for RailFriction {
    /// The nominal balance plus, per axis, the filtered `tanh(v / v_s)` and the
    /// velocity (coefficients `Fc`, `b`: the friction force is `−(Fc tanh + b v)`, so
    /// on the target side of `u + F = m a + Fc tanh + b v` both enter with `+`).
    fn design(
        &self,
        sig: &BalanceSignals,
        s: usize,
        latency_s: f64,
    ) -> Result<Design, DiscrepancyError> {
        let vs = smooth_velocity_m_per_s(s);
        let own = |axis: usize| -> Result<Vec<Vec<f64>>, DiscrepancyError> {
            let raw: Vec<f64> = sig.v[axis].iter().map(|v| (v / vs).tanh()).collect();
            Ok(vec![
                sig.at_rows(&sig.smooth(&raw)?),
                sig.at_rows(&sig.v[axis]),
            ])
        };
        Ok(Design::nominal(sig, latency_s).with_own([own(0)?, own(1)?]))
    }
}

impl Candidate for RailFriction {
    fn kind(&self) -> Option<EffectKind> {
        Some(EffectKind::RailFriction)
    }
    fn settings(&self) -> usize {
        SMOOTH_VELOCITY_STEPS
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("smooth_velocity_m_per_s", smooth_velocity_m_per_s(s))
    }
    fn columns(&self) -> usize {
        4
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
        let vs = smooth_velocity_m_per_s(s);
        Some(-(beta.get(2)? * (v / vs).tanh() + beta.get(3)? * v))
    }
}
