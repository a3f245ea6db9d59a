//! The project's own example session (`recordings/example-ripple`, README there): its
//! hidden force ripple (1.8 N on both axes, 24 mm pitch, magnets at `q = 0`) must be
//! named with every parameter within 20 % (README § Requirements) and a held-out gain of
//! at least 50 %.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use rigtwin::session::Session;
use rigtwin_diagnose::{DiagnoseOptions, ExtendedModel, diagnose, write_report};

#[test]
fn example_ripple_is_found_and_its_model_round_trips() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../recordings/example-ripple");
    let s = Session::read(&dir).unwrap();
    let a = diagnose(&s, &DiagnoseOptions::default()).unwrap();
    let d = &a.diagnosis;
    assert_eq!(d.cause, "force-ripple");
    // The session's law is one amplitude on both axes with the magnets at q = 0: each
    // axis's own amplitude within 20 % and its phase within 0.2 rad of zero.
    for axis in ["x", "y"] {
        let amp = d.parameters[&format!("amplitude_{axis}_n")];
        let phase = d.parameters[&format!("phase_{axis}_rad")];
        assert!((amp - 1.8).abs() < 0.2 * 1.8, "amplitude {axis} {amp}");
        assert!(phase.abs() < 0.2, "phase {axis} {phase}");
    }
    let pitch = d.parameters["pitch_m"];
    assert!((pitch - 0.024).abs() < 0.2 * 0.024, "pitch {pitch}");
    assert!(d.gain.unwrap() >= 0.5);

    // The model file reads back as written and names the world's effect.
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("model.toml");
    let m = ExtendedModel::from_diagnosis(d);
    m.write(&path).unwrap();
    let back = ExtendedModel::read(&path).unwrap();
    assert_eq!(back, m);
    // It carries the fitted law per axis, phases included.
    let r = back.effects.force_ripple.unwrap();
    assert_eq!(r.amplitude_n[1], d.parameters["amplitude_y_n"]);
    assert_eq!(r.phase_rad[0], d.parameters["phase_x_rad"]);

    // The report and its three figures are written.
    let files = write_report(&a, &tmp.path().join("report")).unwrap();
    assert_eq!(files.len(), 4, "{files:?}");
    for f in &files {
        assert!(std::fs::metadata(f).unwrap().len() > 100, "{}", f.display());
    }
}
