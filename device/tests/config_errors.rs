//! Bad configs give errors that name the key; good TOML round-trips.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::{Controller, ControllerConfig, LawKind, Rate};

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
    assert!(c.validate().unwrap_err().to_string().contains(&format!(
        "motor_rate_hz must divide control_rate_hz = {}",
        Rate::CONTROL.hz()
    )));
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

#[test]
fn watchdog_keys_are_checked_by_name() {
    // stale_force_ticks = 1 would trip on every reading (each is a run of one); a stall
    // threshold above the smaller force limit (150 N here) can never be reached by a
    // clamped command; a deadline window longer than its 64-tick word, or a budget a
    // window can never exceed (a 16-tick window holds at most 8 late ticks, since each
    // follows a skipped one), would never trip.
    let text = "[safety]\nforce_limit_n = [200.0, 150.0]\nstale_force_ticks = 1\n\
                encoder_stall_force_n = 160.0\ndeadline_window_ticks = 65\n";
    let e = toml::from_str::<ControllerConfig>(text)
        .unwrap()
        .validate()
        .unwrap_err();
    for key in [
        "safety.stale_force_ticks",
        "safety.encoder_stall_force_n",
        "safety.deadline_window_ticks",
    ] {
        assert!(e.names(key), "{key} missing from: {e}");
    }
    assert_eq!(e.errors.len(), 3, "{e}");
    let s = e.to_string();
    assert!(
        s.contains("safety.stale_force_ticks must be 0 (off) or >= 2"),
        "{s}"
    );
    assert!(s.contains("smaller safety.force_limit_n = 150"), "{s}");
    assert!(
        s.contains("safety.deadline_window_ticks must be 0 (off) or <= 64, got 65"),
        "{s}"
    );

    let text = "[safety]\ndeadline_window_ticks = 16\nmax_deadline_overruns = 8\n\
                encoder_stall_force_n = nan\n";
    let e = toml::from_str::<ControllerConfig>(text)
        .unwrap()
        .validate()
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("safety.max_deadline_overruns must be < 8"),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("safety.encoder_stall_force_n must be finite, got NaN"),
        "{e}"
    );
    assert_eq!(e.errors.len(), 2, "{e}");
    // One less is valid: 8 late ticks in 16 is the most there can be, so 7 can be exceeded.
    let c: ControllerConfig =
        toml::from_str("[safety]\ndeadline_window_ticks = 16\nmax_deadline_overruns = 7\n")
            .unwrap();
    assert_eq!(c.validate(), Ok(()));
}

#[test]
fn watchdogs_are_on_by_default_and_zero_switches_each_off_in_toml() {
    // A file that says nothing gets the three watchdogs on: 40 readings (10 ms), 50 N for
    // 80 readings (20 ms), more than 4 late ticks in 64 (16 ms).
    let c: ControllerConfig = toml::from_str("").unwrap();
    let s = &c.safety;
    assert_eq!(
        (
            s.stale_force_ticks,
            s.encoder_stall_force_n,
            s.encoder_stall_ticks,
            s.deadline_window_ticks,
            s.max_deadline_overruns
        ),
        (40, 50.0, 80, 64, 4)
    );
    // A protocol run against a noiseless simulator, or a clamped handle, says so in its
    // file; 0 is valid and survives a round trip (TOML has no null, so "off" is a number).
    let text =
        "[safety]\nstale_force_ticks = 0\nencoder_stall_ticks = 0\ndeadline_window_ticks = 0\n";
    let c: ControllerConfig = toml::from_str(text).unwrap();
    assert_eq!(c.validate(), Ok(()));
    assert_eq!(
        (
            c.safety.stale_force_ticks,
            c.safety.encoder_stall_ticks,
            c.safety.deadline_window_ticks
        ),
        (0, 0, 0)
    );
    let back: ControllerConfig = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
    assert_eq!(back, c);
    assert!(Controller::new(c).is_ok());
}
