//! Bad configs give errors that name the key; good TOML round-trips.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::{Controller, ControllerConfig, LawKind};

#[test]
fn negative_mass_is_named() {
    let c: ControllerConfig = toml::from_str("[admittance]\nmass_kg = [-1.0, 5.0]\n").unwrap();
    let e = Controller::new(c).unwrap_err();
    assert!(e.names("admittance.mass_kg[0]"));
    assert!(
        e.to_string()
            .contains("admittance.mass_kg[0] must be > 0, got -1"),
        "{e}"
    );
}

#[test]
fn zero_rates_are_rejected_by_name() {
    let c: ControllerConfig = toml::from_str("control_rate_hz = 0\nmotor_rate_hz = 0\n").unwrap();
    let e = c.validate().unwrap_err();
    assert!(
        e.names("control_rate_hz") && e.names("motor_rate_hz"),
        "{e}"
    );
    let c: ControllerConfig = toml::from_str("motor_rate_hz = 3000\n").unwrap();
    assert!(
        c.validate()
            .unwrap_err()
            .to_string()
            .contains("motor_rate_hz must divide control_rate_hz = 4000")
    );
}

#[test]
fn unknown_keys_are_named() {
    for (text, key) in [
        ("admitance_mass = 3\n", "admitance_mass"),
        ("[safety]\nwall = 0.1\n", "wall"),
        ("[virtual_spring]\nstiffness = [1.0, 1.0]\n", "stiffness"),
    ] {
        let e = toml::from_str::<ControllerConfig>(text)
            .unwrap_err()
            .to_string();
        assert!(e.contains(key), "{e}");
    }
}

#[test]
fn pulse_duration_must_be_whole_ticks_and_other_keys_are_checked() {
    let mut c = ControllerConfig::default();
    c.force_pulse.duration_s = 0.15001;
    c.position_perturbation.transition_s = 0.2;
    c.sensors.force_calibration.matrix = [[1.0, 2.0], [0.5, 1.0]];
    c.virtual_spring.stiffness_n_per_m[1] = f64::NAN;
    c.safety.nonfinite_force_ticks = 0;
    c.imposed_motion.amplitude_m = 0.2;
    let e = c.validate().unwrap_err();
    for key in [
        "force_pulse.duration_s",
        "position_perturbation.transition_s",
        "sensors.force_calibration.matrix",
        "virtual_spring.stiffness_n_per_m[1]",
        "safety.nonfinite_force_ticks",
        "imposed_motion.amplitude_m",
    ] {
        assert!(e.names(key), "{key} missing from: {e}");
    }
    assert_eq!(e.errors.len(), 6, "{e}");
}

#[test]
fn toml_round_trip_and_law_switch() {
    let text = "law = \"virtual-spring\"\n[imposed_motion]\naxis = \"x\"\ncycles = 3\n";
    let c: ControllerConfig = toml::from_str(text).unwrap();
    assert_eq!(c.law, LawKind::VirtualSpring);
    assert_eq!(c.imposed_motion.cycles, 3);
    let back: ControllerConfig = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
    assert_eq!(back, c);
    let mut ctl = Controller::new(c).unwrap();
    assert!(ctl.set_law(LawKind::Admittance).is_ok());
}
