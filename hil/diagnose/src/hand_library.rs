//! What the catalog leaves in the hand balance: a library of the subject's force laws
//! outside the catalog, each linear in one coefficient per axis, selected on the hand
//! balance by held-out gain given the named human-side causes, like the cart balance's
//! library ([`super::unexplained`]).
//!
//! Every term is a law of the hand's restoring force `−ΔF_hand` (the sign of the
//! baseline's `K`: a positive coefficient resists the perturbation), added to the
//! baseline and the named effects, one column per axis (zero on the other axis's rows),
//! except the late feedback, which acts in muscle space through the known shape `S`
//! like the baseline's own feedback and has one gain:
//!
//! | term | law of `−ΔF_hand` on axis i | unit | what it hints at |
//! |---|---|---|---|
//! | `late-feedback` | `c · [S (Δx_h + ρ Δv_h)]_i (t − τ)`, one `c` for both axes, τ on a grid of 80–200 ms | N/m | the subject's feedback acts later than the model's 60 ms (a long-latency or voluntary correction) |
//! | `cubic-stiffness` | `c · Δx_i³` | N/m³ | a stiffness that grows (c > 0) or yields (c < 0) with the stretch |
//! | `velocity-squared` | `c · Δv_i \|Δv_i\|` | N s²/m² | a damping that grows (c > 0) or saturates (c < 0) with the speed: the muscles' force–velocity curve |
//!
//! `S`, `ρ` and `x_h` are the baseline's ([`super::hand`]). None is a catalog law: a
//! handle mass is an acceleration term, a reflex a velocity term at 10–50 ms, a grip a
//! change of the hand's kinematics; the baseline's own feedback is at 60 ms, and the
//! late feedback's grid starts well after the reflex's and the baseline's delays. All
//! three laws are odd in the perturbation, so they survive the odd parts the balance is
//! fitted on; the odd part of a cubic of a response is, to first order, the cubic of
//! its odd part.
//!
//! A term is judged like a candidate (the t-test on the repetitions, the gain floor on
//! its held-out gain, not at the edge of its grid) and must make at least
//! [`super::decide::FORCE_RESOLUTION_N`] of force somewhere in the responses; terms
//! enter one at a time, at most [`MAX_HAND_TERMS`]. What passes is reported as the hand
//! balance's `unexplained` structure, never as a cause.

use super::hand::{HandCandidate, Kin, base_columns, effect_rows, feedback_velocity_ratio_s};
use super::hand_signals::{HandResponse, lagged};
use crate::effect::EffectKind;
use nalgebra::Vector2;

/// Delays of the late feedback, ms: `(first, last, step)`. The baseline's feedback is at
/// 60 ms and a reflex at 10–50 ms; the long-latency responses to a stretch of the upper
/// limb reach ~100 ms (the M2 and M3 responses of Lee & Tatton 1975) and voluntary
/// corrections start at 100–150 ms.
pub const LATE_FEEDBACK_MS: (f64, f64, f64) = (80.0, 200.0, 10.0);

/// At most this many terms enter the hand's hint.
pub const MAX_HAND_TERMS: usize = 2;

/// A force law of the hand's library.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HandTerm {
    /// `c · [S (Δx_h + ρ Δv_h)]_i (t − τ)`.
    LateFeedback,
    /// `c · Δx_i³`.
    CubicStiffness,
    /// `c · Δv_i |Δv_i|`.
    VelocitySquared,
}

/// Every term of the hand's library.
pub const HAND_LIBRARY: [HandTerm; 3] = [
    HandTerm::LateFeedback,
    HandTerm::CubicStiffness,
    HandTerm::VelocitySquared,
];

fn late_feedback_settings() -> usize {
    let (a, b, step) = LATE_FEEDBACK_MS;
    ((b - a) / step).round() as usize + 1
}

fn late_feedback_s(s: usize) -> f64 {
    (LATE_FEEDBACK_MS.0 + s as f64 * LATE_FEEDBACK_MS.2) * 1e-3
}

impl HandTerm {
    /// The term's name (`late-feedback`, ...).
    #[must_use]
    pub fn term_name(self) -> &'static str {
        match self {
            HandTerm::LateFeedback => "late-feedback",
            HandTerm::CubicStiffness => "cubic-stiffness",
            HandTerm::VelocitySquared => "velocity-squared",
        }
    }

    /// The fitted law with coefficients `coef` (`[x, y]`) at setting `s`.
    #[must_use]
    pub fn law(self, coef: [f64; 2], s: usize) -> String {
        let u = self.unit();
        match self {
            HandTerm::LateFeedback => format!(
                "{:.4} {u} · S (Δx + {:.2} s · Δv)(t − {:.0} ms) on both axes",
                coef[0],
                feedback_velocity_ratio_s(),
                late_feedback_s(s) * 1e3
            ),
            _ => format!(
                "{:.4} {u} · {} on x, {:.4} {u} · {} on y",
                coef[0],
                self.expression("x", s),
                coef[1],
                self.expression("y", s)
            ),
        }
    }

    /// The law's expression on `axis` (`x` or `y`) at setting `s`.
    #[must_use]
    pub fn expression(self, axis: &str, s: usize) -> String {
        match self {
            HandTerm::LateFeedback => format!(
                "[S (Δx + {:.2} s · Δv)]{axis}(t − {:.0} ms)",
                feedback_velocity_ratio_s(),
                late_feedback_s(s) * 1e3
            ),
            HandTerm::CubicStiffness => format!("Δ{axis}³"),
            HandTerm::VelocitySquared => format!("Δv{axis}·|Δv{axis}|"),
        }
    }

    /// Unit of the coefficient.
    #[must_use]
    pub fn unit(self) -> &'static str {
        match self {
            HandTerm::LateFeedback => "N/m",
            HandTerm::CubicStiffness => "N/m³",
            HandTerm::VelocitySquared => "N s²/m²",
        }
    }

    /// What a term found hints at.
    #[must_use]
    pub fn meaning(self) -> &'static str {
        match self {
            HandTerm::LateFeedback => {
                "the subject's feedback acts later than the model's: a long-latency or voluntary correction"
            }
            HandTerm::CubicStiffness => {
                "a stiffness that grows (c > 0) or yields (c < 0) with the stretch"
            }
            HandTerm::VelocitySquared => {
                "a damping that grows (c > 0) or saturates (c < 0) with the speed: the muscles' force–velocity curve"
            }
        }
    }

    /// The term on row `axis` at sample `j`, before its coefficient, with the hand's
    /// kinematics `kin` at setting `s`.
    #[must_use]
    pub fn value(self, r: &HandResponse, kin: &Kin, s: usize, axis: usize, j: usize) -> f64 {
        match self {
            HandTerm::LateFeedback => {
                let lag = late_feedback_s(s) * r.rate_hz;
                let rho = feedback_velocity_ratio_s();
                let at =
                    |v: &[Vec<f64>; 2]| Vector2::new(lagged(&v[0], j, lag), lagged(&v[1], j, lag));
                let u = r.s[j] * (at(&kin.x) + rho * at(&kin.v));
                u[axis]
            }
            HandTerm::CubicStiffness => kin.x[axis][j].powi(3),
            HandTerm::VelocitySquared => {
                let v = kin.v[axis][j];
                v * v.abs()
            }
        }
    }
}

impl HandCandidate for HandTerm {
    fn kind(&self) -> Option<EffectKind> {
        None
    }
    fn name(&self) -> &'static str {
        self.term_name()
    }
    fn settings(&self) -> usize {
        match self {
            HandTerm::LateFeedback => late_feedback_settings(),
            _ => 1,
        }
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        match self {
            HandTerm::LateFeedback => ("delay_ms", late_feedback_s(s) * 1e3),
            _ => ("none", 0.0),
        }
    }
    /// The late feedback has one gain for both axes (it acts in muscle space through
    /// the known `S`, like the baseline's); the other terms one per axis.
    fn columns(&self) -> usize {
        base_columns()
            + match self {
                HandTerm::LateFeedback => 1,
                _ => 2,
            }
    }
    fn rows(&self, r: &HandResponse, s: usize, fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        effect_rows(self, r, s, fb, f);
    }
    fn extra(&self, r: &HandResponse, kin: &Kin, s: usize, axis: usize, j: usize, out: &mut [f64]) {
        let v = self.value(r, kin, s, axis, j);
        if *self == HandTerm::LateFeedback {
            out[0] = v;
        } else {
            out.iter_mut().for_each(|o| *o = 0.0);
            out[axis] = v;
        }
    }
    /// The coefficient of the hand's restoring force on each axis (`x`, `y`; the late
    /// feedback's one gain on both), and the late feedback's delay.
    fn parameters(&self, s: usize, beta: &[f64], _fb: f64) -> Vec<(String, f64)> {
        let nb = base_columns();
        let c = |i: usize| beta.get(nb + i).copied().unwrap_or(f64::NAN);
        if *self == HandTerm::LateFeedback {
            return vec![
                ("x".to_string(), c(0)),
                ("y".to_string(), c(0)),
                ("delay_ms".to_string(), late_feedback_s(s) * 1e3),
            ];
        }
        vec![("x".to_string(), c(0)), ("y".to_string(), c(1))]
    }
}
