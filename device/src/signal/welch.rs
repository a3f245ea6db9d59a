//! Power spectral density by Welch's method, as `scipy.signal.welch(x, fs,
//! nperseg=nperseg)` with its defaults: periodic Hann window, 50 % overlap
//! (`noverlap = nperseg / 2`), `nfft = nperseg`, constant detrend per segment,
//! one-sided density scaling, mean over segments. Trailing samples that do not fill
//! a segment are ignored, as in scipy.

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

use super::error::{SignalError, check_finite, check_rate};

/// A one-sided power spectral density.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// Frequencies `k·fs/nperseg`, k = 0..=nperseg/2, in Hz.
    pub freq_hz: Vec<f64>,
    /// Density at each frequency, in `[x]²/Hz`.
    pub density: Vec<f64>,
}

/// scipy's `get_window('hann', n)` (periodic): `0.5 + 0.5·cos(−π + 2πk/n)`.
fn hann_periodic(n: usize) -> Vec<f64> {
    let step = 2.0 * std::f64::consts::PI / n as f64;
    (0..n)
        .map(|k| 0.5 + 0.5 * (k as f64 * step - std::f64::consts::PI).cos())
        .collect()
}

/// Welch PSD of `x` sampled at `fs_hz` with segments of `nperseg` samples.
///
/// # Errors
/// [`SignalError::BadWindow`] for `nperseg < 2`; [`SignalError::TooShort`] when `x`
/// is shorter than one segment (scipy would silently shorten the segment);
/// [`SignalError::BadRate`] for a bad `fs_hz`; [`SignalError::NonFinite`] for a bad
/// sample.
pub fn welch(x: &[f64], fs_hz: f64, nperseg: usize) -> Result<Psd, SignalError> {
    check_rate("fs_hz", fs_hz)?;
    if nperseg < 2 {
        return Err(SignalError::BadWindow {
            window: nperseg,
            why: "a Welch segment needs at least 2 samples",
        });
    }
    if x.len() < nperseg {
        return Err(SignalError::TooShort {
            needed: nperseg,
            got: x.len(),
            what: "welch (one segment)",
        });
    }
    check_finite(x)?;
    let noverlap = nperseg / 2;
    let step = nperseg - noverlap;
    let n_segments = (x.len() - noverlap) / step;
    let win = hann_periodic(nperseg);
    let scale = 1.0 / (fs_hz * win.iter().map(|w| w * w).sum::<f64>());
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(nperseg);
    let mut input = fft.make_input_vec();
    let mut spectrum = fft.make_output_vec();
    let n_freq = spectrum.len();
    let mut acc = vec![0.0; n_freq];
    for s in 0..n_segments {
        let seg = &x[s * step..s * step + nperseg];
        let mean = seg.iter().sum::<f64>() / nperseg as f64;
        for ((dst, v), w) in input.iter_mut().zip(seg).zip(&win) {
            *dst = (v - mean) * w;
        }
        fft.process(&mut input, &mut spectrum)
            .map_err(|e| SignalError::Fft(e.to_string()))?;
        for (a, c) in acc.iter_mut().zip(&spectrum) {
            *a += power(*c) * scale;
        }
    }
    // One-sided: double all but DC and, for even nperseg, Nyquist.
    let last_doubled = if nperseg.is_multiple_of(2) {
        n_freq - 1
    } else {
        n_freq
    };
    let density = acc
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let d = a / n_segments as f64;
            if k >= 1 && k < last_doubled {
                2.0 * d
            } else {
                d
            }
        })
        .collect();
    let freq_hz = (0..n_freq)
        .map(|k| k as f64 * fs_hz / nperseg as f64)
        .collect();
    Ok(Psd { freq_hz, density })
}

fn power(c: Complex<f64>) -> f64 {
    c.re * c.re + c.im * c.im
}
