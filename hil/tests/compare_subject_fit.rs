//! `compare`'s subject fit and its report fields.
//!
//! A session made by the project's own runtime with a drawn (non-nominal) subject: the
//! fit, which sees the session folder only, must recover the drawn factors. Measured
//! (`compare` defaults: 8 perturbed trials, 45 evaluations) on 32-trial sessions of the
//! reach-perturb protocol, truth → fitted:
//!
//! | seed | muscle stiffness | co-contraction | feedback gain | discrepancy nominal → fitted |
//! |---|---|---|---|---|
//! | 3 | 1.128 → 1.113 | 1.037 → 1.194 | 1.300 → 1.114 | 0.145 → 0.087 |
//! | 4 | 1.157 → 1.179 | 0.648 → 0.601 | 0.600 → 0.668 | 0.103 → 0.075 |
//! | 5 | 0.955 → 0.881 | 1.010 → 1.000 | 0.737 → 1.212 | 0.103 → 0.094 |
//!
//! The stiffness factor comes within 8 % and co-contraction within 15 %; the feedback
//! gain is the weakest identified (its 60 ms delayed action is only the tail of the
//! 150 ms response, and motor noise of the same size hides it: seed 5 is 64 % off; with
//! twice the trials and evaluations, `--fit-trials 16 --fit-evaluations 90`, it comes to
//! 0.935, 27 % off, at four times the run time). The
//! test runs seed 4 with tolerances of about twice its errors (stiffness 10 %,
//! co-contraction 20 %, feedback 25 %) and asks the fitted discrepancy to be at most
//! 0.85 of the nominal one (measured 0.72). The reach timing of the generated session is
//! the protocol's plan (0.25 s, 3.0 s), which the fit must find within 10 ms and 20 ms
//! (measured 5.5 ms and 6 ms; motor noise moves single reaches by a few ms).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use rigtwin::compare::{CompareOptions, Comparison, compare};
use rigtwin::protocol::{EstimateConfig, Protocol};
use rigtwin::rehearse::{Options, rehearse};
use rigtwin::report::borner_on_session;
use rigtwin::session::Session;

/// Frequency and D/K fields are finite, and D/K measured is `rigtwin estimate`'s.
fn check_report_fields(c: &Comparison, s: &Session) {
    assert_eq!(c.frequency.len(), 6 * 3, "6 channels x 3 bands");
    for b in &c.frequency {
        for v in [b.measured_rms, b.simulated_rms, b.power_ratio, b.diff_rms] {
            assert!(v.is_finite() && v >= 0.0, "{b:?}");
        }
    }
    let i = c.impedance.as_ref().unwrap();
    for m in [
        i.measured.d_ns_per_m,
        i.measured.k_n_per_m,
        i.simulated.d_ns_per_m,
        i.simulated.k_n_per_m,
        i.d_diff_ns_per_m,
        i.k_diff_n_per_m,
    ] {
        assert!(m.iter().flatten().all(|v| v.is_finite()), "{m:?}");
    }
    // Same code path, same numbers, bit for bit.
    let e = borner_on_session(s, &EstimateConfig::default()).unwrap();
    assert_eq!(i.measured.d_ns_per_m, e.d_ns_per_m);
    assert_eq!(i.measured.k_n_per_m, e.k_n_per_m);
    assert_eq!(i.measured.trials, e.trials);
    for r in 0..2 {
        for k in 0..2 {
            let d = i.simulated.d_ns_per_m[r][k] - i.measured.d_ns_per_m[r][k];
            assert!((i.d_diff_ns_per_m[r][k] - d).abs() < 1e-12);
        }
    }
}

#[test]
fn the_fit_recovers_a_drawn_subject() {
    let tmp = tempfile::tempdir().unwrap();
    let mut p = Protocol::builtin("reach-perturb").unwrap();
    p.recording.truth_columns = false;
    p.subjects.first_is_nominal = false;
    p.reach.as_mut().unwrap().trials = 32;
    let o = Options {
        subjects: 1,
        seed: 4,
        out_dir: tmp.path().join("r"),
        jobs: 2,
        max_trials: None,
    };
    let r = rehearse(&p, &o, &|_| {}, &AtomicBool::new(false)).unwrap();
    let truth = r.subjects[0].subject.factors;
    let s = Session::read(&r.subjects[0].dir).unwrap();
    let c = compare(&s, None, &CompareOptions::default()).unwrap();
    let f = &c.subject;
    let rel = |fit: f64, t: f64| (fit / t - 1.0).abs();
    assert!(
        rel(f.muscle_stiffness, truth[0]) < 0.10,
        "{f:?} vs {truth:?}"
    );
    assert!(rel(f.co_contraction, truth[1]) < 0.20, "{f:?} vs {truth:?}");
    assert!(rel(f.feedback_gain, truth[4]) < 0.25, "{f:?} vs {truth:?}");
    // Lengths are the manifest's, applied as the draw applied them.
    assert!(rel(f.upper_arm_factor, truth[2]) < 1e-9 && rel(f.forearm_factor, truth[3]) < 1e-9);
    assert!((f.timing.start_s - 0.25).abs() < 0.010, "{:?}", f.timing);
    assert!((f.timing.duration_s - 3.0).abs() < 0.020, "{:?}", f.timing);
    assert!(
        f.discrepancy_fitted <= 0.85 * f.discrepancy_nominal,
        "{} -> {}",
        f.discrepancy_nominal,
        f.discrepancy_fitted
    );
    assert!(f.at_bound.is_empty());
    check_report_fields(&c, &s);
}

/// The independent rig's `example-none`: the fit runs and reduces the discrepancy.
/// Measured: 0.264 → 0.127 (stiffness 0.893, co-contraction 1.870, feedback gain 2.373;
/// most of the gain is the lateral drift of the reach, x NRMSE 0.585 → 0.195). The test
/// asks for at most 0.7 of the nominal discrepancy.
#[test]
fn the_fit_reduces_the_discrepancy_on_example_none() {
    // The shared recordings sit next to the repository (`../shared/recordings`, or where
    // RIGTWIN_SHARED_RECORDINGS says); a checkout without them skips with a message.
    let base = std::env::var_os("RIGTWIN_SHARED_RECORDINGS").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/recordings"),
        PathBuf::from,
    );
    let dir = base.join("example-none");
    if !dir.join("session.toml").is_file() {
        eprintln!("skipped: {} not present", dir.display());
        return;
    }
    let s = Session::read(&dir).unwrap();
    let c = compare(&s, None, &CompareOptions::default()).unwrap();
    let f = &c.subject;
    assert_eq!(c.trials, 32);
    assert!(
        f.discrepancy_fitted <= 0.7 * f.discrepancy_nominal,
        "{} -> {}",
        f.discrepancy_nominal,
        f.discrepancy_fitted
    );
    check_report_fields(&c, &s);
}
