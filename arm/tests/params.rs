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

/// A subject's body mass scales the arm's inertia and nothing else: the default
/// segments are Winter's fractions of 69 kg (0.028 and 0.022 of it, to the gram); a
/// 69 kg subject keeps the arm bit for bit; an 80 kg one has every segment mass and
/// moment of inertia, and so the endpoint inertia `J⁻ᵀ M(q) J⁻¹` (linear in both) at any
/// posture, 80/69 of the default's to round-off (1e-12), with lengths and centres of mass
/// unchanged; a body mass that is not positive and finite is refused by its key.
#[test]
fn body_mass_scales_the_arms_inertia_in_proportion() {
    use rigtwin_arm::impedance::endpoint_inertia;
    use rigtwin_arm::params::DEFAULT_BODY_MASS_KG;
    let d = ArmParams::default();
    assert!((0.028 * DEFAULT_BODY_MASS_KG - d.upper.mass_kg).abs() < 5e-3);
    assert!((0.022 * DEFAULT_BODY_MASS_KG - d.fore.mass_kg).abs() < 5e-3);
    assert_eq!(d.clone().with_body_mass(DEFAULT_BODY_MASS_KG).unwrap(), d);
    let f = 80.0 / DEFAULT_BODY_MASS_KG;
    let heavy = ArmParams::of_subject(Some(0.31), Some(0.35), Some(80.0)).unwrap();
    let light = ArmParams::of_subject(Some(0.31), Some(0.35), None).unwrap();
    for (h, l) in [(heavy.upper, light.upper), (heavy.fore, light.fore)] {
        assert_eq!((h.length_m, h.com_m), (l.length_m, l.com_m));
        assert!((h.mass_kg / l.mass_kg - f).abs() < 1e-12);
        assert!((h.inertia_kg_m2 / l.inertia_kg_m2 - f).abs() < 1e-12);
    }
    for q in [[0.3, 1.2], [0.8, 1.9], [-0.2, 0.7]] {
        let (mh, ml) = (
            endpoint_inertia(&heavy, q).unwrap(),
            endpoint_inertia(&light, q).unwrap(),
        );
        assert!((mh - ml * f).norm() < 1e-12 * ml.norm(), "{mh} vs {ml}");
    }
    for bad in [0.0, -70.0, f64::NAN, f64::INFINITY] {
        let err = d.clone().with_body_mass(bad).unwrap_err();
        assert!(err.to_string().contains("body_mass_kg"), "{err}");
    }
}
