//! Bad protocol input is rejected with an error that names the key, never a panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use rigtwin::protocol::{BUILTIN, Protocol, ProtocolError};

fn parse(text: &str) -> Result<Protocol, ProtocolError> {
    Protocol::from_toml(text, Path::new("test.toml"))
}

fn reach() -> String {
    BUILTIN[0].1.to_owned()
}

/// Replace the first line that starts with `key =` by `key = value`.
fn set(text: &str, key: &str, value: &str) -> String {
    let mut done = false;
    text.lines()
        .map(|l| {
            if !done && l.trim_start().starts_with(&format!("{key} =")) {
                done = true;
                format!("{key} = {value}")
            } else {
                l.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn shipped_protocols_are_valid() {
    for (name, _) in BUILTIN {
        let p = Protocol::builtin(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(p.name, name);
        assert!(p.trials_per_subject() > 0);
    }
    // The files on disk are the built-in copies.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../hil/protocols");
    for (name, text) in BUILTIN {
        let on_disk = std::fs::read_to_string(dir.join(format!("{name}.toml"))).unwrap();
        assert_eq!(on_disk, text, "{name}");
    }
}

#[test]
fn unknown_key_is_named_with_its_line() {
    let text = reach().replace(
        "movement_s = 3.0",
        "movement_s = 3.0\nmovement_time_s = 3.0",
    );
    let e = parse(&text).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ProtocolError::Parse { .. }), "{msg}");
    assert!(msg.contains("movement_time_s"), "{msg}");
    assert!(msg.contains("line"), "{msg}");
}

#[test]
fn unknown_key_in_the_embedded_controller_is_named() {
    let text = reach().replace("amplitude_n = 15.0", "amplitude_n = 15.0\namplitude = 15.0");
    let msg = parse(&text).unwrap_err().to_string();
    assert!(msg.contains("amplitude"), "{msg}");
}

#[test]
fn wrong_type_is_named() {
    let text = set(&reach(), "trials", "\"many\"");
    let e = parse(&text).unwrap_err();
    assert!(e.to_string().contains("trials"), "{e}");
}

#[test]
fn bad_values_name_every_key() {
    let mut text = set(&reach(), "trials", "10");
    text = set(&text, "movement_s", "-3.0");
    text = set(&text, "rate_hz", "3000");
    text = set(&text, "trigger_position_m", "0.5");
    text = text.replace("mass_kg = [5.0, 5.0]", "mass_kg = [0.0, 5.0]");
    let e = parse(&text).unwrap_err();
    for key in [
        "reach.repetitions",
        "reach.movement_s",
        "recording.rate_hz",
        "reach.trigger_position_m",
        "controller.admittance.mass_kg[0]",
    ] {
        assert!(e.names(key), "{key} not named in: {e}");
    }
}

/// Centre-out goals must lie inside the rig and away from the start.
#[test]
fn centre_out_goals_are_checked() {
    let text = reach().replace(
        "trigger_position_m = -0.025",
        "trigger_position_m = -0.025\ntargets_m = [[0.0, -0.12], [0.5, 0.0], [0.1, 0.0]]",
    );
    let e = parse(&text).unwrap_err();
    for key in ["reach.targets_m[0]", "reach.targets_m[1][0]"] {
        assert!(e.names(key), "{key} not named in: {e}");
    }
    assert!(!e.names("reach.targets_m[2]"), "{e}");
    assert!(e.to_string().contains("20 mm"), "{e}");
}

#[test]
fn durations_must_be_whole_ticks() {
    let e = parse(&set(&reach(), "still_before_s", "0.00001")).unwrap_err();
    assert!(e.names("reach.still_before_s"), "{e}");
}

/// The time at the goal of a reach out and back is a duration like the others: not
/// negative, whole ticks; a good one lengthens the trial by it and the way back.
#[test]
fn the_time_at_the_goal_before_the_way_back_is_checked() {
    let with = |v: &str| {
        reach().replace(
            "movement_s = 3.0",
            &format!("movement_s = 3.0\nback_after_s = {v}"),
        )
    };
    for bad in ["-0.25", "0.00001"] {
        let e = parse(&with(bad)).unwrap_err();
        assert!(e.names("reach.back_after_s"), "{bad}: {e}");
    }
    let p = parse(&with("0.25")).unwrap();
    // 0.25 still + 3 out + 0.25 at the goal + 3 back + 0.25 still.
    assert!(
        (p.reach().trial_s() - 6.75).abs() < 1e-12,
        "{}",
        p.reach().trial_s()
    );
    assert!((p.trial_s().0 - 6.75).abs() < 1e-12);
}

#[test]
fn a_section_of_another_kind_is_refused() {
    let text = format!("{}\n[hold]\nforce_n = 10.0\n", reach());
    let e = parse(&text).unwrap_err();
    assert!(e.names("hold"), "{e}");
}

#[test]
fn subject_arm_errors_are_named() {
    let text = format!(
        "{}\n[subjects.arm.upper]\nlength_m = -0.3\nmass_kg = 1.9\ncom_m = 0.1\ninertia_kg_m2 = 0.01\n",
        reach()
    );
    let e = parse(&text).unwrap_err();
    assert!(e.names("subjects.arm.upper"), "{e}");
}

#[test]
fn garbage_never_panics() {
    for text in [
        "",
        "name = 1",
        "[[[",
        "kind = \"reach-perturb\"",
        "name = \"x\"\nkind = \"fly\"",
    ] {
        assert!(parse(text).is_err(), "{text:?} was accepted");
    }
    let e = Protocol::load(Path::new("/nonexistent/protocol.toml")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/protocol.toml"), "{e}");
    // The I/O cause is the error's source (printed once by the command's error chain).
    assert!(std::error::Error::source(&e).is_some());
}
