//! The extended model that `diagnose --write-model` writes and `compare --model` and
//! `rehearse --model` read: every effect named as a cause, in the world's own
//! [`PlantEffects`] keys (so the same table configures `rigtwin_world::RigConfig::effects`;
//! `handle_mass` and `grip_compliance` live there too) and, for `stretch-reflex`, the
//! arm's own [`StretchReflex`] keys. [`ExtendedModel::apply_to`] puts both into a
//! plant's effects and a subject's reflex (a protocol's, in the `rigtwin` crate).

use std::collections::BTreeMap;
use std::path::Path;

use rigtwin_arm::params::StretchReflex;
use rigtwin_world::PlantEffects;
use rigtwin_world::config::{
    ActuationDelay, ForceRipple, GripCompliance, HandleMass, RailFriction, SensorEffect,
};
use serde::{Deserialize, Serialize};

use super::diagnose::Diagnosis;
use super::error::DiscrepancyError;

/// A model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtendedModel {
    /// Session it was fitted to.
    pub fitted_to: String,
    /// Catalog name of the strongest cause, or `none`.
    pub cause: String,
    /// Every cause the model carries, strongest first (all of them are in `effects`
    /// and `stretch_reflex`).
    #[serde(default)]
    pub causes: Vec<String>,
    /// Held-out gain of the model over the nominal balance.
    pub gain: f64,
    /// Fitted moving mass of the x axis (both carts), kg, from the fit with the causes
    /// (`Diagnosis::model`); 0 on a rig without that axis.
    pub moving_mass_x_kg: f64,
    /// Fitted moving mass of the y axis (upper cart), kg, as the x axis's.
    pub moving_mass_y_kg: f64,
    /// The effects, as `rigtwin_world::PlantEffects`.
    pub effects: PlantEffects,
    /// The subject's short-latency stretch reflex (`stretch-reflex`), as
    /// `rigtwin_arm::params::StretchReflex`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stretch_reflex: Option<StretchReflex>,
}

fn get(p: &BTreeMap<String, f64>, k: &str) -> Option<f64> {
    p.get(k).copied()
}

/// Adds the effect `name` with its fitted `p` to the world's effects (or the arm's
/// reflex); an unknown name adds nothing.
fn add_effect(
    effects: &mut PlantEffects,
    stretch_reflex: &mut Option<StretchReflex>,
    name: &str,
    p: &BTreeMap<String, f64>,
) {
    match name {
        "rail-friction" => {
            if let (Some(c), Some(b), Some(vs)) = (
                get(p, "coulomb_n"),
                get(p, "viscous_n_s_per_m"),
                get(p, "smooth_velocity_m_per_s"),
            ) {
                effects.rail_friction = Some(RailFriction {
                    coulomb_n: c.max(0.0),
                    viscous_n_s_per_m: b.max(0.0),
                    smooth_velocity_m_per_s: vs,
                });
            }
        }
        "force-ripple" => {
            // Each axis has its own amplitude and phase; a rig of one axis has only its
            // own, and the other axis has no ripple.
            let axis = |a: &str| {
                get(p, &format!("amplitude_{a}_n"))
                    .map(|amp| (amp, get(p, &format!("phase_{a}_rad"))))
            };
            let (x, y) = (axis("x"), axis("y"));
            if let (Some(pitch), true) = (get(p, "pitch_m"), x.is_some() || y.is_some()) {
                let (ax, px) = x.map_or((0.0, 0.0), |(a, ph)| (a, ph.unwrap_or(0.0)));
                let (ay, py) = y.map_or((0.0, 0.0), |(a, ph)| (a, ph.unwrap_or(0.0)));
                effects.force_ripple = Some(ForceRipple {
                    amplitude_n: [ax, ay],
                    pitch_m: pitch,
                    phase_rad: [px, py],
                });
            }
        }
        "actuation-delay" => {
            if let Some(ms) = get(p, "delay_ms") {
                effects.actuation_delay = Some(ActuationDelay {
                    delay_ms: ms.max(0.0),
                });
            }
        }
        "sensor-rotation" => {
            if let Some(deg) = get(p, "angle_deg") {
                effects.sensor = Some(SensorEffect {
                    rotation_deg: deg,
                    offset_n: [0.0; 2],
                    lowpass_hz: 0.0,
                });
            }
        }
        "handle-mass" => {
            if let Some(kg) = get(p, "extra_mass_kg") {
                effects.handle_mass = Some(HandleMass {
                    extra_mass_kg: kg.max(0.0),
                });
            }
        }
        "grip-compliance" => {
            if let Some(k) = get(p, "stiffness_n_per_m") {
                effects.grip_compliance = Some(GripCompliance {
                    stiffness_n_per_m: k,
                    damping_n_s_per_m: get(p, "damping_n_s_per_m").unwrap_or(0.0).max(0.0),
                });
            }
        }
        "stretch-reflex" => {
            if let (Some(ms), Some(g)) = (get(p, "delay_ms"), get(p, "gain")) {
                *stretch_reflex = Some(StretchReflex {
                    delay_ms: ms.max(0.0),
                    gain_n_s_per_m: g.max(0.0),
                });
            }
        }
        _ => {}
    }
}

impl ExtendedModel {
    /// The model a diagnosis names.
    #[must_use]
    pub fn from_diagnosis(d: &Diagnosis) -> ExtendedModel {
        let mut effects = PlantEffects::default();
        let mut stretch_reflex = None;
        for c in &d.causes {
            add_effect(&mut effects, &mut stretch_reflex, &c.name, &c.parameters);
        }
        // The masses fitted with the causes (`Diagnosis::model`); an axis a rig lacks has
        // none, and is written as 0 (nothing moves on it).
        let nominal = if d.model.is_empty() {
            &d.baseline
        } else {
            &d.model
        };
        let m = |k: &str| {
            nominal
                .get(k)
                .copied()
                .unwrap_or(if nominal.is_empty() { f64::NAN } else { 0.0 })
        };
        ExtendedModel {
            fitted_to: d.session.clone(),
            cause: d.cause.clone(),
            causes: d.causes.iter().map(|c| c.name.clone()).collect(),
            gain: d.gain.unwrap_or(0.0),
            moving_mass_x_kg: m("moving_mass_x_kg"),
            moving_mass_y_kg: m("moving_mass_y_kg"),
            effects,
            stretch_reflex,
        }
    }

    /// Puts the model into a plant and a subject: its plant effects replace `effects`,
    /// and a fitted stretch reflex replaces `stretch_reflex` (the effects the model does
    /// not name are the nominal ones, off; a subject's reflex stays when the model has
    /// none).
    pub fn apply_to(&self, effects: &mut PlantEffects, stretch_reflex: &mut Option<StretchReflex>) {
        *effects = self.effects.clone();
        if self.stretch_reflex.is_some() {
            *stretch_reflex = self.stretch_reflex;
        }
    }

    /// Writes the model as TOML.
    ///
    /// # Errors
    /// [`DiscrepancyError::Model`] when it cannot be serialised or written.
    pub fn write(&self, path: &Path) -> Result<(), DiscrepancyError> {
        let err = |reason: String| DiscrepancyError::Model {
            path: path.to_path_buf(),
            reason,
        };
        let text = toml::to_string(self).map_err(|e| err(e.to_string()))?;
        let text = format!("# Extended plant model written by `rigtwin diagnose`.\n{text}");
        std::fs::write(path, text).map_err(|e| err(e.to_string()))
    }

    /// Reads a model file.
    ///
    /// # Errors
    /// [`DiscrepancyError::Model`] naming the file and the TOML error (line, key).
    pub fn read(path: &Path) -> Result<ExtendedModel, DiscrepancyError> {
        let err = |reason: String| DiscrepancyError::Model {
            path: path.to_path_buf(),
            reason,
        };
        let text = rigtwin_session::files::read_regular_text(
            path,
            rigtwin_session::files::MAX_CONFIG_BYTES,
        )
        .map_err(|e| err(e.to_string()))?;
        toml::from_str(&text).map_err(|e| err(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    fn with_ripple(ripple: &str) -> String {
        format!(
            "fitted_to = \"s\"\ncause = \"force-ripple\"\ngain = 0.9\nmoving_mass_x_kg = 12.0\n\
             moving_mass_y_kg = 5.0\n[effects.force_ripple]\n{ripple}\n"
        )
    }

    fn read(text: &str) -> Result<ExtendedModel, DiscrepancyError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.toml");
        std::fs::write(&path, text).unwrap();
        ExtendedModel::read(&path)
    }

    /// A ripple is one amplitude for both axes (the form older model files and
    /// protocols have, magnets at `q = 0`) or one per axis with its phases; a third form
    /// is refused naming the file, the key and the forms accepted.
    #[test]
    fn ripple_amplitude_is_one_number_or_one_per_axis() {
        let one = read(&with_ripple("amplitude_n = 1.5\npitch_m = 0.02")).unwrap();
        assert_eq!(
            one.effects.force_ripple,
            Some(ForceRipple::uniform(1.5, 0.02))
        );
        let two = read(&with_ripple(
            "amplitude_n = [1.5, 0.5]\npitch_m = 0.02\nphase_rad = [0.1, -2.0]",
        ))
        .unwrap();
        let r = two.effects.force_ripple.unwrap();
        assert_eq!(r.amplitude_n, [1.5, 0.5]);
        assert_eq!(r.phase_rad, [0.1, -2.0]);
        // What is written reads back the same.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.toml");
        two.write(&path).unwrap();
        assert_eq!(ExtendedModel::read(&path).unwrap(), two);

        let err = read(&with_ripple(
            "amplitude_n = [1.5, 0.5, 2.0]\npitch_m = 0.02",
        ))
        .unwrap_err()
        .to_string();
        assert!(err.contains("model.toml"), "{err}");
        assert!(err.contains("amplitude_n"), "{err}");
        assert!(err.contains("[x, y]"), "{err}");
    }
}
