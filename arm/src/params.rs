//! Anthropometric and neuromuscular parameters of the simulated arm.
//!
//! Every key carries its unit. Defaults reproduce the seeds' set-ups: segments of
//! Shadmehr & Mussa-Ivaldi (1994), moment arms of Selen, Franklin & Wolpert (2009).

use serde::{Deserialize, Serialize};

use crate::error::ArmError;
use crate::muscles::{MuscleModel, MuscleParams};
use crate::noise::NoiseParams;

/// One rigid link of the planar arm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    /// Joint-to-joint (or joint-to-hand) length \[m\].
    pub length_m: f64,
    /// Mass \[kg\].
    pub mass_kg: f64,
    /// Distance of the centre of mass from the proximal joint, along the link \[m\].
    pub com_m: f64,
    /// Moment of inertia about the centre of mass, perpendicular to the plane \[kg m²\].
    pub inertia_kg_m2: f64,
}

impl Segment {
    /// Upper arm of Shadmehr & Mussa-Ivaldi (1994), Table 1.
    pub const SHADMEHR_UPPER: Segment = Segment {
        length_m: 0.33,
        mass_kg: 1.93,
        com_m: 0.165,
        inertia_kg_m2: 0.0141,
    };
    /// Forearm plus hand of Shadmehr & Mussa-Ivaldi (1994), Table 1.
    pub const SHADMEHR_FORE: Segment = Segment {
        length_m: 0.34,
        mass_kg: 1.52,
        com_m: 0.19,
        inertia_kg_m2: 0.0188,
    };

    /// The same segment rescaled to a subject's measured length \[m\].
    ///
    /// Geometric similarity at constant mass: the centre of mass keeps its fractional
    /// position (`com_m` scales by `s = length_m / self.length_m`) and the radius of
    /// gyration scales with length, so the inertia about the centre of mass scales by
    /// `s²`. Mass is kept, since a length says nothing about body mass; override
    /// `mass_kg` separately when it is known.
    pub fn scaled_to_length(&self, length_m: f64) -> Result<Segment, ArmError> {
        if !(length_m.is_finite() && length_m > 0.0) {
            return Err(ArmError::InvalidParameter {
                key: "length_m",
                reason: format!("must be finite and > 0, got {length_m}"),
            });
        }
        let s = length_m / self.length_m;
        Ok(Segment {
            length_m,
            mass_kg: self.mass_kg,
            com_m: self.com_m * s,
            inertia_kg_m2: self.inertia_kg_m2 * s * s,
        })
    }

    /// Checks that the segment is physical: positive finite length, mass and inertia,
    /// centre of mass within the link.
    pub fn validate(&self, name: &'static str) -> Result<(), ArmError> {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !ok(self.length_m) || !ok(self.mass_kg) || !ok(self.inertia_kg_m2) {
            return Err(ArmError::InvalidParameter {
                key: name,
                reason: format!("length, mass and inertia must be finite and > 0: {self:?}"),
            });
        }
        if !(self.com_m.is_finite() && self.com_m >= 0.0 && self.com_m <= self.length_m) {
            return Err(ArmError::InvalidParameter {
                key: name,
                reason: format!("com_m must lie in [0, length_m]: {self:?}"),
            });
        }
        Ok(())
    }
}

/// Delayed PD feedback on the muscle-level tracking error (000_* section 4):
/// `a_FB(t) = G_p e(t − δ) + G_d ė(t − δ)` \[N\] for each muscle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedbackParams {
    /// Delay δ \[ms\]; must be a whole number of neural ticks. Default 60 ms (000_* δ_s).
    pub delay_ms: f64,
    /// Position gain G_p \[N of activation per m of stretch\]. Default 500 N/m (chosen:
    /// adds about a third of the intrinsic joint stiffness, stable with the 60 ms delay).
    pub position_gain_n_per_m: f64,
    /// Velocity gain G_d \[N s/m\]. Default 25 N s/m (chosen, same ratio 1/20 s).
    pub velocity_gain_n_s_per_m: f64,
}

impl Default for FeedbackParams {
    fn default() -> Self {
        FeedbackParams {
            delay_ms: 60.0,
            position_gain_n_per_m: 500.0,
            velocity_gain_n_s_per_m: 25.0,
        }
    }
}

/// Extension (off by default): short-latency stretch reflex. Each muscle adds the
/// activation `gain · ė(t − delay)` \[N\], with ė its stretch velocity relative to the plan.
/// Linear (not rectified) so it appears in estimates as a delayed damping.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StretchReflex {
    /// Reflex delay \[ms\], 10–40 ms in humans (000_* section 2); whole neural ticks.
    pub delay_ms: f64,
    /// Gain \[N of activation per m/s of stretch velocity\].
    pub gain_n_s_per_m: f64,
}

impl StretchReflex {
    /// A typical short-latency reflex: 25 ms, 50 N s/m.
    pub const TYPICAL: StretchReflex = StretchReflex {
        delay_ms: 25.0,
        gain_n_s_per_m: 50.0,
    };
}

/// Extension (off by default): muscle stiffness that changes over a session. In trial
/// `n` (0-based, from [`crate::human::HumanConfig::trial_index`]) every muscle stiffness
/// `K_m` (and so its damping) is multiplied by `scale_per_trial^n`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StiffnessDrift {
    /// Factor per trial \[-\], e.g. 1.01 for +1 % per trial.
    pub scale_per_trial: f64,
}

impl StiffnessDrift {
    /// The stiffness scale in trial `trial_index`.
    pub fn scale(&self, trial_index: u32) -> f64 {
        self.scale_per_trial.powf(f64::from(trial_index))
    }
}

/// The whole arm. Sections missing from a config take their defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArmParams {
    /// Shoulder to elbow.
    pub upper: Segment,
    /// Elbow to hand (forearm plus hand).
    pub fore: Segment,
    /// The six muscles.
    pub muscles: MuscleParams,
    /// Delayed muscle-level PD feedback.
    pub feedback: FeedbackParams,
    /// Signal-dependent motor noise.
    pub noise: NoiseParams,
    /// Extension, off (absent) by default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stretch_reflex: Option<StretchReflex>,
    /// Extension, off (absent) by default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness_drift: Option<StiffnessDrift>,
}

impl Default for ArmParams {
    fn default() -> Self {
        ArmParams {
            upper: Segment::SHADMEHR_UPPER,
            fore: Segment::SHADMEHR_FORE,
            muscles: MuscleParams::default(),
            feedback: FeedbackParams::default(),
            noise: NoiseParams::default(),
            stretch_reflex: None,
            stiffness_drift: None,
        }
    }
}

/// Body mass of the subject the default segments describe, kg. Derived: Shadmehr &
/// Mussa-Ivaldi's 1.93 and 1.52 kg are, to the gram, Winter's segment fractions of
/// body mass (upper arm 0.028; forearm 0.016 plus hand 0.006, 0.022) of a 69 kg body
/// (Winter, *Biomechanics and Motor Control of Human Movement*, Table 4.1).
pub const DEFAULT_BODY_MASS_KG: f64 = 69.0;

impl ArmParams {
    /// The same arm for a subject of `body_mass_kg` (the session manifest's
    /// `body_mass_kg`): each segment's mass and moment of inertia in proportion to body
    /// mass, its length and centre of mass kept (fixed fractions of body mass, as the
    /// tables behind the defaults: [`DEFAULT_BODY_MASS_KG`]). A 69 kg subject keeps the
    /// arm bit for bit.
    pub fn with_body_mass(self, body_mass_kg: f64) -> Result<ArmParams, ArmError> {
        if !(body_mass_kg.is_finite() && body_mass_kg > 0.0) {
            return Err(ArmError::InvalidParameter {
                key: "body_mass_kg",
                reason: format!("must be finite and > 0, got {body_mass_kg}"),
            });
        }
        // 69 / 69 is exactly 1, and a product with 1 is the value itself.
        Ok(self.with_mass_scale(body_mass_kg / DEFAULT_BODY_MASS_KG))
    }

    /// The same arm with every segment's mass and moment of inertia times `factor`, its
    /// lengths and centres of mass kept: a heavier or lighter arm of the same build.
    #[must_use]
    pub fn with_mass_scale(mut self, factor: f64) -> ArmParams {
        for s in [&mut self.upper, &mut self.fore] {
            s.mass_kg *= factor;
            s.inertia_kg_m2 *= factor;
        }
        self
    }

    /// The default arm of a subject as a session manifest describes one: its segment
    /// lengths and body mass where given ([`Self::with_lengths`],
    /// [`Self::with_body_mass`]), the defaults where not.
    pub fn of_subject(
        upper_arm_m: Option<f64>,
        forearm_m: Option<f64>,
        body_mass_kg: Option<f64>,
    ) -> Result<ArmParams, ArmError> {
        let d = ArmParams::default();
        let arm = ArmParams::with_lengths(
            upper_arm_m.unwrap_or(d.upper.length_m),
            forearm_m.unwrap_or(d.fore.length_m),
        )?;
        match body_mass_kg {
            Some(kg) => arm.with_body_mass(kg),
            None => Ok(arm),
        }
    }

    /// The default arm with a subject's segment lengths \[m\] (the session manifest's
    /// `upper_arm_m`, `forearm_m`); see [`Segment::scaled_to_length`] for the scaling.
    pub fn with_lengths(upper_arm_m: f64, forearm_m: f64) -> Result<ArmParams, ArmError> {
        let mut arm = ArmParams::default();
        arm.upper = arm.upper.scaled_to_length(upper_arm_m)?;
        arm.fore = arm.fore.scaled_to_length(forearm_m)?;
        Ok(arm)
    }

    /// The stiffness-drift scale in a trial (1 when the extension is off).
    pub fn stiffness_scale(&self, trial_index: u32) -> f64 {
        self.stiffness_drift.map_or(1.0, |d| d.scale(trial_index))
    }

    /// Checks every parameter; a bad one is named by its key.
    pub fn validate(&self) -> Result<(), ArmError> {
        self.upper.validate("upper")?;
        self.fore.validate("fore")?;
        MuscleModel::new(&self.muscles)?;
        let nonneg = |key: &'static str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(ArmError::InvalidParameter {
                    key,
                    reason: format!("must be finite and >= 0, got {v}"),
                })
            }
        };
        nonneg("feedback.delay_ms", self.feedback.delay_ms)?;
        nonneg(
            "feedback.position_gain_n_per_m",
            self.feedback.position_gain_n_per_m,
        )?;
        nonneg(
            "feedback.velocity_gain_n_s_per_m",
            self.feedback.velocity_gain_n_s_per_m,
        )?;
        nonneg("noise.activation_cv", self.noise.activation_cv)?;
        nonneg("noise.time_constant_ms", self.noise.time_constant_ms)?;
        if let Some(r) = &self.stretch_reflex {
            nonneg("stretch_reflex.delay_ms", r.delay_ms)?;
            nonneg("stretch_reflex.gain_n_s_per_m", r.gain_n_s_per_m)?;
        }
        if let Some(d) = &self.stiffness_drift
            && !(d.scale_per_trial.is_finite() && d.scale_per_trial > 0.0)
        {
            return Err(ArmError::InvalidParameter {
                key: "stiffness_drift.scale_per_trial",
                reason: format!("must be finite and > 0, got {}", d.scale_per_trial),
            });
        }
        Ok(())
    }
}
