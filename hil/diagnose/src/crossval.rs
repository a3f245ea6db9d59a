//! Held-out judgement: K folds of whole trials, every choice (masses, coefficients
//! and the nonlinear setting) made on the training trials only, the error measured on
//! the trials left out. Trials, not samples, are the unit: samples within a trial are
//! correlated, trials are independent repetitions.

use rayon::prelude::*;

use super::error::DiscrepancyError;
use super::gram::Gram;
use super::stats::mean_sd;

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
    /// Held-out SSE of every fold at every setting, fitted on that fold's training
    /// trials at that setting (`held_out[setting][fold]`; infinite where the training
    /// set cannot be fitted), N².
    pub held_out: Vec<Vec<f64>>,
}

impl CvFit {
    /// Held-out NRMSE over all folds: `sqrt(Σ SSE / Σ u²)`.
    #[must_use]
    pub fn nrmse(&self) -> f64 {
        let sse: f64 = self.folds.iter().map(|f| f.test_sse).sum();
        let norm: f64 = self.folds.iter().map(|f| f.test_norm_sq).sum();
        (sse / norm).sqrt()
    }

    /// The settings the folds cannot tell from the best one held fixed: `ŝ` is the
    /// setting of least summed held-out error, and a setting `s` is told apart when the
    /// folds agree that it predicts worse, the
    /// mean over folds of `sqrt(SSE_k(s) / SSE_k(ŝ)) − 1` more than `t_crit` standard
    /// errors above 0 (a one-sided paired t-test on the folds, which are independent
    /// units however correlated the samples within one are). Empty with a single
    /// setting or fewer than two folds.
    #[must_use]
    pub fn settings_kept(&self, t_crit: f64) -> Vec<usize> {
        let best = self
            .held_out
            .iter()
            .map(|h| h.iter().sum::<f64>())
            .enumerate()
            .filter(|(_, total)| total.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(s, _)| &self.held_out[s]);
        let Some(best) = best.filter(|b| self.held_out.len() > 1 && b.len() > 1) else {
            return Vec::new();
        };
        let kept = self.held_out.iter().enumerate().filter(|(_, h)| {
            let d: Vec<f64> = h
                .iter()
                .zip(best)
                .map(|(e, b)| (e / b).sqrt() - 1.0)
                .collect();
            if d.iter().any(|x| !x.is_finite()) {
                return false;
            }
            let (mean, sd) = mean_sd(&d);
            // Equal errors in every fold (the setting itself): kept.
            mean <= 0.0 || mean <= t_crit * sd / (d.len() as f64).sqrt()
        });
        kept.map(|(s, _)| s).collect()
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
    let held_out = per_setting
        .iter()
        .map(|(_, pf)| {
            pf.iter()
                .map(|x| x.as_ref().map_or(f64::INFINITY, |(_, _, test, _)| *test))
                .collect()
        })
        .collect();
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
        held_out,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::stats::student_t_critical;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Standard deviation of the test problem's white noise (uniform, so that its
    /// variance is exact).
    const NOISE: f64 = 3.0;

    /// Twelve trials of `y = 2 sin(ω (t − δ₀))` at 8 Hz plus white noise of [`NOISE`]; setting `s`
    /// offers the regressor `sin(ω (t − δ_s))` with `δ_s = s` ms (`flat`: the regressor
    /// does not depend on the setting, nothing tells the settings apart).
    fn grams(delay_ms: f64, flat: bool, seed: u64) -> Vec<Vec<Gram>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let w = 2.0 * std::f64::consts::PI * 8.0;
        (0..12)
            .map(|_| {
                let ts: Vec<f64> = (0..200).map(|i| f64::from(i) * 1e-3).collect();
                let y: Vec<f64> = ts
                    .iter()
                    .map(|t| {
                        2.0 * (w * (t - delay_ms * 1e-3)).sin()
                            + NOISE * (rng.random::<f64>() - 0.5) * 12_f64.sqrt()
                    })
                    .collect();
                (0..41)
                    .map(|s| {
                        let d = if flat { delay_ms } else { f64::from(s) } * 1e-3;
                        let mut g = Gram::new(1);
                        for (t, y) in ts.iter().zip(&y) {
                            g.push(&[(w * (t - d)).sin()], *y, y * y);
                        }
                        g
                    })
                    .collect()
            })
            .collect()
    }

    /// Over 100 noise draws the range holds the true setting in at least 95, and it is
    /// wider than the profile-likelihood interval with the noise known (the settings
    /// whose all-trial SSE is within `χ²₁(0.90) σ²` = 2.706 σ² of the least, an
    /// independent reference covering 90 %) by 1.5 to 3.5 times. The paired test
    /// compares two fitted settings, and the noise enters their held-out difference
    /// through the cross term `2 ε (μ̂ − μ_s)`: the t of a setting off by `Δμ` is
    /// `√N |Δμ| / 2σ` against the likelihood ratio's `√N |Δμ| / σ`, so at the t's 1.80
    /// (11 degrees of freedom) against 1.645 its range is about 2.2 times as wide
    /// (more on a 1 ms grid, which rounds both outwards) and covers more than 95 %: a
    /// conservative range, whose price buys independence from how the samples within
    /// a unit are correlated. With nothing telling the settings apart it covers all.
    #[test]
    fn the_setting_range_holds_the_truth_and_only_what_the_folds_cannot_tell() {
        let folds = Folds::interleaved(12, 12);
        let t = student_t_critical(0.05, 11.0);
        let (mut held, mut width, mut reference) = (0, 0.0, 0.0);
        for seed in 0..100 {
            let fit = cross_validate(&grams(23.0, false, seed), &folds, "test").unwrap();
            let kept = fit.settings_kept(t);
            let (lo, hi) = (kept[0], kept[kept.len() - 1]);
            if (lo..=hi).contains(&23) {
                held += 1;
            }
            width += (hi - lo) as f64;
            let least = fit.curve.iter().copied().fold(f64::INFINITY, f64::min);
            let within: Vec<usize> = (0..fit.curve.len())
                .filter(|&s| fit.curve[s] - least <= 2.706 * NOISE * NOISE)
                .collect();
            reference += (within[within.len() - 1] - within[0]) as f64;
        }
        println!(
            "truth held {held} of 100; mean width {} ms, reference {} ms",
            width / 100.0,
            reference / 100.0
        );
        assert!(held >= 95, "the truth in {held} of 100 ranges");
        let ratio = width / reference;
        assert!(
            (1.5..=3.5).contains(&ratio),
            "width {width} against {reference}"
        );
        let fit = cross_validate(&grams(23.0, true, 1), &folds, "test").unwrap();
        assert_eq!(fit.settings_kept(t), (0..41).collect::<Vec<_>>());
    }
}
