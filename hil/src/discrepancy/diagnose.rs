//! `diagnose`: fit every candidate plant effect to the cart force balance on training
//! trials, judge it on held-out trials against the nominal balance, and name the cause
//! only when the held-out gain is both beyond chance and material.
//!
//! The chance threshold: each fold gives a held-out gain `gₖ = 1 − √(SSEₖ,ext / SSEₖ,base)`.
//! Under "the candidate explains nothing" the folds' gains scatter around a value ≤ 0
//! (the extended model only adds variance), so a one-sided t-test on the `K` fold gains
//! (df = K − 1) at level α, Bonferroni-divided by the number of candidates judged,
//! tells a consistent gain from luck. Because with thousands of samples per trial even
//! a tiny systematic mismatch is "significant", the gain must also reach a material
//! floor ([`DiagnoseOptions::min_gain`], 10 % of the baseline residual RMS by default):
//! an effect that explains less than that is not what makes the simulation wrong.

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::Serialize;

use super::candidate::{Baseline, Candidate};
use super::crossval::{CvFit, Folds, cross_validate};
use super::delay::ActuationDelay;
use super::error::DiscrepancyError;
use super::friction::RailFriction;
use super::gram::Gram;
use super::ripple::ForceRipple;
use super::rotation::SensorRotation;
use super::signals::BalanceSignals;
use super::stats::{jackknife_se, mean_sd, student_t_critical};
use crate::session::Session;

/// Catalog effects that act on the human side of the sensor and so cannot show in the
/// cart balance, with the reason.
pub const HUMAN_SIDE: [(&str, &str); 3] = [
    (
        "handle-mass",
        "mass above the sensor: the sensor already reads the handle's inertia, so the cart balance is unchanged; \
         it only changes the coupled arm-handle response (needs the simulation replay, `rigtwin compare`)",
    ),
    (
        "grip-compliance",
        "acts between hand and handle, above the sensor; needs the simulation replay (`rigtwin compare`)",
    ),
    (
        "stretch-reflex",
        "a property of the subject, above the sensor; needs the simulation replay (`rigtwin compare`)",
    ),
];

/// Catalog effects judged from the cart force balance.
pub const PLANT_SIDE: [&str; 4] = [
    "rail-friction",
    "force-ripple",
    "actuation-delay",
    "sensor-rotation",
];

/// Options of [`diagnose`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiagnoseOptions {
    /// Number of cross-validation folds (whole trials; fewer if the session is short).
    pub folds: usize,
    /// Family-wise false-alarm level of the fold t-test.
    pub alpha: f64,
    /// Smallest held-out gain that names a cause.
    pub min_gain: f64,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            folds: 8,
            alpha: 0.01,
            min_gain: 0.10,
        }
    }
}

/// One candidate's judgement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ranked {
    /// Catalog name.
    pub name: String,
    /// Held-out gain `1 − extended/baseline` NRMSE.
    pub gain: f64,
    /// Held-out NRMSE of the extended model.
    pub extended_nrmse: f64,
    /// Held-out gain of each fold.
    pub fold_gains: Vec<f64>,
    /// One-sided t statistic of the fold gains.
    pub t_statistic: f64,
    /// Beyond chance and at least the material floor.
    pub significant: bool,
    /// Parameters fitted on all trials (units in the names).
    pub parameters: BTreeMap<String, f64>,
    /// Jackknife standard error of each parameter over the folds.
    pub parameter_se: BTreeMap<String, f64>,
}

/// The decision rule with its numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Threshold {
    /// Family-wise level.
    pub alpha: f64,
    /// Candidates judged (Bonferroni divisor).
    pub candidates: usize,
    /// Degrees of freedom (folds − 1).
    pub df: usize,
    /// Critical t.
    pub t_critical: f64,
    /// Material floor on the gain.
    pub min_gain: f64,
    /// The rule in words.
    pub rule: String,
}

/// An effect that could not be judged, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NotJudged {
    /// Catalog name.
    pub effect: String,
    /// Why.
    pub reason: String,
}

/// The outcome of [`diagnose`], as `rigtwin diagnose --json` prints it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// Session directory.
    pub session: String,
    /// Trials in the session.
    pub trials_total: usize,
    /// Trials with the channels the balance needs.
    pub trials_used: usize,
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// Cross-validation folds.
    pub folds: usize,
    /// Catalog name of the cause, or `none`.
    pub cause: String,
    /// The cause's parameters (units in the names); empty for `none`.
    pub parameters: BTreeMap<String, f64>,
    /// Their jackknife standard errors over the folds.
    pub parameter_se: BTreeMap<String, f64>,
    /// Held-out NRMSE of the nominal balance (fitted masses and latency only).
    pub baseline_nrmse: Option<f64>,
    /// Held-out NRMSE with the cause (equal to the baseline for `none`).
    pub extended_nrmse: Option<f64>,
    /// `1 − extended/baseline`.
    pub gain: Option<f64>,
    /// The nominal balance's own fitted parameters.
    pub baseline: BTreeMap<String, f64>,
    /// Every judged candidate, best held-out gain first.
    pub ranking: Vec<Ranked>,
    /// The best candidate after the cause (or the best one when the cause is `none`).
    pub runner_up: Option<String>,
    /// The decision rule.
    pub threshold: Option<Threshold>,
    /// Effects not judged, with the reason.
    pub not_judged: Vec<NotJudged>,
    /// Sentences a person can check.
    pub evidence: Vec<String>,
}

/// A candidate with its cross-validated fit, kept for plots and reports.
pub struct CandidateFit {
    /// The candidate.
    pub candidate: Box<dyn Candidate>,
    /// Its fit.
    pub fit: CvFit,
}

impl std::fmt::Debug for CandidateFit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CandidateFit")
            .field("candidate", &self.candidate.name())
            .field("fit", &self.fit)
            .finish()
    }
}

/// Everything [`diagnose`] computed.
#[derive(Debug)]
pub struct Analysis {
    /// The verdict.
    pub diagnosis: Diagnosis,
    /// The smoothed channels of the trials used.
    pub signals: Vec<BalanceSignals>,
    /// Nominal latency, s.
    pub latency_s: f64,
    /// The baseline's fit (`None` when the session lacks the command channels).
    pub baseline: Option<CvFit>,
    /// Each judged candidate's fit, in ranking order.
    pub fits: Vec<CandidateFit>,
}

fn grams_of(
    c: &dyn Candidate,
    signals: &[BalanceSignals],
    latency_s: f64,
) -> Result<Vec<Vec<Gram>>, DiscrepancyError> {
    signals.par_iter().map(|s| c.grams(s, latency_s)).collect()
}

/// Diagnoses a session: see the module docs.
///
/// # Errors
/// A [`DiscrepancyError`] when a trial cannot be smoothed or a fit is singular.
pub fn diagnose(session: &Session, opts: &DiagnoseOptions) -> Result<Analysis, DiscrepancyError> {
    let rate = session.manifest.rate_hz;
    let signals: Vec<BalanceSignals> = session
        .iter()
        .collect::<Vec<_>>()
        .par_iter()
        .map(|(e, t)| BalanceSignals::from_trial(e, t, rate))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .collect();
    let mut not_judged: Vec<NotJudged> = HUMAN_SIDE
        .iter()
        .map(|(e, r)| NotJudged {
            effect: (*e).to_string(),
            reason: (*r).to_string(),
        })
        .collect();
    let mut d = Diagnosis {
        session: session.dir.display().to_string(),
        trials_total: session.trials.len(),
        trials_used: signals.len(),
        rate_hz: rate,
        folds: 0,
        cause: "none".to_string(),
        parameters: BTreeMap::new(),
        parameter_se: BTreeMap::new(),
        baseline_nrmse: None,
        extended_nrmse: None,
        gain: None,
        baseline: BTreeMap::new(),
        ranking: Vec::new(),
        runner_up: None,
        threshold: None,
        not_judged: Vec::new(),
        evidence: Vec::new(),
    };
    const MIN_TRIALS: usize = 4;
    if signals.len() < MIN_TRIALS {
        let reason = format!(
            "needs the motor command columns cmd_fx_n, cmd_fy_n in at least {MIN_TRIALS} trials; {} of {} have them",
            signals.len(),
            session.trials.len()
        );
        for e in PLANT_SIDE {
            not_judged.push(NotJudged {
                effect: e.to_string(),
                reason: reason.clone(),
            });
        }
        d.not_judged = not_judged;
        d.evidence.push(
            "no plant-side judgement possible: the cart force balance needs the motor command"
                .into(),
        );
        return Ok(Analysis {
            diagnosis: d,
            signals,
            latency_s: 0.0,
            baseline: None,
            fits: Vec::new(),
        });
    }
    let folds = Folds::interleaved(signals.len(), opts.folds);
    d.folds = folds.k;

    // The nominal latency, from all trials (one shared timing parameter; it is part of
    // the baseline and of every extended model alike, so it cannot favour any).
    let nominal = ActuationDelay::nominal();
    let lat_grams = grams_of(&nominal, &signals, 0.0)?;
    let lat_fit = cross_validate(&lat_grams, &folds, "nominal latency")?;
    let latency_s = nominal.lag_s(lat_fit.setting);

    let baseline = cross_validate(
        &grams_of(&Baseline, &signals, latency_s)?,
        &folds,
        "baseline",
    )?;
    let base_nrmse = baseline.nrmse();
    d.baseline = Baseline
        .parameters(0, &baseline.beta, latency_s)
        .into_iter()
        .collect();

    let travel = signals
        .iter()
        .map(|s| s.travel_m(0).max(s.travel_m(1)))
        .fold(0.0, f64::max);
    let candidates: Vec<Box<dyn Candidate>> = vec![
        Box::new(RailFriction),
        Box::new(ForceRipple::for_travel(travel)),
        Box::new(ActuationDelay::candidate()),
        Box::new(SensorRotation::default()),
    ];
    let fits: Vec<CandidateFit> = candidates
        .into_par_iter()
        .map(|c| {
            let g = grams_of(c.as_ref(), &signals, latency_s)?;
            let fit = cross_validate(&g, &folds, c.name())?;
            Ok(CandidateFit { candidate: c, fit })
        })
        .collect::<Result<Vec<_>, DiscrepancyError>>()?;

    let df = folds.k.saturating_sub(1).max(1);
    let t_crit = student_t_critical(opts.alpha / fits.len() as f64, df as f64);
    let mut ranked: Vec<(Ranked, CandidateFit)> = fits
        .into_iter()
        .map(|cf| {
            let c = cf.candidate.as_ref();
            let fit = &cf.fit;
            let nrmse = fit.nrmse();
            let gain = 1.0 - nrmse / base_nrmse;
            let fold_gains: Vec<f64> = fit
                .folds
                .iter()
                .zip(&baseline.folds)
                .map(|(e, b)| 1.0 - (e.test_sse / b.test_sse).sqrt())
                .collect();
            let (m, sd) = mean_sd(&fold_gains);
            let t = if sd > 0.0 {
                m / (sd / (fold_gains.len() as f64).sqrt())
            } else if m > 0.0 {
                f64::INFINITY
            } else {
                0.0
            };
            let parameters: BTreeMap<String, f64> = c
                .parameters(fit.setting, &fit.beta, latency_s)
                .into_iter()
                .collect();
            let fold_params: Vec<Vec<(String, f64)>> = fit
                .folds
                .iter()
                .map(|f| c.parameters(f.setting, &f.beta, latency_s))
                .collect();
            let parameter_se = parameters
                .keys()
                .map(|k| {
                    let est: Vec<f64> = fold_params
                        .iter()
                        .filter_map(|fp| fp.iter().find(|(n, _)| n == k).map(|(_, v)| *v))
                        .collect();
                    (k.clone(), jackknife_se(&est))
                })
                .collect();
            let r = Ranked {
                name: c.name().to_string(),
                gain,
                extended_nrmse: nrmse,
                fold_gains,
                t_statistic: t,
                significant: t > t_crit && gain >= opts.min_gain,
                parameters,
                parameter_se,
            };
            (r, cf)
        })
        .collect();
    ranked.sort_by(|a, b| b.0.gain.total_cmp(&a.0.gain));

    d.baseline_nrmse = Some(base_nrmse);
    d.extended_nrmse = Some(base_nrmse);
    d.gain = Some(0.0);
    let cause_index = ranked.iter().position(|(r, _)| r.significant);
    if let Some(i) = cause_index {
        let r = &ranked[i].0;
        d.cause = r.name.clone();
        d.parameters = r.parameters.clone();
        d.parameter_se = r.parameter_se.clone();
        d.extended_nrmse = Some(r.extended_nrmse);
        d.gain = Some(r.gain);
    }
    d.runner_up = ranked
        .iter()
        .enumerate()
        .find(|(i, _)| Some(*i) != cause_index)
        .map(|(_, (r, _))| r.name.clone());
    d.threshold = Some(Threshold {
        alpha: opts.alpha,
        candidates: ranked.len(),
        df,
        t_critical: t_crit,
        min_gain: opts.min_gain,
        rule: format!(
            "a candidate is named when the one-sided t of its {} fold gains exceeds t({:.4}, df {df}) = {t_crit:.2} \
             (alpha {} / {} candidates) and its held-out gain is at least {:.0} %; the largest such gain wins",
            folds.k,
            opts.alpha / ranked.len() as f64,
            opts.alpha,
            ranked.len(),
            opts.min_gain * 100.0
        ),
    });
    d.evidence = evidence(&d, &ranked, base_nrmse);
    d.not_judged = not_judged;
    let (ranking, fits): (Vec<Ranked>, Vec<CandidateFit>) = ranked.into_iter().unzip();
    d.ranking = ranking;
    Ok(Analysis {
        diagnosis: d,
        signals,
        latency_s,
        baseline: Some(baseline),
        fits,
    })
}

fn evidence(d: &Diagnosis, ranked: &[(Ranked, CandidateFit)], base_nrmse: f64) -> Vec<String> {
    let mut ev = Vec::new();
    let g = |k: &str| d.baseline.get(k).copied().unwrap_or(f64::NAN);
    ev.push(format!(
        "nominal balance: moving mass x {:.3} kg (both carts), y {:.3} kg (upper cart), latency {:.3} ms; held-out NRMSE {:.4}",
        g("moving_mass_x_kg"),
        g("moving_mass_y_kg"),
        g("latency_ms"),
        base_nrmse
    ));
    for (r, _) in ranked {
        let min = r.fold_gains.iter().copied().fold(f64::INFINITY, f64::min);
        let max = r
            .fold_gains
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let params: Vec<String> = r
            .parameters
            .iter()
            .map(|(k, v)| {
                format!(
                    "{k} {v:.4} ± {:.2e}",
                    r.parameter_se.get(k).copied().unwrap_or(f64::NAN)
                )
            })
            .collect();
        ev.push(format!(
            "{}: held-out gain {:.1} % (folds {:.1} … {:.1} %), t = {:.1}{}; {}",
            r.name,
            100.0 * r.gain,
            100.0 * min,
            100.0 * max,
            r.t_statistic,
            if r.significant {
                ", beyond chance and material"
            } else {
                ""
            },
            params.join(", ")
        ));
    }
    ev
}
