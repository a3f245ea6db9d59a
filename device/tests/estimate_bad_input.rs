//! Bad input to the estimators gives typed errors, never a panic: too-short
//! records and windows, non-finite samples, rank-deficient regressors,
//! perturbations running off the end of a trial.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::needless_range_loop,
    clippy::single_range_in_vec_init
)]

#[path = "estimate_support.rs"]
mod support;

use proptest::prelude::*;
use rigtwin_device::estimate::{
    Admittance, BornerConfig, EstimateError, ImposedMotionTrial, PerturbedTrial, PiovesanConfig,
    PositionPerturbation, canonical_correlation, cycle_force_measures,
    estimate_involuntary_impedance, perturbation_responses, windowed_impedance,
};
use support::*;

/// Named `estimate` so that `cargo test -p rigtwin-device estimate` selects these tests.
mod estimate {
    use super::*;

    fn admittance() -> Admittance {
        Admittance {
            m_adm_kg: M_ADM,
            d_adm_ns_per_m: D_ADM,
            m_handle_kg: M_HANDLE,
        }
    }

    fn sim(phi: f64) -> SimTrial {
        let m = add(&add(&M_ADM, &M_HANDLE), &M_ARM);
        simulate_pulse(
            &m,
            &add(&D_ADM, &D_TABLE1),
            &K_TABLE1,
            phi,
            15.0,
            0.15,
            4000.0,
            2.0,
            0.8,
            1,
            [0.0, 0.4],
        )
    }

    fn view(s: &SimTrial) -> PerturbedTrial<'_> {
        PerturbedTrial {
            x_m: [&s.x_m[0], &s.x_m[1]],
            u_pert_n: [&s.u_n[0], &s.u_n[1]],
            onset_index: s.onset_index,
        }
    }

    #[test]
    fn perturbation_running_off_the_end_is_a_typed_error() {
        let s = sim(30.0);
        let mut t = view(&s);
        // T_est = 150 ms = 601 samples at 4 kHz: an onset 100 samples from the end fails.
        t.onset_index = s.x_m[0].len() - 100;
        let err = estimate_involuntary_impedance(
            &[t],
            4000.0,
            &admittance(),
            &M_ARM,
            &BornerConfig::default(),
        )
        .unwrap_err();
        assert_eq!(
            err,
            EstimateError::PerturbationBeyondRecord {
                onset_index: t.onset_index,
                needed_end: t.onset_index + 601,
                len: s.x_m[0].len()
            }
        );
    }

    #[test]
    fn nan_sample_is_reported_with_its_index() {
        let mut s = sim(30.0);
        s.x_m[1][1234] = f64::NAN;
        let err = estimate_involuntary_impedance(
            &[view(&s)],
            4000.0,
            &admittance(),
            &M_ARM,
            &BornerConfig::default(),
        )
        .unwrap_err();
        assert_eq!(
            err,
            EstimateError::NonFinite {
                what: "position",
                index: 1234
            }
        );
    }

    #[test]
    fn one_direction_on_an_isotropic_system_is_rank_deficient() {
        // Isotropic, uncoupled system pushed along x only: Δx₂ ≡ 0, so the columns of
        // D12, D22, K12 (row 2), K22 vanish and ζ̄ is not determined.
        let iso = [[1.0, 0.0], [0.0, 1.0]];
        let m = add(&add(&M_ADM, &M_HANDLE), &iso);
        let s = simulate_pulse(
            &m,
            &add(&D_ADM, &[[10.0, 0.0], [0.0, 10.0]]),
            &[[200.0, 0.0], [0.0, 200.0]],
            0.0,
            15.0,
            0.15,
            4000.0,
            2.0,
            0.8,
            1,
            [0.0, 0.0],
        );
        let err = estimate_involuntary_impedance(
            &[view(&s), view(&s), view(&s)],
            4000.0,
            &admittance(),
            &iso,
            &BornerConfig::default(),
        )
        .unwrap_err();
        assert!(
            matches!(err, EstimateError::RankDeficient { .. }),
            "{err:?}"
        );
    }

    #[test]
    fn record_shorter_than_the_savgol_window_is_a_signal_error() {
        let x = vec![0.0; 200]; // window at 4 kHz, 30 Hz, order 5 is 253 samples
        let t = PerturbedTrial {
            x_m: [&x, &x],
            u_pert_n: [&x, &x],
            onset_index: 0,
        };
        let cfg = BornerConfig {
            t_est_s: 0.01,
            ..BornerConfig::default()
        };
        let err =
            estimate_involuntary_impedance(&[t], 4000.0, &admittance(), &M_ARM, &cfg).unwrap_err();
        assert!(matches!(err, EstimateError::Signal { .. }), "{err:?}");
    }

    #[test]
    fn piovesan_trial_with_fewer_cycles_than_a_window_is_too_short() {
        let x = vec![0.0; 5000];
        let perts = [PositionPerturbation {
            onset_index: 100,
            cycle: 0,
        }];
        let t = ImposedMotionTrial {
            x_m: [&x, &x],
            force_n: [&x, &x],
            perturbations: &perts,
            n_cycles: 5,
        };
        let err = windowed_impedance(
            &t,
            250.0,
            &[[1.0, 0.0], [0.0, 1.0]],
            &PiovesanConfig::default(),
        )
        .unwrap_err();
        assert_eq!(
            err,
            EstimateError::TooShort {
                what: "trial (cycles) for one window",
                needed: 10,
                got: 5
            }
        );
    }

    #[test]
    fn piovesan_baseline_past_the_end_is_a_typed_error() {
        let x = vec![0.0; 1000];
        // Baseline 0.7 s = 175 samples at 250 Hz: onset 900 needs sample 1075.
        let perts = [PositionPerturbation {
            onset_index: 900,
            cycle: 0,
        }];
        let t = ImposedMotionTrial {
            x_m: [&x, &x],
            force_n: [&x, &x],
            perturbations: &perts,
            n_cycles: 1,
        };
        let err = perturbation_responses(&t, 250.0, &PiovesanConfig::default()).unwrap_err();
        assert_eq!(
            err,
            EstimateError::PerturbationBeyondRecord {
                onset_index: 900,
                needed_end: 1076,
                len: 1000
            }
        );
    }

    fn sample() -> impl Strategy<Value = f64> {
        prop_oneof![
            8 => -1.0..1.0f64,
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
            1 => Just(0.0),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        /// Any lengths, onsets, sample rates and sample values: the Börner estimator
        /// returns Ok or a typed error, never panics.
        #[test]
        fn borner_never_panics(
            x1 in prop::collection::vec(sample(), 0..700),
            x2 in prop::collection::vec(sample(), 0..700),
            onset in 0usize..800,
            fs in prop_oneof![Just(4000.0), Just(250.0), Just(0.0), Just(-1.0), Just(f64::NAN), 1.0..10_000.0f64],
            t_est in prop_oneof![Just(0.15), Just(0.0), Just(1e-6), Just(f64::INFINITY), 0.0..0.5f64],
        ) {
            let t = PerturbedTrial { x_m: [&x1, &x2], u_pert_n: [&x2, &x1], onset_index: onset };
            let cfg = BornerConfig { t_est_s: t_est, ..BornerConfig::default() };
            let _ = estimate_involuntary_impedance(&[t, t, t], fs, &admittance(), &M_ARM, &cfg);
        }

        /// The same for the Piovesan regression and the eq. 8 / eq. 9 helpers.
        #[test]
        fn piovesan_never_panics(
            x in prop::collection::vec(sample(), 0..600),
            f in prop::collection::vec(sample(), 0..600),
            onsets in prop::collection::vec((0usize..700, 0usize..12), 0..6),
            n_cycles in 0usize..12,
            fs in prop_oneof![Just(250.0), Just(0.0), 1.0..5000.0f64],
        ) {
            let perts: Vec<PositionPerturbation> = onsets.iter().map(|(o, c)| PositionPerturbation { onset_index: *o, cycle: *c }).collect();
            let t = ImposedMotionTrial { x_m: [&x, &f], force_n: [&f, &x], perturbations: &perts, n_cycles };
            let cfg = PiovesanConfig { window_cycles: 2, ..PiovesanConfig::default() };
            let _ = windowed_impedance(&t, fs, &[[1.0, 0.0], [0.0, 1.0]], &cfg);
            let n = x.len().min(f.len());
            let force: Vec<[f64; 2]> = (0..n).map(|i| [x[i], f[i]]).collect();
            let kin: Vec<[f64; 4]> = (0..n).map(|i| [f[i], x[i], x[i] * 2.0, f[i] - x[i]]).collect();
            let _ = canonical_correlation(&force, &kin);
            let bounds: Vec<usize> = onsets.iter().map(|(o, _)| *o).collect();
            let _ = cycle_force_measures(&f, 10.0, &bounds, &[3..9]);
        }
    }
}
