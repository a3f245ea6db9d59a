//! Odd extension of a signal, as `scipy.signal._arraytools.odd_ext`, used by the
//! forward-backward filters to start and end without transients.

/// `x` with `edge` samples added at each end by point reflection about the end
/// samples: `2·x[0] − x[edge..0]`, `x`, `2·x[n−1] − x[n−2..n−2−edge]`.
///
/// Callers guarantee `edge < x.len()`.
pub(crate) fn odd_ext(x: &[f64], edge: usize) -> Vec<f64> {
    let n = x.len();
    let mut ext = Vec::with_capacity(n + 2 * edge);
    let first = x[0];
    let last = x[n - 1];
    ext.extend((1..=edge).rev().map(|i| 2.0 * first - x[i]));
    ext.extend_from_slice(x);
    ext.extend((1..=edge).map(|i| 2.0 * last - x[n - 1 - i]));
    ext
}
