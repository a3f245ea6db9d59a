//! The baseline subject fitted to a session, before anything is called a discrepancy:
//! subjects differ, and a stiffer or slower subject than the nominal one is not a fault
//! of the model.
//!
//! What is fitted, and how:
//!
//! - **Segment lengths** are not fitted: they come from the manifest (`upper_arm_m`,
//!   `forearm_m`), applied as factors on the nominal arm exactly as a drawn virtual
//!   subject applies its own ([`crate::protocol::SubjectsConfig::with_factors`]).
//! - **Reach timing** (planned start and duration) is read from the measured positions,
//!   without replay: the mean times at which the unperturbed trials pass 5 % and 95 % of
//!   their start-to-goal travel. The simulated times of the same plan are measured on a
//!   noise-free replay of one unperturbed reach, and the plan is corrected by fixed-point
//!   steps (start shifted by the 5 % error, duration scaled by the ratio of 5–95 %
//!   times) until both agree within 0.5 ms. It is redone after the factor fit, since a
//!   stiffer arm lags its plan less.
//! - **Muscle stiffness, co-contraction and feedback gain factors** (the keys of
//!   [`crate::protocol::SubjectSpread`]) by Nelder–Mead in the logarithms of the
//!   factors, bounded to `[1/4, 4]`, from the nominal subject (all 1) with initial steps
//!   of 0.3 (about one σ of the population spread), on a subset of trials
//!   ([`fit_trials`]) replayed in parallel.
//!
//! The discrepancy minimised is the root-mean-square of six NRMSEs (RMSE over the RMS
//! of the measured channel about its mean in that phase, pooled over the subset):
//! `x_m, y_m` over the whole reach, and `x_m, y_m, fx_n, fy_n` over the 150 ms response
//! (from each table's own onset, as the change from the onset value). The forces over
//! the whole reach are left out (motor and sensor noise dominate them: NRMSE near 0.9
//! even for the true subject), and so are the motor commands: plant effects live there,
//! and the subject must not absorb them.
//!
//! The replays of the fit are **noise-free** (no motor noise, no force-sensor noise; the
//! encoder quantum stays): the noise-free replay is the model's expected trajectory, which
//! minimises the expected squared error to a noisy measurement, and the objective is then
//! a deterministic smooth function of the factors that the simplex can follow. No random
//! draw is made, so the fit is the same on every run and machine.

use rayon::prelude::*;
use serde::Serialize;

use rigtwin_diagnose::DiscrepancyError;

use super::errors::{Acc, ChannelError, accumulate, channel_errors};
use super::resim::{Timing, length_factors, noise_free, onsets, replay_trial};
use crate::protocol::Protocol;
use crate::session::{Session, Trial, TrialEntry};

/// Whether a channel and phase is a term of the objective: positions over the whole
/// reach; positions and forces over the response.
fn in_objective(channel: &str, phase: &str) -> bool {
    match phase {
        "reach" => channel == "x_m" || channel == "y_m",
        "response" => ["x_m", "y_m", "fx_n", "fy_n"].contains(&channel),
        _ => false,
    }
}

/// Log-factor bounds of the search: factors within `[1/4, 4]`.
const LOG_BOUND: f64 = 1.386_294_361_119_890_6;

/// Timing agreement that ends the fixed-point steps, s.
const TIMING_TOL_S: f64 = 0.5e-3;

/// How the subject is fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Trials replayed per evaluation (see [`fit_trials`]).
    pub max_trials: usize,
    /// Nelder–Mead evaluations at most (checked before each simplex step, which makes up
    /// to 5 more).
    pub max_evaluations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            max_trials: 8,
            max_evaluations: 45,
        }
    }
}

/// One term of the fit's residual: a channel and phase before and after the fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitResidual {
    /// Column name.
    pub channel: String,
    /// `reach` or `response`.
    pub phase: String,
    /// NRMSE with the nominal subject and plan.
    pub nrmse_nominal: f64,
    /// NRMSE with the fitted subject and timing.
    pub nrmse_fitted: f64,
    /// Whether the term is in the objective.
    pub in_objective: bool,
}

/// The fitted subject and how well the fit went.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SubjectFit {
    /// Muscle stiffness factor (K₀ and K₁ of every muscle; impedance scale).
    pub muscle_stiffness: f64,
    /// Co-contraction factor.
    pub co_contraction: f64,
    /// Feedback gain factor (position and velocity gains).
    pub feedback_gain: f64,
    /// Upper arm length over the nominal arm's, from the manifest.
    pub upper_arm_factor: f64,
    /// Forearm length over the nominal arm's, from the manifest.
    pub forearm_factor: f64,
    /// The nominal plan's timing.
    pub nominal_timing: Timing,
    /// The fitted timing.
    pub timing: Timing,
    /// Measured mean time of 5 % and 95 % of the travel, s.
    pub measured_travel_s: [f64; 2],
    /// Trials those times are averaged over.
    pub timing_trials: usize,
    /// Ids of the trials replayed by the factor fit.
    pub fit_trials: Vec<u32>,
    /// Objective evaluations (each a replay of `fit_trials`).
    pub evaluations: usize,
    /// Evaluations whose replay failed (scored as infinitely bad).
    pub failed_evaluations: usize,
    /// Objective with the nominal subject and plan.
    pub discrepancy_nominal: f64,
    /// Objective with the fitted subject and timing.
    pub discrepancy_fitted: f64,
    /// Per channel and phase, before and after.
    pub residuals: Vec<FitResidual>,
    /// Factors that ended within 1 % of a search bound (not identified within `[1/4, 4]`).
    pub at_bound: Vec<String>,
}

impl SubjectFit {
    /// The five subject factors in [`crate::protocol::VirtualSubject::factors`] order.
    #[must_use]
    pub fn factors(&self) -> [f64; 5] {
        [
            self.muscle_stiffness,
            self.co_contraction,
            self.upper_arm_factor,
            self.forearm_factor,
            self.feedback_gain,
        ]
    }
}

/// The trials the factor fit replays: for each perturbation angle in session order its
/// first trial, then the other perturbed trials, then unperturbed ones, up to `max` in
/// all; returned as session indices in session order. The perturbed trials come first
/// because the response to the pulse is what tells stiffness from feedback; the reach
/// timing is read from the unperturbed ones without replay. Deterministic: no draw.
#[must_use]
pub fn fit_trials(session: &Session, max: usize) -> Vec<usize> {
    let entries = &session.manifest.trials;
    let mut order: Vec<usize> = Vec::with_capacity(entries.len());
    let mut angles: Vec<f64> = Vec::new();
    for (i, e) in entries.iter().enumerate() {
        if let Some(p) = &e.perturbation
            && !angles.iter().any(|a| (a - p.angle_deg).abs() < 1e-9)
        {
            angles.push(p.angle_deg);
            order.push(i);
        }
    }
    for pass_perturbed in [true, false] {
        for (i, e) in entries.iter().enumerate() {
            if e.perturbation.is_some() == pass_perturbed && !order.contains(&i) {
                order.push(i);
            }
        }
    }
    order.truncate(max.max(1));
    order.sort_unstable();
    order
}

/// Times at which a reach passes 5 % and 95 % of its travel from `start` to `goal`,
/// linearly interpolated between rows, s; `None` if it never does.
#[must_use]
pub fn travel_times_s(
    t: &Trial,
    start: [f64; 2],
    goal: [f64; 2],
    rate_hz: f64,
) -> Option<[f64; 2]> {
    let d = [goal[0] - start[0], goal[1] - start[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    if len2 <= 0.0 {
        return None;
    }
    let s = |k: usize| ((t.x_m[k] - start[0]) * d[0] + (t.y_m[k] - start[1]) * d[1]) / len2;
    let n = t.x_m.len().min(t.y_m.len());
    let mut out = [0.0; 2];
    let mut k0 = 0;
    for (j, level) in [0.05, 0.95].into_iter().enumerate() {
        let k = (k0.max(1)..n).find(|&k| s(k) >= level && s(k - 1) < level)?;
        let (a, b) = (s(k - 1), s(k));
        out[j] = ((k - 1) as f64 + (level - a) / (b - a)) / rate_hz;
        k0 = k;
    }
    Some(out)
}

fn start_goal(e: &TrialEntry, p: &Protocol) -> ([f64; 2], [f64; 2]) {
    let r = p.reach();
    (e.start_m.unwrap_or(r.start_m), e.goal_m.unwrap_or(r.goal_m))
}

struct Evaluator<'a> {
    session: &'a Session,
    protocol: Protocol,
    lengths: [f64; 2],
    subset: Vec<usize>,
    rate: f64,
}

impl Evaluator<'_> {
    fn factors(&self, log: &[f64; 3]) -> [f64; 5] {
        [
            log[0].exp(),
            log[1].exp(),
            self.lengths[0],
            self.lengths[1],
            log[2].exp(),
        ]
    }

    /// Accumulated errors of the subset: reach and response per channel.
    fn accs(&self, log: &[f64; 3], timing: Timing) -> Result<[[Acc; 6]; 2], DiscrepancyError> {
        let subject = self.protocol.subjects.with_factors(1, self.factors(log));
        let per: Vec<[[Acc; 6]; 2]> = self
            .subset
            .par_iter()
            .map(|&i| {
                let entry = &self.session.manifest.trials[i];
                let meas = &self.session.trials[i];
                let sim = replay_trial(&self.protocol, &subject, timing, i, entry, meas)?;
                let mut a = [[Acc::default(); 6]; 2];
                let [reach, resp] = &mut a;
                accumulate(
                    meas,
                    &sim.table,
                    onsets(entry, &sim, self.rate),
                    self.rate,
                    reach,
                    resp,
                );
                Ok(a)
            })
            .collect::<Result<_, DiscrepancyError>>()?;
        let mut total = [[Acc::default(); 6]; 2];
        for a in &per {
            for (t, x) in total.iter_mut().zip(a) {
                for (tc, xc) in t.iter_mut().zip(x) {
                    tc.add(xc);
                }
            }
        }
        Ok(total)
    }

    /// The objective of accumulated errors.
    fn objective(errors: &[ChannelError]) -> f64 {
        let terms: Vec<f64> = errors
            .iter()
            .filter(|e| in_objective(&e.channel, &e.phase))
            .map(|e| e.nrmse)
            .filter(|v| v.is_finite())
            .collect();
        if terms.is_empty() {
            return f64::INFINITY;
        }
        (terms.iter().map(|v| v * v).sum::<f64>() / terms.len() as f64).sqrt()
    }

    fn evaluate(
        &self,
        log: &[f64; 3],
        timing: Timing,
    ) -> Result<(f64, Vec<ChannelError>), DiscrepancyError> {
        let [reach, resp] = self.accs(log, timing)?;
        let errors = channel_errors(&reach, &resp);
        Ok((Self::objective(&errors), errors))
    }

    /// Fixed-point timing fit for the subject with log-factors `log` (see the module docs).
    fn timing(
        &self,
        log: &[f64; 3],
        measured: [f64; 2],
        from: Timing,
    ) -> Result<Timing, DiscrepancyError> {
        let subject = self.protocol.subjects.with_factors(1, self.factors(log));
        let i = self
            .subset
            .iter()
            .copied()
            .find(|&i| self.session.manifest.trials[i].perturbation.is_none())
            .unwrap_or(0);
        let mut entry = self.session.manifest.trials[i].clone();
        entry.perturbation = None;
        let meas = &self.session.trials[i];
        let (start, goal) = start_goal(&entry, &self.protocol);
        let mut timing = from;
        for _ in 0..8 {
            let sim = replay_trial(&self.protocol, &subject, timing, i, &entry, meas)?;
            let Some(s) = travel_times_s(&sim.table, start, goal, self.rate) else {
                return Err(DiscrepancyError::Replay {
                    trial: entry.id,
                    reason: "the simulated reach never covers 95 % of its travel".into(),
                });
            };
            let (e5, e95) = (measured[0] - s[0], measured[1] - s[1]);
            if e5.abs() < TIMING_TOL_S && e95.abs() < TIMING_TOL_S {
                break;
            }
            let ratio = (measured[1] - measured[0]) / (s[1] - s[0]);
            timing = Timing {
                start_s: (timing.start_s + e5).max(0.0),
                duration_s: timing.duration_s * ratio.clamp(0.5, 2.0),
            };
        }
        Ok(timing)
    }
}

/// Measured 5 % and 95 % travel times, averaged over the unperturbed trials (all trials
/// if none is unperturbed), and how many trials went in.
fn measured_timing(
    session: &Session,
    protocol: &Protocol,
) -> Result<([f64; 2], usize), DiscrepancyError> {
    let rate = session.manifest.rate_hz;
    let any_unperturbed = session
        .manifest
        .trials
        .iter()
        .any(|e| e.perturbation.is_none());
    let mut sum = [0.0; 2];
    let mut n = 0;
    for (e, t) in session.iter() {
        if any_unperturbed && e.perturbation.is_some() {
            continue;
        }
        let (s, g) = start_goal(e, protocol);
        if let Some(tt) = travel_times_s(t, s, g, rate) {
            sum[0] += tt[0];
            sum[1] += tt[1];
            n += 1;
        }
    }
    if n == 0 {
        return Err(DiscrepancyError::Replay {
            trial: 0,
            reason: "no measured reach covers 5 % to 95 % of its travel: the reach timing cannot be read"
                .into(),
        });
    }
    Ok(([sum[0] / n as f64, sum[1] / n as f64], n))
}

/// Bounded Nelder–Mead on `f` from `x0`; returns the best point, its value and the
/// number of evaluations.
fn nelder_mead(
    mut f: impl FnMut(&[f64; 3]) -> f64,
    x0: [f64; 3],
    step: f64,
    max_evals: usize,
) -> ([f64; 3], f64, usize) {
    let clamp = |x: [f64; 3]| x.map(|v| v.clamp(-LOG_BOUND, LOG_BOUND));
    let mut evals = 0;
    let mut eval = |x: &[f64; 3], evals: &mut usize| {
        *evals += 1;
        f(x)
    };
    let mut simplex: Vec<([f64; 3], f64)> = Vec::with_capacity(4);
    let v0 = eval(&x0, &mut evals);
    simplex.push((x0, v0));
    for d in 0..3 {
        let mut x = x0;
        x[d] += step;
        let x = clamp(x);
        let v = eval(&x, &mut evals);
        simplex.push((x, v));
    }
    let lin =
        |a: &[f64; 3], b: &[f64; 3], t: f64| clamp([0, 1, 2].map(|i| a[i] + t * (b[i] - a[i])));
    while evals < max_evals {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (best, worst) = (simplex[0].1, simplex[3].1);
        let size = simplex[1..]
            .iter()
            .map(|(x, _)| {
                (0..3)
                    .map(|i| (x[i] - simplex[0].0[i]).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        if (worst - best) <= 1e-3 * best.abs() && size < 0.01 {
            break;
        }
        let mut c = [0.0; 3];
        for (x, _) in &simplex[..3] {
            for i in 0..3 {
                c[i] += x[i] / 3.0;
            }
        }
        let xw = simplex[3].0;
        let xr = lin(&c, &xw, -1.0);
        let fr = eval(&xr, &mut evals);
        if fr < best {
            let xe = lin(&c, &xw, -2.0);
            let fe = eval(&xe, &mut evals);
            simplex[3] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[2].1 {
            simplex[3] = (xr, fr);
        } else {
            let (xc, fc) = if fr < worst {
                let x = lin(&c, &xr, 0.5);
                (x, eval(&x, &mut evals))
            } else {
                let x = lin(&c, &xw, 0.5);
                (x, eval(&x, &mut evals))
            };
            if fc < fr.min(worst) {
                simplex[3] = (xc, fc);
            } else {
                let xb = simplex[0].0;
                for s in &mut simplex[1..] {
                    let x = lin(&xb, &s.0, 0.5);
                    *s = (x, eval(&x, &mut evals));
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    (simplex[0].0, simplex[0].1, evals)
}

/// Fits the baseline subject of `protocol` (as `super::resim::session_protocol` makes
/// it) to `session`; see the module docs.
///
/// # Errors
/// [`DiscrepancyError::Replay`] when no measured reach covers its travel, or the
/// nominal replay itself fails.
pub fn fit_subject(
    session: &Session,
    protocol: &Protocol,
    options: &FitOptions,
) -> Result<SubjectFit, DiscrepancyError> {
    let quiet = noise_free(protocol);
    let ev = Evaluator {
        session,
        lengths: length_factors(session, &quiet),
        subset: fit_trials(session, options.max_trials),
        rate: session.manifest.rate_hz,
        protocol: quiet,
    };
    if ev.subset.is_empty() {
        return Err(DiscrepancyError::Replay {
            trial: 0,
            reason: "the session has no trial".into(),
        });
    }
    let r = ev.protocol.reach();
    let nominal_timing = Timing {
        start_s: r.still_before_s,
        duration_s: r.movement_s,
    };
    let (measured, timing_trials) = measured_timing(session, &ev.protocol)?;
    let zero = [0.0; 3];
    let (j0, nominal_errors) = ev.evaluate(&zero, nominal_timing)?;
    let timing0 = ev.timing(&zero, measured, nominal_timing)?;
    let failed = std::cell::Cell::new(0usize);
    let (best, _, evaluations) = nelder_mead(
        |x| match ev.evaluate(x, timing0) {
            Ok((j, _)) => j,
            Err(_) => {
                failed.set(failed.get() + 1);
                f64::INFINITY
            }
        },
        zero,
        0.3,
        options.max_evaluations,
    );
    let timing = ev.timing(&best, measured, timing0)?;
    let (j1, fitted_errors) = ev.evaluate(&best, timing)?;
    let residuals = nominal_errors
        .iter()
        .map(|n| FitResidual {
            channel: n.channel.clone(),
            phase: n.phase.clone(),
            nrmse_nominal: n.nrmse,
            nrmse_fitted: fitted_errors
                .iter()
                .find(|f| f.channel == n.channel && f.phase == n.phase)
                .map_or(f64::NAN, |f| f.nrmse),
            in_objective: in_objective(&n.channel, &n.phase),
        })
        .collect();
    let names = ["muscle_stiffness", "co_contraction", "feedback_gain"];
    let at_bound = names
        .iter()
        .zip(best)
        .filter(|(_, v)| v.abs() >= LOG_BOUND - 0.01)
        .map(|(n, _)| (*n).to_owned())
        .collect();
    Ok(SubjectFit {
        muscle_stiffness: best[0].exp(),
        co_contraction: best[1].exp(),
        feedback_gain: best[2].exp(),
        upper_arm_factor: ev.lengths[0],
        forearm_factor: ev.lengths[1],
        nominal_timing,
        timing,
        measured_travel_s: measured,
        timing_trials,
        fit_trials: ev
            .subset
            .iter()
            .map(|&i| session.manifest.trials[i].id)
            .collect(),
        evaluations: evaluations + 2,
        failed_evaluations: failed.get(),
        discrepancy_nominal: j0,
        discrepancy_fitted: j1,
        residuals,
        at_bound,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn travel_times_of_a_linear_reach() {
        // y from -0.1 to 0.1 m linearly between rows 100 and 300 at 1 kHz: 5 % of the
        // travel at row 110, 95 % at row 290, exactly (linear interpolation is exact).
        let y: Vec<f64> = (0..400)
            .map(|k| -0.1 + 0.2 * ((k as f64 - 100.0) / 200.0).clamp(0.0, 1.0))
            .collect();
        let t = Trial {
            t_s: (0..400).map(|k| k as f64 / 1000.0).collect(),
            x_m: vec![0.0; 400],
            y_m: y,
            fx_n: vec![0.0; 400],
            fy_n: vec![0.0; 400],
            pert_fx_n: vec![0.0; 400],
            pert_fy_n: vec![0.0; 400],
            vx_m_per_s: None,
            vy_m_per_s: None,
            ref_x_m: None,
            ref_y_m: None,
            cmd_fx_n: None,
            cmd_fy_n: None,
            extra: Vec::new(),
        };
        let tt = travel_times_s(&t, [0.0, -0.1], [0.0, 0.1], 1000.0).unwrap();
        assert!(
            (tt[0] - 0.110).abs() < 1e-12 && (tt[1] - 0.290).abs() < 1e-12,
            "{tt:?}"
        );
        // A reach that stops at half its travel never passes 95 %.
        assert!(travel_times_s(&t, [0.0, -0.1], [0.0, 0.3], 1000.0).is_none());
    }

    #[test]
    fn nelder_mead_finds_a_bounded_quadratic_minimum() {
        // Minimum at (0.5, -0.3, 0.1): well inside the bounds; 200 evaluations are
        // plenty for 3 dimensions, and the stop rule (1 % simplex size) bounds the error.
        let (x, v, n) = nelder_mead(
            |x| (x[0] - 0.5).powi(2) + 2.0 * (x[1] + 0.3).powi(2) + 3.0 * (x[2] - 0.1).powi(2),
            [0.0; 3],
            0.3,
            200,
        );
        // The budget is checked before each step; a step makes at most 5 evaluations.
        assert!(n <= 204, "{n}");
        assert!(
            (x[0] - 0.5).abs() < 0.02 && (x[1] + 0.3).abs() < 0.02 && (x[2] - 0.1).abs() < 0.02,
            "{x:?}"
        );
        assert!(v < 1e-3);
        // A minimum beyond the bound ends on it.
        let (x, _, _) = nelder_mead(
            |x| (x[0] - 3.0).powi(2) + x[1] * x[1] + x[2] * x[2],
            [0.0; 3],
            0.3,
            200,
        );
        // Within the stop rule's 1 % simplex size of the bound.
        assert!((x[0] - LOG_BOUND).abs() < 0.01, "{x:?}");
    }
}
