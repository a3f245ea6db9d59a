//! Frequency content of the discrepancy: per channel, the Welch PSD
//! (`rigtwin_device::signal::welch`, Hann, 50 % overlap, segment mean removed) of the
//! measured trial, of the simulated one and of their difference, averaged over trials,
//! integrated over bands.
//!
//! A band's power is `Σ S(f) Δf` over the PSD bins with `lo ≤ f < hi`; its RMS is the
//! square root. `power_ratio` = simulated over measured band power (1: the simulation
//! has the measured amount of motion or force in that band); `diff_rms` is the RMS of
//! simulated − measured in the band (0: the two agree sample by sample there).

use rigtwin_device::signal::welch;
use serde::Serialize;

use rigtwin_session::Trial;

/// Channel names compared, in order (units in the names).
pub const CHANNELS: [&str; 6] = ["x_m", "y_m", "fx_n", "fy_n", "cmd_fx_n", "cmd_fy_n"];

/// The compared channels of a table, in [`CHANNELS`] order; a missing optional column is
/// empty.
pub fn channels_of(t: &Trial) -> [&[f64]; 6] {
    [
        &t.x_m,
        &t.y_m,
        &t.fx_n,
        &t.fy_n,
        t.cmd_fx_n.as_deref().unwrap_or(&[]),
        t.cmd_fy_n.as_deref().unwrap_or(&[]),
    ]
}

/// The bands reported, Hz: the reach itself (below 2 Hz), the corrections and the
/// perturbation response (2–8 Hz), and the fast part of the response and noise (8–30 Hz,
/// up to the estimator's Savitzky–Golay cut-off).
pub const BANDS_HZ: [[f64; 2]; 3] = [[0.0, 2.0], [2.0, 8.0], [8.0, 30.0]];

/// Welch segment length, s (0.5 Hz bins; a 3.5 s trial gives 2 segments at 50 %
/// overlap).
pub const SEGMENT_S: f64 = 2.0;

/// The discrepancy of one channel in one band.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandError {
    /// Column name (unit in the name).
    pub channel: String,
    /// `[lo, hi)`, Hz.
    pub band_hz: [f64; 2],
    /// Band RMS of the measured channel, its unit.
    pub measured_rms: f64,
    /// Band RMS of the simulated channel, its unit.
    pub simulated_rms: f64,
    /// Simulated over measured band power.
    pub power_ratio: f64,
    /// Band RMS of simulated − measured, the channel's unit.
    pub diff_rms: f64,
    /// Trials averaged.
    pub trials: usize,
}

/// `Σ S(f) Δf` over the bins of `[lo, hi)`.
pub(super) fn band_power(freq_hz: &[f64], density: &[f64], band: [f64; 2]) -> f64 {
    let df = freq_hz.get(1).copied().unwrap_or(0.0) - freq_hz.first().copied().unwrap_or(0.0);
    freq_hz
        .iter()
        .zip(density)
        .filter(|(f, _)| **f >= band[0] && **f < band[1])
        .map(|(_, s)| s * df)
        .sum()
}

/// Band errors per channel over the (measured, simulated) trial pairs at `rate_hz`.
/// A trial too short for one segment, or missing the channel in either table, is left
/// out of that channel; a channel no trial has is not reported.
#[must_use]
pub fn band_errors(pairs: &[(&Trial, &Trial)], rate_hz: f64) -> Vec<BandError> {
    let nperseg = (SEGMENT_S * rate_hz).round() as usize;
    let mut out = Vec::new();
    for (c, name) in CHANNELS.iter().enumerate() {
        // Per band: summed powers of measured, simulated, difference; trials.
        let mut acc = [[0.0_f64; 3]; BANDS_HZ.len()];
        let mut trials = 0;
        for (m, s) in pairs {
            let (mc, sc) = (channels_of(m)[c], channels_of(s)[c]);
            let n = mc.len().min(sc.len());
            if n == 0 || n < nperseg {
                continue;
            }
            let d: Vec<f64> = (0..n).map(|k| sc[k] - mc[k]).collect();
            let (Ok(pm), Ok(ps), Ok(pd)) = (
                welch(&mc[..n], rate_hz, nperseg),
                welch(&sc[..n], rate_hz, nperseg),
                welch(&d, rate_hz, nperseg),
            ) else {
                continue;
            };
            for (b, band) in BANDS_HZ.iter().enumerate() {
                acc[b][0] += band_power(&pm.freq_hz, &pm.density, *band);
                acc[b][1] += band_power(&ps.freq_hz, &ps.density, *band);
                acc[b][2] += band_power(&pd.freq_hz, &pd.density, *band);
            }
            trials += 1;
        }
        if trials == 0 {
            continue;
        }
        let n = trials as f64;
        for (b, band) in BANDS_HZ.iter().enumerate() {
            let [pm, ps, pd] = acc[b].map(|p| p / n);
            out.push(BandError {
                channel: (*name).to_owned(),
                band_hz: *band,
                measured_rms: pm.sqrt(),
                simulated_rms: ps.sqrt(),
                power_ratio: if pm > 0.0 { ps / pm } else { f64::NAN },
                diff_rms: pd.sqrt(),
                trials,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn trial(x: Vec<f64>) -> Trial {
        let n = x.len();
        Trial {
            t_s: (0..n).map(|i| i as f64 / 1000.0).collect(),
            x_m: x,
            y_m: vec![0.0; n],
            fx_n: vec![0.0; n],
            fy_n: vec![0.0; n],
            pert_fx_n: vec![0.0; n],
            pert_fy_n: vec![0.0; n],
            vx_m_per_s: None,
            vy_m_per_s: None,
            ref_x_m: None,
            ref_y_m: None,
            cmd_fx_n: None,
            cmd_fy_n: None,
            extra: Vec::new(),
        }
    }

    #[test]
    fn a_sinusoid_lands_in_its_band_with_its_rms() {
        // 5 Hz of amplitude 1 mm has RMS 1/√2 mm: all of it in 2-8 Hz, within the Hann
        // window's leakage (< 1 % of the power outside the main lobe's ±1 Hz).
        let x: Vec<f64> = (0..4000)
            .map(|i| 1e-3 * (std::f64::consts::TAU * 5.0 * i as f64 / 1000.0).sin())
            .collect();
        let zero = trial(vec![0.0; 4000]);
        let meas = trial(x);
        let b = band_errors(&[(&meas, &zero)], 1000.0);
        let mid = b
            .iter()
            .find(|e| e.channel == "x_m" && e.band_hz == [2.0, 8.0])
            .unwrap();
        assert!(
            (mid.measured_rms - 1e-3 / 2f64.sqrt()).abs() < 0.01e-3,
            "{mid:?}"
        );
        // The simulation is 0, so the difference is the measured signal itself.
        assert!((mid.diff_rms - mid.measured_rms).abs() < 1e-12);
        assert_eq!(mid.power_ratio, 0.0);
        let low = b
            .iter()
            .find(|e| e.channel == "x_m" && e.band_hz == [0.0, 2.0])
            .unwrap();
        assert!(low.measured_rms < 0.01e-3, "{low:?}");
    }
}
