//! The project's own example session (`recordings/example-ripple`, README there): its
//! hidden force ripple (1.8 N, 24 mm pitch) must be named with both parameters within
//! 20 % (the tolerance) and a held-out gain of at least 50 %.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use rigtwin::discrepancy::{DiagnoseOptions, ExtendedModel, diagnose, write_report};
use rigtwin::session::Session;

#[test]
fn example_ripple_is_found_and_its_model_round_trips() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../recordings/example-ripple");
    let s = Session::read(&dir).unwrap();
    let a = diagnose(&s, &DiagnoseOptions::default()).unwrap();
    let d = &a.diagnosis;
    assert_eq!(d.cause, "force-ripple");
    let amp = d.parameters["amplitude_n"];
    let pitch = d.parameters["pitch_m"];
    assert!((amp - 1.8).abs() < 0.2 * 1.8, "amplitude {amp}");
    assert!((pitch - 0.024).abs() < 0.2 * 0.024, "pitch {pitch}");
    assert!(d.gain.unwrap() >= 0.5);

    // The model file reads back as written and names the world's effect.
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("model.toml");
    let m = ExtendedModel::from_diagnosis(d);
    m.write(&path).unwrap();
    let back = ExtendedModel::read(&path).unwrap();
    assert_eq!(back, m);
    assert!(back.effects.force_ripple.is_some());

    // The report and its three figures are written.
    let files = write_report(&a, &tmp.path().join("report")).unwrap();
    assert_eq!(files.len(), 4, "{files:?}");
    for f in &files {
        assert!(std::fs::metadata(f).unwrap().len() > 100, "{}", f.display());
    }
}
