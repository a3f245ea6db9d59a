//! The PSD comparison that picks the high-pass cut-off (000_* section 4.3): Welch
//! spectra of the jerk of unperturbed and perturbed movements along one axis,
//! averaged over trials; the unperturbed spectral peak, the unperturbed level at a
//! candidate cut-off in dB re that peak (seed: peak 0.6385 Hz, −2.913 dB at 1 Hz),
//! and the frequency above which the perturbed spectrum exceeds the unperturbed one.

use super::error::{EstimateError, check_positive};
use crate::signal::{EdgeMode, savgol_filter, savgol_window_for_cutoff, welch};

/// Settings of [`compare_jerk_spectra`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectrumConfig {
    /// Savitzky–Golay polynomial order for the jerk (seed: 5).
    pub savgol_polyorder: usize,
    /// Savitzky–Golay cut-off, Hz (seed: 30).
    pub savgol_cutoff_hz: f64,
    /// Welch segment length, samples; the frequency resolution is `fs / nperseg`.
    pub nperseg: usize,
    /// The candidate high-pass cut-off at which the unperturbed level is reported, Hz.
    pub candidate_cutoff_hz: f64,
    /// How far (dB) the perturbed spectrum must exceed the unperturbed one to count
    /// as diverged (the seed: "significantly larger").
    pub divergence_db: f64,
}

/// Result of [`compare_jerk_spectra`].
#[derive(Debug, Clone, PartialEq)]
pub struct JerkSpectra {
    /// Frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Mean unperturbed jerk PSD, (m/s³)²/Hz.
    pub unperturbed: Vec<f64>,
    /// Mean perturbed jerk PSD, (m/s³)²/Hz.
    pub perturbed: Vec<f64>,
    /// Frequency of the unperturbed spectral peak (DC excluded), Hz, refined by a
    /// parabola through the log-density of the peak bin and its neighbours.
    pub unperturbed_peak_hz: f64,
    /// Unperturbed level at `candidate_cutoff_hz` relative to the peak bin, dB
    /// (linear interpolation between bins).
    pub level_at_cutoff_db: f64,
    /// Lowest frequency above the unperturbed peak at which the perturbed spectrum
    /// exceeds the unperturbed one by `divergence_db` (interpolated in dB between
    /// bins), Hz; `None` if it never does.
    pub divergence_hz: Option<f64>,
}

fn mean_jerk_psd(
    trials: &[&[f64]],
    fs_hz: f64,
    window: usize,
    config: &SpectrumConfig,
) -> Result<(Vec<f64>, Vec<f64>), EstimateError> {
    let mut freq = Vec::new();
    let mut sum: Vec<f64> = Vec::new();
    for x in trials {
        let jerk = savgol_filter(
            x,
            window,
            config.savgol_polyorder,
            3,
            1.0 / fs_hz,
            EdgeMode::Interp,
        )
        .map_err(EstimateError::signal(
            "differentiating to jerk (Savitzky-Golay)",
        ))?;
        let psd = welch(&jerk, fs_hz, config.nperseg)
            .map_err(EstimateError::signal("estimating the jerk PSD (Welch)"))?;
        if sum.is_empty() {
            freq = psd.freq_hz;
            sum = psd.density;
        } else {
            for (s, d) in sum.iter_mut().zip(&psd.density) {
                *s += d;
            }
        }
    }
    let n = trials.len() as f64;
    Ok((freq, sum.into_iter().map(|s| s / n).collect()))
}

/// Compares the jerk spectra of unperturbed and perturbed movements (000_* section
/// 4.3). Each trial is the position along the analysed axis, m, at `fs_hz`.
///
/// # Errors
/// [`EstimateError::TooShort`] for an empty set; [`EstimateError::Signal`] for a
/// trial shorter than the Savitzky–Golay window or `nperseg`, or non-finite data;
/// [`EstimateError::BadParameter`] for bad settings or an all-zero spectrum.
pub fn compare_jerk_spectra(
    unperturbed_m: &[&[f64]],
    perturbed_m: &[&[f64]],
    fs_hz: f64,
    config: &SpectrumConfig,
) -> Result<JerkSpectra, EstimateError> {
    check_positive("fs_hz", fs_hz)?;
    check_positive("candidate_cutoff_hz", config.candidate_cutoff_hz)?;
    for (what, set) in [
        ("unperturbed trials", unperturbed_m),
        ("perturbed trials", perturbed_m),
    ] {
        if set.is_empty() {
            return Err(EstimateError::TooShort {
                what,
                needed: 1,
                got: 0,
            });
        }
    }
    let window = savgol_window_for_cutoff(config.savgol_polyorder, config.savgol_cutoff_hz, fs_hz)
        .map_err(EstimateError::signal("choosing the Savitzky-Golay window"))?;
    let (freq_hz, unperturbed) = mean_jerk_psd(unperturbed_m, fs_hz, window, config)?;
    let (_, perturbed) = mean_jerk_psd(perturbed_m, fs_hz, window, config)?;
    if freq_hz.len() < 3 {
        return Err(EstimateError::TooShort {
            what: "spectrum (frequency bins)",
            needed: 3,
            got: freq_hz.len(),
        });
    }
    // Peak, DC excluded.
    let (i_peak, p_peak) =
        unperturbed
            .iter()
            .enumerate()
            .skip(1)
            .fold(
                (1, f64::MIN),
                |acc, (i, p)| if *p > acc.1 { (i, *p) } else { acc },
            );
    if !(p_peak > 0.0 && p_peak.is_finite()) {
        return Err(EstimateError::BadParameter {
            what: "unperturbed jerk PSD peak",
            value: p_peak,
            why: "the unperturbed jerk has no power",
        });
    }
    let df = freq_hz[1] - freq_hz[0];
    let mut unperturbed_peak_hz = freq_hz[i_peak];
    if i_peak + 1 < unperturbed.len()
        && unperturbed[i_peak - 1] > 0.0
        && unperturbed[i_peak + 1] > 0.0
    {
        let (l, c, r) = (
            unperturbed[i_peak - 1].ln(),
            p_peak.ln(),
            unperturbed[i_peak + 1].ln(),
        );
        let denom = l - 2.0 * c + r;
        if denom < 0.0 {
            unperturbed_peak_hz += 0.5 * (l - r) / denom * df;
        }
    }
    let level = interp(&freq_hz, &unperturbed, config.candidate_cutoff_hz);
    let level_at_cutoff_db = 10.0 * (level / p_peak).log10();
    let ratio_db: Vec<f64> = perturbed
        .iter()
        .zip(&unperturbed)
        .map(|(p, u)| 10.0 * (p / u).log10())
        .collect();
    let mut divergence_hz = None;
    for i in (i_peak + 1)..ratio_db.len() {
        if ratio_db[i] >= config.divergence_db {
            let (r0, r1) = (ratio_db[i - 1], ratio_db[i]);
            let frac = if r1 > r0 && r0.is_finite() {
                ((config.divergence_db - r0) / (r1 - r0)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            divergence_hz = Some(freq_hz[i - 1] + frac * df);
            break;
        }
    }
    Ok(JerkSpectra {
        freq_hz,
        unperturbed,
        perturbed,
        unperturbed_peak_hz,
        level_at_cutoff_db,
        divergence_hz,
    })
}

/// Linear interpolation of `y(x)` at `x0` on ascending `x`, clamped at the ends.
fn interp(x: &[f64], y: &[f64], x0: f64) -> f64 {
    match x.iter().position(|v| *v >= x0) {
        None => y.last().copied().unwrap_or(f64::NAN),
        Some(0) => y.first().copied().unwrap_or(f64::NAN),
        Some(i) => {
            let t = (x0 - x[i - 1]) / (x[i] - x[i - 1]);
            y[i - 1] + t * (y[i] - y[i - 1])
        }
    }
}
