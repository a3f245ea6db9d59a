//! The Piovesan windowed regression (001_*) against a passive spring-mass-damper
//! of known K, B, M under the seed's protocol: a ±10 cm, 0.125 Hz imposed sinusoid,
//! 8 mm / 300 ms min-snap position perturbations twice per cycle, 25 cycles,
//! windows of 10 cycles, sampled at the HapticMaster's 250 Hz.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::needless_range_loop)]

#[path = "estimate_support.rs"]
mod support;

use rigtwin_device::estimate::{
    CovarianceKind, ImposedMotionTrial, PiovesanConfig, PositionPerturbation, windowed_impedance,
};
use support::*;

/// Named `estimate` so that `cargo test -p rigtwin-device estimate` selects these tests.
mod estimate {
    use super::*;

    const FS_HZ: f64 = 250.0;
    const M_RIG: Mat2 = [[1.87, 0.0], [0.0, 1.87]];
    /// Appendix B's diagonal plus a symmetric coupling, N/m.
    const K_RIG: Mat2 = [[615.0, 40.0], [40.0, 507.0]];
    const B_RIG: Mat2 = [[6.0, 1.5], [1.5, 5.0]];

    fn run(k: &Mat2, noise_n: f64, seed: u64) -> Vec<rigtwin_device::estimate::WindowEstimate> {
        let trial = imposed_motion(&M_RIG, &B_RIG, k, FS_HZ, 25, 1, noise_n, seed);
        let perts: Vec<PositionPerturbation> = trial
            .perturbations
            .iter()
            .map(|(onset_index, cycle)| PositionPerturbation {
                onset_index: *onset_index,
                cycle: *cycle,
            })
            .collect();
        let view = ImposedMotionTrial {
            x_m: [&trial.x_m[0], &trial.x_m[1]],
            force_n: [&trial.force_n[0], &trial.force_n[1]],
            perturbations: &perts,
            n_cycles: trial.n_cycles,
        };
        windowed_impedance(&view, FS_HZ, &M_RIG, &PiovesanConfig::default()).unwrap()
    }

    #[test]
    fn noiseless_rig_gives_sixteen_windows_with_k_and_b_within_one_percent() {
        let windows = run(&K_RIG, 0.0, 7);
        // 25 cycles, N_w = 10: N_WT = 25 − 9 = 16 (001_*).
        assert_eq!(windows.len(), 16);
        let mut worst_k: f64 = 0.0;
        let mut worst_b: f64 = 0.0;
        let mut min_r2: f64 = 1.0;
        for w in &windows {
            assert_eq!(w.n_perturbations, 20);
            assert_eq!(w.covariance_kind, CovarianceKind::Jackknife);
            for i in 0..2 {
                for j in 0..2 {
                    // Relative to the largest entry of the matrix: the off-diagonals are
                    // small and their absolute error is what matters.
                    worst_k = worst_k.max((w.k_n_per_m[i][j] - K_RIG[i][j]).abs() / 615.0);
                    worst_b = worst_b.max((w.b_ns_per_m[i][j] - B_RIG[i][j]).abs() / 6.0);
                }
            }
            min_r2 = min_r2.min(w.canonical_r2);
        }
        println!(
            "worst K error {:.4} %, worst B error {:.4} %, min r2 {min_r2:.6}",
            100.0 * worst_k,
            100.0 * worst_b
        );
        // The estimator filters position and force with the same Savitzky–Golay
        // smoother and the system is exactly linear: 1 % of the largest entry.
        assert!(worst_k < 0.01, "K error {worst_k}");
        assert!(worst_b < 0.01, "B error {worst_b}");
        // A linear system: canonical correlation near 1 (the rig of Appendix B gave 0.96).
        assert!(min_r2 > 0.99, "r2 {min_r2}");
    }

    #[test]
    fn passive_rig_with_force_noise_shows_no_significant_curl() {
        // 0.3 N RMS force-sensor noise. A passive rig has K12 = K21; the seed found
        // no significant curl in any of 16 windows (Table 5, p < 0.01). With 16
        // independent-ish tests at α = 0.01 a false alarm has probability ~15 %, so the
        // assertion allows at most one.
        let windows = run(&K_RIG, 0.3, 11);
        let flagged = windows
            .iter()
            .filter(|w| w.stiffness_curl(0.01).unwrap().significant)
            .count();
        println!("windows with significant curl: {flagged}");
        assert!(
            flagged <= 1,
            "{flagged} of 16 windows show curl on a passive rig"
        );
        // And the estimate stays within 3.3 standard errors of the truth on the diagonal.
        for w in &windows {
            for i in 0..2 {
                let z = (w.k_n_per_m[i][i] - K_RIG[i][i]) / w.k_std_err_n_per_m[i][i];
                assert!(z.abs() < 3.3, "window {}: K{i}{i} z = {z}", w.first_cycle);
            }
        }
    }

    #[test]
    fn curl_of_a_non_conservative_field_is_detected() {
        // K12 − K21 = 80 N/m (curl 40 N/m), far above what 0.3 N of noise can hide.
        let k_curl: Mat2 = [[615.0, 80.0], [0.0, 507.0]];
        let windows = run(&k_curl, 0.3, 13);
        for w in &windows {
            let t = w.stiffness_curl(0.01).unwrap();
            assert!(
                t.significant,
                "window {}: curl {} ± {}",
                w.first_cycle, t.curl, t.std_err
            );
            // The estimated curl within 10 % of −40 N/m ((K21 − K12)/2).
            assert!((t.curl + 40.0).abs() < 4.0, "curl {}", t.curl);
        }
    }
}
