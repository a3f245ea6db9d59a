//! Transfer-function (b, a) filtering and zero-phase forward-backward filtering, as
//! scipy's `lfilter`, `lfilter_zi` and `filtfilt` with default padding.
//!
//! Prefer [`sosfiltfilt`](super::sosfiltfilt) for designs from
//! [`butter`](super::butter): the expanded polynomials of a high-order or
//! low-cut-off filter lose digits that the sections keep. This path exists for
//! filters that only come as `(b, a)`.

use nalgebra::{DMatrix, DVector};

use super::error::{SignalError, check_finite};
use super::pad::odd_ext;

/// `(b, a)` normalised by `a[0]` and zero-padded to a common length.
fn normalise(b: &[f64], a: &[f64]) -> Result<(Vec<f64>, Vec<f64>), SignalError> {
    if b.is_empty() || a.is_empty() {
        return Err(SignalError::BadCoefficients {
            why: "b and a must both be non-empty",
        });
    }
    if b.iter().chain(a).any(|c| !c.is_finite()) {
        return Err(SignalError::BadCoefficients {
            why: "a filter coefficient is not finite",
        });
    }
    let a0 = a[0];
    if a0 == 0.0 {
        return Err(SignalError::BadCoefficients {
            why: "a[0] must be non-zero",
        });
    }
    let n = a.len().max(b.len());
    let mut bn: Vec<f64> = b.iter().map(|v| v / a0).collect();
    let mut an: Vec<f64> = a.iter().map(|v| v / a0).collect();
    bn.resize(n, 0.0);
    an.resize(n, 0.0);
    Ok((bn, an))
}

/// Transposed direct form II over `x` in place, with state `z` (length n − 1).
fn run(b: &[f64], a: &[f64], x: &mut [f64], z: &mut [f64]) {
    let n = b.len();
    for v in x.iter_mut() {
        let xn = *v;
        if n == 1 {
            *v = b[0] * xn;
            continue;
        }
        let yn = z[0] + b[0] * xn;
        for k in 1..n - 1 {
            z[k - 1] = z[k] + xn * b[k] - yn * a[k];
        }
        z[n - 2] = xn * b[n - 1] - yn * a[n - 1];
        *v = yn;
    }
}

/// Steady-state initial state of `lfilter` for a unit step, as
/// `scipy.signal.lfilter_zi(b, a)`: the solution of `(I − companion(a)ᵀ) z = b[1..] −
/// a[1..]·b[0]` after normalising by `a[0]`. Length `max(len a, len b) − 1`.
///
/// # Errors
/// [`SignalError::BadCoefficients`] for empty or non-finite coefficients,
/// `a[0] = 0`, or a pole at z = 1 (singular system).
pub fn lfilter_zi(b: &[f64], a: &[f64]) -> Result<Vec<f64>, SignalError> {
    let (b, a) = normalise(b, a)?;
    let m = b.len() - 1;
    if m == 0 {
        return Ok(Vec::new());
    }
    // companion(a)ᵀ has −a[1..] down its first column and ones on the superdiagonal.
    let lhs = DMatrix::from_fn(m, m, |i, j| {
        let eye = if i == j { 1.0 } else { 0.0 };
        let comp_t = if j == 0 {
            -a[i + 1]
        } else if j == i + 1 {
            1.0
        } else {
            0.0
        };
        eye - comp_t
    });
    let rhs = DVector::from_fn(m, |i, _| b[i + 1] - a[i + 1] * b[0]);
    let z = lhs.lu().solve(&rhs).ok_or(SignalError::BadCoefficients {
        why: "the filter has a pole at z = 1 and no steady state",
    })?;
    Ok(z.iter().copied().collect())
}

/// Filters `x` through `b(z)/a(z)` from rest, as `scipy.signal.lfilter(b, a, x)`.
///
/// # Errors
/// [`SignalError::BadCoefficients`] for empty or non-finite coefficients or `a[0] = 0`.
pub fn lfilter(b: &[f64], a: &[f64], x: &[f64]) -> Result<Vec<f64>, SignalError> {
    let (b, a) = normalise(b, a)?;
    let mut z = vec![0.0; b.len() - 1];
    let mut y = x.to_vec();
    run(&b, &a, &mut y, &mut z);
    Ok(y)
}

/// Zero-phase forward-backward filtering by `b(z)/a(z)`, as
/// `scipy.signal.filtfilt(b, a, x)` with its defaults: odd extension by
/// `padlen = 3·max(len a, len b)` samples and `lfilter_zi` initial conditions scaled
/// by the first sample of each pass.
///
/// # Errors
/// As [`lfilter_zi`], plus [`SignalError::TooShort`] unless `x.len() > padlen`, and
/// [`SignalError::NonFinite`] for a bad sample.
pub fn filtfilt(b: &[f64], a: &[f64], x: &[f64]) -> Result<Vec<f64>, SignalError> {
    let zi = lfilter_zi(b, a)?;
    let (bn, an) = normalise(b, a)?;
    let edge = 3 * a.len().max(b.len());
    if x.len() <= edge {
        return Err(SignalError::TooShort {
            needed: edge + 1,
            got: x.len(),
            what: "filtfilt (more than its padding)",
        });
    }
    check_finite(x)?;
    let mut y = odd_ext(x, edge);
    let x0 = y[0];
    let mut z: Vec<f64> = zi.iter().map(|v| v * x0).collect();
    run(&bn, &an, &mut y, &mut z);
    y.reverse();
    let y0 = y[0];
    let mut z: Vec<f64> = zi.iter().map(|v| v * y0).collect();
    run(&bn, &an, &mut y, &mut z);
    y.reverse();
    Ok(y[edge..y.len() - edge].to_vec())
}
