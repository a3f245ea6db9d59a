//! A linear servo axis on a test bench, logged as a lab logs it (one axis, position,
//! reference and drive command, no force sensor) and diagnosed: the cart balance on one
//! axis must identify the axis as a careful identification would — moving mass,
//! Coulomb and viscous friction, the constant force it holds against — and name what
//! else is in it (cogging, the loop's transport delay), while the human side is
//! reported as not judged. The axis (`rigtwin_tests::servo_axis`) is an emulator with
//! stick–slip friction, a law the diagnosis's smoothed friction does not share.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin::session::Session;
use rigtwin_diagnose::{DiagnoseOptions, Diagnosis, diagnose};
use rigtwin_tests::servo_axis::{ServoAxis, run, write_session};

fn diagnosed(axis: &ServoAxis, seed: u64) -> Diagnosis {
    let log = run(axis, 40, 0.1, seed);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("session");
    write_session(&log, axis, &path).unwrap();
    let session = Session::read(&path).unwrap();
    diagnose(&session, &DiagnoseOptions::default())
        .unwrap()
        .diagnosis
}

fn param(d: &Diagnosis, cause: &str, key: &str) -> f64 {
    let c = d
        .causes
        .iter()
        .find(|c| c.name.name() == cause)
        .unwrap_or_else(|| panic!("{cause} not named: {:?}", d.causes));
    c.parameters[key]
}

fn close(what: &str, got: f64, want: f64, rel: f64) {
    assert!(
        (got - want).abs() <= rel * want.abs(),
        "{what}: {got} for {want} (tolerance {:.0} %)",
        rel * 100.0
    );
}

/// The bench axis: friction, cogging and a one-tick transport delay are named, and
/// every parameter is recovered. Tolerances: mass 2 % and Coulomb 3 % (measured
/// within 0.3 %: the fit sees 25 000 moving rows); viscous 5 % (measured 0.3 %; the
/// viscous force is a fifth of the Coulomb's at the moves' mean speed); offset 0.1 N
/// (measured 7 mN); cogging amplitude 10 % and pitch 2 % (measured 2.6 % and 0.7 %,
/// the pitch grid's step); the delay the balance sees is the tick plus half a tick of
/// zero-order hold, 1.5 ms, found at 1.8 ms: 0.5 ms is the bound.
#[test]
fn a_bench_servo_axis_is_identified_on_one_axis() {
    let axis = ServoAxis::bench();
    let d = diagnosed(&axis, 7);
    let names: Vec<&str> = d.causes.iter().map(|c| c.name.name()).collect();
    assert_eq!(
        names,
        ["rail-friction", "force-ripple", "actuation-delay"],
        "{d:#?}"
    );
    close("mass", d.model["moving_mass_x_kg"], axis.mass_kg, 0.02);
    assert!(!d.model.contains_key("moving_mass_y_kg"), "{:?}", d.model);
    let offset = d.model["offset_x_n"];
    assert!(
        (offset + axis.offset_n).abs() < 0.1,
        "the command holds {offset} N against a {} N pull",
        axis.offset_n
    );
    close(
        "Coulomb",
        param(&d, "rail-friction", "coulomb_n"),
        axis.coulomb_n,
        0.03,
    );
    close(
        "viscous",
        param(&d, "rail-friction", "viscous_n_s_per_m"),
        axis.viscous_n_s_per_m,
        0.05,
    );
    close(
        "cogging",
        param(&d, "force-ripple", "amplitude_x_n"),
        axis.cogging_n,
        0.10,
    );
    close(
        "pitch",
        param(&d, "force-ripple", "pitch_m"),
        axis.cogging_pitch_m,
        0.02,
    );
    let delay = param(&d, "actuation-delay", "delay_ms");
    assert!((delay - 1.5).abs() <= 0.5, "delay {delay} ms for 1.5 ms");
    assert!(
        d.causes
            .iter()
            .all(|c| c.parameters.keys().all(|k| !k.contains("_y_"))),
        "no parameter of the absent axis: {:?}",
        d.causes
    );
    for human in ["stretch-reflex", "grip-compliance", "handle-mass"] {
        assert!(
            d.not_judged.iter().any(|n| n.effect.name() == human),
            "{human} must be reported as not judged: {:?}",
            d.not_judged
        );
    }
    assert!(d.unexplained.is_none(), "{:?}", d.unexplained);
}

/// An axis with friction alone (no cogging, the command acting within its tick): only
/// friction is named, so the one-axis balance does not invent effects.
#[test]
fn a_servo_axis_with_friction_alone_names_friction_alone() {
    let mut axis = ServoAxis::bench();
    axis.cogging_n = 0.0;
    axis.delay_ticks = 0;
    let d = diagnosed(&axis, 11);
    let names: Vec<&str> = d.causes.iter().map(|c| c.name.name()).collect();
    assert_eq!(names, ["rail-friction"], "{d:#?}");
    close("mass", d.model["moving_mass_x_kg"], axis.mass_kg, 0.02);
    close(
        "Coulomb",
        param(&d, "rail-friction", "coulomb_n"),
        axis.coulomb_n,
        0.03,
    );
    assert!(d.unexplained.is_none(), "{:?}", d.unexplained);
}

/// A command logged with the opposite sign (a map's scale of the wrong sign) is an
/// error that says so, not a diagnosis of "friction that drives the motion".
#[test]
fn a_reversed_command_is_an_error_naming_the_sign() {
    let axis = ServoAxis::bench();
    let mut log = run(&axis, 12, 0.1, 3);
    log.cmd_v.iter_mut().for_each(|u| *u = -*u);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("session");
    write_session(&log, &axis, &path).unwrap();
    let session = Session::read(&path).unwrap();
    let Err(e) = diagnose(&session, &DiagnoseOptions::default()) else {
        panic!("a reversed command must not diagnose");
    };
    let text = e.to_string();
    assert!(
        text.contains("moving mass of the x axis is -") && text.contains("reversed"),
        "{text}"
    );
}
