//! The plant's configuration: masses, geometry, sensors, solver settings, what the
//! handle is attached to, and the optional plant effects.
//!
//! Every key carries its unit. `Default` reproduces the Börner rig (000_* section 5.1)
//! with the masses this crate has to assume (the paper does not give them).

use rigtwin_arm::params::ArmParams;
use serde::{Deserialize, Serialize};

use crate::error::WorldError;

/// The whole plant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RigConfig {
    /// Mass of the lower (x) cart, kg. **Assumption**: the seed does not state it; 8 kg
    /// is a plausible moving mass of a Thrusttube stage that carries the second stage.
    pub lower_cart_mass_kg: f64,
    /// Mass of the upper (y) cart, kg. **Assumption**, as above: 4 kg.
    pub upper_cart_mass_kg: f64,
    /// Mass between the force sensor and the hand, kg (recording spec `handle_mass_kg`).
    pub handle_mass_kg: f64,
    /// Handle position at construction, rig frame, m.
    pub initial_handle_m: [f64; 2],
    /// Positions of the rail end-stops' inner faces, rig frame, m:
    /// `[[x_min, x_max], [y_min, y_max]]` for the handle (cart) position.
    pub rail_limits_m: [[f64; 2]; 2],
    /// Stiffness of the rubber end-stop bumpers, N/m. **Assumption** (no data).
    pub end_stop_stiffness_n_per_m: f64,
    /// Damping of the end-stop bumpers while compressed, N s/m (2000: damping ratio
    /// ≈ 0.6 for the x carts and ≈ 1 for the y cart on the default bumper, a rubber stop
    /// that does not bounce the carts back across the workspace).
    pub end_stop_damping_n_s_per_m: f64,
    /// Encoder quantum, m (1 µm on the Börner rig).
    pub encoder_quantum_m: f64,
    /// Standard deviation of the white Gaussian noise on each force-sensor axis, N.
    pub force_noise_rms_n: f64,
    /// rapier solver settings.
    pub solver: SolverConfig,
    /// What holds the handle.
    pub attachment: Attachment,
    /// Optional non-ideal effects, all off by default.
    pub effects: PlantEffects,
    /// The small imperfections every real rig has (offset, gain tolerance, motor
    /// noise): not effects a diagnosis should name, all off by default.
    pub nuisance: RigNuisance,
}

/// The imperfections of one trial of a real rig, as realised values (a protocol draws
/// them per session and per trial). None of them is a catalog effect: a diagnosis must
/// fit them as part of the nominal model and never name them.
///
/// - the force sensor's reading carries `sensor_offset_n` on top of the true force
///   (an imperfect tare, plus the drift since it);
/// - the motor force is `motor_gain · command` per axis (force constant tolerance);
/// - a band-limited current-loop noise of `motor_noise_rms_n` RMS (first-order
///   low-pass of white noise at `motor_noise_bw_hz`) adds to the motor force; it is
///   not in the logged command.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RigNuisance {
    /// Offset of the force reading per axis, N (sensor frame).
    pub sensor_offset_n: [f64; 2],
    /// Ratio of the motor force to its command per axis (1 is nominal).
    pub motor_gain: [f64; 2],
    /// RMS of the current-loop noise on each motor, N (0 disables it).
    pub motor_noise_rms_n: f64,
    /// Bandwidth of that noise, Hz.
    pub motor_noise_bw_hz: f64,
}

impl Default for RigNuisance {
    fn default() -> Self {
        RigNuisance {
            sensor_offset_n: [0.0; 2],
            motor_gain: [1.0; 2],
            motor_noise_rms_n: 0.0,
            motor_noise_bw_hz: 200.0,
        }
    }
}

impl RigNuisance {
    /// Checks that gains are positive and the noise's RMS and bandwidth usable.
    ///
    /// # Errors
    /// [`WorldError::InvalidConfig`] naming the key.
    pub fn validate(&self) -> Result<(), WorldError> {
        for g in self.motor_gain {
            positive("nuisance.motor_gain", g)?;
        }
        non_negative("nuisance.motor_noise_rms_n", self.motor_noise_rms_n)?;
        positive("nuisance.motor_noise_bw_hz", self.motor_noise_bw_hz)?;
        for o in self.sensor_offset_n {
            finite("nuisance.sensor_offset_n", o)?;
        }
        Ok(())
    }
}

impl Default for RigConfig {
    fn default() -> Self {
        RigConfig {
            lower_cart_mass_kg: 8.0,
            upper_cart_mass_kg: 4.0,
            handle_mass_kg: 0.35,
            initial_handle_m: [0.0, -0.125],
            rail_limits_m: [[-0.16, 0.16], [-0.16, 0.16]],
            end_stop_stiffness_n_per_m: 2.0e5,
            end_stop_damping_n_s_per_m: 2000.0,
            encoder_quantum_m: 1.0e-6,
            force_noise_rms_n: 0.05,
            solver: SolverConfig::default(),
            attachment: Attachment::default(),
            effects: PlantEffects::default(),
            nuisance: RigNuisance::default(),
        }
    }
}

/// rapier's integration settings. The defaults are the cheapest settings that pass the
/// accuracy tests (`tests/accuracy.rs`); see the crate docs for the measurements.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverConfig {
    /// rapier's `num_solver_iterations`: in rapier 0.36 these are substeps of the tick.
    pub substeps: usize,
    /// rapier's `num_internal_pgs_iterations` per substep.
    pub pgs_iterations: usize,
    /// rapier's `num_internal_stabilization_iterations` per substep (the unbiased pass
    /// that removes the position-correction velocity).
    pub stabilization_iterations: usize,
    /// Warm-start joint impulses from the previous substep/step.
    pub warmstart_joints: bool,
}

impl Default for SolverConfig {
    fn default() -> Self {
        SolverConfig {
            substeps: 1,
            pgs_iterations: 1,
            stabilization_iterations: 1,
            warmstart_joints: true,
        }
    }
}

/// What is attached to the handle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case", tag = "kind")]
pub enum Attachment {
    /// A two-link arm with the shoulder fixed in the rig frame.
    Arm {
        /// Shoulder joint centre in the rig frame, m. Default `[0, -0.425]`: the Börner
        /// reach from y = −0.125 m to 0.125 m then runs 0.30 m → 0.55 m from the shoulder
        /// (000_* section 4).
        shoulder_m: [f64; 2],
        /// Segments (Shadmehr & Mussa-Ivaldi by default). Boxed: the arm's parameter set
        /// is large and the other variants are small.
        arm: Box<ArmParams>,
        /// Whether the hand holds the handle.
        grasp: Grasp,
    },
    /// The calibrated spring-mass rig of 001_* Appendix B: a test mass held by the
    /// handle, tied to the base by springs along x and y whose rest point is
    /// [`RigConfig::initial_handle_m`].
    SpringMass {
        /// The test mass, kg (1.87 kg in Appendix B).
        mass_kg: f64,
        /// Spring stiffness along x and y, N/m (615, 507 in Appendix B).
        stiffness_n_per_m: [f64; 2],
    },
    /// Nothing: the bare handle.
    None,
}

impl Default for Attachment {
    fn default() -> Self {
        Attachment::Arm {
            shoulder_m: [0.0, -0.425],
            arm: Box::default(),
            grasp: Grasp::Held,
        }
    }
}

impl Attachment {
    /// The Appendix B calibration rig: 1.87 kg on K = diag(615, 507) N/m.
    #[must_use]
    pub fn appendix_b() -> Self {
        Attachment::SpringMass {
            mass_kg: 1.87,
            stiffness_n_per_m: [615.0, 507.0],
        }
    }
}

/// How the hand meets the handle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Grasp {
    /// The hand holds the handle: a revolute pin at the hand (or the
    /// [`GripCompliance`] spring-damper when that effect is on).
    #[default]
    Held,
    /// The hand has let go: arm and handle move independently.
    Released,
}

/// Non-ideal plant effects. Each is off (`None`) by default and changes only what it
/// names; `tests/effects.rs` checks both halves of that sentence.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantEffects {
    /// Rail friction on each cart.
    pub rail_friction: Option<RailFriction>,
    /// Position-periodic motor force (cogging).
    pub force_ripple: Option<ForceRipple>,
    /// Whole-tick delay between a motor command and the force.
    pub actuation_delay: Option<ActuationDelay>,
    /// Force-sensor miscalibration and bandwidth.
    pub sensor: Option<SensorEffect>,
    /// Extra mass between the sensor and the hand.
    pub handle_mass: Option<HandleMass>,
    /// A compliant grip instead of the rigid pin.
    pub grip_compliance: Option<GripCompliance>,
    /// A cable carrier pulling each cart towards a rest position (not in the
    /// diagnosis's catalog: an effect a lab's rig may have that the diagnosis must
    /// report as unexplained rather than as the nearest catalog entry).
    pub cable_spring: Option<CableSpring>,
}

/// Friction on each cart by its own rail velocity `v`:
/// `F = −(coulomb_n · tanh(v / smooth_velocity_m_per_s) + viscous_n_s_per_m · v)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RailFriction {
    /// Coulomb level, N.
    pub coulomb_n: f64,
    /// Viscous coefficient, N s/m.
    pub viscous_n_s_per_m: f64,
    /// Velocity scale of the tanh smoothing of the Coulomb term, m/s.
    pub smooth_velocity_m_per_s: f64,
}

/// Additive cogging of a linear motor: axis `i` (0 = x, 1 = y) gets
/// `amplitude_n[i] · sin(2π · q_i / pitch_m + phase_rad[i])` on top of its command at
/// its cart's rail position `q_i`, whatever the command (cogging is a detent force of
/// the magnets, present with the drive off). Each axis has its own magnet track, so its
/// own amplitude and phase; the two motors share the magnet pitch.
///
/// In TOML, `amplitude_n` is one number for both axes or `[x, y]`; `phase_rad` is
/// `[x, y]` and zero when absent (the magnets start at `q = 0`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceRipple {
    /// Peak cogging force per axis, N.
    #[serde(deserialize_with = "one_or_per_axis")]
    pub amplitude_n: [f64; 2],
    /// Magnet pitch, m.
    pub pitch_m: f64,
    /// Phase of the cogging per axis, rad.
    #[serde(default)]
    pub phase_rad: [f64; 2],
}

impl ForceRipple {
    /// The same cogging on both axes, starting at `q = 0`.
    #[must_use]
    pub fn uniform(amplitude_n: f64, pitch_m: f64) -> Self {
        ForceRipple {
            amplitude_n: [amplitude_n; 2],
            pitch_m,
            phase_rad: [0.0; 2],
        }
    }
}

/// One number for both axes, or `[x, y]`.
fn one_or_per_axis<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum OneOrTwo {
        One(f64),
        Two([f64; 2]),
    }
    match OneOrTwo::deserialize(d) {
        Ok(OneOrTwo::One(v)) => Ok([v, v]),
        Ok(OneOrTwo::Two(a)) => Ok(a),
        Err(_) => Err(serde::de::Error::custom(
            "expected one number (both axes) or two, [x, y]",
        )),
    }
}

/// Delay of the motor force behind its command, rounded to whole 250 µs ticks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActuationDelay {
    /// Delay, ms (rounded to the nearest tick).
    pub delay_ms: f64,
}

/// Force-sensor errors: `raw = R(rotation_deg) · lowpass(F) + offset_n`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorEffect {
    /// Rotation of the sensor frame relative to the rig frame, degrees, counter-clockwise.
    pub rotation_deg: f64,
    /// Constant offset of the raw reading per axis, N.
    pub offset_n: [f64; 2],
    /// Cut-off of a first-order low-pass on the true force, Hz; 0 disables it.
    pub lowpass_hz: f64,
}

/// A cable carrier (energy chain) on each rail: the cables bend around the carrier's
/// loop and pull the cart towards where the loop is relaxed, about linearly over the
/// travel: `F_i = −stiffness_n_per_m[i] · (q_i − rest_m[i])` on axis `i` at its cart's
/// rail position `q_i`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CableSpring {
    /// Stiffness per axis, N/m.
    pub stiffness_n_per_m: [f64; 2],
    /// Rail position where the pull vanishes, per axis, m.
    pub rest_m: [f64; 2],
}

/// Extra mass added to the handle (between sensor and hand).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandleMass {
    /// Added mass, kg.
    pub extra_mass_kg: f64,
}

/// A spring-damper between hand and handle instead of the rigid pin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GripCompliance {
    /// Isotropic stiffness, N/m.
    pub stiffness_n_per_m: f64,
    /// Isotropic damping, N s/m.
    pub damping_n_s_per_m: f64,
}

fn positive(key: &'static str, v: f64) -> Result<(), WorldError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(WorldError::InvalidConfig {
            key,
            reason: format!("must be finite and > 0, got {v}"),
        })
    }
}

fn non_negative(key: &'static str, v: f64) -> Result<(), WorldError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(WorldError::InvalidConfig {
            key,
            reason: format!("must be finite and >= 0, got {v}"),
        })
    }
}

fn finite(key: &'static str, v: f64) -> Result<(), WorldError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(WorldError::InvalidConfig {
            key,
            reason: format!("must be finite, got {v}"),
        })
    }
}

impl RigConfig {
    /// Checks every key; the error names the first bad one.
    pub fn validate(&self) -> Result<(), WorldError> {
        positive("lower_cart_mass_kg", self.lower_cart_mass_kg)?;
        positive("upper_cart_mass_kg", self.upper_cart_mass_kg)?;
        positive("handle_mass_kg", self.handle_mass_kg)?;
        positive("encoder_quantum_m", self.encoder_quantum_m)?;
        non_negative("force_noise_rms_n", self.force_noise_rms_n)?;
        positive(
            "end_stop_stiffness_n_per_m",
            self.end_stop_stiffness_n_per_m,
        )?;
        non_negative(
            "end_stop_damping_n_s_per_m",
            self.end_stop_damping_n_s_per_m,
        )?;
        for axis in 0..2 {
            finite("initial_handle_m", self.initial_handle_m[axis])?;
            let [lo, hi] = self.rail_limits_m[axis];
            finite("rail_limits_m", lo)?;
            finite("rail_limits_m", hi)?;
            let p = self.initial_handle_m[axis];
            if !(lo < p && p < hi) {
                return Err(WorldError::InvalidConfig {
                    key: "initial_handle_m",
                    reason: format!(
                        "axis {axis}: {p} m is not strictly inside the rail limits [{lo}, {hi}] m"
                    ),
                });
            }
        }
        if self.solver.substeps == 0 || self.solver.substeps > 64 {
            return Err(WorldError::InvalidConfig {
                key: "solver.substeps",
                reason: format!("must be in 1..=64, got {}", self.solver.substeps),
            });
        }
        if self.solver.pgs_iterations == 0 || self.solver.pgs_iterations > 64 {
            return Err(WorldError::InvalidConfig {
                key: "solver.pgs_iterations",
                reason: format!("must be in 1..=64, got {}", self.solver.pgs_iterations),
            });
        }
        if self.solver.stabilization_iterations > 64 {
            return Err(WorldError::InvalidConfig {
                key: "solver.stabilization_iterations",
                reason: format!(
                    "must be in 0..=64, got {}",
                    self.solver.stabilization_iterations
                ),
            });
        }
        self.nuisance.validate()?;
        match &self.attachment {
            Attachment::Arm {
                shoulder_m, arm, ..
            } => {
                finite("attachment.shoulder_m", shoulder_m[0])?;
                finite("attachment.shoulder_m", shoulder_m[1])?;
                arm.validate()?;
            }
            Attachment::SpringMass {
                mass_kg,
                stiffness_n_per_m,
            } => {
                positive("attachment.mass_kg", *mass_kg)?;
                positive("attachment.stiffness_n_per_m", stiffness_n_per_m[0])?;
                positive("attachment.stiffness_n_per_m", stiffness_n_per_m[1])?;
            }
            Attachment::None => {}
        }
        let e = &self.effects;
        if let Some(f) = &e.rail_friction {
            non_negative("effects.rail_friction.coulomb_n", f.coulomb_n)?;
            non_negative(
                "effects.rail_friction.viscous_n_s_per_m",
                f.viscous_n_s_per_m,
            )?;
            positive(
                "effects.rail_friction.smooth_velocity_m_per_s",
                f.smooth_velocity_m_per_s,
            )?;
        }
        if let Some(r) = &e.force_ripple {
            for a in 0..2 {
                finite("effects.force_ripple.amplitude_n", r.amplitude_n[a])?;
                finite("effects.force_ripple.phase_rad", r.phase_rad[a])?;
            }
            positive("effects.force_ripple.pitch_m", r.pitch_m)?;
        }
        if let Some(d) = &e.actuation_delay {
            non_negative("effects.actuation_delay.delay_ms", d.delay_ms)?;
            if d.delay_ms > 1000.0 {
                return Err(WorldError::InvalidConfig {
                    key: "effects.actuation_delay.delay_ms",
                    reason: format!("must be at most 1000 ms, got {}", d.delay_ms),
                });
            }
        }
        if let Some(s) = &e.sensor {
            finite("effects.sensor.rotation_deg", s.rotation_deg)?;
            finite("effects.sensor.offset_n", s.offset_n[0])?;
            finite("effects.sensor.offset_n", s.offset_n[1])?;
            non_negative("effects.sensor.lowpass_hz", s.lowpass_hz)?;
        }
        if let Some(c) = &e.cable_spring {
            for a in 0..2 {
                non_negative(
                    "effects.cable_spring.stiffness_n_per_m",
                    c.stiffness_n_per_m[a],
                )?;
                finite("effects.cable_spring.rest_m", c.rest_m[a])?;
            }
        }
        if let Some(h) = &e.handle_mass {
            non_negative("effects.handle_mass.extra_mass_kg", h.extra_mass_kg)?;
        }
        if let Some(g) = &e.grip_compliance {
            positive(
                "effects.grip_compliance.stiffness_n_per_m",
                g.stiffness_n_per_m,
            )?;
            non_negative(
                "effects.grip_compliance.damping_n_s_per_m",
                g.damping_n_s_per_m,
            )?;
        }
        Ok(())
    }
}
