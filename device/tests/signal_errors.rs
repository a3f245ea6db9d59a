//! Bad input gets a typed error naming what is wrong, never a panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::signal::{
    EdgeMode, FilterKind, SignalError, Sos, butter, butter_bandpass, filtfilt, lfilter_zi,
    savgol_coeffs, savgol_filter, sosfilt_with_state, sosfilt_zi, sosfiltfilt, welch,
};

#[test]
fn savgol_rejects_bad_windows_orders_and_samples() {
    let x = [1.0; 10];
    assert!(matches!(
        savgol_coeffs(4, 2, 0, 1.0),
        Err(SignalError::BadWindow { window: 4, .. })
    ));
    assert!(matches!(
        savgol_coeffs(0, 0, 0, 1.0),
        Err(SignalError::BadWindow { window: 0, .. })
    ));
    assert!(matches!(
        savgol_coeffs(5, 5, 0, 1.0),
        Err(SignalError::BadOrder { order: 5, .. })
    ));
    assert!(matches!(
        savgol_coeffs(5, 2, 0, 0.0),
        Err(SignalError::BadRate { .. })
    ));
    // interp needs a full window; the padding modes need one sample.
    assert_eq!(
        savgol_filter(&x[..6], 7, 2, 0, 1.0, EdgeMode::Interp),
        Err(SignalError::TooShort {
            needed: 7,
            got: 6,
            what: "savgol_filter"
        })
    );
    assert_eq!(
        savgol_filter(&x[..2], 7, 2, 0, 1.0, EdgeMode::Mirror)
            .unwrap()
            .len(),
        2
    );
    assert!(matches!(
        savgol_filter(&[], 1, 0, 0, 1.0, EdgeMode::Nearest),
        Err(SignalError::TooShort { .. })
    ));
    let mut bad = x;
    bad[3] = f64::NAN;
    assert!(matches!(
        savgol_filter(&bad, 5, 2, 0, 1.0, EdgeMode::Interp),
        Err(SignalError::NonFinite { index: 3, .. })
    ));
}

#[test]
fn butter_rejects_bad_designs() {
    assert!(matches!(
        butter(0, 10.0, 1000.0, FilterKind::LowPass),
        Err(SignalError::BadOrder { order: 0, .. })
    ));
    for fc in [0.0, -1.0, 500.0, 600.0, f64::INFINITY, f64::NAN] {
        assert!(matches!(
            butter(2, fc, 1000.0, FilterKind::HighPass),
            Err(SignalError::CutoffOutOfRange { .. })
        ));
    }
    assert!(matches!(
        butter(2, 10.0, 0.0, FilterKind::LowPass),
        Err(SignalError::BadRate { .. })
    ));
    assert!(matches!(
        butter_bandpass(2, 50.0, 10.0, 1000.0),
        Err(SignalError::CutoffOutOfRange { .. })
    ));
}

#[test]
fn forward_backward_filters_need_more_than_their_padding() {
    // 5th-order Butterworth: 3 sections, one first-order → ntaps 6, padlen 18.
    let sos = butter(5, 1.0, 4000.0, FilterKind::HighPass).unwrap();
    assert_eq!(
        sosfiltfilt(&sos, &[0.0; 18]),
        Err(SignalError::TooShort {
            needed: 19,
            got: 18,
            what: "sosfiltfilt (more than its padding)"
        })
    );
    assert_eq!(sosfiltfilt(&sos, &[0.0; 19]).unwrap().len(), 19);
    // (b, a) of length 3: padlen 9.
    assert!(matches!(
        filtfilt(&[1.0, 2.0, 1.0], &[1.0, -0.5, 0.1], &[0.0; 9]),
        Err(SignalError::TooShort { needed: 10, .. })
    ));
    assert!(matches!(
        sosfiltfilt(&sos, &[f64::INFINITY; 40]),
        Err(SignalError::NonFinite { index: 0, .. })
    ));
}

#[test]
fn bad_coefficients_are_refused() {
    assert!(matches!(
        lfilter_zi(&[1.0], &[0.0, 1.0]),
        Err(SignalError::BadCoefficients { .. })
    ));
    assert!(matches!(
        lfilter_zi(&[], &[1.0]),
        Err(SignalError::BadCoefficients { .. })
    ));
    // An integrator 1/(1 − z⁻¹) has no steady state for a step.
    assert!(matches!(
        lfilter_zi(&[1.0], &[1.0, -1.0]),
        Err(SignalError::BadCoefficients { .. })
    ));
    let integrator = Sos {
        sections: vec![[1.0, 0.0, 0.0, 1.0, -1.0, 0.0]],
    };
    assert!(matches!(
        sosfilt_zi(&integrator),
        Err(SignalError::BadCoefficients { .. })
    ));
    assert!(matches!(
        sosfiltfilt(&Sos { sections: vec![] }, &[0.0; 10]),
        Err(SignalError::BadCoefficients { .. })
    ));
    let sos = butter(2, 10.0, 1000.0, FilterKind::LowPass).unwrap();
    let mut wrong_state = vec![[0.0; 2]; 2];
    assert!(matches!(
        sosfilt_with_state(&sos, &[1.0], &mut wrong_state),
        Err(SignalError::BadCoefficients { .. })
    ));
}

#[test]
fn welch_rejects_short_signals_and_tiny_segments() {
    assert!(matches!(
        welch(&[0.0; 10], 100.0, 16),
        Err(SignalError::TooShort {
            needed: 16,
            got: 10,
            ..
        })
    ));
    assert!(matches!(
        welch(&[0.0; 10], 100.0, 1),
        Err(SignalError::BadWindow { window: 1, .. })
    ));
    assert!(matches!(
        welch(&[0.0; 10], f64::NAN, 4),
        Err(SignalError::BadRate { .. })
    ));
}

/// State carried across calls equals one call over the whole signal (to the last
/// bit: same operations in the same order), so long recordings can be filtered in
/// chunks.
#[test]
fn sosfilt_with_state_chunks_equal_one_pass() {
    let sos = butter(4, 30.0, 1000.0, FilterKind::LowPass).unwrap();
    let x: Vec<f64> = (0..500).map(|i| (i as f64 * 0.05).sin()).collect();
    let mut state = vec![[0.0; 2]; sos.sections.len()];
    let mut chunked = sosfilt_with_state(&sos, &x[..123], &mut state).unwrap();
    chunked.extend(sosfilt_with_state(&sos, &x[123..], &mut state).unwrap());
    assert_eq!(chunked, rigtwin_device::signal::sosfilt(&sos, &x));
}
