//! The signal module against scipy/numpy on committed golden vectors.
//!
//! `golden/make_golden.py` wrote `golden/signal_golden.json` (scipy version inside);
//! CI only reads it. Error norm everywhere: max |ours − reference| / max |reference|
//! over the vector (absolute when the reference is all zeros). Tolerance 1e-9 unless
//! a case says otherwise and why. Run with `--nocapture` to see the measured errors.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::OnceLock;

use rigtwin_device::signal::{
    EdgeMode, FilterKind, Sos, butter, butter_bandpass, cumulative_trapezoid, filtfilt, gradient,
    lfilter, lfilter_zi, savgol_coeffs, savgol_filter, savgol_window_for_cutoff, sosfilt,
    sosfilt_zi, sosfiltfilt, welch,
};
use serde::Deserialize;

const TOL: f64 = 1e-9;

#[derive(Deserialize)]
struct Golden {
    signals: std::collections::BTreeMap<String, Vec<f64>>,
    savgol: Vec<SavgolCase>,
    butter: Vec<ButterCase>,
    sosfiltfilt: Vec<SosfiltfiltCase>,
    filtfilt: Vec<FiltfiltCase>,
    welch: Vec<WelchCase>,
    calculus: Vec<CalculusCase>,
}

#[derive(Deserialize)]
struct SavgolCase {
    signal: String,
    window: usize,
    polyorder: usize,
    deriv: usize,
    delta: f64,
    mode: String,
    cval: f64,
    coeffs: Vec<f64>,
    coeffs_exact: Vec<f64>,
    y: Vec<f64>,
    y_exact: Vec<f64>,
}

#[derive(Deserialize)]
struct ButterCase {
    order: usize,
    kind: String,
    cutoff_hz: Vec<f64>,
    fs_hz: f64,
    sos: Vec<f64>,
}

#[derive(Deserialize)]
struct SosfiltfiltCase {
    signal: String,
    order: usize,
    cutoff_hz: f64,
    fs_hz: f64,
    kind: String,
    sos: Vec<f64>,
    zi: Vec<f64>,
    sosfilt: Vec<f64>,
    y: Vec<f64>,
}

#[derive(Deserialize)]
struct FiltfiltCase {
    signal: String,
    b: Vec<f64>,
    a: Vec<f64>,
    zi: Vec<f64>,
    lfilter: Vec<f64>,
    y: Vec<f64>,
}

#[derive(Deserialize)]
struct WelchCase {
    signal: String,
    fs_hz: f64,
    nperseg: usize,
    freq_hz: Vec<f64>,
    density: Vec<f64>,
}

#[derive(Deserialize)]
struct CalculusCase {
    signal: String,
    dt_s: f64,
    cumulative_trapezoid: Vec<f64>,
    gradient: Vec<f64>,
}

fn golden() -> &'static Golden {
    static G: OnceLock<Golden> = OnceLock::new();
    G.get_or_init(|| {
        let text = include_str!("golden/signal_golden.json");
        serde_json::from_str(text).expect("golden JSON parses")
    })
}

fn signal(name: &str) -> &'static [f64] {
    golden().signals.get(name).expect("signal in golden file")
}

/// max |a − b| / max |b| (absolute when b is all zeros); lengths must agree.
fn rel_err(ours: &[f64], reference: &[f64]) -> f64 {
    assert_eq!(ours.len(), reference.len(), "length mismatch");
    let scale = reference.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let err = ours
        .iter()
        .zip(reference)
        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    if scale > 0.0 { err / scale } else { err }
}

fn mode(case: &SavgolCase) -> EdgeMode {
    match case.mode.as_str() {
        "interp" => EdgeMode::Interp,
        "nearest" => EdgeMode::Nearest,
        "mirror" => EdgeMode::Mirror,
        "wrap" => EdgeMode::Wrap,
        "constant" => EdgeMode::Constant(case.cval),
        other => panic!("unknown mode {other}"),
    }
}

fn kind(name: &str) -> FilterKind {
    match name {
        "lowpass" => FilterKind::LowPass,
        "highpass" => FilterKind::HighPass,
        other => panic!("unknown kind {other}"),
    }
}

fn flat(sos: &Sos) -> Vec<f64> {
    sos.sections.iter().flatten().copied().collect()
}

/// Savitzky–Golay. scipy solves the unscaled Vandermonde system, so for long windows
/// its own coefficients are off the exact rational ones by up to ~6e-9 (window 253,
/// order 5). We therefore hold ours to the exact weights at 1e-12, and to scipy at
/// 1e-9 or, where scipy's own error is larger, at scipy's error + 1e-12 (triangle
/// inequality: that is all the disagreement scipy's error can explain).
#[test]
fn savgol_matches_exact_weights_and_scipy() {
    let mut worst_exact: f64 = 0.0;
    let mut worst_scipy: f64 = 0.0;
    for c in &golden().savgol {
        let label = format!(
            "{} w={} p={} d={} {}",
            c.signal, c.window, c.polyorder, c.deriv, c.mode
        );
        let coeffs = savgol_coeffs(c.window, c.polyorder, c.deriv, c.delta).unwrap();
        let y = savgol_filter(
            signal(&c.signal),
            c.window,
            c.polyorder,
            c.deriv,
            c.delta,
            mode(c),
        )
        .unwrap();
        let scipy_own_c = rel_err(&c.coeffs, &c.coeffs_exact);
        let scipy_own_y = rel_err(&c.y, &c.y_exact);
        let e_c_exact = rel_err(&coeffs, &c.coeffs_exact);
        let e_y_exact = rel_err(&y, &c.y_exact);
        let e_c_scipy = rel_err(&coeffs, &c.coeffs);
        let e_y_scipy = rel_err(&y, &c.y);
        eprintln!(
            "savgol {label:<32} vs exact: c {e_c_exact:.1e} y {e_y_exact:.1e} | vs scipy: c {e_c_scipy:.1e} y {e_y_scipy:.1e} | scipy vs exact: c {scipy_own_c:.1e} y {scipy_own_y:.1e}"
        );
        // A dot product of `window` terms carries rounding of order eps·Σ|c||x|, which
        // for derivatives of a smooth signal is far above eps·|y| (cancellation); so
        // the output tolerance is 1e-12 times that condition number.
        let x_max = signal(&c.signal)
            .iter()
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        let c_abs: f64 = c.coeffs_exact.iter().map(|v| v.abs()).sum();
        let y_max = c.y_exact.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let cond = if y_max > 0.0 {
            (x_max * c_abs / y_max).max(1.0)
        } else {
            1.0
        };
        assert!(e_c_exact <= 1e-12, "{label}: coeffs vs exact {e_c_exact:e}");
        assert!(
            e_y_exact <= 1e-12 * cond,
            "{label}: output vs exact {e_y_exact:e} (condition {cond:.1e})"
        );
        assert!(
            e_c_scipy <= TOL.max(scipy_own_c + 1e-12),
            "{label}: coeffs vs scipy {e_c_scipy:e}"
        );
        assert!(
            e_y_scipy <= TOL.max(scipy_own_y + 1e-12),
            "{label}: output vs scipy {e_y_scipy:e}"
        );
        worst_exact = worst_exact.max(e_c_exact).max(e_y_exact);
        worst_scipy = worst_scipy.max(e_c_scipy).max(e_y_scipy);
    }
    eprintln!("savgol worst: vs exact {worst_exact:.1e}, vs scipy {worst_scipy:.1e}");
}

/// The seeds' settings map to these windows by Schafer's formula (see `savgol_cutoff.rs`).
#[test]
fn savgol_windows_for_the_seed_settings() {
    assert_eq!(savgol_window_for_cutoff(5, 30.0, 4000.0).unwrap(), 253);
    assert_eq!(savgol_window_for_cutoff(5, 30.0, 1000.0).unwrap(), 67);
    assert_eq!(savgol_window_for_cutoff(6, 23.4, 250.0).unwrap(), 27);
}

/// Butterworth SOS equal scipy's section by section (same pairing and order), not just
/// in response. Relative to the largest coefficient of the design: 1e-9.
#[test]
fn butter_sos_matches_scipy() {
    let mut worst: f64 = 0.0;
    for c in &golden().butter {
        let sos = if c.kind == "bandpass" {
            butter_bandpass(c.order, c.cutoff_hz[0], c.cutoff_hz[1], c.fs_hz).unwrap()
        } else {
            butter(c.order, c.cutoff_hz[0], c.fs_hz, kind(&c.kind)).unwrap()
        };
        let e = rel_err(&flat(&sos), &c.sos);
        // Also per coefficient, relative to itself where it is not tiny: the poles near
        // z = 1 of the 1 Hz / 4 kHz designs live in the last digits of a1, a2.
        let per_coeff = flat(&sos)
            .iter()
            .zip(&c.sos)
            .filter(|(_, r)| r.abs() > 1e-300)
            .fold(0.0_f64, |m, (o, r)| m.max(((o - r) / r).abs()));
        eprintln!(
            "butter {} {} {:?} Hz @ {} Hz: {e:.1e} (per coefficient {per_coeff:.1e})",
            c.kind, c.order, c.cutoff_hz, c.fs_hz
        );
        assert!(
            e <= TOL && per_coeff <= TOL,
            "butter {} {} {:?}: {e:e} / {per_coeff:e}",
            c.kind,
            c.order,
            c.cutoff_hz
        );
        worst = worst.max(per_coeff);
    }
    eprintln!("butter worst per-coefficient error: {worst:.1e}");
}

/// sosfilt, sosfilt_zi and sosfiltfilt on scipy's own sections (so that a design error
/// cannot hide a filtering error), and sosfiltfilt on our design as well.
#[test]
fn sosfilt_and_sosfiltfilt_match_scipy() {
    for c in &golden().sosfiltfilt {
        let x = signal(&c.signal);
        let sections: Vec<[f64; 6]> = c
            .sos
            .chunks(6)
            .map(|s| <[f64; 6]>::try_from(s).unwrap())
            .collect();
        let sos = Sos { sections };
        let zi: Vec<f64> = sosfilt_zi(&sos).unwrap().into_iter().flatten().collect();
        let e_zi = rel_err(&zi, &c.zi);
        let e_f = rel_err(&sosfilt(&sos, x), &c.sosfilt);
        let e_ff = rel_err(&sosfiltfilt(&sos, x).unwrap(), &c.y);
        let ours = butter(c.order, c.cutoff_hz, c.fs_hz, kind(&c.kind)).unwrap();
        let e_design = rel_err(&sosfiltfilt(&ours, x).unwrap(), &c.y);
        eprintln!(
            "sos {} {} {} Hz on {}: zi {e_zi:.1e} sosfilt {e_f:.1e} sosfiltfilt {e_ff:.1e} (our design {e_design:.1e})",
            c.kind, c.order, c.cutoff_hz, c.signal
        );
        for (what, e) in [
            ("zi", e_zi),
            ("sosfilt", e_f),
            ("sosfiltfilt", e_ff),
            ("design+sosfiltfilt", e_design),
        ] {
            assert!(
                e <= TOL,
                "{what} {} {} on {}: {e:e}",
                c.kind,
                c.order,
                c.signal
            );
        }
    }
}

/// lfilter, lfilter_zi and filtfilt on (b, a), including a0 ≠ 1 and len(b) < len(a).
#[test]
fn lfilter_and_filtfilt_match_scipy() {
    for c in &golden().filtfilt {
        let x = signal(&c.signal);
        let e_zi = rel_err(&lfilter_zi(&c.b, &c.a).unwrap(), &c.zi);
        let e_f = rel_err(&lfilter(&c.b, &c.a, x).unwrap(), &c.lfilter);
        let e_ff = rel_err(&filtfilt(&c.b, &c.a, x).unwrap(), &c.y);
        eprintln!(
            "filtfilt b={} a={} on {}: zi {e_zi:.1e} lfilter {e_f:.1e} filtfilt {e_ff:.1e}",
            c.b.len(),
            c.a.len(),
            c.signal
        );
        for (what, e) in [("zi", e_zi), ("lfilter", e_f), ("filtfilt", e_ff)] {
            assert!(e <= TOL, "{what} on {}: {e:e}", c.signal);
        }
    }
}

#[test]
fn welch_matches_scipy() {
    for c in &golden().welch {
        let psd = welch(signal(&c.signal), c.fs_hz, c.nperseg).unwrap();
        let e_f = rel_err(&psd.freq_hz, &c.freq_hz);
        let e_d = rel_err(&psd.density, &c.density);
        eprintln!(
            "welch {} nperseg {}: freq {e_f:.1e} density {e_d:.1e}",
            c.signal, c.nperseg
        );
        assert!(e_f <= TOL && e_d <= TOL, "welch {} {}", c.signal, c.nperseg);
    }
}

#[test]
fn cumulative_trapezoid_and_gradient_match_scipy_numpy() {
    for c in &golden().calculus {
        let y = signal(&c.signal);
        let e_t = rel_err(&cumulative_trapezoid(y, c.dt_s), &c.cumulative_trapezoid);
        let e_g = rel_err(&gradient(y, c.dt_s), &c.gradient);
        eprintln!(
            "calculus {}: trapezoid {e_t:.1e} gradient {e_g:.1e}",
            c.signal
        );
        assert!(e_t <= TOL && e_g <= TOL, "calculus {}", c.signal);
    }
}
