//! The two measured-style sessions from the independent emulated rig
//! (`shared/recordings/`): their hidden effects are disclosed, so they check the
//! diagnosis on data the project did not make. `example-none` must yield no cause;
//! `example-friction` must yield rail friction with the disclosed
//! `Fc = 2.66 N, b = 5.29 N s/m` within 20 % (the tolerance) and a large gain.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use rigtwin::discrepancy::{DiagnoseOptions, diagnose};
use rigtwin::session::Session;

/// The shared recordings sit next to the repository (`../shared/recordings`); a
/// checkout without them skips these checks with a message.
fn shared(name: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/recordings")
        .join(name);
    if p.join("session.toml").is_file() {
        Some(p)
    } else {
        eprintln!("skipped: {} not present", p.display());
        None
    }
}

#[test]
fn example_none_names_no_cause() {
    let Some(dir) = shared("example-none") else {
        return;
    };
    let s = Session::read(&dir).unwrap();
    let a = diagnose(&s, &DiagnoseOptions::default()).unwrap();
    let d = &a.diagnosis;
    eprintln!("{}", serde_json::to_string_pretty(d).unwrap());
    assert_eq!(d.cause, "none");
    // Every judged candidate explains less than the material floor (10 %).
    for r in &d.ranking {
        assert!(r.gain < 0.10, "{} gains {}", r.name, r.gain);
    }
    // The nominal balance already explains the motor command to a few per cent.
    assert!(d.baseline_nrmse.unwrap() < 0.1);
}

#[test]
fn example_friction_names_rail_friction_with_disclosed_parameters() {
    let Some(dir) = shared("example-friction") else {
        return;
    };
    let s = Session::read(&dir).unwrap();
    let a = diagnose(&s, &DiagnoseOptions::default()).unwrap();
    let d = &a.diagnosis;
    eprintln!("{}", serde_json::to_string_pretty(d).unwrap());
    assert_eq!(d.cause, "rail-friction");
    let fc = d.parameters["coulomb_n"];
    let b = d.parameters["viscous_n_s_per_m"];
    assert!((fc - 2.66).abs() < 0.2 * 2.66, "Fc {fc}");
    assert!((b - 5.29).abs() < 0.2 * 5.29, "b {b}");
    assert!(d.gain.unwrap() > 0.5);
    // Friction leaves every other candidate far behind.
    assert!(d.ranking[1].gain < 0.5 * d.ranking[0].gain);
}
