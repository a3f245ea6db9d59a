//! Least squares `A ζ = b` (Börner eq. 25–29; Piovesan's pseudoinverse regression)
//! with a rank check, ordinary and grouped-jackknife covariances.
//!
//! The regressor's columns are equilibrated (scaled to unit 2-norm) before the SVD,
//! because stiffness and damping columns differ by orders of magnitude in scale
//! (m vs m/s); the condition number reported is that of the equilibrated matrix,
//! which is what decides whether the data determine the parameters.
//!
//! Rows at 4 kHz within one perturbation are strongly autocorrelated (they are
//! filtered and integrated signals), so the ordinary covariance `σ² (AᵀA)⁻¹`, which
//! assumes independent residuals, is far too optimistic. When the rows come in
//! three or more independent groups (trials, perturbations), the delete-one-group
//! jackknife covariance is computed as well; it is what confidence intervals should
//! use.

use nalgebra::{DMatrix, DVector};

use super::error::EstimateError;

/// Which covariance an estimate's standard errors come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CovarianceKind {
    /// Delete-one-group jackknife over trials or perturbations (honest under
    /// within-group autocorrelation).
    Jackknife,
    /// Ordinary least squares `σ² (AᵀA)⁻¹`, used when there are fewer than three
    /// groups; optimistic for autocorrelated residuals.
    Ordinary,
}

/// A least-squares fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LsqFit {
    /// The estimate `ζ̂` (eq. 29 of 000_*, or the pseudoinverse solution of 001_*).
    pub params: Vec<f64>,
    /// Parameter covariance used for standard errors (see `covariance_kind`).
    pub covariance: DMatrix<f64>,
    /// Where `covariance` comes from.
    pub covariance_kind: CovarianceKind,
    /// The ordinary covariance `σ² (AᵀA)⁻¹`, always computed.
    pub covariance_ordinary: DMatrix<f64>,
    /// Residuals `b − A ζ̂`, one per row.
    pub residuals: Vec<f64>,
    /// 2-norm condition number of the column-equilibrated regressor.
    pub condition_number: f64,
    /// RMS residual divided by the largest `|b|`: the seed's NRMSE normalisation
    /// (000_* section 4.3: "normalized with the largest value ... in the interval").
    pub nrmse: f64,
}

impl LsqFit {
    /// Standard error of parameter `i` (square root of the covariance diagonal).
    pub fn std_err(&self, i: usize) -> f64 {
        self.covariance
            .get((i, i))
            .map_or(f64::NAN, |v| v.max(0.0).sqrt())
    }
}

/// Solves `A ζ = b` for `A` given row-major (`a.len() == b.len() * n_params`).
///
/// `groups` lists the row ranges of independent groups (contiguous, covering all
/// rows); with three or more the jackknife covariance is used.
pub(crate) fn solve(
    a: &[f64],
    b: &[f64],
    n_params: usize,
    groups: &[std::ops::Range<usize>],
    max_condition: f64,
) -> Result<LsqFit, EstimateError> {
    let m = b.len();
    if n_params == 0 || a.len() != m * n_params {
        return Err(EstimateError::LengthMismatch {
            what: "regressor rows x columns vs output vector",
            left: a.len(),
            right: m * n_params,
        });
    }
    if m <= n_params {
        return Err(EstimateError::TooShort {
            what: "least-squares problem (rows)",
            needed: n_params + 1,
            got: m,
        });
    }
    super::error::check_finite("regressor", a)?;
    super::error::check_finite("output vector", b)?;
    let a_mat = DMatrix::from_row_slice(m, n_params, a);
    let b_vec = DVector::from_column_slice(b);

    // Equilibrate the columns.
    let scale: Vec<f64> = (0..n_params).map(|j| a_mat.column(j).norm()).collect();
    if scale.contains(&0.0) {
        return Err(EstimateError::RankDeficient {
            condition: f64::INFINITY,
            limit: max_condition,
        });
    }
    let mut a_s = a_mat.clone();
    for (j, s) in scale.iter().enumerate() {
        a_s.column_mut(j).scale_mut(1.0 / s);
    }
    let svd = a_s.clone().svd(true, true);
    let sv = &svd.singular_values;
    let s_max = sv.max();
    let s_min = sv.min();
    let condition = if s_min > 0.0 {
        s_max / s_min
    } else {
        f64::INFINITY
    };
    if !(condition.is_finite() && condition <= max_condition) {
        return Err(EstimateError::RankDeficient {
            condition,
            limit: max_condition,
        });
    }
    let (Some(u), Some(v_t)) = (&svd.u, &svd.v_t) else {
        return Err(EstimateError::RankDeficient {
            condition,
            limit: max_condition,
        });
    };
    // ζ_s = V Σ⁻¹ Uᵀ b (the Moore–Penrose pseudoinverse at full rank).
    let utb = u.transpose() * &b_vec;
    let mut tmp = utb;
    for (t, s) in tmp.iter_mut().zip(sv.iter()) {
        *t /= s;
    }
    let zeta_s = v_t.transpose() * tmp;
    let params: Vec<f64> = zeta_s.iter().zip(&scale).map(|(z, s)| z / s).collect();
    let fitted = &a_s * &zeta_s;
    let residuals: Vec<f64> = b_vec
        .iter()
        .zip(fitted.iter())
        .map(|(b, f)| b - f)
        .collect();
    let rss: f64 = residuals.iter().map(|r| r * r).sum();
    let dof = (m - n_params) as f64;
    let sigma2 = rss / dof;

    // (A_sᵀA_s)⁻¹ = V Σ⁻² Vᵀ.
    let mut v_scaled = v_t.transpose();
    for (j, s) in sv.iter().enumerate() {
        v_scaled.column_mut(j).scale_mut(1.0 / (s * s));
    }
    let gram_inv_s = v_scaled * v_t;
    let unscale = |c: DMatrix<f64>| {
        DMatrix::from_fn(n_params, n_params, |i, j| c[(i, j)] / (scale[i] * scale[j]))
    };
    let covariance_ordinary = unscale(gram_inv_s * sigma2);

    let jack = if groups.len() >= 3 {
        jackknife(&a_s, &b_vec, groups).map(unscale)
    } else {
        None
    };
    let (covariance, covariance_kind) = match jack {
        Some(c) => (c, CovarianceKind::Jackknife),
        None => (covariance_ordinary.clone(), CovarianceKind::Ordinary),
    };
    let b_max = b.iter().fold(0.0_f64, |acc, v| acc.max(v.abs()));
    let nrmse = if b_max > 0.0 {
        (rss / m as f64).sqrt() / b_max
    } else {
        0.0
    };
    Ok(LsqFit {
        params,
        covariance,
        covariance_kind,
        covariance_ordinary,
        residuals,
        condition_number: condition,
        nrmse,
    })
}

/// Delete-one-group jackknife covariance of the (equilibrated) parameters, from the
/// per-group normal equations. `None` when a leave-one-out problem is singular.
fn jackknife(
    a_s: &DMatrix<f64>,
    b: &DVector<f64>,
    groups: &[std::ops::Range<usize>],
) -> Option<DMatrix<f64>> {
    let p = a_s.ncols();
    let mut parts = Vec::with_capacity(groups.len());
    let mut gram = DMatrix::<f64>::zeros(p, p);
    let mut rhs = DVector::<f64>::zeros(p);
    for g in groups {
        if g.start > g.end || g.end > a_s.nrows() {
            return None;
        }
        let rows = a_s.rows(g.start, g.end - g.start);
        let gg = rows.transpose() * rows;
        let hg = rows.transpose() * b.rows(g.start, g.end - g.start);
        gram += &gg;
        rhs += &hg;
        parts.push((gg, hg));
    }
    let n = parts.len() as f64;
    let mut estimates = Vec::with_capacity(parts.len());
    for (gg, hg) in &parts {
        let chol = (&gram - gg).cholesky()?;
        estimates.push(chol.solve(&(&rhs - hg)));
    }
    let mean = estimates
        .iter()
        .fold(DVector::<f64>::zeros(p), |acc, e| acc + e)
        / n;
    let mut cov = DMatrix::<f64>::zeros(p, p);
    for e in &estimates {
        let d = e - &mean;
        cov += &d * d.transpose();
    }
    Some(cov * ((n - 1.0) / n))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn exact_line_is_recovered_to_rounding() {
        // y = 2 x + 3 on 10 points: a consistent system, so the fit is exact up to
        // rounding (1e-12 relative).
        let xs: Vec<f64> = (0..10).map(f64::from).collect();
        let a: Vec<f64> = xs.iter().flat_map(|x| [*x, 1.0]).collect();
        let b: Vec<f64> = xs.iter().map(|x| 2.0 * x + 3.0).collect();
        let fit = solve(&a, &b, 2, &[], 1e10).unwrap();
        assert!((fit.params[0] - 2.0).abs() < 1e-12);
        assert!((fit.params[1] - 3.0).abs() < 1e-12);
        assert_eq!(fit.covariance_kind, CovarianceKind::Ordinary);
    }

    #[test]
    fn duplicate_column_is_rank_deficient() {
        let a: Vec<f64> = (0..10).flat_map(|i| [f64::from(i), f64::from(i)]).collect();
        let b: Vec<f64> = (0..10).map(f64::from).collect();
        assert!(matches!(
            solve(&a, &b, 2, &[], 1e10),
            Err(EstimateError::RankDeficient { .. })
        ));
    }
}
