//! How a sliding window sees samples beyond the ends of a signal.
//!
//! The non-`Interp` modes follow `scipy.ndimage.convolve1d`, which
//! `scipy.signal.savgol_filter` uses for every mode except its default `interp`.

/// Edge handling of [`savgol_filter`](super::savgol_filter), named after scipy's `mode`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EdgeMode {
    /// scipy's default: the first and last `window / 2` outputs are the
    /// polynomial of order `polyorder` fitted to the first / last `window` samples
    /// (or its derivative), evaluated at those samples. No padding.
    Interp,
    /// Repeat the end sample: `a a a | a b c d | d d d`.
    Nearest,
    /// Reflect about the end sample, which is not repeated: `d c b | a b c d | c b a`.
    Mirror,
    /// Pad with a constant: `k k k | a b c d | k k k`.
    Constant(f64),
    /// Periodic continuation: `b c d | a b c d | a b c`.
    Wrap,
}

/// Sample `i` (possibly outside `0..x.len()`) of `x` extended by `mode`.
///
/// `x` must be non-empty; `Interp` never reaches here and is treated as `Nearest`.
pub(crate) fn extended(x: &[f64], i: isize, mode: EdgeMode) -> f64 {
    let n = x.len() as isize;
    if (0..n).contains(&i) {
        return x[i as usize];
    }
    let idx = match mode {
        EdgeMode::Constant(c) => return c,
        EdgeMode::Nearest | EdgeMode::Interp => i.clamp(0, n - 1),
        EdgeMode::Wrap => i.rem_euclid(n),
        EdgeMode::Mirror => {
            if n == 1 {
                0
            } else {
                let period = 2 * (n - 1);
                let r = i.rem_euclid(period);
                if r < n { r } else { period - r }
            }
        }
    };
    x[idx as usize]
}
