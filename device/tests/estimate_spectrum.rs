//! The jerk-PSD comparison of 000_* section 4.3 on a minimum-jerk reach with and
//! without the Table-1 system's pulse response, against values scipy gives for the
//! same construction:
//!
//! ```text
//! j = savgol_filter(x, 253, 5, deriv=3, delta=1/4000); f, p = welch(j, 4000, nperseg=8000)
//! mean over the 8 angles -> unperturbed peak bin 0.5 Hz, level at 1 Hz -5.120 dB re peak,
//! perturbed/unperturbed ratio 4.97 dB at 0.5 Hz and 16.2 dB at 1.0 Hz
//! ```
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::needless_range_loop)]

#[path = "estimate_support.rs"]
mod support;

use rigtwin_device::estimate::{SpectrumConfig, compare_jerk_spectra};
use support::*;

/// Named `estimate` so that `cargo test -p rigtwin-device estimate` selects these tests.
mod estimate {
    use super::*;

    #[test]
    fn min_jerk_reach_peaks_below_the_cutoff_and_the_pulse_response_diverges_above_it() {
        let fs = 4000.0;
        let n = 16_000; // 4 s
        // Minimum-jerk reach 0.30 -> 0.55 m in 3 s starting at 0.5 s (000_* section 4.1-4.2).
        let reach: Vec<f64> = (0..n)
            .map(|i| {
                let tau = ((i as f64 / fs - 0.5) / 3.0).clamp(0.0, 1.0);
                0.30 + 0.25 * (10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5))
            })
            .collect();
        let m = add(&add(&M_ADM, &M_HANDLE), &M_ARM);
        let d = add(&D_ADM, &D_TABLE1);
        let perturbed: Vec<Vec<f64>> = ANGLES_DEG
            .iter()
            .map(|phi| {
                let s = simulate_pulse(
                    &m,
                    &d,
                    &K_TABLE1,
                    *phi,
                    15.0,
                    0.15,
                    fs,
                    3.5,
                    1.5,
                    2,
                    [0.0, 0.0],
                );
                let mut x = reach.clone();
                // Response placed so that its onset falls at 2.0 s.
                for (i, r) in s.x_m[1].iter().enumerate() {
                    if 2000 + i < n {
                        x[2000 + i] += r;
                    }
                }
                x
            })
            .collect();
        let unperturbed: Vec<&[f64]> = (0..8).map(|_| reach.as_slice()).collect();
        let perturbed: Vec<&[f64]> = perturbed.iter().map(Vec::as_slice).collect();
        let config = SpectrumConfig {
            savgol_polyorder: 5,
            savgol_cutoff_hz: 30.0,
            nperseg: 8000,
            candidate_cutoff_hz: 1.0,
            divergence_db: 3.0,
        };
        let s = compare_jerk_spectra(&unperturbed, &perturbed, fs, &config).unwrap();
        println!(
            "peak {:.4} Hz, level at 1 Hz {:.3} dB, divergence {:?} Hz",
            s.unperturbed_peak_hz, s.level_at_cutoff_db, s.divergence_hz
        );
        // Peak within one 0.5 Hz bin of scipy's peak bin (the parabola refines it).
        assert!((s.unperturbed_peak_hz - 0.5).abs() <= 0.25);
        // 1 Hz is a bin centre: the level equals scipy's to 0.01 dB (same SG, Welch).
        assert!(
            (s.level_at_cutoff_db - (-5.120)).abs() < 0.01,
            "{}",
            s.level_at_cutoff_db
        );
        // The ratio already exceeds 3 dB at the first bin above the peak's bin region:
        // divergence between 0.5 and 1.0 Hz (scipy: 4.97 dB at 0.5 Hz).
        let div = s.divergence_hz.unwrap();
        assert!((0.5..=1.0).contains(&div), "{div}");
    }
}
