//! Candidate `actuation-delay`: the motor force lags its command, `u(t − τ)`.
//!
//! With the balance filter of `signals.rs` the nominal balance is exact in time: the
//! logged command is the command as the motor holds it, tick by tick, so a rig that
//! applies the command in the tick it is computed shows no lag at all (the project's
//! plant and the shared rig both fit 0–0.05 ms). The baseline still fits a latency
//! within [`NOMINAL_LATENCY_MAX_S`] — one 4 kHz tick, for a rig that applies the
//! command of tick k from tick k + 1 — and this candidate searches the whole lag. Its
//! `delay_ms` is that whole lag from the logged command to the force, which is what
//! the simulator's delay line adds to a plant without latency (`--write-model`); the
//! baseline's latency is reported beside it, not subtracted (on a delayed rig the
//! baseline's latency sits at its bound, so subtracting it would bias the delay low by
//! a tick). The whole lag includes the rig's own: a delay line of `n` ticks is found at
//! `n` × 0.25 ms plus what the same rig fits without it, to one grid step (0.05 ms on
//! the project's plant, noise-free; `the_found_delay_is_the_hidden_one_plus_the_rigs_own_lag`
//! in `tests/tests/hidden_delay.rs`). Between samples the filtered command is interpolated linearly: the balance
//! filter passes little above ~30 Hz, where linear interpolation at 1 kHz is exact to
//! 0.1 %.

use super::candidate::{Candidate, Design, Designed, Reshape};
use super::error::DiscrepancyError;
use super::signals::BalanceSignals;
use crate::effect::EffectKind;

/// Largest latency a nominal rig may have, s: one 4 kHz tick — the command computed at
/// tick k acts from tick k + 1 at the latest. The 2 kHz zero-order hold adds nothing:
/// the logged command is already the held one. (A looser bound lets the baseline
/// absorb part of a delay; `hil/docs/notes/2026-12-03-cart-balance.md`.)
pub const NOMINAL_LATENCY_MAX_S: f64 = 0.25e-3;
pub use crate::signals::MAX_DELAY_S;

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

    /// The nominal latency search of the baseline: 0–0.25 ms in 25 µs steps.
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

impl Designed for ActuationDelay {
    fn design(
        &self,
        sig: &BalanceSignals,
        s: usize,
        _latency_s: f64,
    ) -> Result<Design, DiscrepancyError> {
        Ok(Design::balance(sig, self.lag_s(s), 0.0))
    }
}

impl Candidate for ActuationDelay {
    fn kind(&self) -> Option<EffectKind> {
        Some(EffectKind::ActuationDelay)
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
    fn reshapes(&self) -> Reshape {
        Reshape::Command
    }
    fn parameters(&self, s: usize, _beta: &[f64], _latency_s: f64) -> Vec<(String, f64)> {
        vec![("delay_ms".to_string(), self.lag_s(s) * 1e3)]
    }
}
