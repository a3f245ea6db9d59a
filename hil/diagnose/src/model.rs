//! The extended model that `diagnose --write-model` writes and `compare --model` and
//! `rehearse --model` read: every effect named as a cause, in the world's own
//! [`PlantEffects`] keys (so the same table configures `rigtwin_world::RigConfig::effects`;
//! `handle_mass` and `grip_compliance` live there too) and, for `stretch-reflex`, the
//! arm's own [`StretchReflex`] keys. [`ExtendedModel::apply_to`] puts both into a
//! plant's effects and a subject's reflex (a protocol's, in the `rigtwin` crate).

use std::path::Path;

use rigtwin_arm::params::StretchReflex;
use rigtwin_world::PlantEffects;
use serde::{Deserialize, Serialize};

use super::diagnose::Diagnosis;
use super::effect::EffectKind;
use super::error::DiscrepancyError;

/// A model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtendedModel {
    /// Session it was fitted to.
    pub fitted_to: String,
    /// Catalog name of the strongest cause, or `none` (checked on reading).
    pub cause: String,
    /// Every cause the model carries, strongest first (all of them are in `effects`
    /// and `stretch_reflex`).
    #[serde(default)]
    pub causes: Vec<EffectKind>,
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

impl ExtendedModel {
    /// The model a diagnosis names.
    #[must_use]
    pub fn from_diagnosis(d: &Diagnosis) -> ExtendedModel {
        let mut effects = PlantEffects::default();
        let mut stretch_reflex = None;
        for c in &d.causes {
            c.effect.add_to(&mut effects, &mut stretch_reflex);
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
            causes: d.causes.iter().map(|c| c.name).collect(),
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
        let model: ExtendedModel = toml::from_str(&text).map_err(|e| err(e.to_string()))?;
        if model.cause != "none"
            && let Err(e) = model.cause.parse::<EffectKind>()
        {
            let line = text
                .lines()
                .position(|l| l.trim_start().starts_with("cause"))
                .map_or(0, |i| i + 1);
            return Err(err(format!("line {line}: `cause`: {e} (or `none`)")));
        }
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use rigtwin_world::config::ForceRipple;

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

    /// The catalog's names are checked where they enter: a cause the catalog does not
    /// have (a renamed or misspelt one) is refused naming the file, the key and the
    /// names that exist, never read as a model that silently lacks the effect.
    #[test]
    fn an_unknown_cause_is_refused_naming_the_key_and_the_catalog() {
        let base = with_ripple("amplitude_n = 1.5\npitch_m = 0.02");
        let listed = base.replace(
            "gain = 0.9",
            "causes = [\"force-ripple\", \"rail_friction\"]\ngain = 0.9",
        );
        let err = read(&listed).unwrap_err().to_string();
        assert!(err.contains("model.toml"), "{err}");
        assert!(err.contains("rail_friction"), "{err}");
        assert!(err.contains("rail-friction"), "{err}");
        let first = base.replace("cause = \"force-ripple\"", "cause = \"cogging\"");
        let err = read(&first).unwrap_err().to_string();
        assert!(
            err.contains("line 2: `cause`: `cogging` is not in the catalog"),
            "{err}"
        );
        assert!(err.contains("force-ripple"), "{err}");
        let ok = base.replace("gain = 0.9", "causes = [\"force-ripple\"]\ngain = 0.9");
        assert_eq!(read(&ok).unwrap().causes, vec![EffectKind::ForceRipple]);
    }
}
