//! Parameter files: TOML round trip, defaults, unknown keys.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_arm::params::{ArmParams, StiffnessDrift, StretchReflex};

/// Every parameter survives TOML and back, extensions included.
#[test]
fn toml_round_trip() {
    let p = ArmParams {
        stretch_reflex: Some(StretchReflex::TYPICAL),
        stiffness_drift: Some(StiffnessDrift {
            scale_per_trial: 1.01,
        }),
        ..ArmParams::default()
    };
    let text = toml::to_string(&p).unwrap();
    assert!(
        text.contains("length_m") && text.contains("delay_ms") && text.contains("scale_per_trial")
    );
    let back: ArmParams = toml::from_str(&text).unwrap();
    assert_eq!(back, p);
}

/// A partial file keeps the defaults (extensions off) and overrides what it names.
#[test]
fn partial_file_takes_defaults() {
    let p: ArmParams = toml::from_str(
        "[upper]\nlength_m = 0.31\nmass_kg = 1.93\ncom_m = 0.155\ninertia_kg_m2 = 0.0124\n",
    )
    .unwrap();
    assert_eq!(p.upper.length_m, 0.31);
    assert_eq!(p.fore, ArmParams::default().fore);
    assert!(p.stretch_reflex.is_none() && p.stiffness_drift.is_none());
}

/// A misspelt key is rejected and named.
#[test]
fn unknown_keys_are_rejected() {
    let err = toml::from_str::<ArmParams>("[feedback]\ndelay_s = 0.06\n").unwrap_err();
    assert!(err.to_string().contains("delay_s"), "{err}");
}

/// Non-physical values fail validation with their key.
#[test]
fn validation_names_the_key() {
    let mut p = ArmParams::default();
    p.fore.mass_kg = 0.0;
    assert!(p.validate().unwrap_err().to_string().contains("fore"));
    let p = ArmParams {
        stiffness_drift: Some(StiffnessDrift {
            scale_per_trial: 0.0,
        }),
        ..ArmParams::default()
    };
    assert!(
        p.validate()
            .unwrap_err()
            .to_string()
            .contains("scale_per_trial")
    );
}
