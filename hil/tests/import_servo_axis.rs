//! The one-axis example, end to end as a lab runs it: `rigtwin import` of the bench's
//! MATLAB log (`recordings/example-servo-axis.mat`, a struct of column vectors in mm and
//! V) with the map a user writes (`recordings/example-servo-axis.map.toml`) gives the
//! committed session byte for byte, and `rigtwin diagnose --json` on it identifies the
//! emulated axis (`rigtwin_tests::servo_axis::ServoAxis::bench`, disclosed in
//! `recordings/README.md`): moving mass 3.2 kg, Coulomb 4.5 N, viscous 12 N s/m, a
//! 1.5 N cable pull, 0.8 N cogging at a 32 mm pitch, and the loop's one-tick delay.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

#[test]
fn the_bench_log_imports_to_the_committed_session_and_is_identified() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("servo");
    let run = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .current_dir(root())
        .args([
            "import",
            "recordings/example-servo-axis.mat",
            "--map",
            "recordings/example-servo-axis.map.toml",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let committed = root().join("recordings/example-servo-axis");
    let (got, want) = (tree(&out), tree(&committed));
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        want.keys().collect::<Vec<_>>(),
        "the imported session's files"
    );
    for (k, v) in &want {
        assert!(
            got[k] == *v,
            "{} differs from the committed session",
            k.display()
        );
    }

    let model_file = dir.path().join("model.toml");
    let diag = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["diagnose", "--json", "--no-report", "--write-model"])
        .arg(&model_file)
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        diag.status.success(),
        "{}",
        String::from_utf8_lossy(&diag.stderr)
    );
    let d: serde_json::Value = serde_json::from_slice(&diag.stdout).unwrap();
    let names: Vec<&str> = d["causes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["rail-friction", "force-ripple", "actuation-delay"],
        "{d:#}"
    );
    let cause = |name: &str, key: &str| -> f64 {
        d["causes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == name)
            .unwrap()["parameters"][key]
            .as_f64()
            .unwrap()
    };
    let model = |key: &str| d["model"][key].as_f64().unwrap();
    // Tolerances as in tests/tests/servo_axis.rs (there measured over seeds 100-109:
    // mass and Coulomb within 0.15 %, viscous 0.3 %, offset 12 mN, cogging 3.3 %,
    // pitch 1 %, delay 1.53-1.65 ms for the 1.5 ms the balance sees).
    let within = |what: &str, got: f64, want: f64, rel: f64| {
        assert!(
            (got - want).abs() <= rel * want.abs(),
            "{what}: {got} for {want}"
        );
    };
    within("mass", model("moving_mass_x_kg"), 3.2, 0.02);
    within("offset", model("offset_x_n"), 1.5, 0.07);
    within("Coulomb", cause("rail-friction", "coulomb_n"), 4.5, 0.03);
    within(
        "viscous",
        cause("rail-friction", "viscous_n_s_per_m"),
        12.0,
        0.05,
    );
    within("cogging", cause("force-ripple", "amplitude_x_n"), 0.8, 0.10);
    within("pitch", cause("force-ripple", "pitch_m"), 0.032, 0.02);
    within("delay", cause("actuation-delay", "delay_ms"), 1.5, 0.34);
    assert!(d["unexplained"].is_null(), "{}", d["unexplained"]);
    // Its command's one-sample spikes (31, the PID's derivative kicks from single
    // encoder counts) are forces the motor made, not glitches: the command is not
    // searched, and the measured channels have none.
    assert_eq!(
        d["glitches"].as_array().unwrap().len(),
        0,
        "{}",
        d["glitches"]
    );
    assert_eq!(d["slips"].as_array().unwrap().len(), 0, "{}", d["slips"]);
    // Its encoder counts repeat where the axis creeps, not at a fixed share of the
    // rows where it moves: no channel is taken for one held between readings.
    assert_eq!(d["held"].as_array().unwrap().len(), 0, "{}", d["held"]);
    assert_eq!(
        d["repeated_frames"].as_array().unwrap().len(),
        0,
        "{}",
        d["repeated_frames"]
    );
    // The written model carries every cause, the cogging on x alone, and the masses
    // fitted with the causes (none on the absent y axis).
    let m = rigtwin_diagnose::ExtendedModel::read(&model_file).unwrap();
    let model_names: Vec<&str> = m.causes.iter().map(|k| k.name()).collect();
    assert_eq!(model_names, names, "{m:?}");
    let ripple = m.effects.force_ripple.expect("the cogging is in the model");
    within("model cogging", ripple.amplitude_n[0], 0.8, 0.10);
    assert!(ripple.amplitude_n[1] == 0.0, "{ripple:?}");
    assert!(m.effects.rail_friction.is_some() && m.effects.actuation_delay.is_some());
    within("model mass", m.moving_mass_x_kg, 3.2, 0.02);
    assert!(m.moving_mass_y_kg == 0.0, "{m:?}");
    let not_judged: Vec<&str> = d["not_judged"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["effect"].as_str().unwrap())
        .collect();
    for e in [
        "sensor-rotation",
        "stretch-reflex",
        "grip-compliance",
        "handle-mass",
    ] {
        assert!(
            not_judged.contains(&e),
            "{e} must be not judged: {not_judged:?}"
        );
    }
}

/// The other commands accept the one-axis session: `inspect` names the axis, and
/// `estimate` and `compare`, which need a subject's planar arm, say that nothing of
/// theirs applies and where to go instead, and succeed (the session is valid).
#[test]
fn inspect_estimate_and_compare_accept_a_one_axis_session() {
    let session = root().join("recordings/example-servo-axis");
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
            .args(args)
            .arg(&session)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    assert!(run(&["inspect"]).contains("one axis (x"), "inspect");
    let inspected: serde_json::Value = serde_json::from_str(&run(&["inspect", "--json"])).unwrap();
    assert_eq!(inspected["axes"], serde_json::json!(["x"]));
    for cmd in ["estimate", "compare"] {
        let v: serde_json::Value = serde_json::from_str(&run(&[cmd, "--json"])).unwrap();
        assert_eq!(v["applicable"], false, "{cmd}: {v}");
        assert!(
            v["reason"].as_str().unwrap().contains("rigtwin diagnose"),
            "{cmd}: {v}"
        );
    }
}
