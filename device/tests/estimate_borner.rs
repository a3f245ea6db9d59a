//! The Börner involuntary-impedance estimator (000_* eq. 19–32) against linear
//! 2-DoF systems of known D and K coupled to the admittance.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::needless_range_loop)]

#[path = "estimate_support.rs"]
mod support;

use rigtwin_device::estimate::{
    Admittance, BornerConfig, CovarianceKind, PerturbedTrial, VariationalMode,
    estimate_involuntary_impedance,
};
use support::*;

/// Named `estimate` so that `cargo test -p rigtwin-device estimate` selects these tests.
mod estimate {
    use super::*;

    const FS_HZ: f64 = 4000.0;

    fn admittance() -> Admittance {
        Admittance {
            m_adm_kg: M_ADM,
            d_adm_ns_per_m: D_ADM,
            m_handle_kg: M_HANDLE,
        }
    }

    /// The eight seed angles, 15 N, 150 ms pulses (000_* section 4.2), at rest at the
    /// seed's perturbation point (0, 0.4) m, 3.5 s records with the onset at 1.5 s.
    fn table1_trials(reps: usize) -> Vec<SimTrial> {
        let m_total = add(&add(&M_ADM, &M_HANDLE), &M_ARM);
        let d_total = add(&D_ADM, &D_TABLE1);
        (0..reps)
            .flat_map(|_| ANGLES_DEG.iter())
            .map(|phi| {
                simulate_pulse(
                    &m_total,
                    &d_total,
                    &K_TABLE1,
                    *phi,
                    15.0,
                    0.150,
                    FS_HZ,
                    3.5,
                    1.5,
                    8,
                    [0.0, 0.4],
                )
            })
            .collect()
    }

    fn views(trials: &[SimTrial]) -> Vec<PerturbedTrial<'_>> {
        trials
            .iter()
            .map(|t| PerturbedTrial {
                x_m: [&t.x_m[0], &t.x_m[1]],
                u_pert_n: [&t.u_n[0], &t.u_n[1]],
                onset_index: t.onset_index,
            })
            .collect()
    }

    fn truth() -> [f64; 7] {
        let (d, k) = (D_TABLE1, K_TABLE1);
        [
            d[0][0], d[0][1], d[1][0], d[1][1], k[0][0], k[0][1], k[1][1],
        ]
    }

    #[test]
    fn consistent_mode_recovers_table1_within_one_percent_without_noise() {
        let sims = table1_trials(1);
        let config = BornerConfig {
            mode: VariationalMode::Consistent,
            ..BornerConfig::default()
        };
        let est =
            estimate_involuntary_impedance(&views(&sims), FS_HZ, &admittance(), &M_ARM, &config)
                .unwrap();
        // Exact filtering of force and kinematics leaves only discretisation and the
        // filters' edge handling: every parameter within 1 % of the truth.
        for (i, (e, t)) in est.params.iter().zip(truth()).enumerate() {
            let r = rel(*e, t);
            println!("param {i}: est {e:.4} truth {t:.4} rel {:.4} %", 100.0 * r);
            assert!(r < 0.01, "param {i}: {e} vs {t} ({:.3} %)", 100.0 * r);
        }
        // K is symmetric by construction (eq. 30).
        assert_eq!(est.k_n_per_m[0][1], est.k_n_per_m[1][0]);
        assert_eq!(est.covariance_kind, CovarianceKind::Jackknife);
        println!(
            "condition {:.1}, nrmse {:.2e}",
            est.condition_number, est.nrmse
        );
    }

    #[test]
    fn seed_mode_variational_kinematics_meet_the_seed_nrmse_bounds() {
        // 000_* section 4.3: NRMSE (normalised by the largest value in [0, 150] ms)
        // below 5 % for position and velocity and 7.5 % for acceleration. Here the
        // truth is the simulated response itself (the system starts at rest).
        let sims = table1_trials(1);
        let config = BornerConfig::default();
        let est =
            estimate_involuntary_impedance(&views(&sims), FS_HZ, &admittance(), &M_ARM, &config)
                .unwrap();
        let mut worst = [0.0_f64; 3];
        for (sim, vd) in sims.iter().zip(&est.variational) {
            let k0 = sim.onset_index;
            let n = vd.dx_m.len();
            for axis in 0..2 {
                let x: Vec<f64> = sim.x_m[axis][k0..k0 + n]
                    .iter()
                    .map(|v| v - sim.x_m[axis][0])
                    .collect();
                let v: Vec<f64> = (0..n)
                    .map(|i| {
                        (x[(i + 1).min(n - 1)] - x[i.saturating_sub(1)]) * FS_HZ
                            / if i == 0 || i == n - 1 { 1.0 } else { 2.0 }
                    })
                    .collect();
                let a: Vec<f64> = (0..n)
                    .map(|i| {
                        (v[(i + 1).min(n - 1)] - v[i.saturating_sub(1)]) * FS_HZ
                            / if i == 0 || i == n - 1 { 1.0 } else { 2.0 }
                    })
                    .collect();
                let est_x: Vec<f64> = vd.dx_m.iter().map(|p| p[axis]).collect();
                let est_v: Vec<f64> = vd.dv_m_per_s.iter().map(|p| p[axis]).collect();
                let est_a: Vec<f64> = vd.da_m_per_s2.iter().map(|p| p[axis]).collect();
                for (w, (t, e)) in worst
                    .iter_mut()
                    .zip([(&x, &est_x), (&v, &est_v), (&a, &est_a)])
                {
                    // Ends of the finite-difference truth are first order; skip them.
                    let peak = t.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    let rms = (t[1..n - 1]
                        .iter()
                        .zip(&e[1..n - 1])
                        .map(|(a, b)| (a - b).powi(2))
                        .sum::<f64>()
                        / (n - 2) as f64)
                        .sqrt();
                    *w = w.max(rms / peak);
                }
            }
        }
        println!(
            "worst NRMSE x {:.3} %, v {:.3} %, a {:.3} %",
            100.0 * worst[0],
            100.0 * worst[1],
            100.0 * worst[2]
        );
        assert!(
            worst[0] < 0.05 && worst[1] < 0.05,
            "position/velocity NRMSE {worst:?}"
        );
        assert!(worst[2] < 0.075, "acceleration NRMSE {worst:?}");
        for (i, (e, t)) in est.params.iter().zip(truth()).enumerate() {
            println!(
                "seed mode param {i}: est {e:.3} truth {t:.3} rel {:.1} %",
                100.0 * rel(*e, t)
            );
        }
    }

    #[test]
    fn with_position_noise_the_truth_lies_inside_the_jackknife_interval() {
        // 24 trials (3 x 8 angles, as the seed's session), white position noise of
        // 5 µm RMS (five encoder quanta) on both axes.
        let mut sims = table1_trials(3);
        for (t, sim) in sims.iter_mut().enumerate() {
            for axis in 0..2 {
                let noise = gaussian_noise(sim.x_m[axis].len(), 5e-6, 1000 + (2 * t + axis) as u64);
                for (x, n) in sim.x_m[axis].iter_mut().zip(noise) {
                    *x += n;
                }
            }
        }
        let config = BornerConfig {
            mode: VariationalMode::Consistent,
            ..BornerConfig::default()
        };
        let est =
            estimate_involuntary_impedance(&views(&sims), FS_HZ, &admittance(), &M_ARM, &config)
                .unwrap();
        assert_eq!(est.covariance_kind, CovarianceKind::Jackknife);
        for (i, t) in truth().iter().enumerate() {
            let e = est.params[i];
            let se = est.covariance[i][i].sqrt();
            println!(
                "param {i}: est {e:.3} truth {t:.3} se {se:.3} z {:.2}",
                (e - t) / se
            );
            // 3.3 standard errors: a 0.1 % two-sided miss per parameter if the
            // jackknife is honest; it would fail at this level if the interval were
            // the ordinary one (residuals autocorrelated at 4 kHz).
            assert!((e - t).abs() <= 3.3 * se, "param {i}: {e} vs {t}, se {se}");
            // And the interval is informative: below 25 % of the largest |truth| of its block.
            let scale = if i < 4 { 10.98 } else { 313.75 };
            assert!(
                se < 0.25 * scale,
                "param {i}: se {se} too wide to mean anything"
            );
        }
    }
}
