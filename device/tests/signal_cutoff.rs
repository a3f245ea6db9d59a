//! Savitzky–Golay window ↔ cut-off (Schafer 2011) and the measured 3 dB points.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::signal::{
    SignalError, savgol_coeffs, savgol_cutoff_for_window, savgol_measured_cutoff_hz,
    savgol_window_for_cutoff,
};

/// The inverse is the formula: the window returned has a half-width within 0.5 of
/// M = ((N+1)·(fs/2)/fc + 4.6)/3.2, for orders 0..10 and cut-offs over two decades;
/// and feeding that window back through the forward formula lands within the
/// rounding step of the target (|Δf/f| ≤ 3.2·0.5/(3.2M − 4.6)).
#[test]
fn window_for_cutoff_inverts_schafers_formula() {
    for n in 0..10usize {
        for fc in [1.0, 3.0, 10.0, 23.4, 30.0, 60.0, 100.0] {
            for fs in [250.0, 1000.0, 4000.0] {
                let Ok(w) = savgol_window_for_cutoff(n, fc, fs) else {
                    continue;
                };
                assert_eq!(w % 2, 1);
                let m_exact = ((n as f64 + 1.0) * fs / 2.0 / fc + 4.6) / 3.2;
                let m = (w / 2) as f64;
                assert!(
                    (m - m_exact).abs() <= 0.5,
                    "N={n} fc={fc} fs={fs}: {m} vs {m_exact}"
                );
                let back = savgol_cutoff_for_window(n, w, fs).unwrap();
                let bound = 3.2 * 0.5 / (3.2 * m - 4.6) + 1e-12;
                assert!(
                    ((back - fc) / fc).abs() <= bound,
                    "N={n} fc={fc} fs={fs}: {back}"
                );
            }
        }
    }
}

/// The seeds' settings: windows 253, 67 and 27; their true 3 dB points measured from
/// the coefficients are 26.763, 25.294 and 21.814 Hz (scipy `freqz` of
/// `savgol_coeffs` + brentq gave the same to 1e-3 Hz, which is the tolerance).
#[test]
fn seed_windows_and_their_true_cutoffs() {
    for (n, fc, fs, window, measured) in [
        (5, 30.0, 4000.0, 253, 26.763),
        (5, 30.0, 1000.0, 67, 25.294),
        (6, 23.4, 250.0, 27, 21.814),
    ] {
        assert_eq!(savgol_window_for_cutoff(n, fc, fs).unwrap(), window);
        let f3 = savgol_measured_cutoff_hz(n, window, fs).unwrap();
        eprintln!("order {n} {fc} Hz @ {fs} Hz -> window {window}, true 3 dB at {f3:.3} Hz");
        assert!((f3 - measured).abs() <= 1e-3, "{f3} vs {measured}");
    }
}

/// The measured cut-off is where the gain is 1/√2: check it against a direct
/// evaluation of |Σ c_k e^{-iωk}| (a different formula from the cosine sum used
/// inside), to 1e-9.
#[test]
fn measured_cutoff_is_the_3db_point() {
    let (n, w, fs) = (4, 51, 1000.0);
    let f3 = savgol_measured_cutoff_hz(n, w, fs).unwrap();
    let c = savgol_coeffs(w, n, 0, 1.0).unwrap();
    let om = 2.0 * std::f64::consts::PI * f3 / fs;
    let (re, im) = c.iter().enumerate().fold((0.0, 0.0), |(re, im), (k, ck)| {
        (
            re + ck * (om * k as f64).cos(),
            im - ck * (om * k as f64).sin(),
        )
    });
    let g = re.hypot(im);
    assert!((g - std::f64::consts::FRAC_1_SQRT_2).abs() <= 1e-9, "{g}");
}

#[test]
fn bad_cutoffs_are_typed_errors() {
    assert!(matches!(
        savgol_window_for_cutoff(5, 0.0, 1000.0),
        Err(SignalError::CutoffOutOfRange { .. })
    ));
    assert!(matches!(
        savgol_window_for_cutoff(5, 500.0, 1000.0),
        Err(SignalError::CutoffOutOfRange { .. })
    ));
    assert!(matches!(
        savgol_window_for_cutoff(5, f64::NAN, 1000.0),
        Err(SignalError::CutoffOutOfRange { .. })
    ));
    assert!(matches!(
        savgol_window_for_cutoff(5, 10.0, -1.0),
        Err(SignalError::BadRate { .. })
    ));
    // Order 20 at 450 Hz / 1 kHz gives M = 9 → window 19, not longer than the order.
    assert!(matches!(
        savgol_window_for_cutoff(20, 450.0, 1000.0),
        Err(SignalError::BadOrder { .. })
    ));
    assert!(matches!(
        savgol_cutoff_for_window(5, 4, 1000.0),
        Err(SignalError::BadWindow { .. })
    ));
}
