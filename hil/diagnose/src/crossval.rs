//! Held-out judgement: K folds of whole trials, every choice (masses, coefficients
//! and the nonlinear setting) made on the training trials only, the error measured on
//! the trials left out. Trials, not samples, are the unit: samples within a trial are
//! correlated, trials are independent repetitions.

use rayon::prelude::*;

use super::error::DiscrepancyError;
use super::gram::Gram;

/// Assignment of trials to folds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Folds {
    /// Number of folds.
    pub k: usize,
    /// Fold of each trial.
    pub of_trial: Vec<usize>,
}

impl Folds {
    /// Trial `i` goes to fold `i mod k`, with `k = min(k, trials)`: interleaving keeps
    /// each fold a mix of perturbed and unperturbed trials in a randomised protocol.
    #[must_use]
    pub fn interleaved(trials: usize, k: usize) -> Folds {
        let k = k.min(trials).max(1);
        Folds {
            k,
            of_trial: (0..trials).map(|i| i % k).collect(),
        }
    }
}

/// One fold's fit and held-out error.
#[derive(Debug, Clone, PartialEq)]
pub struct FoldFit {
    /// Setting chosen on the training trials.
    pub setting: usize,
    /// Coefficients fitted on the training trials.
    pub beta: Vec<f64>,
    /// Sum of squared residuals on the held-out trials, N².
    pub test_sse: f64,
    /// Sum of squares of the motor command on the held-out trials, N².
    pub test_norm_sq: f64,
}

/// A candidate's cross-validated fit.
#[derive(Debug, Clone, PartialEq)]
pub struct CvFit {
    /// Per fold.
    pub folds: Vec<FoldFit>,
    /// Setting chosen on all trials.
    pub setting: usize,
    /// Coefficients on all trials at that setting.
    pub beta: Vec<f64>,
    /// Gram of all trials at that setting.
    pub gram: Gram,
    /// SSE over all trials of the best fit at every setting (the search curve), N².
    pub curve: Vec<f64>,
}

impl CvFit {
    /// Held-out NRMSE over all folds: `sqrt(Σ SSE / Σ u²)`.
    #[must_use]
    pub fn nrmse(&self) -> f64 {
        let sse: f64 = self.folds.iter().map(|f| f.test_sse).sum();
        let norm: f64 = self.folds.iter().map(|f| f.test_norm_sq).sum();
        (sse / norm).sqrt()
    }
}

/// Cross-validates a family of least-squares problems. `grams[t][s]` is trial `t`'s
/// Gram at setting `s`; every trial must have the same number of settings.
///
/// # Errors
/// [`DiscrepancyError::Singular`] when no setting can be fitted on some training set.
pub fn cross_validate(
    grams: &[Vec<Gram>],
    folds: &Folds,
    what: &str,
) -> Result<CvFit, DiscrepancyError> {
    let singular = || DiscrepancyError::Singular {
        what: what.to_string(),
    };
    let settings = grams.first().map_or(0, Vec::len);
    let p = grams.first().and_then(|g| g.first()).map_or(0, |g| g.p);
    if settings == 0 || grams.iter().any(|g| g.len() != settings) {
        return Err(singular());
    }
    // Per setting: all-trial SSE and, per fold, the training SSE, coefficients and
    // held-out SSE.
    type PerFold = Vec<Option<(f64, Vec<f64>, f64, f64)>>;
    let per_setting: Vec<(f64, PerFold)> = (0..settings)
        .into_par_iter()
        .map(|s| {
            let fold_tests: Vec<Gram> = (0..folds.k)
                .map(|k| {
                    Gram::sum(
                        p,
                        grams
                            .iter()
                            .zip(&folds.of_trial)
                            .filter(|(_, f)| **f == k)
                            .map(|(g, _)| &g[s]),
                    )
                })
                .collect();
            let total = Gram::sum(p, &fold_tests);
            let all_sse = total.solve().map_or(f64::INFINITY, |b| total.sse(&b));
            let per_fold = fold_tests
                .iter()
                .map(|test| {
                    let mut train = total.clone();
                    train.sub(test);
                    let beta = train.solve()?;
                    Some((
                        train.sse(&beta),
                        beta.clone(),
                        test.sse(&beta),
                        test.norm_sq,
                    ))
                })
                .collect();
            (all_sse, per_fold)
        })
        .collect();
    let mut fold_fits = Vec::with_capacity(folds.k);
    for k in 0..folds.k {
        let best = per_setting
            .iter()
            .enumerate()
            .filter_map(|(s, (_, pf))| pf.get(k).and_then(|x| x.as_ref()).map(|x| (s, x)))
            .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
            .ok_or_else(singular)?;
        let (s, (_, beta, test_sse, test_norm_sq)) = best;
        fold_fits.push(FoldFit {
            setting: s,
            beta: beta.clone(),
            test_sse: *test_sse,
            test_norm_sq: *test_norm_sq,
        });
    }
    let curve: Vec<f64> = per_setting.iter().map(|(sse, _)| *sse).collect();
    let setting = curve
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map(|(s, _)| s)
        .ok_or_else(singular)?;
    let gram = Gram::sum(p, grams.iter().map(|g| &g[setting]));
    let beta = gram.solve().ok_or_else(singular)?;
    Ok(CvFit {
        folds: fold_fits,
        setting,
        beta,
        gram,
        curve,
    })
}
