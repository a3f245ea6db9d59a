//! The statistics behind "is this gain more than chance": Student's t distribution
//! (through the regularised incomplete beta function, Numerical Recipes §6.4) and the
//! delete-a-group jackknife for the spread of parameters over folds; the median that
//! robust scales and the faulty-unit rule read.

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9; relative error < 1e-14).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..400 {
        let m = f64::from(m);
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// Regularised incomplete beta function `I_x(a, b)`.
#[must_use]
pub fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

/// `P(T > t)` for Student's t with `df` degrees of freedom.
#[must_use]
pub fn student_t_sf(t: f64, df: f64) -> f64 {
    let tail = 0.5 * incomplete_beta(0.5 * df, 0.5, df / (df + t * t));
    if t >= 0.0 { tail } else { 1.0 - tail }
}

/// The `t` with `P(T > t) = alpha` (one-sided critical value), by bisection.
#[must_use]
pub fn student_t_critical(alpha: f64, df: f64) -> f64 {
    let (mut lo, mut hi) = (0.0_f64, 1.0e4_f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if student_t_sf(mid, df) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The median of `v` (reordered in place), the upper one of an even count; `v` must
/// not be empty.
#[must_use]
pub fn upper_median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Mean and sample standard deviation.
#[must_use]
pub fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    if x.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let m = x.iter().sum::<f64>() / n;
    if x.len() < 2 {
        return (m, f64::NAN);
    }
    let v = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0);
    (m, v.sqrt())
}

/// Delete-a-group jackknife standard error from the estimates of `K` fits that each
/// left one fold out: `sqrt((K−1)/K · Σ(θₖ − θ̄)²)`.
#[must_use]
pub fn jackknife_se(estimates: &[f64]) -> f64 {
    let k = estimates.len() as f64;
    if estimates.len() < 2 {
        return f64::NAN;
    }
    let m = estimates.iter().sum::<f64>() / k;
    ((k - 1.0) / k * estimates.iter().map(|e| (e - m) * (e - m)).sum::<f64>()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    // scipy.stats.t.ppf(0.99, 7) = 2.9979515668685277, t.ppf(0.975, 30) = 2.0422724563012378,
    // t.sf(1.0, 3) = 0.19550110947788524.
    #[test]
    fn student_t_matches_scipy() {
        assert!((student_t_critical(0.01, 7.0) - 2.997_951_566_868_527_7).abs() < 1e-9);
        assert!((student_t_critical(0.025, 30.0) - 2.042_272_456_301_237_8).abs() < 1e-9);
        assert!((student_t_sf(1.0, 3.0) - 0.195_501_109_477_885_24).abs() < 1e-12);
        assert!((student_t_sf(-1.0, 3.0) - (1.0 - 0.195_501_109_477_885_24)).abs() < 1e-12);
    }

    #[test]
    fn jackknife_of_equal_estimates_is_zero() {
        assert!(jackknife_se(&[2.0, 2.0, 2.0]).abs() < 1e-15);
    }
}
