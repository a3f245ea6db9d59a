//! The catalog: every effect the diagnosis can name, as a type.
//!
//! [`EffectKind`] is an effect's identity (its catalog name, the balance that judges it);
//! [`Effect`] is an effect with its fitted parameters in the types that simulate it, the
//! world's [`PlantEffects`] entries and the arm's [`StretchReflex`]. The catalog's names are
//! strings only at the file boundary (`diagnose --json`, the model file): there an unknown
//! or renamed name is an error naming it and the names that exist.
//!
//! Adding an effect is one arm in each enum here and one candidate file on the side that
//! judges it (`friction.rs` … for the cart balance, `hand.rs` for the hand's); every
//! `match` over [`EffectKind`] (the physical checks of `decide.rs`, the report's units and
//! figures, the generator of hidden effects in `tests/`) then fails to compile until it
//! says what the new effect means to it.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use rigtwin_arm::params::StretchReflex;
use rigtwin_world::PlantEffects;
use rigtwin_world::config::{
    ActuationDelay, ForceRipple, GripCompliance, HandleMass, RailFriction, SensorEffect,
};
use serde::{Deserialize, Serialize};

/// The balance that judges an effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    /// The cart force balance (motor command, sensor force, cart motion): the rig's own
    /// effects.
    Plant,
    /// The hand balance (the response to each force pulse): what sits between the sensor
    /// and the subject's arm, and the subject's reflex.
    Human,
}

/// An effect of the catalog, by identity. Serialised as its catalog name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EffectKind {
    /// Coulomb and viscous friction on each rail ([`RailFriction`]).
    RailFriction,
    /// Position-periodic motor force, cogging ([`ForceRipple`]).
    ForceRipple,
    /// The motor force behind its command ([`ActuationDelay`]).
    ActuationDelay,
    /// The force sensor's frame turned against the rig's ([`SensorEffect::rotation_deg`]).
    SensorRotation,
    /// The subject's short-latency stretch reflex ([`StretchReflex`]).
    StretchReflex,
    /// A compliant grip between handle and hand ([`GripCompliance`]).
    GripCompliance,
    /// Extra mass between the sensor and the hand ([`HandleMass`]).
    HandleMass,
}

impl EffectKind {
    /// The whole catalog, plant side first, each side in the order the report lists it.
    pub const ALL: [EffectKind; 7] = [
        EffectKind::RailFriction,
        EffectKind::ForceRipple,
        EffectKind::ActuationDelay,
        EffectKind::SensorRotation,
        EffectKind::StretchReflex,
        EffectKind::GripCompliance,
        EffectKind::HandleMass,
    ];

    /// The catalog name (as in `diagnose --json`, the model file and the report).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            EffectKind::RailFriction => "rail-friction",
            EffectKind::ForceRipple => "force-ripple",
            EffectKind::ActuationDelay => "actuation-delay",
            EffectKind::SensorRotation => "sensor-rotation",
            EffectKind::StretchReflex => "stretch-reflex",
            EffectKind::GripCompliance => "grip-compliance",
            EffectKind::HandleMass => "handle-mass",
        }
    }

    /// The parameters a diagnosis reports for it (`Cause::parameters`' keys, units in
    /// the names); a sweep compares one of them with the size it hid.
    #[must_use]
    pub const fn parameter_names(self) -> &'static [&'static str] {
        match self {
            EffectKind::RailFriction => {
                &["coulomb_n", "viscous_n_s_per_m", "smooth_velocity_m_per_s"]
            }
            EffectKind::ForceRipple => &[
                "amplitude_x_n",
                "amplitude_y_n",
                "pitch_m",
                "phase_x_rad",
                "phase_y_rad",
            ],
            EffectKind::ActuationDelay => &["delay_ms"],
            EffectKind::SensorRotation => &["angle_deg"],
            EffectKind::StretchReflex => &["delay_ms", "gain"],
            EffectKind::GripCompliance => &["stiffness_n_per_m", "damping_n_s_per_m"],
            EffectKind::HandleMass => &["extra_mass_kg"],
        }
    }

    /// The balance that judges it.
    #[must_use]
    pub const fn side(self) -> Side {
        match self {
            EffectKind::RailFriction
            | EffectKind::ForceRipple
            | EffectKind::ActuationDelay
            | EffectKind::SensorRotation => Side::Plant,
            EffectKind::StretchReflex | EffectKind::GripCompliance | EffectKind::HandleMass => {
                Side::Human
            }
        }
    }

    /// The effect of this name, if the catalog has one.
    #[must_use]
    pub fn from_name(name: &str) -> Option<EffectKind> {
        EffectKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl fmt::Display for EffectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // `pad`, so that a width in the format (the report's columns) is honoured.
        f.pad(self.name())
    }
}

/// A name the catalog does not have.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{name}` is not in the catalog (its effects: {})", catalog_names())]
pub struct UnknownEffect {
    /// The name given.
    pub name: String,
}

/// The catalog's names, comma-separated.
fn catalog_names() -> String {
    EffectKind::ALL.map(EffectKind::name).join(", ")
}

impl FromStr for EffectKind {
    type Err = UnknownEffect;

    fn from_str(s: &str) -> Result<EffectKind, UnknownEffect> {
        EffectKind::from_name(s).ok_or_else(|| UnknownEffect {
            name: s.to_string(),
        })
    }
}

/// An effect with its parameters, in the types that simulate it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Effect {
    /// See [`EffectKind::RailFriction`].
    RailFriction(RailFriction),
    /// See [`EffectKind::ForceRipple`]; an axis a rig lacks has amplitude 0.
    ForceRipple(ForceRipple),
    /// See [`EffectKind::ActuationDelay`].
    ActuationDelay(ActuationDelay),
    /// See [`EffectKind::SensorRotation`]: the rotation alone (no offset, no low-pass).
    SensorRotation(SensorEffect),
    /// See [`EffectKind::StretchReflex`].
    StretchReflex(StretchReflex),
    /// See [`EffectKind::GripCompliance`].
    GripCompliance(GripCompliance),
    /// See [`EffectKind::HandleMass`].
    HandleMass(HandleMass),
}

/// A fitted parameter an effect needs and the fit did not give.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{effect}: no fitted `{key}`")]
pub struct MissingParameter {
    /// The effect.
    pub effect: EffectKind,
    /// The parameter's name (unit in the name).
    pub key: &'static str,
}

impl Effect {
    /// Its identity.
    #[must_use]
    pub const fn kind(&self) -> EffectKind {
        match self {
            Effect::RailFriction(_) => EffectKind::RailFriction,
            Effect::ForceRipple(_) => EffectKind::ForceRipple,
            Effect::ActuationDelay(_) => EffectKind::ActuationDelay,
            Effect::SensorRotation(_) => EffectKind::SensorRotation,
            Effect::StretchReflex(_) => EffectKind::StretchReflex,
            Effect::GripCompliance(_) => EffectKind::GripCompliance,
            Effect::HandleMass(_) => EffectKind::HandleMass,
        }
    }

    /// The effect a fit's named parameters describe (units in the names, as the
    /// candidates give them). A fitted level that the simulation cannot take (a
    /// negative friction, delay, mass or reflex gain) is clipped to 0; the diagnosis has
    /// already refused to name an effect whose fit is unphysical (`decide.rs`).
    ///
    /// # Errors
    /// [`MissingParameter`] naming the first parameter the effect needs and `p` lacks.
    pub fn from_parameters(
        kind: EffectKind,
        p: &BTreeMap<String, f64>,
    ) -> Result<Effect, MissingParameter> {
        let get = |key: &'static str| {
            p.get(key)
                .copied()
                .ok_or(MissingParameter { effect: kind, key })
        };
        Ok(match kind {
            EffectKind::RailFriction => Effect::RailFriction(RailFriction {
                coulomb_n: get("coulomb_n")?.max(0.0),
                viscous_n_s_per_m: get("viscous_n_s_per_m")?.max(0.0),
                smooth_velocity_m_per_s: get("smooth_velocity_m_per_s")?,
            }),
            EffectKind::ForceRipple => {
                // Each axis has its own amplitude and phase; a rig of one axis has only
                // its own, and the other axis has no ripple.
                let axis = |a: &str| {
                    p.get(&format!("amplitude_{a}_n")).map(|&amp| {
                        let phase = p.get(&format!("phase_{a}_rad")).copied();
                        (amp, phase.unwrap_or(0.0))
                    })
                };
                let (x, y) = (axis("x"), axis("y"));
                if x.is_none() && y.is_none() {
                    return Err(MissingParameter {
                        effect: kind,
                        key: "amplitude_x_n",
                    });
                }
                let (ax, px) = x.unwrap_or((0.0, 0.0));
                let (ay, py) = y.unwrap_or((0.0, 0.0));
                Effect::ForceRipple(ForceRipple {
                    amplitude_n: [ax, ay],
                    pitch_m: get("pitch_m")?,
                    phase_rad: [px, py],
                })
            }
            EffectKind::ActuationDelay => Effect::ActuationDelay(ActuationDelay {
                delay_ms: get("delay_ms")?.max(0.0),
            }),
            EffectKind::SensorRotation => Effect::SensorRotation(SensorEffect {
                rotation_deg: get("angle_deg")?,
                offset_n: [0.0; 2],
                lowpass_hz: 0.0,
            }),
            EffectKind::StretchReflex => Effect::StretchReflex(StretchReflex {
                delay_ms: get("delay_ms")?.max(0.0),
                gain_n_s_per_m: get("gain")?.max(0.0),
            }),
            EffectKind::GripCompliance => Effect::GripCompliance(GripCompliance {
                stiffness_n_per_m: get("stiffness_n_per_m")?,
                damping_n_s_per_m: p.get("damping_n_s_per_m").copied().unwrap_or(0.0).max(0.0),
            }),
            EffectKind::HandleMass => Effect::HandleMass(HandleMass {
                extra_mass_kg: get("extra_mass_kg")?.max(0.0),
            }),
        })
    }

    /// Puts the effect into a plant's effects, or a subject's reflex.
    pub fn add_to(&self, effects: &mut PlantEffects, stretch_reflex: &mut Option<StretchReflex>) {
        match *self {
            Effect::RailFriction(e) => effects.rail_friction = Some(e),
            Effect::ForceRipple(e) => effects.force_ripple = Some(e),
            Effect::ActuationDelay(e) => effects.actuation_delay = Some(e),
            Effect::SensorRotation(e) => effects.sensor = Some(e),
            Effect::StretchReflex(e) => *stretch_reflex = Some(e),
            Effect::GripCompliance(e) => effects.grip_compliance = Some(e),
            Effect::HandleMass(e) => effects.handle_mass = Some(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every effect is built from exactly the parameters `parameter_names` lists (a sweep
    /// checks its `parameter` against them), and each one it needs is among them.
    #[test]
    fn parameter_names_build_every_effect() {
        for kind in EffectKind::ALL {
            let p: BTreeMap<String, f64> = kind
                .parameter_names()
                .iter()
                .map(|n| ((*n).to_owned(), 0.01))
                .collect();
            assert!(Effect::from_parameters(kind, &p).is_ok(), "{}", kind.name());
            for n in kind.parameter_names() {
                let mut less = p.clone();
                less.remove(*n);
                let optional = matches!(
                    *n,
                    "phase_x_rad"
                        | "phase_y_rad"
                        | "damping_n_s_per_m"
                        | "amplitude_x_n"
                        | "amplitude_y_n"
                );
                assert_eq!(
                    Effect::from_parameters(kind, &less).is_ok(),
                    optional,
                    "{} without {n}",
                    kind.name()
                );
            }
        }
    }

    #[test]
    fn every_name_reads_back_as_its_effect_and_a_wrong_one_lists_the_catalog() {
        for k in EffectKind::ALL {
            assert_eq!(k.name().parse::<EffectKind>(), Ok(k));
            // The JSON and TOML spelling is the catalog name.
            let toml_text = toml::to_string(&BTreeMap::from([("e", k)])).unwrap();
            assert_eq!(toml_text.trim(), format!("e = \"{}\"", k.name()));
        }
        let e = "rail_friction".parse::<EffectKind>().unwrap_err();
        assert!(e.to_string().contains("rail-friction, force-ripple"), "{e}");
    }

    #[test]
    fn each_effect_lands_in_its_own_slot_and_nowhere_else() {
        let p: BTreeMap<String, f64> = [
            ("coulomb_n", 2.0),
            ("viscous_n_s_per_m", 5.0),
            ("smooth_velocity_m_per_s", 0.001),
            ("amplitude_y_n", 0.6),
            ("phase_y_rad", 1.0),
            ("pitch_m", 0.03),
            ("delay_ms", 2.0),
            ("angle_deg", 7.0),
            ("gain", 60.0),
            ("stiffness_n_per_m", 1500.0),
            ("extra_mass_kg", 0.3),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        for k in EffectKind::ALL {
            let e = Effect::from_parameters(k, &p).unwrap();
            assert_eq!(e.kind(), k);
            let (mut plant, mut reflex) = (PlantEffects::default(), None);
            e.add_to(&mut plant, &mut reflex);
            let set = [
                plant.rail_friction.is_some(),
                plant.force_ripple.is_some(),
                plant.actuation_delay.is_some(),
                plant.sensor.is_some(),
                reflex.is_some(),
                plant.grip_compliance.is_some(),
                plant.handle_mass.is_some(),
            ];
            let at = EffectKind::ALL.iter().position(|&x| x == k).unwrap();
            for (i, s) in set.into_iter().enumerate() {
                assert_eq!(s, i == at, "{k}: slot {i}");
            }
        }
        // A rig of one axis: the other axis has no ripple.
        let Effect::ForceRipple(r) = Effect::from_parameters(EffectKind::ForceRipple, &p).unwrap()
        else {
            unreachable!()
        };
        assert_eq!((r.amplitude_n, r.phase_rad), ([0.0, 0.6], [0.0, 1.0]));
        let missing = Effect::from_parameters(EffectKind::HandleMass, &BTreeMap::new());
        assert_eq!(
            missing.unwrap_err().to_string(),
            "handle-mass: no fitted `extra_mass_kg`"
        );
    }

    /// The balances' lists are the catalog split by side, in the catalog's order.
    #[test]
    fn the_two_sides_are_the_catalog_split_by_side() {
        let side = |s: Side| -> Vec<EffectKind> {
            EffectKind::ALL
                .into_iter()
                .filter(|k| k.side() == s)
                .collect()
        };
        assert_eq!(crate::PLANT_SIDE.to_vec(), side(Side::Plant));
        assert_eq!(crate::HUMAN_SIDE.to_vec(), side(Side::Human));
    }
}
