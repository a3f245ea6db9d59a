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
    /// Box bounds `(column, low, high)` on coefficients that [`Self::solve`] respects
    /// (a property of the design, carried by every Gram of it: a sum takes them from
    /// its parts).
    pub bounds: Vec<(usize, f64, f64)>,
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
            bounds: Vec::new(),
        }
    }

    /// The same Gram with box bounds `(column, low, high)` on coefficients.
    #[must_use]
    pub fn with_bounds(mut self, bounds: Vec<(usize, f64, f64)>) -> Gram {
        self.bounds = bounds;
        self
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

    /// Adds the rows of `other` (same `p`); an unbounded Gram takes `other`'s bounds.
    pub fn add(&mut self, other: &Gram) {
        if self.bounds.is_empty() && !other.bounds.is_empty() {
            self.bounds.clone_from(&other.bounds);
        }
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

    /// Removes what per-group intercepts would explain, given each group's sums
    /// ([`Intercepts`]): the Schur complement of the intercept columns, so that a fit
    /// on the result equals a fit with one free constant per group (Frisch–Waugh), and
    /// Grams so reduced still add over trials.
    pub fn absorb(&mut self, ic: &Intercepts) {
        let p = self.p;
        for grp in &ic.groups {
            if grp.n == 0 {
                continue;
            }
            let n = grp.n as f64;
            for i in 0..p {
                for j in 0..p {
                    self.xtx[i * p + j] -= grp.sx[i] * grp.sx[j] / n;
                }
                self.xty[i] -= grp.sx[i] * grp.sy / n;
            }
            self.yty -= grp.sy * grp.sy / n;
        }
        self.yty = self.yty.max(0.0);
    }

    /// The Gram of the first `p − q` columns once the last `q` (nuisance columns of one
    /// group of rows, free per group) are fitted out: the Schur complement of their block,
    /// so that a fit on the result equals the fit that carries them (Frisch–Waugh) and
    /// Grams so reduced still add over groups. A rank-deficient nuisance block (a group
    /// too short for its columns) is inverted in the least-squares sense (pseudo-inverse,
    /// relative tolerance 1e-12), which removes what the columns can explain and no more.
    #[must_use]
    pub fn eliminate_trailing(&self, q: usize) -> Gram {
        let p = self.p;
        if q == 0 || q > p {
            return if q == 0 { self.clone() } else { Gram::new(0) };
        }
        let k = p - q;
        let at = |i: usize, j: usize| self.xtx[i * p + j];
        let ann = DMatrix::from_fn(q, q, |i, j| at(k + i, k + j));
        let scale = ann.diagonal().max().max(f64::MIN_POSITIVE);
        let inv = (ann / scale)
            .pseudo_inverse(1e-12)
            .map_or_else(|_| DMatrix::zeros(q, q), |m| m / scale);
        // `A_kn Ann⁻¹` for the kept columns and for the target.
        let axn = DMatrix::from_fn(k, q, |i, j| at(i, k + j));
        let bn = DVector::from_fn(q, |i, _| self.xty[k + i]);
        let proj = &axn * &inv;
        let red = &proj * axn.transpose();
        let mut g = Gram::new(k);
        for i in 0..k {
            for j in 0..k {
                g.xtx[i * k + j] = at(i, j) - red[(i, j)];
            }
            g.xty[i] = self.xty[i] - (proj.row(i) * &bn)[(0, 0)];
        }
        g.yty = (self.yty - (bn.transpose() * &inv * &bn)[(0, 0)]).max(0.0);
        g.norm_sq = self.norm_sq;
        g.n = self.n;
        g.bounds = self.bounds.iter().copied().filter(|b| b.0 < k).collect();
        g
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

    /// The least-squares coefficients within [`Self::bounds`], or `None` when `XᵀX` is
    /// singular. A column that no row touches (its diagonal exactly zero: the columns
    /// of an axis a rig lacks, a force gain left out) is held at zero, and the others
    /// solved as if it were not there. Columns are scaled to unit diagonal before the Cholesky factorisation,
    /// so that regressors in different units (m/s², N) do not spoil its conditioning.
    ///
    /// When the unconstrained solution breaks a bound, every assignment of the bounded
    /// coefficients to free, low or high is solved (`3^m` small solves for `m` bounded
    /// columns; the design has two) and the feasible one of least squared error kept:
    /// the exact solution of the box-constrained problem, which is convex. Within the
    /// bounds the result is the unconstrained one, bit for bit.
    #[must_use]
    pub fn solve(&self) -> Option<Vec<f64>> {
        let beta = self.solve_free(&[])?;
        let inside = |b: &[f64]| {
            self.bounds
                .iter()
                .all(|&(j, lo, hi)| b.get(j).is_none_or(|v| (lo..=hi).contains(v)))
        };
        if inside(&beta) {
            return Some(beta);
        }
        let m = self.bounds.len();
        let mut best: Option<(f64, Vec<f64>)> = None;
        for code in 0..3usize.pow(u32::try_from(m).ok()?) {
            let mut c = code;
            let fixed: Vec<(usize, f64)> = self
                .bounds
                .iter()
                .filter_map(|&(j, lo, hi)| {
                    let which = c % 3;
                    c /= 3;
                    match which {
                        1 => Some((j, lo)),
                        2 => Some((j, hi)),
                        _ => None,
                    }
                })
                .collect();
            let Some(b) = self.solve_free(&fixed) else {
                continue;
            };
            if inside(&b) {
                let sse = self.sse(&b);
                if best.as_ref().is_none_or(|(s, _)| sse < *s) {
                    best = Some((sse, b));
                }
            }
        }
        best.map(|(_, b)| b)
    }

    /// The least-squares coefficients with the columns of `fixed` held at the given
    /// values (the others free).
    fn solve_free(&self, fixed: &[(usize, f64)]) -> Option<Vec<f64>> {
        let p = self.p;
        if !fixed.is_empty() {
            let value = |j: usize| fixed.iter().find(|f| f.0 == j).map(|f| f.1);
            let free: Vec<usize> = (0..p).filter(|j| value(*j).is_none()).collect();
            let k = free.len();
            // The target less the fixed columns' part, over the free columns.
            let mut g = Gram::new(k);
            for (a, &i) in free.iter().enumerate() {
                for (b, &j) in free.iter().enumerate() {
                    g.xtx[a * k + b] = self.xtx[i * p + j];
                }
                g.xty[a] = self.xty[i]
                    - fixed
                        .iter()
                        .map(|&(j, c)| self.xtx[i * p + j] * c)
                        .sum::<f64>();
            }
            let sub = g.solve_free(&[])?;
            let mut beta = vec![0.0; p];
            for (a, &i) in free.iter().enumerate() {
                beta[i] = sub[a];
            }
            for &(j, c) in fixed {
                beta[j] = c;
            }
            return Some(beta);
        }
        let empty: Vec<(usize, f64)> = (0..p)
            .filter(|&i| self.xtx[i * p + i] == 0.0)
            .map(|i| (i, 0.0))
            .collect();
        if !empty.is_empty() && empty.len() < p {
            return self.solve_free(&empty);
        }
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
        // Columns without a row (an absent axis) have no variance: zero.
        let live: Vec<usize> = (0..p).filter(|&i| self.xtx[i * p + i] != 0.0).collect();
        let k = live.len();
        let a = DMatrix::from_fn(k, k, |i, j| self.xtx[live[i] * p + live[j]]);
        let inv = a.try_inverse()?;
        let s2 = self.sse(beta) / (self.n - k) as f64;
        let mut cov = vec![0.0; p * p];
        for (a, &i) in live.iter().enumerate() {
            for (b, &j) in live.iter().enumerate() {
                cov[i * p + j] = inv[(a, b)] * s2;
            }
        }
        Some(cov)
    }
}

/// Column and target sums per group of rows (one group per axis of a trial): what
/// [`Gram::absorb`] needs to fit a constant per group without carrying its column.
#[derive(Debug, Clone, PartialEq)]
pub struct Intercepts {
    groups: Vec<Group>,
}

#[derive(Debug, Clone, PartialEq)]
struct Group {
    sx: Vec<f64>,
    sy: f64,
    n: usize,
}

impl Intercepts {
    /// `groups` groups of rows with `p` regressors.
    #[must_use]
    pub fn new(groups: usize, p: usize) -> Intercepts {
        Intercepts {
            groups: vec![
                Group {
                    sx: vec![0.0; p],
                    sy: 0.0,
                    n: 0,
                };
                groups
            ],
        }
    }

    /// Adds one row of group `group`.
    pub fn push(&mut self, group: usize, x: &[f64], y: f64) {
        let g = &mut self.groups[group];
        for (s, v) in g.sx.iter_mut().zip(x) {
            *s += v;
        }
        g.sy += y;
        g.n += 1;
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    /// Eliminating trailing nuisance columns gives the kept coefficients and the residual
    /// sum of squares of the fit that carries them (to 1e-9 relative: the same normal
    /// equations, solved by blocks), and a reduced Gram per group adds up to the fit with
    /// one set of nuisance columns per group.
    #[test]
    fn eliminated_columns_equal_the_explicit_fit() {
        let row = |i: usize| {
            let t = i as f64 * 0.01;
            let g = i % 2;
            let x = [t.sin(), (3.0 * t).cos() + 0.1 * t];
            let y = 2.0 * x[0] - 0.5 * x[1]
                + [0.7, -1.3][g]
                + [0.2, -0.4][g] * t
                + 0.01 * (7.0 * t).sin();
            (g, t, x, y)
        };
        let mut per_group = [Gram::new(4), Gram::new(4)];
        let mut full = Gram::new(6);
        for i in 0..200 {
            let (g, t, x, y) = row(i);
            per_group[g].push(&[x[0], x[1], 1.0, t], y, 1.0);
            let mut c = [x[0], x[1], 0.0, 0.0, 0.0, 0.0];
            c[2 + 2 * g] = 1.0;
            c[3 + 2 * g] = t;
            full.push(&c, y, 1.0);
        }
        let reduced = Gram::sum(2, &per_group.map(|g| g.eliminate_trailing(2)));
        let b = reduced.solve().unwrap();
        let bf = full.solve().unwrap();
        for k in 0..2 {
            assert!((b[k] - bf[k]).abs() < 1e-9 * bf[k].abs(), "{b:?} vs {bf:?}");
        }
        let (se, sf) = (reduced.sse(&b), full.sse(&bf));
        assert!((se - sf).abs() < 1e-9 * sf, "{se} vs {sf}");
        // A group with a single row cannot carry two columns: its row is explained away,
        // nothing more (the pseudo-inverse), and nothing is NaN.
        let mut one = Gram::new(3);
        one.push(&[1.0, 1.0, 0.5], 2.0, 1.0);
        let r = one.eliminate_trailing(2);
        assert!(r.xtx[0].abs() < 1e-12 && r.yty.abs() < 1e-12, "{r:?}");
    }

    /// Absorbing one intercept per group gives the coefficients and the residual sum
    /// of squares of the fit that carries the two constants as columns (to 1e-9
    /// relative: the two are the same normal equations, eliminated in a different
    /// order).
    #[test]
    fn absorbed_intercepts_equal_explicit_constants() {
        let rows: Vec<(usize, [f64; 2], f64)> = (0..200)
            .map(|i| {
                let t = i as f64 * 0.01;
                let g = i % 2;
                let x = [t.sin(), (3.0 * t).cos() + 0.1 * t];
                let y = 2.0 * x[0] - 0.5 * x[1] + [0.7, -1.3][g] + 0.01 * (7.0 * t).sin();
                (g, x, y)
            })
            .collect();
        let mut reduced = Gram::new(2);
        let mut ic = Intercepts::new(2, 2);
        let mut full = Gram::new(4);
        for (g, x, y) in &rows {
            reduced.push(x, *y, 1.0);
            ic.push(*g, x, *y);
            let c = [x[0], x[1], f64::from(*g == 0), f64::from(*g == 1)];
            full.push(&c, *y, 1.0);
        }
        reduced.absorb(&ic);
        let b = reduced.solve().unwrap();
        let bf = full.solve().unwrap();
        for k in 0..2 {
            assert!((b[k] - bf[k]).abs() < 1e-9 * bf[k].abs(), "{b:?} vs {bf:?}");
        }
        let (se, sf) = (reduced.sse(&b), full.sse(&bf));
        assert!(
            (se - sf).abs() < 1e-9 * sf.max(1e-12) + 1e-12,
            "{se} vs {sf}"
        );
    }

    /// Box bounds: within them the solution is the unconstrained one, bit for bit;
    /// outside, it is the box-constrained least-squares optimum, checked against a
    /// brute-force grid over the two bounded coefficients (each with the free one
    /// refitted): no feasible point of the grid has a smaller error (to 1e-9), and the
    /// optimum sits on the bound the unconstrained fit broke.
    #[test]
    fn bounded_solve_is_the_constrained_optimum() {
        // y = 3 a + 0.4 u + 0.05 w + a small ripple, with `u`, `w` bounded to ±0.1.
        let mut g = Gram::new(3);
        for i in 0..500 {
            let t = i as f64 * 0.01;
            let x = [
                (1.3 * t).sin(),
                (0.7 * t).cos() + 0.3 * (1.3 * t).sin(),
                t.sin() * t.cos(),
            ];
            let y = 3.0 * x[0] + 0.4 * x[1] + 0.05 * x[2] + 0.01 * (17.0 * t).sin();
            g.push(&x, y, 1.0);
        }
        let free = g.solve().unwrap();
        assert!((free[1] - 0.4).abs() < 0.01, "{free:?}");
        let wide = g.clone().with_bounds(vec![(1, -1.0, 1.0), (2, -1.0, 1.0)]);
        assert_eq!(wide.solve().unwrap(), free);

        let tight = g.clone().with_bounds(vec![(1, -0.1, 0.1), (2, -0.1, 0.1)]);
        let b = tight.solve().unwrap();
        assert!((b[1] - 0.1).abs() < 1e-12, "{b:?}");
        assert!((-0.1..=0.1).contains(&b[2]), "{b:?}");
        let best = tight.sse(&b);
        // The grid: u, w on a 0.005 grid inside the box, `a` refitted for each.
        let refit_a = |u: f64, w: f64| {
            let r = g.xty[0] - g.xtx[1] * u - g.xtx[2] * w;
            r / g.xtx[0]
        };
        for i in 0..=40 {
            for j in 0..=40 {
                let (u, w) = (-0.1 + 0.005 * f64::from(i), -0.1 + 0.005 * f64::from(j));
                let e = g.sse(&[refit_a(u, w), u, w]);
                assert!(e >= best * (1.0 - 1e-9), "({u}, {w}): {e} < {best}");
            }
        }
        // A sum of bounded Grams keeps their bounds.
        let mut sum = Gram::new(3);
        sum.add(&tight);
        assert_eq!(sum.bounds, tight.bounds);
    }
}
