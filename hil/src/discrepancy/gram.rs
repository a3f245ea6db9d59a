//! Sufficient statistics of a linear least-squares fit, so that fits over any set of
//! trials (a cross-validation fold, its complement, all of them) are sums of per-trial
//! pieces and the residual of any held-out set follows without touching samples again.

use nalgebra::{DMatrix, DVector};

/// `XᵀX`, `Xᵀy`, `yᵀy` over some rows, plus the sum of squares of the normalising
/// signal (the motor command) and the row count.
#[derive(Debug, Clone, PartialEq)]
pub struct Gram {
    /// Number of regressors.
    pub p: usize,
    /// `XᵀX`, row-major `p × p`.
    pub xtx: Vec<f64>,
    /// `Xᵀy`.
    pub xty: Vec<f64>,
    /// `yᵀy`.
    pub yty: f64,
    /// Sum of squares of the normalising signal over the same rows.
    pub norm_sq: f64,
    /// Rows.
    pub n: usize,
}

impl Gram {
    /// An empty Gram of `p` regressors.
    #[must_use]
    pub fn new(p: usize) -> Gram {
        Gram {
            p,
            xtx: vec![0.0; p * p],
            xty: vec![0.0; p],
            yty: 0.0,
            norm_sq: 0.0,
            n: 0,
        }
    }

    /// Adds one row: regressors `x` (length `p`), target `y`, normaliser `norm`.
    pub fn push(&mut self, x: &[f64], y: f64, norm: f64) {
        let p = self.p;
        for i in 0..p {
            let xi = x[i];
            if xi == 0.0 {
                continue;
            }
            self.xty[i] += xi * y;
            let row = &mut self.xtx[i * p..(i + 1) * p];
            for (r, xj) in row.iter_mut().zip(x) {
                *r += xi * xj;
            }
        }
        self.yty += y * y;
        self.norm_sq += norm * norm;
        self.n += 1;
    }

    /// Adds the rows of `other` (same `p`).
    pub fn add(&mut self, other: &Gram) {
        for (a, b) in self.xtx.iter_mut().zip(&other.xtx) {
            *a += b;
        }
        for (a, b) in self.xty.iter_mut().zip(&other.xty) {
            *a += b;
        }
        self.yty += other.yty;
        self.norm_sq += other.norm_sq;
        self.n += other.n;
    }

    /// Removes the rows of `other`, which must have been added before.
    pub fn sub(&mut self, other: &Gram) {
        for (a, b) in self.xtx.iter_mut().zip(&other.xtx) {
            *a -= b;
        }
        for (a, b) in self.xty.iter_mut().zip(&other.xty) {
            *a -= b;
        }
        self.yty -= other.yty;
        self.norm_sq -= other.norm_sq;
        self.n -= other.n.min(self.n);
    }

    /// Sum of several Grams of the same size.
    #[must_use]
    pub fn sum<'a>(p: usize, grams: impl IntoIterator<Item = &'a Gram>) -> Gram {
        let mut g = Gram::new(p);
        for x in grams {
            g.add(x);
        }
        g
    }

    /// The least-squares coefficients, or `None` when `XᵀX` is singular. Columns are
    /// scaled to unit diagonal before the Cholesky factorisation, so that regressors in
    /// different units (m/s², N) do not spoil its conditioning.
    #[must_use]
    pub fn solve(&self) -> Option<Vec<f64>> {
        let p = self.p;
        let scale: Vec<f64> = (0..p)
            .map(|i| self.xtx[i * p + i])
            .map(|d| if d > 0.0 { 1.0 / d.sqrt() } else { 0.0 })
            .collect();
        if scale.iter().any(|s| *s == 0.0 || !s.is_finite()) {
            return None;
        }
        let a = DMatrix::from_fn(p, p, |i, j| self.xtx[i * p + j] * scale[i] * scale[j]);
        let b = DVector::from_fn(p, |i, _| self.xty[i] * scale[i]);
        let chol = a.cholesky()?;
        let z = chol.solve(&b);
        let beta: Vec<f64> = (0..p).map(|i| z[i] * scale[i]).collect();
        beta.iter().all(|b| b.is_finite()).then_some(beta)
    }

    /// Sum of squared residuals of coefficients `beta` over these rows (never negative).
    #[must_use]
    pub fn sse(&self, beta: &[f64]) -> f64 {
        let p = self.p;
        let mut quad = 0.0;
        for (i, bi) in beta.iter().enumerate().take(p) {
            let row = &self.xtx[i * p..(i + 1) * p];
            quad += bi * row.iter().zip(beta).map(|(a, b)| a * b).sum::<f64>();
        }
        let lin: f64 = beta.iter().zip(&self.xty).map(|(b, c)| b * c).sum();
        (self.yty - 2.0 * lin + quad).max(0.0)
    }

    /// Covariance of the coefficients, `σ² (XᵀX)⁻¹` with `σ² = SSE/(n − p)`, row-major.
    /// Rows are treated as independent, which smoothed samples are not: the spread over
    /// folds is the honest uncertainty, this one a lower bound.
    #[must_use]
    pub fn covariance(&self, beta: &[f64]) -> Option<Vec<f64>> {
        let p = self.p;
        if self.n <= p {
            return None;
        }
        let a = DMatrix::from_fn(p, p, |i, j| self.xtx[i * p + j]);
        let inv = a.try_inverse()?;
        let s2 = self.sse(beta) / (self.n - p) as f64;
        Some((0..p * p).map(|k| inv[(k / p, k % p)] * s2).collect())
    }
}
