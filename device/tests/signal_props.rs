//! Properties of the signal module that hold for any input, checked with proptest.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use proptest::prelude::*;
use rigtwin_device::signal::{
    EdgeMode, FilterKind, butter, cumulative_trapezoid, filtfilt, gradient, savgol_coeffs,
    savgol_filter, sosfilt, sosfiltfilt, welch,
};

fn poly_eval(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, ck| acc * t + ck)
}

fn poly_deriv(c: &[f64], d: usize) -> Vec<f64> {
    let mut c = c.to_vec();
    for _ in 0..d {
        c = c
            .iter()
            .enumerate()
            .skip(1)
            .map(|(k, ck)| k as f64 * ck)
            .collect();
        if c.is_empty() {
            c.push(0.0);
        }
    }
    c
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// A least-squares polynomial of order `polyorder` reproduces any polynomial of
    /// degree ≤ polyorder, and its derivatives are the polynomial's, at every sample
    /// (the `interp` edges included). Tolerance 1e-8 × Σ|coefficients of the
    /// derivative| × n^deriv: the samples carry rounding of 1e-16 relative, which
    /// differentiation with step 1/n amplifies by n^deriv, summed over ≤ 59 weights
    /// whose absolute sum grows with the window; 1e-8 leaves margin over that.
    #[test]
    fn savgol_reproduces_polynomials(
        half in 1usize..30,
        polyorder in 0usize..7,
        deriv in 0usize..3,
        coeffs in prop::collection::vec(-1.0f64..1.0, 7),
        extra in 0usize..50,
    ) {
        let window = 2 * half + 1;
        prop_assume!(polyorder < window);
        let degree = polyorder.min(6);
        let c = &coeffs[..=degree];
        let n = window + extra;
        let delta = 1.0 / n as f64;
        let x: Vec<f64> = (0..n).map(|i| poly_eval(c, i as f64 * delta)).collect();
        let y = savgol_filter(&x, window, polyorder, deriv, delta, EdgeMode::Interp).unwrap();
        let dc = poly_deriv(c, deriv);
        let expect: Vec<f64> = (0..n).map(|i| poly_eval(&dc, i as f64 * delta)).collect();
        let scale = dc.iter().map(|v| v.abs()).sum::<f64>().max(1.0);
        let amplification = (n as f64).powi(deriv as i32);
        for (i, (a, b)) in y.iter().zip(&expect).enumerate() {
            prop_assert!(
                (a - b).abs() <= 1e-8 * amplification * scale,
                "sample {i}: {a} vs {b}"
            );
        }
    }

    /// A high-pass Butterworth of any order has a zero at z = 1, so a constant signal
    /// filtered forward-backward comes out as zero. The residue is rounding in the
    /// steady-state initial conditions, which for the 1 Hz / 4 kHz designs is
    /// amplified by 1/(1 + a1 + a2) ~ 1e6 per section; 1e-6 of the constant bounds it.
    #[test]
    fn highpass_kills_a_constant(
        order in 1usize..9,
        cutoff_frac in 0.0002f64..0.4,
        level in -100.0f64..100.0,
        n in 60usize..400,
    ) {
        let fs = 1000.0;
        let sos = butter(order, cutoff_frac * fs / 2.0, fs, FilterKind::HighPass).unwrap();
        let x = vec![level; n];
        let y = sosfiltfilt(&sos, &x).unwrap();
        for v in &y {
            prop_assert!(v.abs() <= 1e-6 * level.abs().max(1.0), "{v} from {level}");
        }
        // Its DC gain is zero.
        prop_assert!(sos.gain(0.0, fs) <= 1e-12);
    }

    /// Forward-backward filtering has zero phase: a passband sinusoid comes out in
    /// phase with the input. The phase of the central part (away from the padded
    /// ends) is measured by projecting on sin and cos over whole periods; both the
    /// SOS and the (b, a) paths must be within 1e-6 rad of zero, where a single
    /// forward pass of the same filter lags by 0.1 rad or more.
    #[test]
    fn filtfilt_has_zero_phase_in_the_passband(
        order in 1usize..5,
        periods in 4usize..12,
        phase0 in 0.0f64..std::f64::consts::TAU,
    ) {
        let fs = 1000.0;
        let n = 4000;
        let f = periods as f64 * fs / 1000.0; // whole periods in each 1000-sample block
        let fc = 4.0 * f;
        let x: Vec<f64> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 / fs + phase0).sin())
            .collect();
        let sos = butter(order, fc, fs, FilterKind::LowPass).unwrap();
        let (b, a) = ba_lowpass_1st(fc, fs);
        let measure = |y: &[f64]| {
            let (mut s, mut c) = (0.0, 0.0);
            for (i, yi) in y.iter().enumerate().take(2500).skip(1500) {
                let th = 2.0 * std::f64::consts::PI * f * i as f64 / fs + phase0;
                s += yi * th.sin();
                c += yi * th.cos();
            }
            c.atan2(s)
        };
        let p_sos = measure(&sosfiltfilt(&sos, &x).unwrap());
        let p_ba = measure(&filtfilt(&b, &a, &x).unwrap());
        let p_forward = measure(&sosfilt(&sos, &x));
        prop_assert!(p_sos.abs() <= 1e-6, "sosfiltfilt phase {p_sos}");
        prop_assert!(p_ba.abs() <= 1e-6, "filtfilt phase {p_ba}");
        prop_assert!(p_forward.abs() >= 0.1, "a forward pass lags: {p_forward}");
    }

    /// No input length makes any function panic: short signals get a typed error.
    #[test]
    fn short_signals_never_panic(n in 0usize..40, window in 1usize..30, order in 0usize..8) {
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let _ = savgol_filter(&x, window, order, 1, 0.01, EdgeMode::Interp);
        let _ = savgol_filter(&x, window, order, 0, 0.01, EdgeMode::Mirror);
        if let Ok(sos) = butter(order.max(1), 10.0, 1000.0, FilterKind::HighPass) {
            let _ = sosfiltfilt(&sos, &x);
            let _ = sosfilt(&sos, &x);
        }
        let _ = filtfilt(&[0.2, 0.3], &[1.0, -0.5], &x);
        let _ = welch(&x, 100.0, window);
        prop_assert_eq!(cumulative_trapezoid(&x, 0.01).len(), n);
        prop_assert_eq!(gradient(&x, 0.01).len(), n);
    }
}

/// First-order Butterworth low-pass as (b, a), by the bilinear transform with
/// pre-warping: an independent closed form for the `filtfilt` path.
fn ba_lowpass_1st(fc: f64, fs: f64) -> (Vec<f64>, Vec<f64>) {
    let k = (std::f64::consts::PI * fc / fs).tan();
    (
        vec![k / (1.0 + k), k / (1.0 + k)],
        vec![1.0, (k - 1.0) / (k + 1.0)],
    )
}

/// The closed form above equals our first-order design (one section, b2 = a2 = 0).
#[test]
fn first_order_lowpass_matches_its_closed_form() {
    let (b, a) = ba_lowpass_1st(30.0, 1000.0);
    let sos = butter(1, 30.0, 1000.0, FilterKind::LowPass).unwrap();
    let s = sos.sections[0];
    for (ours, theirs) in [(s[0], b[0]), (s[1], b[1]), (s[3], a[0]), (s[4], a[1])] {
        assert!((ours - theirs).abs() <= 1e-15, "{ours} vs {theirs}");
    }
    assert_eq!((s[2], s[5]), (0.0, 0.0));
}

/// Every design has its 3 dB point at the cut-off (|H| = 1/√2) and unit gain deep in
/// the passband; this checks the pre-warping independently of scipy. Tolerance 1e-9:
/// evaluating a high-pass numerator 1 − 2cos ω + cos 2ω ≈ ω² at ω = 2π·1/4000 cancels
/// about 6 of the 16 digits (measured error 5e-12 for order 2).
#[test]
fn butter_is_3db_down_at_the_cutoff() {
    for order in 1..=8 {
        for (fc, fs) in [(1.0, 4000.0), (30.0, 1000.0), (23.4, 250.0), (100.0, 250.0)] {
            for kind in [FilterKind::LowPass, FilterKind::HighPass] {
                let sos = butter(order, fc, fs, kind).unwrap();
                let g = sos.gain(fc, fs);
                assert!(
                    (g - std::f64::consts::FRAC_1_SQRT_2).abs() <= 1e-9,
                    "{kind:?} {order} {fc}/{fs}: {g}"
                );
                let pass = match kind {
                    FilterKind::LowPass => 0.0,
                    FilterKind::HighPass => fs / 2.0,
                };
                assert!((sos.gain(pass, fs) - 1.0).abs() <= 1e-9, "{kind:?} {order}");
            }
        }
    }
}

/// Long windows go through FFT correlation: for every edge mode, a 101-tap filter
/// (above the FFT threshold) equals the direct sum Σ c[k]·x_ext[i + 50 − k] built from
/// `savgol_coeffs` here, to 1e-12 of the output's scale (FFT rounding is
/// ~eps·log2(n)·‖x‖·‖c‖, far below that).
#[test]
fn fft_path_equals_direct_sum() {
    let n = 700;
    let x: Vec<f64> = (0..n)
        .map(|i| (i as f64 * 0.031).sin() + 0.3 * (i as f64 * 0.17).cos() + 2.0)
        .collect();
    let (w, p, d, delta) = (101usize, 4usize, 1usize, 0.01);
    let half = (w / 2) as isize;
    let c = savgol_coeffs(w, p, d, delta).unwrap();
    for mode in [
        EdgeMode::Nearest,
        EdgeMode::Mirror,
        EdgeMode::Wrap,
        EdgeMode::Constant(-0.5),
        EdgeMode::Interp,
    ] {
        let y = savgol_filter(&x, w, p, d, delta, mode).unwrap();
        let ext = |i: isize| -> f64 {
            let m = n as isize;
            if (0..m).contains(&i) {
                return x[i as usize];
            }
            match mode {
                EdgeMode::Nearest => x[i.clamp(0, m - 1) as usize],
                EdgeMode::Wrap => x[i.rem_euclid(m) as usize],
                EdgeMode::Constant(v) => v,
                EdgeMode::Mirror => {
                    let r = i.rem_euclid(2 * (m - 1));
                    x[(if r < m { r } else { 2 * (m - 1) - r }) as usize]
                }
                EdgeMode::Interp => f64::NAN,
            }
        };
        let (lo, hi) = match mode {
            EdgeMode::Interp => (half as usize, n - half as usize),
            _ => (0, n),
        };
        let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (i, yi) in y.iter().enumerate().take(hi).skip(lo) {
            let direct: f64 = (0..w)
                .map(|k| c[k] * ext(i as isize + half - k as isize))
                .sum();
            assert!(
                (yi - direct).abs() <= 1e-12 * scale,
                "{mode:?} sample {i}: {yi} vs {direct}"
            );
        }
    }
}

/// The FFT correlation of long windows (≥ 64 taps) against the direct dot product of
/// `savgol_coeffs` with every window of the signal, through a planner reused across
/// lengths as the Börner estimator reuses it over a session's trials. 1e-9 of the
/// output's scale: FFT rounding is ~1e-13 relative at these lengths.
#[test]
fn planned_fft_savgol_equals_the_direct_dot_product() {
    let mut planner = realfft::RealFftPlanner::new();
    for n in [3000_u32, 2000, 3000] {
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let t = f64::from(i) / 4000.0;
                let rough = f64::from(i * 7919 % 1000) / 1000.0 - 0.5;
                0.3 + 0.1 * (3.0 * t).sin() + 1e-4 * rough
            })
            .collect();
        for deriv in [0, 3] {
            let dt = 1.0 / 4000.0;
            let h = savgol_coeffs(253, 5, deriv, dt).unwrap();
            let fft = rigtwin_device::signal::savgol_filter_planned(
                &mut planner,
                &y,
                253,
                5,
                deriv,
                dt,
                EdgeMode::Interp,
            )
            .unwrap();
            let unplanned = savgol_filter(&y, 253, 5, deriv, dt, EdgeMode::Interp).unwrap();
            let scale = fft.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for i in 126..y.len() - 126 {
                // `savgol_coeffs` are convolution weights (scipy's order): reversed.
                let direct: f64 = h
                    .iter()
                    .rev()
                    .zip(&y[i - 126..=i + 126])
                    .map(|(a, b)| a * b)
                    .sum();
                assert!(
                    (direct - fft[i]).abs() <= 1e-9 * scale,
                    "n {n} deriv {deriv} sample {i}: {direct} vs {}",
                    fft[i]
                );
            }
            assert_eq!(fft, unplanned);
        }
    }
}
