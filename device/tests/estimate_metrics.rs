//! Ellipse metrics, curl test, Z(ω), force errors and skill gain (001_* eq. 9–13)
//! against closed forms.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::needless_range_loop,
    clippy::single_range_in_vec_init
)]

use rigtwin_device::estimate::{
    CycleForce, EstimateError, canonical_correlation, curl_test, cycle_force_measures,
    ellipse_metrics, impedance_at, sign_correlation, skill_gain, stiffness_change,
    window_force_errors,
};

/// Named `estimate` so that `cargo test -p rigtwin-device estimate` selects these tests.
mod estimate {
    use super::*;

    /// `R(θ) diag(a, b) R(θ)ᵀ`.
    fn rotated(a: f64, b: f64, theta_deg: f64) -> [[f64; 2]; 2] {
        let (s, c) = theta_deg.to_radians().sin_cos();
        [
            [a * c * c + b * s * s, (a - b) * c * s],
            [(a - b) * c * s, a * s * s + b * c * c],
        ]
    }

    #[test]
    fn ellipse_of_a_rotated_diagonal_stiffness_has_its_axes_and_angle() {
        // Appendix B's K = diag(615, 507) turned by 30°: principal values, angle,
        // determinant and area follow in closed form (1e-9 relative: rounding only).
        let k = rotated(615.0, 507.0, 30.0);
        let e = ellipse_metrics(&k).unwrap();
        assert!((e.major - 615.0).abs() < 1e-9 * 615.0);
        assert!((e.minor - 507.0).abs() < 1e-9 * 615.0);
        assert!((e.orientation_deg - 30.0).abs() < 1e-9);
        assert!((e.determinant - 615.0 * 507.0).abs() < 1e-9 * 615.0 * 507.0);
        assert!((e.area - std::f64::consts::PI * 615.0 * 507.0).abs() < 1e-6);
        assert!(e.curl.abs() < 1e-12);
        // 150° and −30° are the same axis: the angle is reported in [0, 180).
        let e2 = ellipse_metrics(&rotated(615.0, 507.0, -30.0)).unwrap();
        assert!((e2.orientation_deg - 150.0).abs() < 1e-9);
    }

    #[test]
    fn curl_is_the_antisymmetric_part_and_its_test_uses_the_covariance() {
        let k = [[600.0, 50.0], [30.0, 500.0]];
        let e = ellipse_metrics(&k).unwrap();
        assert_eq!(e.curl, -10.0);
        // var(curl) = (4 + 4 − 2·0)/4 = 2, se = √2; z = −10/√2 = −7.07: p ≈ 1.5e-12.
        let t = curl_test(&k, 4.0, 4.0, 0.0, 0.01).unwrap();
        assert!((t.std_err - 2.0_f64.sqrt()).abs() < 1e-12);
        assert!(t.significant && t.p_value < 1e-10);
        // With var 200 each: var(curl) = 100, se = 10, z = −1, p = 0.317311 (normal, 1e-6 abs).
        let t = curl_test(&k, 200.0, 200.0, 0.0, 0.01).unwrap();
        assert!(!t.significant);
        assert!((t.p_value - 0.317_311).abs() < 1e-6, "p {}", t.p_value);
        assert!(matches!(
            curl_test(&k, 1.0, 1.0, 1.0, 0.01),
            Err(EstimateError::BadParameter { .. })
        ));
    }

    #[test]
    fn impedance_at_the_movement_frequency_is_k_plus_j_omega_b_minus_omega2_m() {
        let k = [[615.0, 0.0], [0.0, 507.0]];
        let b = [[6.0, 0.0], [0.0, 5.0]];
        let m = [[1.87, 0.0], [0.0, 1.87]];
        let w = 2.0 * std::f64::consts::PI * 0.125;
        let z = impedance_at(&k, &b, &m, w).unwrap();
        let expect = (615.0 - w * w * 1.87_f64).hypot(w * 6.0);
        assert!((z.modulus()[0][0] - expect).abs() < 1e-12 * expect);
        // Diagonal system: det |Z| is the product of the two diagonal moduli (1e-12
        // relative), and at 0.125 Hz stiffness dominates (001_*: det Z ≈ det K): the
        // inertial term ω²M = 1.15 N/m shifts it by 0.4 %, inside 1 %.
        let dz = ellipse_metrics(&z.modulus()).unwrap().determinant;
        let expect_det = expect * (507.0 - w * w * 1.87_f64).hypot(w * 5.0);
        assert!((dz - expect_det).abs() < 1e-12 * expect_det);
        assert!(((dz - 615.0 * 507.0) / (615.0 * 507.0)).abs() < 1e-2);
    }

    #[test]
    fn force_errors_and_skill_gain_follow_eq_9_to_13() {
        // Three cycles of 4 samples, F_ref = 10 N; sample 5 lies in a perturbation.
        let f = [
            9.0, 11.0, 10.0, 10.0, /* c1 */ 8.0, 100.0, 8.0, 8.0, /* c2 */ 10.0, 10.0,
            10.0, 10.0,
        ];
        let cycles = cycle_force_measures(&f, 10.0, &[0, 4, 8, 12], &[5..6]).unwrap();
        assert_eq!(
            cycles[0],
            CycleForce {
                mean_n: 10.0,
                abs_error_n: 0.5,
                n_samples: 4
            }
        );
        // The perturbed sample is excluded from both sums and from N (eq. 9).
        assert_eq!(
            cycles[1],
            CycleForce {
                mean_n: 8.0,
                abs_error_n: 2.0,
                n_samples: 3
            }
        );
        assert_eq!(
            cycles[2],
            CycleForce {
                mean_n: 10.0,
                abs_error_n: 0.0,
                n_samples: 4
            }
        );
        let windows = window_force_errors(&cycles, 10.0, 2).unwrap();
        assert_eq!(windows.len(), 2);
        assert!((windows[0].signed_n - (-1.0)).abs() < 1e-12);
        assert!((windows[0].abs_n - 1.25).abs() < 1e-12);
        assert!((windows[1].abs_n - 1.0).abs() < 1e-12);
        assert!((skill_gain(&windows).unwrap() - 0.25).abs() < 1e-12);
        assert_eq!(stiffness_change(&[500.0, 520.0, 560.0]).unwrap(), 60.0);
        // eq. 13: (+1 +1 −1 0)/4.
        let r = sign_correlation(&[1.0, -2.0, 3.0, 0.0], &[5.0, -1.0, -4.0, 2.0]).unwrap();
        assert_eq!(r, 0.25);
    }

    #[test]
    fn canonical_correlation_is_one_for_an_exact_linear_map_and_low_for_noise() {
        // F = K e + B ė exactly: r² = 1 to rounding (1e-9).
        let kin: Vec<[f64; 4]> = (0..200)
            .map(|i| {
                let t = f64::from(i) * 0.01;
                [t.sin(), (1.7 * t).cos(), t.cos(), -1.7 * (1.7 * t).sin()]
            })
            .collect();
        let force: Vec<[f64; 2]> = kin
            .iter()
            .map(|k| {
                [
                    600.0 * k[0] + 20.0 * k[1] + 5.0 * k[2],
                    20.0 * k[0] + 500.0 * k[1] + 4.0 * k[3],
                ]
            })
            .collect();
        let r2 = canonical_correlation(&force, &kin).unwrap();
        assert!((r2 - 1.0).abs() < 1e-9, "r2 {r2}");
        // A force unrelated to the kinematics (a different frequency): r² well below 1.
        let unrelated: Vec<[f64; 2]> = (0..200)
            .map(|i| {
                let t = f64::from(i) * 0.01;
                [(13.0 * t).sin(), (17.0 * t).cos()]
            })
            .collect();
        assert!(canonical_correlation(&unrelated, &kin).unwrap() < 0.5);
    }
}
