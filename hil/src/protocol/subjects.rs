//! Virtual subjects: parameter sets drawn around a nominal arm with a stated spread.
//!
//! Subject `i` (1-based) is drawn from its own seeded stream (session seed, subject
//! index), so adding subjects never changes the earlier ones. Each varied quantity is
//! multiplied by a log-normal factor `exp(σ z − σ²/2)`, `z ~ N(0, 1)`, whose mean is 1
//! and whose relative standard deviation is about σ for small σ:
//!
//! | key | multiplies | default σ | why |
//! |---|---|---|---|
//! | `muscle_stiffness` | K₀ and K₁ of every muscle (one factor) | 0.25 | Table 1 of 000_* has a CV near 0.3-0.4 over 5 subjects |
//! | `co_contraction` | both co-contraction torques | 0.25 | as above |
//! | `segment_length` | upper arm and forearm lengths (independent) | 0.05 | adult male anthropometry, CV ≈ 5 % |
//! | `feedback_gain` | position and velocity gains of the delayed feedback | 0.20 | unverified; a stated guess |
//! | `reflex_gain` | the stretch reflex's gain, when the arm has a reflex | 0 | a population of one reflex gain unless a sweep says otherwise |
//!
//! The reflex factor is drawn after the other five, so a spread of it never changes
//! them; it is not one of [`VirtualSubject::factors`] (which `compare`'s subject fit
//! varies), so a subject fit of a session with a reflex spread starts from the nominal
//! reflex.
//!
//! With `first_is_nominal` (default), subject 1 is the nominal arm itself: the one the
//! seed-reproduction tests calibrate against Table 1.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigtwin_arm::params::ArmParams;
use serde::{Deserialize, Serialize};

use super::Checker;

/// Relative spread (log-normal σ) of each varied quantity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SubjectSpread {
    /// σ of the muscle stiffness factor (K₀, K₁).
    pub muscle_stiffness: f64,
    /// σ of the co-contraction factor.
    pub co_contraction: f64,
    /// σ of each segment length factor.
    pub segment_length: f64,
    /// σ of the feedback gain factor.
    pub feedback_gain: f64,
    /// σ of the stretch reflex's gain factor (when the arm has a reflex).
    pub reflex_gain: f64,
}

impl Default for SubjectSpread {
    fn default() -> Self {
        SubjectSpread {
            muscle_stiffness: 0.25,
            co_contraction: 0.25,
            segment_length: 0.05,
            feedback_gain: 0.20,
            reflex_gain: 0.0,
        }
    }
}

/// The population of virtual subjects.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SubjectsConfig {
    /// Subjects when the command line gives no `--subjects`.
    pub count: u32,
    /// Subject 1 is the nominal arm, undrawn.
    pub first_is_nominal: bool,
    /// Shoulder joint centre, rig frame, m (000_*: the reach runs 0.30 → 0.55 m).
    pub shoulder_m: [f64; 2],
    /// Co-contraction level at the start of a trial, 1 = the arm's default.
    pub co_contraction_level: f64,
    /// The nominal arm (`rigtwin_arm::params::ArmParams`).
    pub arm: ArmParams,
    /// Spread around the nominal arm.
    pub spread: SubjectSpread,
}

impl Default for SubjectsConfig {
    fn default() -> Self {
        SubjectsConfig {
            count: 1,
            first_is_nominal: true,
            shoulder_m: [0.0, -0.425],
            co_contraction_level: 1.0,
            arm: ArmParams::default(),
            spread: SubjectSpread::default(),
        }
    }
}

/// One drawn subject.
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualSubject {
    /// 1-based index.
    pub index: u32,
    /// Code, `S01`, `S02`, ...
    pub id: String,
    /// The arm.
    pub arm: ArmParams,
    /// Shoulder, rig frame, m.
    pub shoulder_m: [f64; 2],
    /// Co-contraction level.
    pub co_contraction_level: f64,
    /// The factors drawn, for the record: (stiffness, co-contraction, upper, fore,
    /// feedback).
    pub factors: [f64; 5],
}

impl SubjectsConfig {
    pub(crate) fn check(&self, c: &mut Checker) {
        if self.count == 0 {
            c.fail("subjects.count", "must be > 0, got 0");
        }
        for i in 0..2 {
            c.finite(&format!("subjects.shoulder_m[{i}]"), self.shoulder_m[i]);
        }
        c.non_negative("subjects.co_contraction_level", self.co_contraction_level);
        let s = &self.spread;
        for (key, v) in [
            ("subjects.spread.muscle_stiffness", s.muscle_stiffness),
            ("subjects.spread.co_contraction", s.co_contraction),
            ("subjects.spread.segment_length", s.segment_length),
            ("subjects.spread.feedback_gain", s.feedback_gain),
            ("subjects.spread.reflex_gain", s.reflex_gain),
        ] {
            c.non_negative(key, v);
            if v.is_finite() && v > 1.0 {
                c.fail(key, format!("must be <= 1 (a relative spread), got {v}"));
            }
        }
        if let Err(e) = self.arm.validate() {
            match e {
                rigtwin_arm::ArmError::InvalidParameter { key, reason } => {
                    c.fail(format!("subjects.arm.{key}"), reason);
                }
                other => c.fail("subjects.arm", other.to_string()),
            }
        }
    }

    /// Subject `index` (1-based) of the session with seed `session_seed`.
    #[must_use]
    pub fn draw(&self, session_seed: u64, index: u32) -> VirtualSubject {
        let id = format!("S{index:02}");
        if index == 1 && self.first_is_nominal {
            return VirtualSubject {
                index,
                id,
                arm: self.arm.clone(),
                shoulder_m: self.shoulder_m,
                co_contraction_level: self.co_contraction_level,
                factors: [1.0; 5],
            };
        }
        let mut rng = ChaCha8Rng::seed_from_u64(super::seed::mix(&[
            session_seed,
            0x5B7E_C7D0,
            u64::from(index),
        ]));
        let mut factor = |sigma: f64| {
            // Box-Muller: a standard normal from two uniforms in (0, 1].
            let u1 = 1.0 - rng.random::<f64>();
            let u2 = rng.random::<f64>();
            let z = (-2.0 * u1.ln()).sqrt() * (core::f64::consts::TAU * u2).cos();
            (sigma * z - 0.5 * sigma * sigma).exp()
        };
        let s = self.spread;
        let f = [
            factor(s.muscle_stiffness),
            factor(s.co_contraction),
            factor(s.segment_length),
            factor(s.segment_length),
            factor(s.feedback_gain),
        ];
        let reflex = factor(s.reflex_gain);
        let mut subject = self.with_factors(index, f);
        if let Some(r) = &mut subject.arm.stretch_reflex {
            r.gain_n_s_per_m *= reflex;
        }
        subject
    }

    /// Subject `index` (1-based) made from the nominal arm with the given factors
    /// (stiffness, co-contraction, upper arm length, forearm length, feedback gain), as
    /// [`SubjectsConfig::draw`] applies its drawn ones; `compare`'s subject fit uses it to
    /// build the subject it fits. A length factor that gives a bad segment keeps the
    /// nominal segment.
    #[must_use]
    pub fn with_factors(&self, index: u32, f: [f64; 5]) -> VirtualSubject {
        let mut arm = self.arm.clone();
        for k in &mut arm.muscles.stiffness_passive_n_per_m {
            *k *= f[0];
        }
        for k in &mut arm.muscles.stiffness_per_activation_per_m {
            *k *= f[0];
        }
        for c in &mut arm.muscles.co_contraction_n_m {
            *c *= f[1];
        }
        arm.upper = arm
            .upper
            .scaled_to_length(arm.upper.length_m * f[2])
            .unwrap_or(arm.upper);
        arm.fore = arm
            .fore
            .scaled_to_length(arm.fore.length_m * f[3])
            .unwrap_or(arm.fore);
        arm.feedback.position_gain_n_per_m *= f[4];
        arm.feedback.velocity_gain_n_s_per_m *= f[4];
        VirtualSubject {
            index,
            id: format!("S{index:02}"),
            arm,
            shoulder_m: self.shoulder_m,
            co_contraction_level: self.co_contraction_level,
            factors: f,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drawn_subject_is_the_nominal_arm_with_its_factors() {
        // `compare`'s subject fit builds subjects with `with_factors`; a drawn subject must
        // be exactly that subject for its drawn factors, or the fit would chase another arm.
        let c = SubjectsConfig {
            first_is_nominal: false,
            ..SubjectsConfig::default()
        };
        for index in 1..4 {
            let d = c.draw(7, index);
            assert_ne!(d.factors, [1.0; 5]);
            assert_eq!(c.with_factors(index, d.factors), d);
        }
    }
}
