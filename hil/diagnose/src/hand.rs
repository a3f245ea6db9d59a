//! The hand balance: the human-side catalog effects judged on the variational response
//! to the force pulses ([`super::hand_signals`]), by linear least squares on measured
//! regressors, with the same Gram / folds / cross-validation as the cart balance and no
//! simulation.
//!
//! The project's arm (`rigtwin_arm::human`) makes muscle tension from activation and
//! muscle stretch `e = −A(q − q_ref)`, its rate, and a delayed PD feedback on both; a
//! stretch reflex adds `g · ė(t − δ)` per muscle. Linearised about the unperturbed
//! reach and mapped to the hand with the Jacobian `J`, the force the hand exerts on the
//! handle changes by
//!
//! ```text
//! −ΔF_hand(t) = M_arm Δa_h + D Δv_h + K Δx_h + S (p Δx_h(t − τ) + d Δv_h(t − τ))   [+ candidate]
//! ```
//!
//! with `M_arm = J⁻ᵀ M(q) J⁻¹` known from the manifest's segment lengths and body mass
//! ([`rigtwin_arm::params::ArmParams::of_subject`]: [`rigtwin_arm::params::Segment::scaled_to_length`]
//! keeps mass and scales inertia with length², the body mass scales both), `S = J⁻ᵀ Aᵀ diag(w) A J⁻¹` the known shape of any
//! muscle-space feedback in the odd parts below (`w` 1 for toned muscles, ½ for the
//! others: [`super::hand_signals::odd_part_weights`]), `D`, `K` free 2×2 (the muscles' impedance plus the linearised arm dynamics,
//! neither symmetric during a reach: [`base_columns`]), `p` the free
//! feedback gain (N of activation per m of stretch) with `d = ρ p`, `ρ` the velocity to
//! position ratio of the arm's delayed feedback ([`feedback_velocity_ratio_s`]), and `τ`
//! the feedback delay, searched once on a grid for the baseline and then kept for every
//! candidate (like the cart balance's latency). `x_h` is the hand, equal to the handle
//! for a rigid grip. Every response also carries a constant force per axis, fitted out
//! and never named ([`RESPONSE_OFFSET_COLUMNS`]): what the trial and its references
//! differ by over the window that is not the response. The candidates, each nested on
//! this baseline:
//!
//! - `handle-mass`: `+ m_extra Δa` (isotropic): mass above the sensor that the manifest's
//!   `m_h` did not remove. Identifiable only because `M_arm` is known.
//! - `stretch-reflex`: `+ g S Δv_h(t − δ)`, δ on a 1 ms grid over 10–50 ms; the tension
//!   law `m = a + K_m(e + τ_d ė)` passes an activation change to the tension with factor
//!   1 (up to `K₁ e`, < 5 % at the arm's tracking errors), so `g` is directly the arm's
//!   `StretchReflex::gain_n_s_per_m`. It is also reported in the units a lab compares:
//!   the joint damping `g Aᵀ diag(w) A` (N m s/rad) and the endpoint damping `g S`
//!   (N s/m) at the pulse onsets ([`HandJudgement::reflex_units`]).
//! - `grip-compliance`: the hand is held by a spring-damper, `F_hand = k (x_h − x) + b
//!   (v_h − v)`: `Δx_h = Δx + ΔF_hand/(k + b s)` from the measured force, then the
//!   baseline refitted, for `k` and `b/k` on log grids.
//!
//! The tables' `M_arm` is not the subject's ([`ARM_INERTIA_TOLERANCE`]), and the
//! subject's impedance is not constant over the window when the reach's torque swings
//! within it (a fast reach). [`SubjectArm`], the baseline plus `c M_arm Δa_h` with `|c|`
//! within that tolerance plus the arm's impedance linearised along the reference's own
//! activations (per muscle pair a stiffness and a damping per newton of the activation
//! the torque split gives the torque the reference holds, [`HandResponse::activation`])
//! and the rigid-body impedance of that held torque ([`HandResponse::held`]), is a
//! rival: a handle mass or a grip, given the same rates, must explain the responses
//! better than it as well as better than the baseline, and a handle's mass fitted
//! beside the rates must still be material; the hand's library is judged given its
//! inertia and then its rates, each where it passes against the named effects. It is
//! never a cause.
//!
//! The target of every fit is `−ΔF_hand − M_arm Δa_h` and the normaliser `ΔF_hand`: the
//! NRMSE is the error of predicting the hand's response force.
//!
//! The units: a single response is dominated by the arm's motor noise, and the balance is
//! linear while the arm is not. With opposite pulse directions in the session (the
//! shared protocol's 30/210°, 60/240°, 120/300°, 150/330°), the fits run on the odd
//! part of each pair's mean responses ([`odd_parts`]): it keeps the linear response and
//! drops the terms even in the pulse (the activation-dependent muscle stiffness makes
//! them) and the reference's own noise. The gains and parameters are measured by
//! leaving out one pair at a time; whether a gain is beyond chance is tested on the
//! independent repetitions (the `i`-th pulse at `θ` with the `i`-th at `θ + 180°`, 12 on
//! the shared protocol, [`ReplicateTest`]), leaving out one at a time, because four
//! folds leave the t-test 3 degrees of freedom (critical t 5.14 for 7 candidates at
//! α 0.05) where twelve leave it 11 (2.91). With fewer than four pairs (a lab's four
//! cardinal directions make two) each pair's repetitions are split into groups, at
//! least four units in all, and the fits run on the odd parts of the groups' means
//! ([`odd_groups`]), tested on the repetitions as above. Fitted on the responses
//! averaged by direction instead, the even terms pulled a 25 ms reflex to 13 ms and a
//! 0.97 kg handle to 0.80 kg; on single odd parts, the arm's motor noise, which is in
//! the regressors too (it moves the handle through the rig's admittance), biased them
//! less but still (`hil/docs/notes/2026-12-07-four-directions.md`).
//! Without opposite pairs the responses are averaged by direction
//! ([`average_by_angle`]) and the folds run over directions.
//!
//! The weighting: every fit runs on rows whitened in time and between the axes
//! ([`Whitening`], generalised least squares), because the residual is smooth (the arm's
//! motor noise, a leaky Brownian motion of 50 ms) and largest along the reach; the time
//! constant is the arm's, not fitted, and the weighting between the axes is read from the
//! spread of the single repetitions about their pair's mean
//! ([`Whitening::from_repetitions`]), where a misfit common to them cancels, so that the
//! weighting never weighs down the axis where a hidden effect shows.
//!
//! The noise floor: the held-out NRMSE that a model missing nothing would leave, read
//! from the same spread of the repetitions about their mean, under the model of the
//! named effects, each repetition's own kinematics through it
//! ([`Whitening::noise_floor_nrmse`]). With `n` repetitions of a direction their summed
//! squared spread is `(n − 1) σ²` and the averaged unit's noise `σ²/n`. No model of the
//! hand goes below it, so it bounds every held-out gain by `1 − f/b`; the diagnosis
//! reports it and, per named hand cause, the share of the excess over it the cause
//! removes. Its sampling error is that of 2 degrees of freedom per direction and
//! sample, correlated over the noise's 50 ms.
//!
//! `d` is tied to `p` (`d = ρ p`): the arm's feedback is one PD law whose two gains a
//! subject scales together (`feedback_gain` of `crate::protocol::subjects`); with both
//! free, the delayed velocity column takes up what the baseline misses.
//!
//! What the data can and cannot tell: the grip and the extra mass change the response's
//! inertia in ways the known `M_arm` cannot take up. A reflex is, to first order,
//! `g S Δv − g δ S Δa`: its instantaneous part is taken up by the free `D`, and what
//! tells `g` from `δ` is the curvature of `e^{−iωδ}` over the pulse's band (below
//! ~10 Hz, `ωδ` < 2); brief pulses (50 ms, 30 N) reach the band where the delay shows
//! (README, "What session measures a reflex").
//!
//! The experiments behind these choices, with their numbers, are in the dated note
//! `hil/docs/notes/2026-12-02-hand-balance.md`.

use crate::effect::EffectKind;
use nalgebra::{Matrix2, Vector2};
use rayon::prelude::*;

use super::crossval::{CvFit, Folds, cross_validate};
use super::error::DiscrepancyError;
use super::gram::Gram;
use super::hand_signals::{
    HandArm, HandData, HandResponse, MUSCLE_PAIRS, OddUnits, average_by_angle, hand_responses,
    lagged, odd_groups, odd_parts,
};
use rigtwin_session::{Axes, Session};

/// Feedback delays the baseline searches, ms: the arm's default (000_*'s δ_s), which
/// the drawn subjects keep. The delay is not searched more widely: the delayed position
/// term is nearly collinear with `K Δx` over the window, so a wider grid buys a
/// baseline that absorbs part of a reflex, not a better one (the measurements:
/// `hil/docs/notes/2026-12-03-hand-balance-settings.md`).
pub const FEEDBACK_DELAYS_MS: [f64; 1] = [60.0];
/// Reflex delays searched, ms: 10 to 50 in steps of 1. A neural loop from stretch to
/// force through the spinal cord takes at least ~10 ms even for the shoulder (short-
/// latency reflexes of the upper limb appear at 20–50 ms); a shorter delay fits a
/// near-instantaneous term that mimics inertia, not a reflex.
pub const REFLEX_DELAY_MS: (f64, f64, f64) = (10.0, 50.0, 1.0);
/// Grip stiffnesses searched: log grid from 500 N/m to 50 kN/m, 81 values (5.9 % apart).
/// On a reflex study's brief pulses a grip found one step of a 12 % grid off (3155 N/m
/// for 3365) behind a heavier handle left a misfit a later round named as a short
/// stretch reflex (2 of 20 sessions, none with this grid;
/// `hil/docs/notes/2026-12-04-grip-load-profile.md`).
pub const GRIP_STIFFNESS_N_PER_M: (f64, f64, usize) = (500.0, 50_000.0, 81);
/// Grip time constants `b/k` searched, s: `(first, last, count)`, a log grid from 1 to
/// 46 ms, 31 values 13.6 % apart, `10^(i/18)` ms: the 19 values of the former 1–10 ms
/// grid and 12 more beyond it (a grasp through skin and soft tissue: a few kN/m with
/// 5–30 N s/m, so a soft grip's time constant reaches tens of ms). A time constant
/// beyond the grid is taken up by the stiffness: a 1.5 kN/m grip with 25 N s/m (17 ms)
/// came out 33–41 % stiff with the grid ending at 10 ms (`hil/sweeps/grip-soft.toml`).
/// Extended rather than re-spaced: a grid 13.1 % apart over 1–40 ms moved a stiff grip
/// behind a heavier handle along their ridge (seed 3003 of a reflex study's: the mass
/// 22 % high).
/// On a reflex study's brief pulses the grip's damping shows, and the
/// misfit a coarser grid leaves is structure the hand's library reports and a later
/// round's candidate takes up: with 7 values about 1.5× apart, 4 of 12 sessions hiding a
/// grip alone reported a velocity-squared damping as `hand_unexplained`, and 3 of 12
/// hiding a grip and a heavier handle named a stretch reflex as a third cause (none and 1
/// with a grid 13.6 % apart; `hil/docs/notes/2026-12-04-grip-time-grid.md`,
/// `hil/docs/notes/2026-12-05-soft-grips.md`).
pub const GRIP_TIME_S: (f64, f64, usize) = (1e-3, 4.641_588_833_612_779e-2, 31);
/// Correlation time of the residual the hand balance whitens in time, s ([`Whitening`]).
/// The residual of a correct model is the arm's motor noise, a leaky Brownian motion in
/// the activations (000_* section 4; the project's arm uses τ = 50 ms), and the
/// reach-to-reach variation of the movement itself, smooth too: their power sits below
/// `1/(2πτ)` ≈ 3 Hz, where the baseline's `K` and feedback act, while what tells a
/// reflex's delay lies at 5–15 Hz.
pub const HAND_NOISE_TIME_S: f64 = 0.05;
/// Whether the baseline fits a scale on the known arm inertia. Off: it buys nothing
/// for an extra mass's estimate and would let the baseline take up part of any inertial
/// effect (free within ±20 %, it cost the shared layout's reflexes: 3 of the first 11
/// named where all are without it; [`SubjectArm`] is the rival instead).
pub const FIT_ARM_MASS_SCALE: bool = false;
/// How far a subject's arm inertia may be from the tables the balance takes it from
/// (`HandArm`: Shadmehr & Mussa-Ivaldi's segments, scaled to the subject's lengths and
/// body mass), a fraction, both ways: the range of [`SubjectArm`]'s scale. The three
/// published arm models of `reference/arm-parameters.md` differ at the reach's middle by
/// 22–33 % in the trace of the endpoint inertia (Selen et al. and Katayama & Kawato
/// against Shadmehr & Mussa-Ivaldi); an individual's arm is not known better than that.
pub const ARM_INERTIA_TOLERANCE: f64 = 0.2;

/// Hand kinematics a fit uses (the handle's, or the hand's through a compliant grip).
#[derive(Debug, Clone)]
pub struct Kin {
    /// Position per axis, m.
    pub x: [Vec<f64>; 2],
    /// Velocity, m/s.
    pub v: [Vec<f64>; 2],
    /// Acceleration, m/s².
    pub a: [Vec<f64>; 2],
}

impl Kin {
    /// The handle's (rigid grip).
    #[must_use]
    pub fn rigid(r: &HandResponse) -> Kin {
        Kin {
            x: r.dx.clone(),
            v: r.dv.clone(),
            a: r.da.clone(),
        }
    }

    /// The hand's through a grip of stiffness `k` and time constant `tau = b/k`:
    /// `b δ̇ + k δ = ΔF_hand`, `δ = x_h − x`, integrated exactly for a force linear
    /// between samples, from `δ = ΔF/k` at the start of the window.
    #[must_use]
    pub fn grip(r: &HandResponse, k: f64, tau: f64) -> Kin {
        Kin::grip_loaded(r, k, tau, 0.0)
    }

    /// [`Kin::grip`] with a mass `load_kg` on the handle's side of the spring beyond
    /// the manifest's: the spring carries the hand's force as the balance reads it plus
    /// that mass's inertial force, `ΔF_hand + m Δa` (and its rate `ΔḞ_hand + m Δȧ`, the
    /// handle's jerk by central differences).
    #[must_use]
    pub fn grip_loaded(r: &HandResponse, k: f64, tau: f64, load_kg: f64) -> Kin {
        let h = 1.0 / r.rate_hz;
        let phi = (-h / tau).exp();
        // First-order hold: `τ δ̇ + δ = u` with `u = F/k` linear between samples gives
        // δ[i] = φ δ[i−1] + (1 − φ) u[i−1] + (u[i] − u[i−1]) (1 − τ/h (1 − φ)).
        let ramp = 1.0 - tau / h * (1.0 - phi);
        let mut out = Kin::rigid(r);
        for axis in 0..2 {
            let a = &r.da[axis];
            let n = a.len();
            let f: Vec<f64> = r.df[axis]
                .iter()
                .zip(a)
                .map(|(f, a)| f + load_kg * a)
                .collect();
            let fd: Vec<f64> = (0..n)
                .map(|i| {
                    let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
                    let jerk = if hi > lo {
                        (a[hi] - a[lo]) * r.rate_hz / (hi - lo) as f64
                    } else {
                        0.0
                    };
                    r.dfd[axis][i] + load_kg * jerk
                })
                .collect();
            let mut d = vec![0.0; n];
            d[0] = f[0] / k;
            for i in 1..n {
                let (u0, u1) = (f[i - 1] / k, f[i] / k);
                d[i] = phi * d[i - 1] + (1.0 - phi) * u0 + (u1 - u0) * ramp;
            }
            for i in 0..n {
                let dd = (f[i] / k - d[i]) / tau;
                let ddd = (fd[i] / k - dd) / tau;
                out.x[axis][i] += d[i];
                out.v[axis][i] += dd;
                out.a[axis][i] += ddd;
            }
        }
        out
    }
}

/// Baseline regressors: `D` (4, row-major), `K` (4), the feedback gain `p` (with
/// `d = ρ p`), and the arm-inertia scale when [`FIT_ARM_MASS_SCALE`].
///
/// `D` and `K` are full 2×2 matrices, not symmetric ones. The muscles' own impedance
/// is symmetric, but the balance is linearised about a moving reach whose joints carry
/// torque: the torque seen through the posture-dependent `J⁻ᵀ(q)` adds a stiffness that
/// is not symmetric (the geometric stiffness), and the velocity-product terms of the
/// arm's dynamics a damping that is not either. Symmetric matrices would leave those
/// parts to the candidates, and a reflex's held-out gain would then hardly depend on
/// its delay.
#[must_use]
pub const fn base_columns() -> usize {
    if FIT_ARM_MASS_SCALE { 10 } else { 9 }
}

/// `ρ = G_d / G_p` of the arm's delayed feedback, s (the default arm's 25 N s/m over
/// 500 N/m: 0.05 s); subjects scale both gains by one factor, so it is kept.
#[must_use]
pub fn feedback_velocity_ratio_s() -> f64 {
    let f = rigtwin_arm::params::FeedbackParams::default();
    f.velocity_gain_n_s_per_m / f.position_gain_n_per_m
}

/// Calls `f(x, y, norm)` for every row (both axes) of the hand balance of `r` with
/// kinematics `kin`, feedback lag `fb_lag` samples, and the candidate's `extra`
/// regressors (`extra(axis, j, out)`, `out` of length `cols − base_columns()`).
pub fn visit_rows(
    r: &HandResponse,
    kin: &Kin,
    fb_lag: f64,
    cols: usize,
    mut extra: impl FnMut(usize, usize, &mut [f64]),
    f: &mut dyn FnMut(&[f64], f64, f64),
) {
    let nb = base_columns();
    let rho = feedback_velocity_ratio_s();
    let mut x = vec![0.0; cols];
    for &j in &r.rows {
        let xl = Vector2::new(lagged(&kin.x[0], j, fb_lag), lagged(&kin.x[1], j, fb_lag));
        let vl = Vector2::new(lagged(&kin.v[0], j, fb_lag), lagged(&kin.v[1], j, fb_lag));
        let sx = r.s[j] * xl;
        let sv = r.s[j] * vl;
        let ma = r.m_arm[j] * Vector2::new(kin.a[0][j], kin.a[1][j]);
        let (v, p) = ([kin.v[0][j], kin.v[1][j]], [kin.x[0][j], kin.x[1][j]]);
        for axis in 0..2 {
            x.iter_mut().for_each(|c| *c = 0.0);
            // Row `axis` of `D v` and `K x`.
            x[2 * axis] = v[0];
            x[2 * axis + 1] = v[1];
            x[4 + 2 * axis] = p[0];
            x[4 + 2 * axis + 1] = p[1];
            x[8] = sx[axis] + rho * sv[axis];
            let mut y = -r.df[axis][j];
            if FIT_ARM_MASS_SCALE {
                x[nb - 1] = ma[axis];
            } else {
                y -= ma[axis];
            }
            if cols > nb {
                extra(axis, j, &mut x[nb..]);
            }
            f(&x, y, r.df[axis][j]);
        }
    }
}

/// A human-side candidate: a family of linear problems of the hand balance.
pub trait HandCandidate: Sync + Send {
    /// The catalog effect it is (`None` for the baseline and the feedback delay, which name themselves).
    fn kind(&self) -> Option<EffectKind>;
    /// Its name in rankings and errors: the catalog name of its effect.
    fn name(&self) -> &'static str {
        self.kind().map_or("(unnamed)", EffectKind::name)
    }
    /// Settings of the nonlinear parameter.
    fn settings(&self) -> usize;
    /// The nonlinear parameter's name (with unit) and value at setting `s`.
    fn setting(&self, s: usize) -> (&'static str, f64);
    /// Where setting `s` lies on the search's range of the parameter [`Self::setting`]
    /// names, and how many values that range has (for the edge rule,
    /// `decide::at_edge`): the setting itself unless the search crosses its parameter
    /// with another (the grip's stiffness with its time constant).
    fn search_position(&self, s: usize) -> (usize, usize) {
        (s, self.settings())
    }
    /// Whether setting `s` holds every other searched parameter where setting `of` does:
    /// the settings that do are the search along [`Self::setting`]'s parameter through
    /// `of` (for the error curve of `cause.png`). Always, unless the search crosses its
    /// parameter with another.
    fn on_the_line_of(&self, _s: usize, _of: usize) -> bool {
        true
    }
    /// Regressors (the baseline's first).
    fn columns(&self) -> usize;
    /// Visits the rows of `r` at setting `s` with feedback delay `fb_delay_s`.
    fn rows(
        &self,
        r: &HandResponse,
        s: usize,
        fb_delay_s: f64,
        f: &mut dyn FnMut(&[f64], f64, f64),
    );
    /// The catalog parameters from setting `s` and coefficients `beta`.
    fn parameters(&self, s: usize, beta: &[f64], fb_delay_s: f64) -> Vec<(String, f64)>;
    /// Whether the fitted effect is physical (a mass or reflex gain of the right sign);
    /// an unphysical fit is never named.
    fn physical(&self, s: usize, beta: &[f64]) -> bool {
        let _ = (s, beta);
        true
    }
    /// The hand's kinematics the effect puts in the balance at setting `s` (a grip's
    /// hand behind its spring), or `None` for the handle's.
    fn hand_kin(&self, r: &HandResponse, s: usize) -> Option<Kin> {
        let _ = (r, s);
        None
    }
    /// Regressors the effect adds to the baseline's (after them, in [`Self::rows`]).
    fn extra_columns(&self) -> usize {
        self.columns().saturating_sub(base_columns())
    }
    /// The effect's own regressors of row `axis` at sample `j` and setting `s`, with the
    /// hand's kinematics `kin` of the balance (`out` of length [`Self::extra_columns`]).
    fn extra(&self, r: &HandResponse, kin: &Kin, s: usize, axis: usize, j: usize, out: &mut [f64]) {
        let _ = (r, kin, s, axis, j, out);
    }
    /// Box bounds `(column, low, high)` on the coefficients ([`Gram::with_bounds`]);
    /// none by default.
    fn bounds(&self) -> Vec<(usize, f64, f64)> {
        Vec::new()
    }
    /// The largest force the effect's own regressors ([`Self::extra`]) make with
    /// coefficients `coef` (one per [`Self::extra_columns`]) at setting `s` over the units
    /// `responses` (one pulse's response each), N, per axis: `|Σ coef_i extra_i|` at any
    /// evaluated row, the hand moving with the handle. NaN for a coefficient that is not
    /// a number. What decides whether a fitted law is material in the rig's units.
    fn peak_force_n(&self, coef: &[f64], s: usize, responses: &[HandResponse]) -> [f64; 2] {
        if coef.iter().any(|c| !c.is_finite()) {
            return [f64::NAN; 2];
        }
        let mut out = vec![0.0; self.extra_columns()];
        let mut peak = [0.0_f64; 2];
        for r in responses {
            let kin = Kin::rigid(r);
            for &j in &r.rows {
                for (axis, p) in peak.iter_mut().enumerate() {
                    self.extra(r, &kin, s, axis, j, &mut out);
                    let f: f64 = coef.iter().zip(&out).map(|(c, x)| c * x).sum();
                    *p = p.max(f.abs());
                }
            }
        }
        peak
    }
}

/// The rows of an effect's candidate: the baseline's on the effect's kinematics
/// ([`HandCandidate::hand_kin`]) with its own regressors ([`HandCandidate::extra`]) after
/// them.
pub(crate) fn effect_rows(
    c: &dyn HandCandidate,
    r: &HandResponse,
    s: usize,
    fb_delay_s: f64,
    f: &mut dyn FnMut(&[f64], f64, f64),
) {
    let kin = c.hand_kin(r, s).unwrap_or_else(|| Kin::rigid(r));
    visit_rows(
        r,
        &kin,
        lag(r, fb_delay_s),
        c.columns(),
        |axis, j, out| c.extra(r, &kin, s, axis, j, out),
        f,
    );
}

/// The weighting of the hand balance's rows: generalised least squares for a residual
/// that is first-order autoregressive in time and correlated between the axes.
///
/// Every row is filtered by `1 − φ z⁻¹` along time (`φ = exp(−Δt/τ)`, `τ` =
/// [`Whitening::noise_time_s`], `Δt` the rows' spacing), then each sample's pair of axes
/// is multiplied by `W` with `WᵀW ∝ Σ⁻¹`, `Σ` the covariance between the axes of the
/// time-filtered noise ([`Whitening::from_repetitions`]; the baseline's residual,
/// [`Whitening::fitted`], for sessions without repetitions, or none whose direction's
/// mean is theirs). Regressors, target and
/// normaliser alike: a linear law that holds for the rows holds for the weighted rows
/// with the same coefficients, and the NRMSE is that of the weighted force.
///
/// Why: unweighted, the fit and the held-out error are dominated by the residual's low
/// band and by its larger axis. The residual is the arm's motor noise, a leaky Brownian
/// motion of the activations ([`HAND_NOISE_TIME_S`]), and the reach-to-reach variation
/// of the movement, largest along the reach (its variance 3–20 times the other axis's
/// on generated sessions hiding nothing). What tells a reflex's delay lies at 5–15 Hz
/// and in both axes. Weighted, every frequency and direction of the response counts by
/// its signal-to-noise ratio. Measured on the hidden-effect sweep:
/// `hil/docs/notes/2026-12-02-hand-balance.md`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Whitening {
    /// Correlation time `τ` removed, s (0 for none).
    pub noise_time_s: f64,
    /// `W` between the axes (identity for none).
    pub axes: Matrix2<f64>,
    /// Where `W` comes from.
    pub source: WeightSource,
}

impl Whitening {
    /// The time filter of [`HAND_NOISE_TIME_S`] alone.
    #[must_use]
    pub fn in_time() -> Whitening {
        Whitening {
            noise_time_s: HAND_NOISE_TIME_S,
            axes: Matrix2::identity(),
            source: WeightSource::Time,
        }
    }

    /// The time filter and `W` from the residual of coefficients `beta` of candidate
    /// `c` at setting `s` over `units`, filtered in time. The fallback of
    /// [`Whitening::from_repetitions`] for sessions without repetitions whose
    /// direction's mean is theirs (a session cut short, pulses dropped): this residual
    /// holds whatever effect the baseline misses besides the noise, so it weighs down
    /// the axis where that effect shows. The time filter alone when the covariance is
    /// not positive definite.
    #[must_use]
    pub fn fitted(
        c: &dyn HandCandidate,
        units: &[HandResponse],
        s: usize,
        beta: &[f64],
        fb_delay_s: f64,
    ) -> Whitening {
        let mut sigma = Matrix2::zeros();
        for r in units {
            for e in time_filtered_residuals(c, r, s, beta, fb_delay_s) {
                sigma += e * e.transpose();
            }
        }
        Whitening::between_axes(sigma, WeightSource::Residual).unwrap_or_else(Whitening::in_time)
    }

    /// The time filter and `W` from the noise alone: the spread of the repetitions
    /// about their mean. Each repetition's time-filtered residual (coefficients `beta`
    /// of `c` at setting `s`) minus that of the averaged unit of its direction: what the
    /// model misses is common to both and cancels, the motor noise does not. Only the
    /// directions whose averaged unit is the mean of their repetitions count
    /// ([`matched_repetitions`]): an unmatched repetition's difference from the mean
    /// would hold a part of the misfit. `None` when no direction counts or the
    /// covariance is not positive definite.
    #[must_use]
    pub fn from_repetitions(
        c: &dyn HandCandidate,
        averaged: &[HandResponse],
        repetitions: &[HandResponse],
        s: usize,
        beta: &[f64],
        fb_delay_s: f64,
    ) -> Option<Whitening> {
        let residuals = |r: &HandResponse| time_filtered_residuals(c, r, s, beta, fb_delay_s);
        let mut sigma = Matrix2::zeros();
        for a in averaged {
            let Some(reps) = matched_repetitions(a, repetitions) else {
                continue;
            };
            let mean = residuals(a);
            for r in reps {
                for (e, m) in residuals(r).iter().zip(&mean) {
                    let d = e - m;
                    sigma += d * d.transpose();
                }
            }
        }
        Whitening::between_axes(sigma, WeightSource::Repetitions)
    }

    /// The held-out NRMSE that a model missing nothing would leave on `averaged` (the
    /// units that average repetitions) under this weighting: the noise of each
    /// averaged unit over the normaliser of all. Each repetition's weighted residual
    /// (coefficients `beta` of `c` at setting `s`) minus that of the averaged unit of its
    /// direction holds the noise alone, what the model misses being common to both; its
    /// constant per axis is removed, as each unit's offset is fitted out
    /// ([`RESPONSE_OFFSET_COLUMNS`]). With `n` repetitions of a direction their summed
    /// square is `(n − 1) σ²` and the averaged unit's noise `σ²/n`. A direction counts
    /// only when its averaged unit is the mean of its repetitions
    /// ([`matched_repetitions`]). The floor is then that of the directions that count,
    /// over their normaliser; `None` when none does.
    #[must_use]
    pub fn noise_floor_nrmse(
        &self,
        c: &dyn HandCandidate,
        averaged: &[HandResponse],
        repetitions: &[HandResponse],
        s: usize,
        beta: &[f64],
        fb_delay_s: f64,
    ) -> Option<f64> {
        let residuals = |r: &HandResponse| -> Vec<f64> {
            hand_fit_rows(c, r, s, beta, fb_delay_s, Some(self))
                .into_iter()
                .map(|(y, fit, _)| y - fit)
                .collect()
        };
        let mut noise = 0.0;
        let mut norm = 0.0;
        for a in averaged {
            let Some(reps) = matched_repetitions(a, repetitions) else {
                continue;
            };
            let n = reps.len();
            // The averaged unit's rows give its residual and the normaliser alike.
            let rows = hand_fit_rows(c, a, s, beta, fb_delay_s, Some(self));
            let mean: Vec<f64> = rows.iter().map(|(y, fit, _)| y - fit).collect();
            let mut spread = 0.0;
            for r in reps {
                let d: Vec<f64> = residuals(r).iter().zip(&mean).map(|(e, m)| e - m).collect();
                for axis in 0..2 {
                    let along: Vec<f64> = d.iter().skip(axis).step_by(2).copied().collect();
                    let m = along.iter().sum::<f64>() / along.len().max(1) as f64;
                    spread += along.iter().map(|v| (v - m).powi(2)).sum::<f64>();
                }
            }
            noise += spread / (n * (n - 1)) as f64;
            norm += rows.iter().map(|(_, _, v)| v * v).sum::<f64>();
        }
        (norm > 0.0).then(|| (noise / norm).sqrt())
    }

    /// The time filter and `W = L⁻¹` with `Σ = L Lᵀ` scaled to a unit determinant (the
    /// NRMSE is a ratio, so only the shape of `Σ` matters); `None` when `Σ` is not
    /// positive definite.
    fn between_axes(sigma: Matrix2<f64>, source: WeightSource) -> Option<Whitening> {
        let det = sigma.determinant();
        if !(det > 0.0 && det.is_finite()) {
            return None;
        }
        let w = (sigma / det.sqrt())
            .cholesky()
            .and_then(|l| l.l().try_inverse())?;
        Some(Whitening {
            axes: w,
            source,
            ..Whitening::in_time()
        })
    }
}

/// The repetitions of the averaged unit `a` (the same angle, the same rows, trials
/// among `a`'s: a pair's repetitions, or a group's of them), when `a` is their mean: at
/// least two of them, and together the same trials as `a`. `None` otherwise: a
/// direction whose two sides of an opposite pair have different counts averages a
/// repetition that no pair holds, and one repetition has no spread.
fn matched_repetitions<'a>(
    a: &HandResponse,
    repetitions: &'a [HandResponse],
) -> Option<Vec<&'a HandResponse>> {
    let reps: Vec<&HandResponse> = repetitions
        .iter()
        .filter(|r| (r.angle_deg - a.angle_deg).abs() < 0.5 && r.rows == a.rows)
        .filter(|r| r.trials.iter().all(|t| a.trials.contains(t)))
        .collect();
    let mut trials: Vec<u32> = reps.iter().flat_map(|r| r.trials.clone()).collect();
    let mut of_unit = a.trials.clone();
    trials.sort_unstable();
    of_unit.sort_unstable();
    (reps.len() >= 2 && trials == of_unit).then_some(reps)
}

/// The residual `(x, y)` per evaluated sample of coefficients `beta` of `c` at setting
/// `s` on `r`, through the time filter alone: what the weighting between the axes is
/// read from.
fn time_filtered_residuals(
    c: &dyn HandCandidate,
    r: &HandResponse,
    s: usize,
    beta: &[f64],
    fb_delay_s: f64,
) -> Vec<Vector2<f64>> {
    hand_fit_rows(c, r, s, beta, fb_delay_s, Some(&Whitening::in_time()))
        .chunks_exact(2)
        .map(|p| Vector2::new(p[0].0 - p[0].1, p[1].0 - p[1].1))
        .collect()
}

/// Where the hand balance's weighting between the axes comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeightSource {
    /// None: the time filter alone.
    Time,
    /// The spread of the repetitions about their mean: the noise alone.
    Repetitions,
    /// The baseline's residual: the noise plus whatever the baseline misses.
    Residual,
}

impl WeightSource {
    /// Name in the report and the JSON.
    #[must_use]
    pub const fn as_str(self) -> &'static str {
        match self {
            WeightSource::Time => "time only",
            WeightSource::Repetitions => "repetitions",
            WeightSource::Residual => "baseline residual",
        }
    }
}

/// Visits the rows of `c` on `r` at setting `s`, weighted by `w` ([`Whitening`]); axes
/// interleaved like [`HandCandidate::rows`]. The first sample has no predecessor and is
/// dropped.
pub fn whitened_rows(
    c: &dyn HandCandidate,
    r: &HandResponse,
    s: usize,
    fb_delay_s: f64,
    w: &Whitening,
    f: &mut dyn FnMut(&[f64], f64, f64),
) {
    weighted_rows(c, r, s, fb_delay_s, w, false, f);
}

/// The nuisance columns every response carries in [`hand_grams`]: a constant force
/// per axis, free per response and fitted out of its Gram ([`Gram::eliminate_trailing`]),
/// never named. It takes up what a perturbed trial and its unperturbed references differ
/// by that is not the response and holds over the 0.3 s window: the force sensor's
/// offset drifting between the trials, the subject's steady push toward an end point a
/// few millimetres from the references'. There is no slope per axis (a reach faster or
/// slower than its references): it takes up part of an extra mass's response
/// (`hil/docs/notes/2026-12-02-hand-balance.md`). The constants are carried as columns,
/// not as [`super::gram::Intercepts`], because the weighting filters them in time and
/// mixes them between the axes like every column.
pub const RESPONSE_OFFSET_COLUMNS: usize = 2;

/// [`whitened_rows`], with the [`RESPONSE_OFFSET_COLUMNS`] (one constant per axis) after
/// the candidate's columns when `offsets`, weighted like them.
fn weighted_rows(
    c: &dyn HandCandidate,
    r: &HandResponse,
    s: usize,
    fb_delay_s: f64,
    w: &Whitening,
    offsets: bool,
    f: &mut dyn FnMut(&[f64], f64, f64),
) {
    let phi = match r.rows.as_slice() {
        [a, b, ..] if w.noise_time_s > 0.0 => {
            (-((b - a) as f64 / r.rate_hz) / w.noise_time_s).exp()
        }
        _ => 0.0,
    };
    // A row as one vector: regressors, the nuisance columns, then target and normaliser.
    let q = if offsets { RESPONSE_OFFSET_COLUMNS } else { 0 };
    let cols = c.columns() + q;
    let mut prev = [vec![0.0; cols + 2], vec![0.0; cols + 2]];
    let mut cur = prev.clone();
    let mut out = vec![0.0; cols + 2];
    let mut nuisance = vec![0.0; q];
    let mut k = 0usize;
    c.rows(r, s, fb_delay_s, &mut |x, y, n| {
        let (axis, sample) = (k % 2, k / 2);
        k += 1;
        if offsets {
            nuisance.iter_mut().for_each(|v| *v = 0.0);
            nuisance[axis] = 1.0;
        }
        let row = x.iter().chain(&nuisance).chain([&y, &n]);
        for ((cu, p), v) in cur[axis].iter_mut().zip(prev[axis].iter_mut()).zip(row) {
            *cu = v - phi * *p;
            *p = *v;
        }
        if axis == 1 && sample > 0 {
            for i in 0..2 {
                for (j, o) in out.iter_mut().enumerate() {
                    *o = w.axes[(i, 0)] * cur[0][j] + w.axes[(i, 1)] * cur[1][j];
                }
                f(&out[..cols], out[cols], out[cols + 1]);
            }
        }
    });
}

/// One response's Grams at every setting, from the weighted rows (`whitened_rows`) with
/// the response's own offset per axis fitted out ([`RESPONSE_OFFSET_COLUMNS`]).
#[must_use]
pub fn hand_grams(
    c: &dyn HandCandidate,
    r: &HandResponse,
    fb_delay_s: f64,
    w: &Whitening,
) -> Vec<Gram> {
    (0..c.settings())
        .map(|s| hand_gram(c, r, s, fb_delay_s, w))
        .collect()
}

/// The Gram of `c` at setting `s` alone on one response ([`hand_grams`]' `s`-th).
#[must_use]
pub fn hand_gram(
    c: &dyn HandCandidate,
    r: &HandResponse,
    s: usize,
    fb_delay_s: f64,
    w: &Whitening,
) -> Gram {
    let q = RESPONSE_OFFSET_COLUMNS;
    let mut g = Gram::new(c.columns() + q).with_bounds(c.bounds());
    weighted_rows(c, r, s, fb_delay_s, w, true, &mut |x, y, n| g.push(x, y, n));
    g.eliminate_trailing(q)
}

/// Per row (axes interleaved: x then y of each evaluated sample): target, fit,
/// normaliser; weighted by `w` (`whitened_rows`, which drops the first sample) or not.
#[must_use]
pub fn hand_fit_rows(
    c: &dyn HandCandidate,
    r: &HandResponse,
    s: usize,
    beta: &[f64],
    fb_delay_s: f64,
    w: Option<&Whitening>,
) -> Vec<(f64, f64, f64)> {
    let mut out = Vec::new();
    let mut push = |x: &[f64], y: f64, n: f64| {
        out.push((y, x.iter().zip(beta).map(|(a, b)| a * b).sum(), n));
    };
    match w {
        Some(w) => whitened_rows(c, r, s, fb_delay_s, w, &mut push),
        None => c.rows(r, s, fb_delay_s, &mut push),
    }
    out
}

/// The baseline hand balance.
#[derive(Debug, Clone, Copy, Default)]
pub struct HandBaseline;

/// The baseline's parameters as named values.
#[must_use]
pub fn baseline_parameters(beta: &[f64], fb_delay_s: f64) -> Vec<(String, f64)> {
    let g = |i: usize| beta.get(i).copied().unwrap_or(f64::NAN);
    let mut v = vec![
        ("d11_n_s_per_m".to_string(), g(0)),
        ("d12_n_s_per_m".to_string(), g(1)),
        ("d21_n_s_per_m".to_string(), g(2)),
        ("d22_n_s_per_m".to_string(), g(3)),
        ("k11_n_per_m".to_string(), g(4)),
        ("k12_n_per_m".to_string(), g(5)),
        ("k21_n_per_m".to_string(), g(6)),
        ("k22_n_per_m".to_string(), g(7)),
        ("feedback_position_gain_n_per_m".to_string(), g(8)),
        (
            "feedback_velocity_gain_n_s_per_m".to_string(),
            g(8) * feedback_velocity_ratio_s(),
        ),
        ("feedback_delay_ms".to_string(), fb_delay_s * 1e3),
    ];
    if FIT_ARM_MASS_SCALE {
        v.push(("arm_inertia_scale".to_string(), g(base_columns() - 1)));
    }
    v
}

fn lag(r: &HandResponse, s: f64) -> f64 {
    s * r.rate_hz
}

impl HandCandidate for HandBaseline {
    fn kind(&self) -> Option<EffectKind> {
        None
    }
    fn name(&self) -> &'static str {
        "hand-baseline"
    }
    fn settings(&self) -> usize {
        1
    }
    fn setting(&self, _s: usize) -> (&'static str, f64) {
        ("none", 0.0)
    }
    fn columns(&self) -> usize {
        base_columns()
    }
    fn rows(&self, r: &HandResponse, _s: usize, fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        visit_rows(
            r,
            &Kin::rigid(r),
            lag(r, fb),
            self.columns(),
            |_, _, _| {},
            f,
        );
    }
    fn parameters(&self, _s: usize, beta: &[f64], fb: f64) -> Vec<(String, f64)> {
        baseline_parameters(beta, fb)
    }
}

/// The baseline over the feedback-delay grid (setting = delay), to choose the delay.
#[derive(Debug, Clone, Copy, Default)]
pub struct FeedbackDelay;

impl HandCandidate for FeedbackDelay {
    fn kind(&self) -> Option<EffectKind> {
        None
    }
    fn name(&self) -> &'static str {
        "feedback delay"
    }
    fn settings(&self) -> usize {
        FEEDBACK_DELAYS_MS.len()
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("feedback_delay_ms", FEEDBACK_DELAYS_MS[s])
    }
    fn columns(&self) -> usize {
        base_columns()
    }
    fn rows(&self, r: &HandResponse, s: usize, _fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        let fb = FEEDBACK_DELAYS_MS[s] * 1e-3;
        visit_rows(
            r,
            &Kin::rigid(r),
            lag(r, fb),
            self.columns(),
            |_, _, _| {},
            f,
        );
    }
    fn parameters(&self, s: usize, beta: &[f64], _fb: f64) -> Vec<(String, f64)> {
        baseline_parameters(beta, FEEDBACK_DELAYS_MS[s] * 1e-3)
    }
}

/// `handle-mass`: isotropic mass above the sensor beyond the manifest's.
#[derive(Debug, Clone, Copy, Default)]
pub struct HandleMass;

impl HandCandidate for HandleMass {
    fn kind(&self) -> Option<EffectKind> {
        Some(EffectKind::HandleMass)
    }
    fn settings(&self) -> usize {
        1
    }
    fn setting(&self, _s: usize) -> (&'static str, f64) {
        ("none", 0.0)
    }
    fn columns(&self) -> usize {
        base_columns() + 1
    }
    fn rows(&self, r: &HandResponse, s: usize, fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        effect_rows(self, r, s, fb, f);
    }
    /// The mass rides on the handle: its force is `m_extra` times the handle's
    /// acceleration, whatever the grip does to the hand's.
    fn extra(
        &self,
        r: &HandResponse,
        _kin: &Kin,
        _s: usize,
        axis: usize,
        j: usize,
        out: &mut [f64],
    ) {
        out[0] = r.da[axis][j];
    }
    fn parameters(&self, _s: usize, beta: &[f64], _fb: f64) -> Vec<(String, f64)> {
        vec![(
            "extra_mass_kg".to_string(),
            beta.last().copied().unwrap_or(f64::NAN),
        )]
    }
    fn physical(&self, _s: usize, beta: &[f64]) -> bool {
        beta.last().is_some_and(|m| *m > 0.0)
    }
}

/// The columns of [`SubjectArm`]'s impedance rates: per muscle pair (shoulder, elbow,
/// two-joint) the stiffness and then the damping per newton of activation, then the
/// scales of the held torque's stiffness and damping.
pub const IMPEDANCE_RATE_COLUMNS: usize = 2 * MUSCLE_PAIRS + 2;

/// The names of [`SubjectArm`]'s rates, in column order: a muscle's stiffness (N/m)
/// and damping (N s/m) per newton of its activation, per pair, and the two scales of
/// the held torque's impedance (1 for an arm of the tables).
pub const RATE_PARAMETERS: [&str; IMPEDANCE_RATE_COLUMNS] = [
    "shoulder_muscle_stiffness_per_activation_per_m",
    "elbow_muscle_stiffness_per_activation_per_m",
    "two_joint_muscle_stiffness_per_activation_per_m",
    "shoulder_muscle_damping_per_activation_s_per_m",
    "elbow_muscle_damping_per_activation_s_per_m",
    "two_joint_muscle_damping_per_activation_s_per_m",
    "held_torque_stiffness_scale",
    "held_torque_damping_scale",
];

/// The rival a heavier handle and a grip are judged against besides the baseline, and
/// the hand's library is given: the subject's own arm where it departs from the
/// baseline's, in two ways every subject may show and neither a cause.
///
/// - Its inertia: `M_arm` scaled by `1 + c` with `|c| ≤` [`ARM_INERTIA_TOLERANCE`]. On
///   the shared layout's long pulses an arm 15 % heavier reads as a heavier handle of
///   0.15–0.21 kg, and one 15–20 % lighter as a short reflex (11–13 ms: `g δ S Δa`
///   lowers the inertia).
/// - Its impedance following the reach's activations over the window, as the arm's
///   own law has it, linearised along the unperturbed movement. Per muscle pair `p`
///   (shoulder, elbow, two-joint) a stiffness `κ_p` and a damping `β_p` per newton of
///   activation times [`HandResponse::activation`], the pair's activations from the
///   arm's torque split of the joint torque the reference holds: a muscle's
///   `K_m = K₀ + K₁ a` (the arm's; a joint's stiffness grows with the torque it holds
///   in people as well: Bennett et al. 1992 at the elbow during movement, Gomi & Kawato
///   1997 at the hand). And the rigid-body part the baseline's constant `D`, `K` leave:
///   how the hand's force changes with its motion while the muscles hold that torque
///   ([`HandResponse::held`]: the turning geometry, the configuration-dependent
///   inertia, Coriolis and centripetal forces), each with a free scale. Eight
///   coefficients on the reference's own activations and torque, which differ between
///   pulses by where in the reach each came (rising, falling, changing muscle), so they
///   cannot stand in for an inertia, as the time itself as the coordinate could. On a
///   1 s reach the activations swing within the window by many times the
///   co-contraction: on quiet sessions of such reaches the baseline's error is 13–15 %
///   of the response, and this rival's 1–1.5 % with the arm's inertia within 3 % of
///   the tables (README, "Reaches much faster than 3 s"). Not in the baseline: free
///   columns there take up part of the shared layout's reflexes, whose evidence is as
///   smooth (`hil/docs/notes/2026-12-05-fast-reaches.md`).
///
/// A heavier handle or a grip is judged against it with the same rates beside it
/// ([`SubjectArm::RATES`]), so that what the two are compared on is the inertia alone:
/// the rates take up part of the misfit a real handle's estimate carries on fast
/// reaches.
///
/// The hand's library is given the inertia alone ([`SubjectArm::INERTIA`]) and then the
/// rates ([`SubjectArm::RATES`]), each where it passes against what entered before, as
/// forward selection admits its members.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SubjectArm {
    /// Whether the impedance's rates are fitted.
    pub rates: bool,
    /// Whether the inertia's scale is fitted.
    pub inertia: bool,
    /// Whether the inertia's scale is held within ±[`ARM_INERTIA_TOLERANCE`].
    pub bounded: bool,
}

impl SubjectArm {
    /// The inertia and the impedance's rates: the rival.
    pub const WHOLE: SubjectArm = SubjectArm {
        rates: true,
        inertia: true,
        bounded: true,
    };
    /// The rival with its inertia's scale free: what the responses make of the arm when
    /// the tables do not hold it. A rival held at its bound and beaten by this one asks
    /// for an arm the tables rule out, and is not the subject's arm.
    pub const OFF_THE_TABLES: SubjectArm = SubjectArm {
        rates: true,
        inertia: true,
        bounded: false,
    };
    /// The inertia alone.
    pub const INERTIA: SubjectArm = SubjectArm {
        rates: false,
        inertia: true,
        bounded: true,
    };
    /// The impedance's rates alone: what a heavier handle or a grip carries when judged
    /// against the rival, so that the two compare on the same footing.
    pub const RATES: SubjectArm = SubjectArm {
        rates: true,
        inertia: false,
        bounded: true,
    };

    /// The inertia's scale of the tables' `M_arm` in `beta`, a fit of this rival (NaN
    /// without the inertia's column).
    #[must_use]
    pub fn inertia_scale(self, beta: &[f64]) -> f64 {
        if !self.inertia {
            return f64::NAN;
        }
        1.0 + beta
            .get(base_columns() + self.rate_columns())
            .copied()
            .unwrap_or(f64::NAN)
    }

    fn rate_columns(self) -> usize {
        if self.rates {
            IMPEDANCE_RATE_COLUMNS
        } else {
            0
        }
    }
}

impl HandCandidate for SubjectArm {
    fn kind(&self) -> Option<EffectKind> {
        None
    }
    fn name(&self) -> &'static str {
        match (self.rates, self.inertia) {
            (true, true) if !self.bounded => "subject-arm-off-the-tables",
            (true, true) => "subject-arm",
            (false, _) => "arm-inertia",
            (true, false) => "impedance-rates",
        }
    }
    fn settings(&self) -> usize {
        1
    }
    fn setting(&self, _s: usize) -> (&'static str, f64) {
        ("none", 0.0)
    }
    fn columns(&self) -> usize {
        base_columns() + self.rate_columns() + usize::from(self.inertia)
    }
    fn rows(&self, r: &HandResponse, s: usize, fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        effect_rows(self, r, s, fb, f);
    }
    /// Row `axis` of each pair's activation shape times `Δx_h` (its `κ`) and times `Δv_h`
    /// (its `β`), and of the held torque's `G_x Δx_h` and `G_v Δv_h` (with the rates),
    /// then the arm's own inertial force at the handle, `c` times `M_arm Δa` (the balance
    /// already carries `M_arm Δa` once).
    fn extra(
        &self,
        r: &HandResponse,
        kin: &Kin,
        _s: usize,
        axis: usize,
        j: usize,
        out: &mut [f64],
    ) {
        if self.rates {
            let x = Vector2::new(kin.x[0][j], kin.x[1][j]);
            let v = Vector2::new(kin.v[0][j], kin.v[1][j]);
            for (p, shape) in r.activation.iter().enumerate() {
                out[p] = (shape[j] * x)[axis];
                out[MUSCLE_PAIRS + p] = (shape[j] * v)[axis];
            }
            out[2 * MUSCLE_PAIRS] = (r.held[0][j] * x)[axis];
            out[2 * MUSCLE_PAIRS + 1] = (r.held[1][j] * v)[axis];
        }
        if self.inertia {
            out[self.rate_columns()] = (r.m_arm[j] * Vector2::new(kin.a[0][j], kin.a[1][j]))[axis];
        }
    }
    /// The inertia's scale first, then the rates.
    fn parameters(&self, _s: usize, beta: &[f64], _fb: f64) -> Vec<(String, f64)> {
        let own = beta.get(base_columns()..).unwrap_or(&[]);
        let g = |i: usize| own.get(i).copied().unwrap_or(f64::NAN);
        let mut p = Vec::new();
        if self.inertia {
            p.push(("arm_inertia_scale".to_string(), self.inertia_scale(beta)));
        }
        if self.rates {
            for (i, n) in RATE_PARAMETERS.into_iter().enumerate() {
                p.push((n.to_string(), g(i)));
            }
        }
        p
    }
    fn bounds(&self) -> Vec<(usize, f64, f64)> {
        if !self.inertia || !self.bounded {
            return Vec::new();
        }
        vec![(
            base_columns() + self.rate_columns(),
            -ARM_INERTIA_TOLERANCE,
            ARM_INERTIA_TOLERANCE,
        )]
    }
}

/// `stretch-reflex`: a delayed velocity reflex of the muscles.
#[derive(Debug, Clone, Copy, Default)]
pub struct StretchReflex;

fn reflex_delay_s(s: usize) -> f64 {
    (REFLEX_DELAY_MS.0 + REFLEX_DELAY_MS.2 * s as f64) * 1e-3
}

impl HandCandidate for StretchReflex {
    fn kind(&self) -> Option<EffectKind> {
        Some(EffectKind::StretchReflex)
    }
    fn settings(&self) -> usize {
        ((REFLEX_DELAY_MS.1 - REFLEX_DELAY_MS.0) / REFLEX_DELAY_MS.2).round() as usize + 1
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("delay_ms", reflex_delay_s(s) * 1e3)
    }
    fn columns(&self) -> usize {
        base_columns() + 1
    }
    fn rows(&self, r: &HandResponse, s: usize, fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        effect_rows(self, r, s, fb, f);
    }
    /// The muscles stretch with the hand: the reflex answers the hand's velocity.
    fn extra(&self, r: &HandResponse, kin: &Kin, s: usize, axis: usize, j: usize, out: &mut [f64]) {
        let l = lag(r, reflex_delay_s(s));
        let vl = Vector2::new(lagged(&kin.v[0], j, l), lagged(&kin.v[1], j, l));
        out[0] = (r.s[j] * vl)[axis];
    }
    fn parameters(&self, s: usize, beta: &[f64], _fb: f64) -> Vec<(String, f64)> {
        vec![
            ("delay_ms".to_string(), reflex_delay_s(s) * 1e3),
            ("gain".to_string(), beta.last().copied().unwrap_or(f64::NAN)),
        ]
    }
    fn physical(&self, _s: usize, beta: &[f64]) -> bool {
        beta.last().is_some_and(|g| *g > 0.0)
    }
}

/// `grip-compliance`: a spring-damper between hand and handle.
#[derive(Debug, Clone, Copy, Default)]
pub struct GripCompliance;

/// The grip's stiffness (N/m) and time constant (s) at setting `s`: the stiffness's
/// index times the time constants' count plus the time constant's index, both on the log
/// grids [`GRIP_STIFFNESS_N_PER_M`] and [`GRIP_TIME_S`].
pub(crate) fn grip_setting(s: usize) -> (f64, f64) {
    let on_log_grid =
        |(lo, hi, n): (f64, f64, usize), i: usize| lo * (hi / lo).powf(i as f64 / (n - 1) as f64);
    let (k, tau) = grip_indices(s);
    (
        on_log_grid(GRIP_STIFFNESS_N_PER_M, k),
        on_log_grid(GRIP_TIME_S, tau),
    )
}

/// The grip's setting `s` as its places on the stiffness grid and the time-constant grid
/// (the settings run over the time constants within each stiffness).
fn grip_indices(s: usize) -> (usize, usize) {
    (s / GRIP_TIME_S.2, s % GRIP_TIME_S.2)
}

/// Every other stiffness and every third time constant of the grip's grids (from the
/// first of each, which keeps both ends: 41 × 11 settings, 24 % and 47 % apart): a coarse
/// search that finds the valley the full grids refine.
pub(crate) fn grip_coarse_settings() -> impl Iterator<Item = usize> {
    let times = GRIP_TIME_S.2;
    (0..GRIP_STIFFNESS_N_PER_M.2)
        .step_by(2)
        .flat_map(move |k| (0..times).step_by(3).map(move |t| k * times + t))
}

impl HandCandidate for GripCompliance {
    fn kind(&self) -> Option<EffectKind> {
        Some(EffectKind::GripCompliance)
    }
    fn settings(&self) -> usize {
        GRIP_STIFFNESS_N_PER_M.2 * GRIP_TIME_S.2
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        ("stiffness_n_per_m", grip_setting(s).0)
    }
    /// The stiffness's place on its grid: at 0.5 or 50 kN/m it is at the edge whatever
    /// the time constant.
    fn search_position(&self, s: usize) -> (usize, usize) {
        (grip_indices(s).0, GRIP_STIFFNESS_N_PER_M.2)
    }
    /// The same time constant.
    fn on_the_line_of(&self, s: usize, of: usize) -> bool {
        grip_indices(s).1 == grip_indices(of).1
    }
    fn columns(&self) -> usize {
        base_columns()
    }
    fn rows(&self, r: &HandResponse, s: usize, fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        effect_rows(self, r, s, fb, f);
    }
    fn hand_kin(&self, r: &HandResponse, s: usize) -> Option<Kin> {
        let (k, tau) = grip_setting(s);
        Some(Kin::grip(r, k, tau))
    }
    fn parameters(&self, s: usize, _beta: &[f64], _fb: f64) -> Vec<(String, f64)> {
        let (k, tau) = grip_setting(s);
        vec![
            ("stiffness_n_per_m".to_string(), k),
            ("damping_n_s_per_m".to_string(), k * tau),
        ]
    }
}

/// A human-side candidate with its cross-validated fit.
pub struct HandFit {
    /// The candidate.
    pub candidate: Box<dyn HandCandidate>,
    /// Its fit.
    pub fit: CvFit,
}

impl std::fmt::Debug for HandFit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HandFit")
            .field("candidate", &self.candidate.name())
            .field("fit", &self.fit)
            .finish()
    }
}

/// The significance test's cross-validation on independent units (`OddUnits::Replicates`),
/// at the feedback delay of the main fit.
#[derive(Debug)]
pub struct ReplicateTest {
    /// Folds over the units (one per repetition of a pair of opposite directions), one
    /// unit each.
    pub folds: Folds,
    /// The baseline's fit.
    pub baseline: CvFit,
    /// The candidates' fits, in the order of [`HandJudgement::fits`].
    pub fits: Vec<CvFit>,
    /// The rival's fit ([`SubjectArm`]).
    pub subject_arm: CvFit,
    /// The repetitions themselves (for the joint fits of forward selection).
    pub units: Vec<HandResponse>,
}

impl ReplicateTest {
    /// Number of units tested.
    #[must_use]
    pub fn units(&self) -> usize {
        self.folds.of_trial.len()
    }
}

/// Everything the hand balance computed.
#[derive(Debug)]
pub struct HandJudgement {
    /// The units fitted: the odd parts of the mean responses to opposite pulses
    /// (`odd_parts`); with fewer pairs, of the means of groups of their repetitions
    /// (`odd_groups`, and then [`Self::repetition_groups`]); without opposite pairs,
    /// the responses averaged by direction (`average_by_angle`).
    pub responses: Vec<HandResponse>,
    /// The test on independent units, when the units above average repetitions
    /// (`OddUnits::Averaged` or `Groups`); `None` when the units are already independent, and
    /// then the folds above carry the test.
    pub replicates: Option<ReplicateTest>,
    /// With fewer than four pairs of opposite directions, the groups each pair's
    /// repetitions are split into (`odd_groups`); `None` otherwise.
    pub repetition_groups: Option<usize>,
    /// How many reaches the session's trials make (`reach_groups`; 1 when every
    /// reach goes one way).
    pub reaches: usize,
    /// Folds over [`Self::responses`].
    pub folds: Folds,
    /// Feedback delay chosen for the baseline, s.
    pub fb_delay_s: f64,
    /// The rows' weighting every fit above shares.
    pub whitening: Whitening,
    /// The baseline's fit.
    pub baseline: CvFit,
    /// The candidates' fits.
    pub fits: Vec<HandFit>,
    /// The rival's fit ([`SubjectArm`]).
    pub subject_arm: CvFit,
    /// The rival's fit with its inertia free ([`SubjectArm::OFF_THE_TABLES`]), on the
    /// units and folds the test runs on (the replicates' when there are any).
    pub subject_arm_free: CvFit,
    /// The arm's geometry the balance used.
    pub arm: HandArm,
}

impl HandJudgement {
    /// A fitted stretch reflex of gain `gain_n_s_per_m` (N of activation per m/s of
    /// muscle stretch velocity, the arm's own unit) in the units a lab compares with
    /// the literature: the joint damping it adds, `g Aᵀ diag(w) A` (N m s/rad; shoulder
    /// `ss`, cross `se`, elbow `ee`; `A` the moment arms, `w` the weights of
    /// `hand_signals::odd_part_weights`, ½ for a muscle without tone, which
    /// answers only its stretch), and the endpoint damping `g S` (N s/m, rig axes) at
    /// the pulse onsets, averaged over the responses. Both act after the reflex delay.
    #[must_use]
    pub fn reflex_units(&self, gain_n_s_per_m: f64) -> Vec<(String, f64)> {
        let joint = self.arm.ata * gain_n_s_per_m;
        let onsets: Vec<Matrix2<f64>> = self
            .responses
            .iter()
            .filter_map(|r| r.s.get(r.onset).copied())
            .collect();
        let endpoint =
            onsets.iter().sum::<Matrix2<f64>>() * (gain_n_s_per_m / onsets.len().max(1) as f64);
        vec![
            ("joint_damping_ss_n_m_s_per_rad".to_string(), joint[(0, 0)]),
            ("joint_damping_se_n_m_s_per_rad".to_string(), joint[(0, 1)]),
            ("joint_damping_ee_n_m_s_per_rad".to_string(), joint[(1, 1)]),
            (
                "endpoint_damping_xx_n_s_per_m".to_string(),
                endpoint[(0, 0)],
            ),
            (
                "endpoint_damping_xy_n_s_per_m".to_string(),
                endpoint[(0, 1)],
            ),
            (
                "endpoint_damping_yy_n_s_per_m".to_string(),
                endpoint[(1, 1)],
            ),
        ]
    }
}

/// The hand balance's candidate for a catalog effect (`None` for the cart balance's):
/// every human-side effect of [`EffectKind`] has one.
pub(crate) fn hand_candidate(kind: EffectKind) -> Option<Box<dyn HandCandidate>> {
    match kind {
        EffectKind::StretchReflex => Some(Box::new(StretchReflex)),
        EffectKind::GripCompliance => Some(Box::new(GripCompliance)),
        EffectKind::HandleMass => Some(Box::new(HandleMass)),
        EffectKind::RailFriction
        | EffectKind::ForceRipple
        | EffectKind::ActuationDelay
        | EffectKind::SensorRotation => None,
    }
}

/// The hand balance of a session: `Ok(Err(reason))` when the session cannot carry it.
///
/// # Errors
/// A signal-processing error, unphysical subject lengths, or a singular fit.
pub fn judge_hand(
    session: &Session,
    folds: usize,
) -> Result<Result<HandJudgement, String>, DiscrepancyError> {
    if session.manifest.axes != Axes::Both {
        return Ok(Err(format!(
            "a rig of one axis ({:?}): the hand balance needs the planar arm on both axes",
            session.manifest.axes.names()
        )));
    }
    if session
        .iter()
        .all(|(_, t)| t.fx_n.iter().chain(&t.fy_n).all(|f| *f == 0.0))
    {
        return Ok(Err(
            "no handle force sensor (every force sample is zero): the hand balance needs the hand's force".to_string(),
        ));
    }
    let arm = HandArm::from_session(session)?;
    let (responses, replicates, groups, reaches) = match hand_responses(session, &arm)? {
        HandData::Responses {
            responses: r,
            reaches,
        } => match (
            odd_parts(&r, OddUnits::Averaged),
            odd_parts(&r, OddUnits::Replicates),
        ) {
            (Some(avg), Some(rep)) => (avg, Some(rep), None, reaches),
            _ => match odd_groups(&r) {
                Some((groups, rep, n)) => (groups, Some(rep), Some(n), reaches),
                None => (average_by_angle(r), None, None, reaches),
            },
        },
        HandData::Missing(why) => return Ok(Err(why)),
    };
    // The averaged units are as many as the pairs of directions (4 on the shared
    // protocol), or their groups: leave-one-out over them; `folds` is for units that are trials or
    // directions.
    let k = if replicates.is_some() {
        responses.len()
    } else {
        folds
    };
    let folds = Folds::interleaved(responses.len(), k);
    let grams_of = |units: &[HandResponse], c: &dyn HandCandidate, fb: f64, w: &Whitening| {
        units
            .par_iter()
            .map(|r| hand_grams(c, r, fb, w))
            .collect::<Vec<_>>()
    };
    let time = Whitening::in_time();
    let delay = cross_validate(
        &grams_of(&responses, &FeedbackDelay, 0.0, &time),
        &folds,
        "hand feedback delay",
    )?;
    let fb_delay_s = FEEDBACK_DELAYS_MS[delay.setting] * 1e-3;
    // Weighted least squares needs the noise's shape between the axes: from the spread
    // of the repetitions about their mean under the baseline's coefficients, or, without
    // repetitions, from the baseline's residual (a weighting, not a fitted effect; every
    // candidate and the baseline then share it). The delay search's fit on all units at
    // its chosen delay is that baseline (the same rows), so the feedback delay is
    // searched with the time filter alone.
    let whitening = replicates
        .as_deref()
        .and_then(|reps| {
            Whitening::from_repetitions(&HandBaseline, &responses, reps, 0, &delay.beta, fb_delay_s)
        })
        .unwrap_or_else(|| {
            Whitening::fitted(&HandBaseline, &responses, 0, &delay.beta, fb_delay_s)
        });
    let grams = |c: &dyn HandCandidate, fb: f64| grams_of(&responses, c, fb, &whitening);
    let baseline = cross_validate(&grams(&HandBaseline, fb_delay_s), &folds, "hand baseline")?;
    let candidates: Vec<Box<dyn HandCandidate>> = EffectKind::ALL
        .into_iter()
        .filter_map(hand_candidate)
        .collect();
    let fits = candidates
        .into_par_iter()
        .map(|c| {
            let fit = cross_validate(&grams(c.as_ref(), fb_delay_s), &folds, c.name())?;
            Ok(HandFit { candidate: c, fit })
        })
        .collect::<Result<Vec<_>, DiscrepancyError>>()?;
    let subject_arm = cross_validate(
        &grams(&SubjectArm::WHOLE, fb_delay_s),
        &folds,
        "subject arm",
    )?;
    let replicates = match replicates {
        Some(units) => {
            // Leave one repetition out: the most degrees of freedom for the t-test.
            let folds = Folds::interleaved(units.len(), units.len());
            let cv = |c: &dyn HandCandidate, what: &str| {
                cross_validate(&grams_of(&units, c, fb_delay_s, &whitening), &folds, what)
            };
            let baseline = cv(&HandBaseline, "hand baseline (replicates)")?;
            let fits = fits
                .par_iter()
                .map(|f| cv(f.candidate.as_ref(), f.candidate.name()))
                .collect::<Result<Vec<_>, DiscrepancyError>>()?;
            let subject_arm = cv(&SubjectArm::WHOLE, "subject arm (replicates)")?;
            Some(ReplicateTest {
                folds,
                baseline,
                fits,
                subject_arm,
                units,
            })
        }
        None => None,
    };
    let subject_arm_free = match &replicates {
        Some(rep) => cross_validate(
            &grams_of(
                &rep.units,
                &SubjectArm::OFF_THE_TABLES,
                fb_delay_s,
                &whitening,
            ),
            &rep.folds,
            "subject arm off the tables (replicates)",
        )?,
        None => cross_validate(
            &grams(&SubjectArm::OFF_THE_TABLES, fb_delay_s),
            &folds,
            "subject arm off the tables",
        )?,
    };
    Ok(Ok(HandJudgement {
        responses,
        replicates,
        repetition_groups: groups,
        reaches,
        folds,
        fb_delay_s,
        whitening,
        baseline,
        fits,
        subject_arm,
        subject_arm_free,
        arm,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn response(f: Vec<f64>, rate_hz: f64) -> HandResponse {
        let n = f.len();
        let fd: Vec<f64> = (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
                (f[b] - f[a]) * rate_hz / (b - a) as f64
            })
            .collect();
        HandResponse {
            id: 1,
            rate_hz,
            onset: 0,
            angle_deg: 0.0,
            dx: [vec![0.0; n], vec![0.0; n]],
            dv: [vec![0.0; n], vec![0.0; n]],
            da: [vec![0.0; n], vec![0.0; n]],
            df: [f.clone(), f],
            dfd: [fd.clone(), fd],
            m_arm: vec![Matrix2::identity(); n],
            s: vec![Matrix2::identity(); n],
            activation: std::array::from_fn(|_| vec![Matrix2::zeros(); n]),
            held: std::array::from_fn(|_| vec![Matrix2::zeros(); n]),
            rows: (0..n).collect(),
            references: 2,
            trials: vec![1],
        }
    }

    /// The hand balance's law with the [`SubjectArm`]'s parts: `−ΔF = (1 + c) M_arm Δa +
    /// D Δv + K Δx + J⁻ᵀ diag(e)(diag(β) J⁻¹ Δv + diag(κ) J⁻¹ Δx) + p S (Δx + ρ Δv)(t − τ)`;
    /// by default a
    /// non-symmetric `D` and `K` (what a moving, torque-bearing arm shows), no rates and
    /// the tables' inertia.
    struct ArmLaw {
        d: Matrix2<f64>,
        d_rate: [f64; MUSCLE_PAIRS],
        k: Matrix2<f64>,
        k_rate: [f64; MUSCLE_PAIRS],
        held: [f64; 2],
        p: f64,
        c: f64,
        fb: f64,
    }

    impl Default for ArmLaw {
        fn default() -> ArmLaw {
            ArmLaw {
                d: Matrix2::new(12.0, -3.0, 5.0, 9.0),
                d_rate: [0.0; MUSCLE_PAIRS],
                k: Matrix2::new(420.0, 60.0, -140.0, 310.0),
                k_rate: [0.0; MUSCLE_PAIRS],
                held: [0.0; 2],
                p: 480.0,
                c: 0.0,
                fb: 0.06,
            }
        }
    }

    impl ArmLaw {
        /// Writes the law's force into `r` from its kinematics.
        fn impose(&self, r: &mut HandResponse) {
            let (n, lag, rho) = (
                r.df[0].len(),
                self.fb * r.rate_hz,
                feedback_velocity_ratio_s(),
            );
            for j in 0..n {
                let v = Vector2::new(r.dv[0][j], r.dv[1][j]);
                let x = Vector2::new(r.dx[0][j], r.dx[1][j]);
                let a = Vector2::new(r.da[0][j], r.da[1][j]);
                let xl = Vector2::new(lagged(&r.dx[0], j, lag), lagged(&r.dx[1], j, lag));
                let vl = Vector2::new(lagged(&r.dv[0], j, lag), lagged(&r.dv[1], j, lag));
                let (kh, dh) = r.activation.iter().enumerate().fold(
                    (self.held[0] * r.held[0][j], self.held[1] * r.held[1][j]),
                    |(k, d), (p, shape)| {
                        (k + self.k_rate[p] * shape[j], d + self.d_rate[p] * shape[j])
                    },
                );
                let f = -((1.0 + self.c) * r.m_arm[j] * a
                    + self.d * v
                    + self.k * x
                    + kh * x
                    + dh * v
                    + self.p * r.s[j] * (xl + rho * vl));
                r.df[0][j] = f[0];
                r.df[1][j] = f[1];
            }
        }
    }

    /// A response moving by two incommensurate motions per axis (so that x, v, a and the
    /// lagged terms are independent regressors), with a fixed arm inertia and feedback
    /// shape, and no force yet: 400 samples at 1 kHz, rows from the 100th.
    fn moving_response() -> HandResponse {
        let (rate, n) = (1000.0, 400);
        let t = |i: usize| i as f64 / rate;
        let pos = |i: usize, f: [f64; 2]| {
            1e-3 * ((2.0 * PI * f[0] * t(i)).sin() + 0.6 * (2.0 * PI * f[1] * t(i)).cos())
        };
        let freqs = [[1.3, 4.1], [2.2, 6.7]];
        let mut r = response(vec![0.0; n], rate);
        for (axis, f) in freqs.iter().enumerate() {
            let w = f.map(|f| 2.0 * PI * f);
            r.dx[axis] = (0..n).map(|i| pos(i, *f)).collect();
            r.dv[axis] = (0..n)
                .map(|i| 1e-3 * (w[0] * (w[0] * t(i)).cos() - 0.6 * w[1] * (w[1] * t(i)).sin()))
                .collect();
            r.da[axis] = (0..n)
                .map(|i| {
                    -1e-3
                        * (w[0] * w[0] * (w[0] * t(i)).sin()
                            + 0.6 * w[1] * w[1] * (w[1] * t(i)).cos())
                })
                .collect();
        }
        let m = Matrix2::new(1.8, 0.3, 0.3, 1.1);
        let sh = Matrix2::new(0.07, 0.02, 0.02, 0.05);
        r.m_arm = vec![m; n];
        r.s = vec![sh; n];
        // The pairs' activation shapes and the held torque's impedance rising and
        // falling over the window, as on a reach whose torque swings within it, each with
        // its own time course and direction (centred on the rows, as `hand_responses`
        // does): N for the shapes (50 N of activation on moment arms of 4–5 cm at J⁻¹ of
        // about 3 rad/m), N/m and N s/m for the held torque's.
        let swing = |f: f64, ph: f64, m: Matrix2<f64>| -> Vec<Matrix2<f64>> {
            let series: Vec<Matrix2<f64>> = (0..n)
                .map(|i| m * (2.0 * PI * f * t(i) + ph).sin())
                .collect();
            let mean = series[100..].iter().sum::<Matrix2<f64>>() / (n - 100) as f64;
            series.iter().map(|e| e - mean).collect()
        };
        r.activation = [
            swing(1.7, 0.0, Matrix2::new(0.9, 0.3, 0.3, 0.4)),
            swing(2.9, 0.4, Matrix2::new(0.2, -0.1, -0.1, 1.1)),
            swing(0.8, 1.1, Matrix2::new(0.6, 0.5, 0.5, 0.7)),
        ];
        r.held = [
            swing(2.3, 0.7, Matrix2::new(30.0, -12.0, 8.0, 25.0)),
            swing(1.2, 2.0, Matrix2::new(1.5, 0.4, -0.6, 2.0)),
        ];
        r.rows = (100..n).collect();
        r
    }

    /// The grip's search crosses the stiffness with the time constant: the settings on
    /// the line of one are every stiffness of the grid, once each and rising, at that
    /// setting's time constant, and the edge rule reads the stiffness's place alone.
    #[test]
    fn the_grips_line_holds_its_time_constant() {
        let g = GripCompliance;
        let of = 7 * GRIP_TIME_S.2 + 5;
        let line: Vec<usize> = (0..g.settings())
            .filter(|s| g.on_the_line_of(*s, of))
            .collect();
        assert_eq!(line.len(), GRIP_STIFFNESS_N_PER_M.2);
        assert!(line.contains(&of));
        let tau = grip_setting(of).1;
        assert!(line.iter().all(|s| grip_setting(*s).1 == tau));
        assert!(
            line.windows(2)
                .all(|w| grip_setting(w[0]).0 < grip_setting(w[1]).0)
        );
        assert_eq!(g.search_position(of), (7, GRIP_STIFFNESS_N_PER_M.2));
        // One parameter searched: every setting is on the line.
        assert!((0..StretchReflex.settings()).all(|s| StretchReflex.on_the_line_of(s, 0)));
    }

    /// A response built exactly by the baseline's law, with a non-symmetric `D` and `K`
    /// (what a moving, torque-bearing arm shows), gives those matrices and the feedback
    /// gain back to round-off: the columns are the law's, in the order the parameters
    /// are named.
    #[test]
    fn baseline_recovers_a_non_symmetric_impedance() {
        let mut r = moving_response();
        let law = ArmLaw::default();
        law.impose(&mut r);
        let (d, k, p, fb) = (law.d, law.k, law.p, law.fb);
        let want = [
            ("d11_n_s_per_m", d[(0, 0)]),
            ("d12_n_s_per_m", d[(0, 1)]),
            ("d21_n_s_per_m", d[(1, 0)]),
            ("d22_n_s_per_m", d[(1, 1)]),
            ("k11_n_per_m", k[(0, 0)]),
            ("k12_n_per_m", k[(0, 1)]),
            ("k21_n_per_m", k[(1, 0)]),
            ("k22_n_per_m", k[(1, 1)]),
            ("feedback_position_gain_n_per_m", p),
        ];
        // Unweighted, and through a weighting that filters in time and mixes the
        // axes: a law that holds for the rows holds for the weighted rows.
        let mixing = Whitening {
            noise_time_s: 0.03,
            axes: Matrix2::new(2.0, 0.0, -0.7, 0.5),
            source: WeightSource::Residual,
        };
        // The coefficients of `g` against `want`; exact data, so only the normal
        // equations' round-off (and the offsets' elimination) remains.
        let recovers = |g: &Gram, what: &str| {
            let Some(beta) = g.solve() else {
                panic!("the baseline's columns are independent here ({what})");
            };
            let got: std::collections::BTreeMap<String, f64> =
                baseline_parameters(&beta, fb).into_iter().collect();
            for (name, value) in want {
                let v = got.get(name).copied().unwrap_or(f64::NAN);
                assert!(
                    (v - value).abs() < 1e-6 * value.abs().max(1.0),
                    "{name} {what}: {v} vs {value}"
                );
            }
            beta
        };
        for w in [None, Some(mixing)] {
            let mut g = Gram::new(base_columns());
            match &w {
                None => HandBaseline.rows(&r, 0, fb, &mut |x, y, nrm| g.push(x, y, nrm)),
                Some(w) => whitened_rows(&HandBaseline, &r, 0, fb, w, &mut |x, y, nrm| {
                    g.push(x, y, nrm);
                }),
            }
            recovers(&g, &format!("with weighting {w:?}"));
        }
        // A constant force per axis on top (a sensor offset drifted between the trial and
        // its references): through the response's Grams, which fit one out per axis, the
        // law comes back as before; without them it would be read as impedance.
        r.df[0].iter_mut().for_each(|f| *f += 0.3);
        r.df[1].iter_mut().for_each(|f| *f -= 0.2);
        let g = &hand_grams(&HandBaseline, &r, fb, &mixing)[0];
        let beta = recovers(g, "with offsets");
        assert!(g.sse(&beta) < 1e-12 * g.norm_sq, "offsets left a residual");
    }

    /// A response built by the baseline's law with an impedance that changes over the
    /// window (what a muscle's activation-dependent impedance does on a fast reach) and an
    /// arm 12 % heavier than the tables: the rival [`SubjectArm`] gives the rates and the
    /// inertia's scale back to round-off, and the baseline, which lacks them, does not fit
    /// it (its error is more than a tenth of the force).
    #[test]
    fn the_subject_arm_recovers_an_impedance_changing_over_the_window() {
        let mut r = moving_response();
        // Per newton of activation, as the arm's K_m = K₀ + K₁ a with K₁ = 100 /m and
        // damping times of 10–120 ms gives; the held torque's impedance as the tables
        // give it (scale 1) and 20 % low.
        let law = ArmLaw {
            d_rate: [12.0, 1.0, 8.0],
            k_rate: [90.0, 120.0, 70.0],
            held: [1.0, 0.8],
            c: 0.12,
            ..ArmLaw::default()
        };
        law.impose(&mut r);
        let (d_rate, k_rate, c, fb) = (law.d_rate, law.k_rate, law.c, law.fb);
        let fit = |cand: &dyn HandCandidate| {
            let mut g = Gram::new(cand.columns()).with_bounds(cand.bounds());
            cand.rows(&r, 0, fb, &mut |x, y, nrm| g.push(x, y, nrm));
            let beta = g.solve().expect("independent columns");
            (g.sse(&beta) / g.norm_sq, beta)
        };
        let (base_err, _) = fit(&HandBaseline);
        assert!(base_err > 0.01, "the baseline fits it: {base_err}");
        let (err, beta) = fit(&SubjectArm::WHOLE);
        assert!(err < 1e-12, "the rival leaves {err}");
        let got: std::collections::BTreeMap<String, f64> = SubjectArm::WHOLE
            .parameters(0, &beta, fb)
            .into_iter()
            .collect();
        let want = [
            ("arm_inertia_scale", 1.0 + c),
            (RATE_PARAMETERS[0], k_rate[0]),
            (RATE_PARAMETERS[1], k_rate[1]),
            (RATE_PARAMETERS[2], k_rate[2]),
            (RATE_PARAMETERS[3], d_rate[0]),
            (RATE_PARAMETERS[4], d_rate[1]),
            (RATE_PARAMETERS[5], d_rate[2]),
            (RATE_PARAMETERS[6], law.held[0]),
            (RATE_PARAMETERS[7], law.held[1]),
        ];
        for (name, value) in want {
            let v = got.get(name).copied().unwrap_or(f64::NAN);
            assert!(
                (v - value).abs() < 1e-6 * value.abs().max(1.0),
                "{name}: {v} vs {value}"
            );
        }
    }

    /// A response with a handle mass *and* a stretch reflex, built exactly by their
    /// joint law: the joint model (the mass named, the reflex searched) gives both back
    /// to round-off, at the reflex's own delay, and its parameters are read per member;
    /// the reflex alone, at the same delay, leaves a residual (the mass's force) and a
    /// gain that is off.
    #[test]
    fn a_handle_mass_and_a_reflex_are_fitted_jointly() {
        use crate::hand_joint::HandJoint;
        use std::sync::Arc;
        let mut r = moving_response();
        let (rate, n, m, sh) = (r.rate_hz, r.df[0].len(), r.m_arm[0], r.s[0]);
        let (d, k, p, fb) = (
            Matrix2::new(12.0, -3.0, 5.0, 9.0),
            Matrix2::new(420.0, 60.0, -140.0, 310.0),
            480.0,
            0.06,
        );
        let (mass, gain, delay_s) = (0.4, 150.0, 0.025);
        let rho = feedback_velocity_ratio_s();
        let v_at =
            |j: usize, lag: f64| Vector2::new(lagged(&r.dv[0], j, lag), lagged(&r.dv[1], j, lag));
        let x_at =
            |j: usize, lag: f64| Vector2::new(lagged(&r.dx[0], j, lag), lagged(&r.dx[1], j, lag));
        let df: Vec<Vector2<f64>> = (0..n)
            .map(|j| {
                let a = Vector2::new(r.da[0][j], r.da[1][j]);
                -((m + Matrix2::identity() * mass) * a
                    + d * v_at(j, 0.0)
                    + k * x_at(j, 0.0)
                    + p * sh * (x_at(j, fb * rate) + rho * v_at(j, fb * rate))
                    + gain * sh * v_at(j, delay_s * rate))
            })
            .collect();
        for axis in 0..2 {
            r.df[axis] = df.iter().map(|f| f[axis]).collect();
        }
        let setting = ((delay_s * 1e3 - REFLEX_DELAY_MS.0) / REFLEX_DELAY_MS.2).round() as usize;
        let fit = |c: &dyn HandCandidate| {
            let mut g = Gram::new(c.columns());
            c.rows(&r, setting, fb, &mut |x, y, nrm| g.push(x, y, nrm));
            let beta = g.solve().unwrap_or_default();
            (g.sse(&beta) / g.norm_sq, beta)
        };
        let joint = HandJoint {
            fixed: vec![(Arc::new(HandleMass), 0)],
            next: Arc::new(StretchReflex),
            grip_load_kg: 0.0,
        };
        let (rel_sse, beta) = fit(&joint);
        assert!(
            rel_sse < 1e-12,
            "the joint law leaves {rel_sse} of the force"
        );
        let params = joint.member_parameters(setting, &beta, fb);
        let value = |i: usize, key: &str| {
            params[i]
                .1
                .iter()
                .find(|(k, _)| k == key)
                .map_or(f64::NAN, |(_, v)| *v)
        };
        assert!(
            (value(0, "extra_mass_kg") - mass).abs() < 1e-6,
            "mass {}",
            value(0, "extra_mass_kg")
        );
        assert!(
            (value(1, "gain") - gain).abs() < 1e-6 * gain,
            "gain {}",
            value(1, "gain")
        );
        assert!((value(1, "delay_ms") - 25.0).abs() < 1e-9);
        assert!(joint.physical(setting, &beta));
        // Alone, the reflex cannot carry the mass's force: a residual of more than 1e-6
        // of the force and a gain more than 1 % off.
        let (rel_alone, beta_alone) = fit(&StretchReflex);
        let gain_alone = beta_alone.last().copied().unwrap_or(f64::NAN);
        assert!(rel_alone > 1e-6, "the reflex alone leaves only {rel_alone}");
        assert!(
            (gain_alone - gain).abs() > 0.01 * gain,
            "the reflex alone finds {gain_alone}"
        );
    }

    /// The hand's library finds laws the catalog lacks in a response built exactly of
    /// the baseline (its feedback at 60 ms) plus the law: a subject's second feedback at
    /// 130 ms, and a stiffness growing with the cube of the stretch. Each term's
    /// least-squares fit leaves nothing (< 1e-12 of the force) with its coefficients
    /// exact to 1e-6, the late feedback at its own delay and at no other on the grid
    /// (10 ms away leaves more than 1e-6), and the baseline alone cannot carry either.
    #[test]
    fn the_hand_library_finds_a_late_feedback_and_a_cubic_stiffness() {
        use crate::hand_library::{HandTerm, LATE_FEEDBACK_MS};
        let base = moving_response();
        let (rate, n, m, sh) = (base.rate_hz, base.df[0].len(), base.m_arm[0], base.s[0]);
        let (d, k, p, fb) = (
            Matrix2::new(12.0, -3.0, 5.0, 9.0),
            Matrix2::new(420.0, 60.0, -140.0, 310.0),
            480.0,
            0.06,
        );
        let rho = feedback_velocity_ratio_s();
        let at = |v: &[Vec<f64>; 2], j: usize, lag: f64| {
            Vector2::new(lagged(&v[0], j, lag), lagged(&v[1], j, lag))
        };
        let with_force = |extra: &dyn Fn(usize) -> Vector2<f64>| {
            let mut r = base.clone();
            let df: Vec<Vector2<f64>> = (0..n)
                .map(|j| {
                    let a = Vector2::new(base.da[0][j], base.da[1][j]);
                    -(m * a
                        + d * at(&base.dv, j, 0.0)
                        + k * at(&base.dx, j, 0.0)
                        + p * sh * (at(&base.dx, j, fb * rate) + rho * at(&base.dv, j, fb * rate))
                        + extra(j))
                })
                .collect();
            for axis in 0..2 {
                r.df[axis] = df.iter().map(|f| f[axis]).collect();
            }
            r
        };
        let fit = |c: &dyn HandCandidate, r: &HandResponse, s: usize| {
            let mut g = Gram::new(c.columns());
            c.rows(r, s, fb, &mut |x, y, nrm| g.push(x, y, nrm));
            let beta = g.solve().unwrap_or_default();
            (g.sse(&beta) / g.norm_sq, beta)
        };
        let coefficient = |t: HandTerm, s: usize, beta: &[f64], key: &str| {
            t.parameters(s, beta, fb)
                .into_iter()
                .find(|(k, _)| k == key)
                .map_or(f64::NAN, |(_, v)| v)
        };

        // A second feedback at 130 ms (one gain for both axes, through the same shape).
        let (late_s, c_late) = (0.13, 350.0);
        let r = with_force(&|j| {
            c_late * sh * (at(&base.dx, j, late_s * rate) + rho * at(&base.dv, j, late_s * rate))
        });
        let t = HandTerm::LateFeedback;
        let s = ((late_s * 1e3 - LATE_FEEDBACK_MS.0) / LATE_FEEDBACK_MS.2).round() as usize;
        let (rel, beta) = fit(&t, &r, s);
        assert!(rel < 1e-12, "the late feedback leaves {rel} of the force");
        for (key, want) in [("x", c_late), ("y", c_late)] {
            let got = coefficient(t, s, &beta, key);
            assert!((got - want).abs() < 1e-6 * want, "{key}: {got} for {want}");
        }
        assert!((coefficient(t, s, &beta, "delay_ms") - 130.0).abs() < 1e-9);
        for other in [s - 1, s + 1] {
            let (rel_other, _) = fit(&t, &r, other);
            assert!(rel_other > 1e-6, "{other}: {rel_other}");
        }
        let (rel_base, _) = fit(&HandBaseline, &r, 0);
        assert!(rel_base > 1e-6, "the baseline alone leaves only {rel_base}");

        // A stiffness growing with the cube of the stretch (3e8 N/m³: 0.3 N at 1 mm).
        let c3 = [3e8, -2e8];
        let r = with_force(&|j| {
            Vector2::new(c3[0] * base.dx[0][j].powi(3), c3[1] * base.dx[1][j].powi(3))
        });
        let t = HandTerm::CubicStiffness;
        let (rel, beta) = fit(&t, &r, 0);
        assert!(rel < 1e-12, "the cubic stiffness leaves {rel} of the force");
        for (key, want) in [("x", c3[0]), ("y", c3[1])] {
            let got = coefficient(t, 0, &beta, key);
            assert!(
                (got - want).abs() < 1e-6 * want.abs(),
                "{key}: {got} for {want}"
            );
        }
        let (rel_base, _) = fit(&HandBaseline, &r, 0);
        assert!(rel_base > 1e-6, "the baseline alone leaves only {rel_base}");
    }

    /// A grip loaded with a mass on the handle's side is the grip under the force the
    /// spring then carries, `ΔF + m Δa` with its rate `ΔḞ + m Δȧ`: the same kinematics as
    /// the unloaded grip of a response whose force has that added (to the central
    /// difference's round-off), and unloaded it is the grip itself, bit for bit.
    #[test]
    fn a_loaded_grip_carries_the_mass_s_force() {
        let mut r = moving_response();
        let n = r.df[0].len();
        for axis in 0..2 {
            r.df[axis] = (0..n)
                .map(|i| 2.0 * r.da[axis][i] + 0.1 * r.dv[axis][i])
                .collect();
            r.dfd[axis] = (0..n)
                .map(|i| {
                    let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
                    2.0 * (r.da[axis][hi] - r.da[axis][lo]) * r.rate_hz / (hi - lo) as f64
                        + 0.1 * r.da[axis][i]
                })
                .collect();
        }
        let (k, tau, m) = (3000.0, 5e-3, 0.6);
        let unloaded = Kin::grip(&r, k, tau);
        let same = Kin::grip_loaded(&r, k, tau, 0.0);
        assert!(unloaded.x == same.x && unloaded.v == same.v && unloaded.a == same.a);
        let loaded = Kin::grip_loaded(&r, k, tau, m);
        let mut heavier = r.clone();
        for axis in 0..2 {
            for i in 0..n {
                let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
                heavier.df[axis][i] += m * r.da[axis][i];
                heavier.dfd[axis][i] +=
                    m * (r.da[axis][hi] - r.da[axis][lo]) * r.rate_hz / (hi - lo) as f64;
            }
        }
        let want = Kin::grip(&heavier, k, tau);
        for axis in 0..2 {
            for i in 0..n {
                assert!((loaded.x[axis][i] - want.x[axis][i]).abs() < 1e-12);
                assert!(
                    (loaded.a[axis][i] - want.a[axis][i]).abs()
                        < 1e-9 * (1.0 + want.a[axis][i].abs())
                );
            }
        }
        // The load moves the hand: a 0.6 kg mass under these accelerations is not nothing.
        let moved = (0..n)
            .map(|i| (loaded.x[1][i] - unloaded.x[1][i]).abs())
            .fold(0.0, f64::max);
        assert!(moved > 1e-7, "the load moved the hand by at most {moved} m");
    }

    /// A response made exactly of a grip (3155 N/m, τ 5.3 ms: a point of the grid) and a
    /// 0.43 kg handle mass on the handle's side of it: the hand moves by two
    /// incommensurate motions per axis, the arm's law gives the force on it, the handle
    /// trails it through the spring (the same filter [`Kin::grip`] integrates), and the
    /// sensor reads that force less the mass's inertial force. The load search finds the
    /// mass to 2 g (a tenth of its 20 g grid; the squared error is not quite a parabola
    /// in the load), the joint fit there leaves nothing of the force (1e-12), and no load
    /// leaves a residual.
    #[test]
    fn the_grip_load_search_finds_the_mass_behind_a_grip() {
        use crate::hand_joint::{HandJoint, least_sse_load};
        use std::sync::Arc;
        let hand = moving_response();
        let (n, rate, m_arm) = (hand.df[0].len(), hand.rate_hz, hand.m_arm[0]);
        let d = Matrix2::new(12.0, -3.0, 5.0, 9.0);
        let k = Matrix2::new(420.0, 60.0, -140.0, 310.0);
        // 3155 N/m: two fifths of the way up the stiffness grid's hundredfold.
        let k_index = (GRIP_STIFFNESS_N_PER_M.2 - 1) * 2 / 5;
        let (setting, mass) = (k_index * GRIP_TIME_S.2 + 13, 0.43);
        let (k_grip, tau) = grip_setting(setting);
        // The hand's jerk, by central differences of its acceleration, for the force's rate.
        let jerk = |a: &[f64], i: usize| {
            let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (a[hi] - a[lo]) * rate / (hi - lo) as f64
        };
        // The force on the hand by the arm's law (no delayed feedback) and its rate.
        let mut spring = response(vec![0.0; n], rate);
        for j in 0..n {
            let at = |s: &[Vec<f64>; 2]| Vector2::new(s[0][j], s[1][j]);
            let f = -(m_arm * at(&hand.da) + d * at(&hand.dv) + k * at(&hand.dx));
            let jk = Vector2::new(jerk(&hand.da[0], j), jerk(&hand.da[1], j));
            let fd = -(m_arm * jk + d * at(&hand.da) + k * at(&hand.dv));
            for axis in 0..2 {
                spring.df[axis][j] = f[axis];
                spring.dfd[axis][j] = fd[axis];
            }
        }
        // The spring's stretch under that force, and the handle behind it.
        let stretch = Kin::grip(&spring, k_grip, tau);
        let mut r = hand.clone();
        for axis in 0..2 {
            for j in 0..n {
                r.dx[axis][j] = hand.dx[axis][j] - stretch.x[axis][j];
                r.dv[axis][j] = hand.dv[axis][j] - stretch.v[axis][j];
                r.da[axis][j] = hand.da[axis][j] - stretch.a[axis][j];
            }
            for j in 0..n {
                r.df[axis][j] = spring.df[axis][j] - mass * r.da[axis][j];
                r.dfd[axis][j] = spring.dfd[axis][j] - mass * jerk(&r.da[axis], j);
            }
        }
        let w = Whitening {
            noise_time_s: 0.03,
            axes: Matrix2::identity(),
            source: WeightSource::Residual,
        };
        let fb = 0.06;
        let mut joint = HandJoint {
            fixed: vec![(Arc::new(GripCompliance), setting)],
            next: Arc::new(HandleMass),
            grip_load_kg: 0.0,
        };
        let found = least_sse_load(&joint, 0, std::slice::from_ref(&r), fb, &w).unwrap();
        assert!((found - mass).abs() < 2e-3, "load {found} kg for {mass}");
        let rel_sse = |joint: &HandJoint| {
            let g = hand_gram(joint, &r, 0, fb, &w);
            let beta = g.solve().unwrap_or_default();
            (g.sse(&beta) / g.norm_sq, beta)
        };
        joint.grip_load_kg = mass;
        let (at_mass, beta) = rel_sse(&joint);
        assert!(at_mass < 1e-12, "the loaded joint leaves {at_mass}");
        let fitted = joint.member_parameters(0, &beta, fb)[1].1[0].1;
        assert!((fitted - mass).abs() < 1e-6, "mass column {fitted}");
        joint.grip_load_kg = 0.0;
        let (unloaded, _) = rel_sse(&joint);
        assert!(
            unloaded > 1e-6,
            "without the load the joint leaves only {unloaded}"
        );
    }

    /// The innovations' shape `L` of [`correlated_noise`]: the y axis follows x.
    fn noise_shape() -> Matrix2<f64> {
        Matrix2::new(1.0, 0.0, 0.8, 0.3)
    }

    /// `n` samples at `rate` of a residual first-order autoregressive in time with the
    /// weighting's own `φ` and innovations `L ξ` ([`noise_shape`]), `ξ` standard normal.
    fn correlated_noise(rng: &mut rand_chacha::ChaCha8Rng, n: usize, rate: f64) -> [Vec<f64>; 2] {
        use rand_distr::{Distribution, StandardNormal};
        let phi = (-1.0 / rate / HAND_NOISE_TIME_S).exp();
        let l = noise_shape();
        let mut e = Vector2::zeros();
        let mut f = [Vec::with_capacity(n), Vec::with_capacity(n)];
        for _ in 0..n {
            let xi = Vector2::from_fn(|_, _| StandardNormal.sample(&mut *rng));
            e = phi * e + l * xi;
            f[0].push(e[0]);
            f[1].push(e[1]);
        }
        f
    }

    /// A residual that is first-order autoregressive in time with the weighting's own
    /// `φ` and innovations `L ξ` correlated between the axes: the fitted weighting's `W`
    /// makes the innovations' covariance a multiple of the identity. 20 000 samples, so
    /// the covariance's sampling error is about `√(2/n)` = 1 %; held to 4 %.
    #[test]
    fn fitted_weighting_decorrelates_the_axes() {
        use rand::SeedableRng;
        let (rate, n) = (500.0, 20_000);
        let l = noise_shape();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let f = correlated_noise(&mut rng, n, rate);
        let mut r = response(f[0].clone(), rate);
        r.df[1] = f[1].clone();
        // No motion: the residual of zero coefficients is the target, `−ΔF`.
        let w = Whitening::fitted(&HandBaseline, &[r], 0, &[0.0; 9], 0.06);
        assert!((w.noise_time_s - HAND_NOISE_TIME_S).abs() < 1e-12);
        let c = w.axes * l * l.transpose() * w.axes.transpose();
        let scale = 0.5 * (c[(0, 0)] + c[(1, 1)]);
        for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let want = if i == j { 1.0 } else { 0.0 };
            assert!(
                (c[(i, j)] / scale - want).abs() < 0.04,
                "W Σ Wᵀ = {c} is not a multiple of the identity"
            );
        }
    }

    /// Six repetitions of one response: a common part the model misses, five times the
    /// noise and along y only, plus noise correlated between the axes as in the test
    /// above. The weighting from the repetitions must see the noise alone (`W Σ Wᵀ` a
    /// multiple of the identity within 5 %; 6 × 4000 samples, sampling error ~1 %); the
    /// one from the averaged unit's residual is pulled by the common part (its `y` weight
    /// falls), which is why the repetitions are used when a session has them.
    #[test]
    fn repetitions_weigh_by_the_noise_not_by_the_misfit() {
        use rand::SeedableRng;
        let (rate, n, m) = (500.0, 4000, 6);
        let l = noise_shape();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let common: Vec<f64> = (0..n)
            .map(|i| 5.0 * (2.0 * PI * 3.0 * i as f64 / rate).sin())
            .collect();
        let reps: Vec<HandResponse> = (0..m)
            .map(|j| {
                let f = correlated_noise(&mut rng, n, rate);
                let mut r = response(f[0].clone(), rate);
                r.df[1] = f[1].iter().zip(&common).map(|(e, c)| e + c).collect();
                r.trials = vec![j as u32];
                r
            })
            .collect();
        // The mean of the repetitions, of their trials.
        let mut avg = response(vec![0.0; n], rate);
        avg.trials = (0..m as u32).collect();
        for axis in 0..2 {
            avg.df[axis] = (0..n)
                .map(|i| reps.iter().map(|r| r.df[axis][i]).sum::<f64>() / m as f64)
                .collect();
        }
        let noise = l * l.transpose();
        // `W Σ Wᵀ` over its mean diagonal: the identity when `W` whitens `Σ`.
        let shape = |w: &Whitening| {
            let c = w.axes * noise * w.axes.transpose();
            c / (0.5 * (c[(0, 0)] + c[(1, 1)]))
        };
        let beta = [0.0; 9];
        let Some(w) =
            Whitening::from_repetitions(&HandBaseline, &[avg.clone()], &reps, 0, &beta, 0.06)
        else {
            panic!("the repetitions' covariance is positive definite");
        };
        assert_eq!(w.source, WeightSource::Repetitions);
        let c = shape(&w);
        eprintln!("repetitions: W Σ Wᵀ = {c}");
        assert!(
            (c - Matrix2::identity()).abs().max() < 0.05,
            "W Σ Wᵀ = {c} is not a multiple of the identity"
        );
        let c = shape(&Whitening::fitted(&HandBaseline, &[avg], 0, &beta, 0.06));
        eprintln!("residual: W Σ Wᵀ = {c}");
        assert!(
            (c - Matrix2::identity()).abs().max() > 0.2,
            "the residual's weighting should be pulled by the common part: {c}"
        );
    }

    /// Two directions of three repetitions each: a common part the model misses (along
    /// y only) plus noise first-order autoregressive in time and correlated between the
    /// axes. The noise floor read from the repetitions must be the held-out NRMSE of the
    /// averaged units' own noise, computed from the noise itself under the same
    /// weighting (within 5 %: 2 × 3 × 3000 samples on two axes, so the two variances'
    /// sampling errors are about 1 % each), and must not see the misfit: with the common
    /// part ten times larger, the noise it reads (floor² × normaliser) is the same to
    /// rounding, because the misfit cancels between a repetition and its mean. A
    /// direction whose mean holds a trial no repetition has is left out of the floor and
    /// of the weighting between the axes alike (to rounding, 1e-12).
    #[test]
    fn the_noise_floor_is_the_averaged_units_noise_not_the_misfit() {
        use rand::SeedableRng;
        let (rate, n, m) = (500.0, 3000, 3);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        let angles = [30.0, 60.0];
        // Per direction, per repetition, the noise on both axes.
        let noise: Vec<Vec<[Vec<f64>; 2]>> = angles
            .iter()
            .map(|_| {
                (0..m)
                    .map(|_| correlated_noise(&mut rng, n, rate))
                    .collect()
            })
            .collect();
        let unit = |angle: f64, f: [Vec<f64>; 2], trials: Vec<u32>| {
            let mut r = response(f[0].clone(), rate);
            r.df[1] = f[1].clone();
            r.angle_deg = angle;
            r.trials = trials;
            r
        };
        // Repetition `j` of direction `i` is the odd part of trials `2k` and `2k + 1`.
        let trials_of = |i: usize, j: usize| {
            let k = (i * m + j) as u32;
            vec![2 * k, 2 * k + 1]
        };
        let all_trials = |i: usize| (0..m).flat_map(|j| trials_of(i, j)).collect::<Vec<_>>();
        let mean = |fs: &[[Vec<f64>; 2]]| -> [Vec<f64>; 2] {
            std::array::from_fn(|axis| {
                (0..n)
                    .map(|i| fs.iter().map(|f| f[axis][i]).sum::<f64>() / fs.len() as f64)
                    .collect()
            })
        };
        let beta = [0.0; 9];
        // The repetitions and their means with a common part of amplitude `a` on y.
        let units = |a: f64| {
            let common: Vec<f64> = (0..n)
                .map(|i| a * (2.0 * PI * 3.0 * i as f64 / rate).sin())
                .collect();
            let with = |f: &[Vec<f64>; 2]| -> [Vec<f64>; 2] {
                [
                    f[0].clone(),
                    f[1].iter().zip(&common).map(|(e, c)| e + c).collect(),
                ]
            };
            let mut reps = Vec::new();
            let mut avgs = Vec::new();
            for (i, (angle, fs)) in angles.iter().zip(&noise).enumerate() {
                let fs: Vec<[Vec<f64>; 2]> = fs.iter().map(with).collect();
                reps.extend(
                    fs.iter()
                        .enumerate()
                        .map(|(j, f)| unit(*angle, f.clone(), trials_of(i, j))),
                );
                avgs.push(unit(*angle, mean(&fs), all_trials(i)));
            }
            (avgs, reps)
        };
        let (avgs, reps) = units(5.0);
        let Some(w) = Whitening::from_repetitions(&HandBaseline, &avgs, &reps, 0, &beta, 0.06)
        else {
            panic!("the repetitions' covariance is positive definite");
        };
        let norm = |avgs: &[HandResponse]| -> f64 {
            avgs.iter()
                .flat_map(|a| hand_fit_rows(&HandBaseline, a, 0, &beta, 0.06, Some(&w)))
                .map(|(_, _, v)| v * v)
                .sum()
        };
        // The averaged units' own noise, weighted, its constant per axis removed.
        let mut truth = 0.0;
        for (i, (angle, fs)) in angles.iter().zip(&noise).enumerate() {
            let rows = hand_fit_rows(
                &HandBaseline,
                &unit(*angle, mean(fs), all_trials(i)),
                0,
                &beta,
                0.06,
                Some(&w),
            );
            for axis in 0..2 {
                let e: Vec<f64> = rows.iter().skip(axis).step_by(2).map(|r| r.0).collect();
                let c = e.iter().sum::<f64>() / e.len() as f64;
                truth += e.iter().map(|v| (v - c).powi(2)).sum::<f64>();
            }
        }
        let want = (truth / norm(&avgs)).sqrt();
        let floor = |avgs: &[HandResponse], reps: &[HandResponse]| {
            w.noise_floor_nrmse(&HandBaseline, avgs, reps, 0, &beta, 0.06)
                .expect("three repetitions per direction")
        };
        let f = floor(&avgs, &reps);
        eprintln!("floor {f:.5}, the averaged units' noise {want:.5}");
        assert!((f / want - 1.0).abs() < 0.05, "floor {f} for {want}");
        let (big_avgs, big_reps) = units(50.0);
        let f_big = floor(&big_avgs, &big_reps);
        let (read, read_big) = (f * f * norm(&avgs), f_big * f_big * norm(&big_avgs));
        assert!(
            (read_big / read - 1.0).abs() < 1e-9,
            "the noise read moved with the misfit: {read} → {read_big}"
        );
        // A single repetition per direction has no spread to read.
        let singles: Vec<HandResponse> = reps.iter().step_by(m).cloned().collect();
        assert!(
            w.noise_floor_nrmse(&HandBaseline, &avgs, &singles, 0, &beta, 0.06)
                .is_none()
        );
        // A direction whose mean holds a trial no repetition has (an unmatched pulse on
        // one side of the pair) is left out: the floor is the other direction's alone.
        let mut unmatched = avgs.clone();
        unmatched[1].trials.push(999);
        let first_alone = floor(&avgs[..1], &reps);
        let with_unmatched = floor(&unmatched, &reps);
        assert!(
            (with_unmatched - first_alone).abs() < 1e-12 * first_alone,
            "{with_unmatched} for {first_alone}"
        );
        // The weighting between the axes leaves it out alike: its repetitions' spread
        // about a mean they do not make would hold a part of the misfit.
        let weighting = |avgs: &[HandResponse]| {
            Whitening::from_repetitions(&HandBaseline, avgs, &reps, 0, &beta, 0.06)
                .expect("the first direction's repetitions are positive definite")
                .axes
        };
        let (w_first, w_unmatched) = (weighting(&avgs[..1]), weighting(&unmatched));
        assert!(
            (w_unmatched - w_first).abs().max() < 1e-12 * w_first.abs().max(),
            "W {w_unmatched} for {w_first}"
        );
    }

    /// A step of force through the grip's spring-damper: the hand moves by
    /// `F/k (1 − e^{−t/τ})` relative to the handle (closed form of `b δ̇ + k δ = F`).
    #[test]
    fn grip_filter_matches_the_first_order_step() {
        let rate = 1000.0;
        let mut f = vec![0.0; 200];
        f.iter_mut().skip(10).for_each(|v| *v = 2.0);
        let (k, tau) = (4000.0, 5e-3);
        let kin = Kin::grip(&response(f, rate), k, tau);
        for i in 12..200 {
            // The ramp-invariant step sees the jump spread over samples 9..10.
            let t = (i as f64 - 9.5) / rate;
            let exact = 2.0 / k * (1.0 - (-t / tau).exp());
            assert!(
                (kin.x[0][i] - exact).abs() < 0.03 * 2.0 / k,
                "sample {i}: {} vs {exact}",
                kin.x[0][i]
            );
        }
    }

    /// The grip's edge rule reads its stiffness's place on the stiffness grid, not the
    /// combined setting: 50 kN/m (the grid's last) with a mid time constant is at the
    /// edge, as is 0.5 kN/m; 5 kN/m with the last time constant is not (a stiffness a
    /// masked pair named at 50 kN/m on 1 s reaches hiding nothing passed the rule before).
    #[test]
    fn a_grip_at_the_stiffness_grids_end_is_at_the_edge() {
        let times = GRIP_TIME_S.2;
        let ks = GRIP_STIFFNESS_N_PER_M.2;
        let grip = GripCompliance;
        let last_k_mid_tau = (ks - 1) * times + times / 2;
        assert_eq!(grip.setting(last_k_mid_tau).1, 50_000.0);
        let edge = |s: usize| {
            let (at, of) = grip.search_position(s);
            !crate::decide::at_edge(grip.kind(), grip.setting(s), at, of, &Default::default())
                .is_empty()
        };
        assert!(edge(last_k_mid_tau));
        assert!(edge(times / 2), "0.5 kN/m");
        let mid_k_last_tau = (ks / 2) * times + times - 1;
        assert!((grip.setting(mid_k_last_tau).1 - 5_000.0).abs() < 1.0);
        assert!(!edge(mid_k_last_tau));
    }
}
