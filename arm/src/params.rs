//! Anthropometric and neuromuscular parameters of the simulated arm.
//!
//! Every key carries its unit. Defaults reproduce the seeds' set-ups: segments of
//! Shadmehr & Mussa-Ivaldi (1994), moment arms of Selen, Franklin & Wolpert (2009).

use serde::{Deserialize, Serialize};

use crate::error::ArmError;

/// One rigid link of the planar arm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    /// Joint-to-joint (or joint-to-hand) length [m].
    pub length_m: f64,
    /// Mass [kg].
    pub mass_kg: f64,
    /// Distance of the centre of mass from the proximal joint, along the link [m].
    pub com_m: f64,
    /// Moment of inertia about the centre of mass, perpendicular to the plane [kg m²].
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

    /// The same segment rescaled to a subject's measured length [m].
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

/// The whole arm.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmParams {
    /// Shoulder to elbow.
    pub upper: Segment,
    /// Elbow to hand (forearm plus hand).
    pub fore: Segment,
}

impl Default for ArmParams {
    fn default() -> Self {
        ArmParams {
            upper: Segment::SHADMEHR_UPPER,
            fore: Segment::SHADMEHR_FORE,
        }
    }
}

impl ArmParams {
    /// The default arm with a subject's segment lengths [m] (the session manifest's
    /// `upper_arm_m`, `forearm_m`); see [`Segment::scaled_to_length`] for the scaling.
    pub fn with_lengths(upper_arm_m: f64, forearm_m: f64) -> Result<ArmParams, ArmError> {
        let mut arm = ArmParams::default();
        arm.upper = arm.upper.scaled_to_length(upper_arm_m)?;
        arm.fore = arm.fore.scaled_to_length(forearm_m)?;
        Ok(arm)
    }

    /// Checks every parameter; a bad one is named by its key.
    pub fn validate(&self) -> Result<(), ArmError> {
        self.upper.validate("upper")?;
        self.fore.validate("fore")?;
        Ok(())
    }
}
