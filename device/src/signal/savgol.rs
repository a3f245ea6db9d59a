//! Savitzky–Golay smoothing and differentiation, as `scipy.signal.savgol_coeffs`
//! and `scipy.signal.savgol_filter`.
//!
//! A Savitzky–Golay filter replaces each sample by the value (or a derivative) at
//! that sample of the least-squares polynomial of order `polyorder` through the
//! `window` samples around it. The weights are linear in the data, so they are
//! computed once per window position as `w = V (VᵀV)⁻¹ g`, where `V` is the
//! Vandermonde matrix of the window and `g` evaluates the requested derivative.
//!
//! Conditioning: scipy solves the unscaled Vandermonde system, whose columns grow
//! like `(window/2)^polyorder` (1.3·10¹² for the seed's order-5 window of 253). Here
//! the abscissae are first scaled to `[-1, 1]` and the system is solved by a
//! Householder QR of the scaled `V`, so the weights stay accurate for long windows.
//! The golden tests compare both against exact rational weights.

use nalgebra::{DMatrix, DVector};
use realfft::RealFftPlanner;

use super::edge::{EdgeMode, extended};
use super::error::{SignalError, check_finite, check_rate};

/// Checks window and order as scipy does, plus oddness (even windows are not supported).
fn check_window(window: usize, polyorder: usize) -> Result<(), SignalError> {
    if window == 0 || window.is_multiple_of(2) {
        return Err(SignalError::BadWindow {
            window,
            why: "must be odd and positive",
        });
    }
    if polyorder >= window {
        return Err(SignalError::BadOrder {
            order: polyorder,
            why: "polyorder must be less than the window length",
        });
    }
    Ok(())
}

/// Least-squares polynomial fit over a window of `window` equally spaced samples,
/// factored once (Householder QR of the Vandermonde matrix in the abscissa scaled
/// to `[-1, 1]`) and reused for every evaluation point and data window.
struct LsqFit {
    window: usize,
    polyorder: usize,
    centre: f64,
    scale: f64,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
}

impl LsqFit {
    fn new(window: usize, polyorder: usize) -> Self {
        let centre = (window as f64 - 1.0) / 2.0;
        let scale = centre.max(1.0);
        let v = DMatrix::from_fn(window, polyorder + 1, |j, k| {
            let u = (j as f64 - centre) / scale;
            u.powi(k as i32)
        });
        let qr = v.qr();
        Self {
            window,
            polyorder,
            centre,
            scale,
            q: qr.q(),
            r: qr.r(),
        }
    }

    /// `g_k` = d^deriv/dt^deriv of `u(t)^k` at `t = pos` (samples from the window
    /// start), with `u = (t − centre)/scale` and t in units of `delta`:
    /// `k!/(k−deriv)! · u0^(k−deriv) / (scale·delta)^deriv`.
    fn functional(&self, deriv: usize, delta: f64, pos: f64) -> DVector<f64> {
        let u0 = (pos - self.centre) / self.scale;
        let denom = (self.scale * delta).powi(deriv as i32);
        DVector::from_fn(self.polyorder + 1, |k, _| {
            if k < deriv {
                0.0
            } else {
                let falling: f64 = ((k - deriv + 1)..=k).map(|m| m as f64).product();
                falling * u0.powi((k - deriv) as i32) / denom
            }
        })
    }

    fn singular(&self) -> SignalError {
        SignalError::BadOrder {
            order: self.polyorder,
            why: "the least-squares polynomial fit is singular",
        }
    }

    /// Weights `w` (data order: `w[j]` multiplies sample `j` of the window) giving
    /// the `deriv`-th derivative per unit `delta` at `pos` of the fitted polynomial:
    /// `w = Q R⁻ᵀ g`.
    fn weights(&self, deriv: usize, delta: f64, pos: f64) -> Result<Vec<f64>, SignalError> {
        if deriv > self.polyorder {
            return Ok(vec![0.0; self.window]);
        }
        let g = self.functional(deriv, delta, pos);
        let z = self
            .r
            .transpose()
            .solve_lower_triangular(&g)
            .ok_or_else(|| self.singular())?;
        Ok((&self.q * z).iter().copied().collect())
    }

    /// Polynomial coefficients (in the scaled abscissa) fitted to `x`
    /// (`x.len() == window`): `a = R⁻¹ Qᵀ x`.
    fn fit(&self, x: &[f64]) -> Result<DVector<f64>, SignalError> {
        let qtx = self.q.tr_mul(&DVector::from_column_slice(x));
        self.r
            .solve_upper_triangular(&qtx)
            .ok_or_else(|| self.singular())
    }

    /// The `deriv`-th derivative per unit `delta` at `pos` of the polynomial `a`.
    fn eval(&self, a: &DVector<f64>, deriv: usize, delta: f64, pos: f64) -> f64 {
        if deriv > self.polyorder {
            return 0.0;
        }
        self.functional(deriv, delta, pos).dot(a)
    }
}

/// Savitzky–Golay FIR coefficients, as `scipy.signal.savgol_coeffs(window, polyorder,
/// deriv, delta)` (its default `use='conv'`, centred `pos`).
///
/// The coefficients are in convolution order: `y[i] = Σ_k c[k] · x[i + window/2 − k]`.
/// For even `deriv` they are symmetric, so the order does not matter; for odd
/// `deriv` they are the reverse of the dot-product weights. The result is in
/// `[x]/s^deriv` when `delta` is the sample spacing in s; when `deriv > polyorder`
/// the coefficients are all zero, as in scipy.
///
/// # Errors
/// [`SignalError::BadWindow`] for an even or zero `window`,
/// [`SignalError::BadOrder`] when `polyorder >= window`,
/// [`SignalError::BadRate`] when `delta` is not finite and positive.
pub fn savgol_coeffs(
    window: usize,
    polyorder: usize,
    deriv: usize,
    delta: f64,
) -> Result<Vec<f64>, SignalError> {
    check_window(window, polyorder)?;
    check_rate("delta", delta)?;
    let mut w = LsqFit::new(window, polyorder).weights(deriv, delta, (window / 2) as f64)?;
    w.reverse();
    Ok(w)
}

/// Applies a Savitzky–Golay filter, as `scipy.signal.savgol_filter(x, window,
/// polyorder, deriv, delta, mode=...)`.
///
/// `delta` is the sample spacing (s for time series); the output of derivative
/// `deriv` is in units of `[x]/s^deriv`. The output has the length of `x`.
///
/// # Errors
/// As [`savgol_coeffs`], plus [`SignalError::TooShort`] when `x` is empty or, in
/// [`EdgeMode::Interp`], shorter than `window`; [`SignalError::NonFinite`] for a NaN
/// or infinite sample.
pub fn savgol_filter(
    x: &[f64],
    window: usize,
    polyorder: usize,
    deriv: usize,
    delta: f64,
    mode: EdgeMode,
) -> Result<Vec<f64>, SignalError> {
    savgol_filter_planned(
        &mut RealFftPlanner::new(),
        x,
        window,
        polyorder,
        deriv,
        delta,
        mode,
    )
}

/// [`savgol_filter`] with the FFT plans of long windows taken from (and cached in)
/// `planner`: callers that filter many signals of one length (the trials of a session)
/// plan each FFT length once. Same output, same errors.
///
/// # Errors
/// As [`savgol_filter`].
pub fn savgol_filter_planned(
    planner: &mut RealFftPlanner<f64>,
    x: &[f64],
    window: usize,
    polyorder: usize,
    deriv: usize,
    delta: f64,
    mode: EdgeMode,
) -> Result<Vec<f64>, SignalError> {
    check_window(window, polyorder)?;
    check_rate("delta", delta)?;
    let needed = if mode == EdgeMode::Interp { window } else { 1 };
    if x.len() < needed {
        return Err(SignalError::TooShort {
            needed,
            got: x.len(),
            what: "savgol_filter",
        });
    }
    check_finite(x)?;
    let n = x.len();
    let half = window / 2;
    let lsq = LsqFit::new(window, polyorder);
    let h = lsq.weights(deriv, delta, half as f64)?;
    let mut y = vec![0.0; n];
    if mode == EdgeMode::Interp {
        let inner = correlate_valid(planner, &h, x)?;
        y[half..n - half].copy_from_slice(&inner);
        // Edges: the polynomial fitted to the first / last window, evaluated at the
        // samples the centred filter cannot reach (scipy's `_fit_edges_polyfit`).
        let left = lsq.fit(&x[..window])?;
        let right = lsq.fit(&x[n - window..])?;
        for i in 0..half {
            y[i] = lsq.eval(&left, deriv, delta, i as f64);
            let pos = window - half + i;
            y[n - half + i] = lsq.eval(&right, deriv, delta, pos as f64);
        }
    } else {
        // Pad once by the mode, then every output is a plain dot product.
        let padded: Vec<f64> = (0..n + 2 * half)
            .map(|j| extended(x, j as isize - half as isize, mode))
            .collect();
        y = correlate_valid(planner, &h, &padded)?;
    }
    Ok(y)
}

/// `out[j] = Σ_k h[k]·s[j + k]` for every `j` where the window fits
/// (`s.len() − h.len() + 1` outputs). Long windows on long signals go through a
/// real FFT (O(n log n) instead of O(n·window): the seed's 253-tap filter on a
/// 14 000-sample trial); short ones are direct dot products.
fn correlate_valid(
    planner: &mut RealFftPlanner<f64>,
    h: &[f64],
    s: &[f64],
) -> Result<Vec<f64>, SignalError> {
    let w = h.len();
    let m = s.len();
    let n_out = m + 1 - w;
    if w < FFT_MIN_WINDOW || n_out < FFT_MIN_WINDOW {
        return Ok((0..n_out).map(|j| dot(h, &s[j..j + w])).collect());
    }
    let l = (m + w - 1).next_power_of_two();
    let forward = planner.plan_fft_forward(l);
    let inverse = planner.plan_fft_inverse(l);
    let fft_err = |e: realfft::FftError| SignalError::Fft(e.to_string());
    let mut a = forward.make_input_vec();
    a[..m].copy_from_slice(s);
    let mut b = forward.make_input_vec();
    for (dst, src) in b.iter_mut().zip(h.iter().rev()) {
        *dst = *src;
    }
    let mut fa = forward.make_output_vec();
    let mut fb = forward.make_output_vec();
    forward.process(&mut a, &mut fa).map_err(fft_err)?;
    forward.process(&mut b, &mut fb).map_err(fft_err)?;
    for (p, q) in fa.iter_mut().zip(&fb) {
        *p *= q;
    }
    // The DC and Nyquist bins of a real signal's spectrum are real.
    let last = fa.len() - 1;
    fa[0].im = 0.0;
    fa[last].im = 0.0;
    let mut full = inverse.make_output_vec();
    inverse.process(&mut fa, &mut full).map_err(fft_err)?;
    let scale = 1.0 / l as f64;
    Ok(full[w - 1..w - 1 + n_out]
        .iter()
        .map(|v| v * scale)
        .collect())
}

/// Windows (and output lengths) from which FFT correlation beats direct dot products.
const FFT_MIN_WINDOW: usize = 64;

/// Dot product with four independent partial sums, so that the additions pipeline
/// (a single running sum is bound by add latency; this is ~3x faster for the
/// seed's 253-sample window) at the same rounding order of magnitude.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (p, q) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += p[k] * q[k];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(p, q)| p * q).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}
