//! Protocols: the TOML file a rehearsal runs, with the controller configuration the rig
//! itself would run, the plant, the virtual subjects and the estimator settings.
//!
//! Three kinds, each with defaults that reproduce a seed's set-up:
//!
//! | kind | seed | what |
//! |---|---|---|
//! | `reach-perturb` | 000_* | reaches along y with force pulses triggered on a line |
//! | `hold-sinusoid` | 001_* | force holding while a virtual spring imposes a sinusoid, with position perturbations |
//! | `calibration-rig` | 001_* App. B | the same perturbations on the spring-mass rig |
//!
//! Every table is `deny_unknown_fields`: a misspelt key is an error that names it and
//! its line. [`Protocol::validate`] names every out-of-range key by its dotted path
//! (`reach.trials`, `controller.admittance.mass_kg[0]`, `subjects.arm.upper`).
//! The shipped files are in `hil/protocols/` and built in ([`Protocol::builtin`]).

pub(crate) mod error;
pub(crate) mod locate;
pub mod nuisance;
pub mod seed;
pub mod subjects;

use std::path::{Path, PathBuf};

use rigtwin_device::ControllerConfig;
use rigtwin_device::config::LawKind;
use rigtwin_world::{PlantEffects, RigConfig, SolverConfig};
use serde::{Deserialize, Serialize};

pub(crate) use rigtwin_device::config::Checker;

/// The 4 kHz control clock whose ticks every protocol duration must be made of.
const CONTROL_RATE: Option<rigtwin_device::time::Rate> = rigtwin_device::time::Rate::new(4000);
pub use error::{InvalidKey, ProtocolError};

/// `s` rounded to whole ticks of the 4 kHz control clock, s.
pub(crate) fn whole_ticks(s: f64) -> f64 {
    let hz = f64::from(rigtwin_device::Rate::CONTROL.hz());
    (s * hz).round() / hz
}
pub use subjects::{SubjectSpread, SubjectsConfig, VirtualSubject};

/// The longest trial a protocol may ask for, s (ten minutes). A trial is simulated and
/// held in memory whole: at this length that is 2.4 M ticks and, at 4 kHz recording, about
/// 300 MB of samples. Longer is an error before anything is allocated.
pub const MAX_TRIAL_S: f64 = 600.0;

/// The longest protocol name, characters: it names the output folder
/// (`out/<name>-<seed>/`), and file systems allow 255 bytes a name.
pub const MAX_NAME_CHARS: usize = 100;

/// The most trials per subject a protocol may ask for (a human session has a few hundred).
pub const MAX_TRIALS: u32 = 10_000;

/// The most virtual subjects one rehearsal may draw.
pub const MAX_SUBJECTS: u32 = 10_000;

/// The shipped protocols, by name: (name, file text).
pub const BUILTIN: [(&str, &str); 3] = [
    (
        "reach-perturb",
        include_str!("../../protocols/reach-perturb.toml"),
    ),
    (
        "hold-sinusoid",
        include_str!("../../protocols/hold-sinusoid.toml"),
    ),
    (
        "calibration-rig",
        include_str!("../../protocols/calibration-rig.toml"),
    ),
];

/// What a protocol rehearses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProtocolKind {
    /// 000_*: point-to-point reaches with force pulses.
    ReachPerturb,
    /// 001_*: force holding during an imposed sinusoid, with position perturbations.
    HoldSinusoid,
    /// 001_* Appendix B: the position perturbations on the calibrated spring-mass rig.
    CalibrationRig,
}

impl ProtocolKind {
    /// The file spelling.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            ProtocolKind::ReachPerturb => "reach-perturb",
            ProtocolKind::HoldSinusoid => "hold-sinusoid",
            ProtocolKind::CalibrationRig => "calibration-rig",
        }
    }
}

/// A whole protocol file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Protocol {
    /// Short name; the default output folder is `out/<name>-<seed>/`.
    pub name: String,
    /// What is rehearsed.
    pub kind: ProtocolKind,
    /// Session seed used when the command line gives none.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// How sessions are recorded.
    #[serde(default)]
    pub recording: RecordingConfig,
    /// The reach task and its force-pulse schedule (`kind = "reach-perturb"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reach: Option<ReachConfig>,
    /// The hold task and its position-perturbation schedule (`hold-sinusoid`,
    /// `calibration-rig`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold: Option<HoldConfig>,
    /// The spring-mass rig (`calibration-rig`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<CalibrationConfig>,
    /// The rig's controller, exactly as the rig runs it (`rigtwin_device`).
    #[serde(default)]
    pub controller: ControllerConfig,
    /// The simulated plant.
    #[serde(default)]
    pub plant: PlantConfig,
    /// The virtual subjects.
    #[serde(default)]
    pub subjects: SubjectsConfig,
    /// Estimator settings for the report.
    #[serde(default)]
    pub estimate: EstimateConfig,
    /// A realistic rig and subject: the ranges of the per-session and per-trial
    /// nuisances ([`nuisance`]); absent, the rig and the subject are ideal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nuisance: Option<nuisance::NuisanceConfig>,
}

fn default_seed() -> u64 {
    1
}

/// How trials are recorded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordingConfig {
    /// Rate of the trial tables, Hz; must divide 4000. Default 1000: each row is the
    /// mean of a block of 4 control ticks, `t_s` at the block centre, as the shared
    /// rig logs (`recordings/README.md`). 4000 records every tick.
    pub rate_hz: u32,
    /// Add the simulator's ground-truth columns (`true_x_m`, `true_y_m`,
    /// `hand_fx_n`, `hand_fy_n`), which readers of the format ignore.
    pub truth_columns: bool,
}

impl Default for RecordingConfig {
    fn default() -> Self {
        RecordingConfig {
            rate_hz: 1000,
            truth_columns: true,
        }
    }
}

/// The reach of 000_* and its force pulses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReachConfig {
    /// Movement start, rig frame, m (000_*: 0.30 m from the shoulder = [0, −0.125]).
    pub start_m: [f64; 2],
    /// Movement goal, rig frame, m (0.55 m from the shoulder = [0, 0.125]).
    pub goal_m: [f64; 2],
    /// Still time before the movement, s.
    pub still_before_s: f64,
    /// Movement duration, s (3 s in 000_* section 4.2).
    pub movement_s: f64,
    /// Still time after the movement, s.
    pub still_after_s: f64,
    /// Movements in the session (100 in 000_* section 5.2).
    pub trials: u32,
    /// Pulse directions, degrees from +x toward +y (000_*: never along an axis).
    pub angles_deg: Vec<f64>,
    /// Perturbed trials per angle (3 in the experiment: 24 of 100 perturbed).
    pub repetitions: u32,
    /// Axis watched by the trigger.
    pub trigger_axis: rigtwin_device::config::Axis,
    /// The pulse fires when the measured position on `trigger_axis` crosses this line
    /// in the direction of the movement, m (−0.025: 0.1 m into the reach, 0.4 m from
    /// the shoulder).
    pub trigger_position_m: f64,
    /// Centre-out reaches: the goals, rig frame, m, every reach starting at `start_m`
    /// (empty, the default: every reach goes to `goal_m`). The unperturbed reaches go to
    /// them in turn, and the `r`-th repetition of a pulse direction on the `p`-th pulse
    /// axis (`θ` and `θ + 180°` share one, numbered in the order of `angles_deg`) to
    /// goal `(r + p) mod n`: with repetitions a multiple of `n` each goal sees every
    /// direction equally often, opposite directions' repetitions go to one goal (the
    /// pairs the diagnosis's hand balance takes), and with fewer repetitions than goals
    /// the pulse axes spread over the goals; the schedule's shuffle then places them.
    /// A reach's pulse fires at the same fraction of its way as `trigger_position_m` is
    /// of the way from `start_m` to `goal_m` on `trigger_axis`, on the crossing of the
    /// axis it travels along more ([`ReachConfig::toward`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub targets_m: Vec<[f64; 2]>,
    /// Reaches out and back in one trial (a centre-out task that logs the return): the
    /// time the hand stays at the goal, s, before it goes back to `start_m` along the
    /// same line in `movement_s`; the trial grows by this and `movement_s`. The pulse
    /// fires on the way out only (the trigger watches the crossing in the direction of
    /// the way out). Absent, the default: the trial ends at the goal.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub back_after_s: Option<f64>,
}

impl Default for ReachConfig {
    fn default() -> Self {
        ReachConfig {
            start_m: [0.0, -0.125],
            goal_m: [0.0, 0.125],
            still_before_s: 0.25,
            movement_s: 3.0,
            still_after_s: 0.25,
            trials: 100,
            angles_deg: vec![30.0, 60.0, 120.0, 150.0, 210.0, 240.0, 300.0, 330.0],
            repetitions: 3,
            trigger_axis: rigtwin_device::config::Axis::Y,
            trigger_position_m: -0.025,
            targets_m: Vec::new(),
            back_after_s: None,
        }
    }
}

impl ReachConfig {
    /// Number of perturbed trials.
    #[must_use]
    pub fn perturbed(&self) -> usize {
        self.angles_deg.len() * self.repetitions as usize
    }

    /// Trial length, s.
    #[must_use]
    pub fn trial_s(&self) -> f64 {
        self.still_before_s + self.movement_s + self.back_s() + self.still_after_s
    }

    /// Time at the goal and on the way back of a reach out and back
    /// (`back_after_s + movement_s`), s; 0 for a reach one way.
    #[must_use]
    pub fn back_s(&self) -> f64 {
        self.back_after_s.map_or(0.0, |b| b + self.movement_s)
    }

    /// The fraction of the way from `start_m` to `goal_m` at which the pulse fires,
    /// along `trigger_axis` (0.4 on 000_*).
    #[must_use]
    pub fn trigger_fraction(&self) -> f64 {
        let axis = self.trigger_axis.index();
        (self.trigger_position_m - self.start_m[axis]) / (self.goal_m[axis] - self.start_m[axis])
    }

    /// The reach to centre-out goal `target` (an index into `targets_m`) as a reach of
    /// its own: `goal_m` that goal, no `targets_m`, and the trigger on the axis the reach
    /// travels along more, at [`Self::trigger_fraction`] of its way. `None` when
    /// `targets_m` has no such goal.
    #[must_use]
    pub fn toward(&self, target: usize) -> Option<ReachConfig> {
        self.targets_m.get(target).map(|g| self.toward_goal(*g))
    }

    /// The reach to `goal` (rig frame, m) as [`Self::toward`] makes it: `goal_m` that
    /// goal, no `targets_m`, the trigger at [`Self::trigger_fraction`] of its way on the
    /// axis it travels along more.
    #[must_use]
    pub fn toward_goal(&self, goal: [f64; 2]) -> ReachConfig {
        use rigtwin_device::config::Axis;
        let fraction = self.trigger_fraction();
        let way = [goal[0] - self.start_m[0], goal[1] - self.start_m[1]];
        let axis = if way[0].abs() > way[1].abs() {
            Axis::X
        } else {
            Axis::Y
        };
        let i = axis.index();
        ReachConfig {
            goal_m: goal,
            trigger_axis: axis,
            trigger_position_m: self.start_m[i] + fraction * way[i],
            targets_m: Vec::new(),
            ..self.clone()
        }
    }
}

/// One condition of 001_*: force direction and motion axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoldCondition {
    /// Direction of the force the hand holds, degrees from +x toward +y.
    pub force_deg: f64,
    /// Axis of the imposed motion.
    pub axis: rigtwin_device::config::Axis,
}

/// The force-holding task of 001_*. The imposed motion itself (amplitude, frequency,
/// cycles, ramps) is the controller's `controller.imposed_motion`; it starts when the
/// controller is activated at tick 1 (the raised-cosine ramp stands in for the seed's
/// 5 s of still holding: the controller must be active to hold the handle at all).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HoldConfig {
    /// Where the hand holds the handle, rig frame, m (centre of the imposed motion).
    pub hand_m: [f64; 2],
    /// Magnitude of the force to hold, N (10 N in 001_*).
    pub force_n: f64,
    /// Still time after the motion ends, s.
    pub after_s: f64,
    /// The conditions, one trial each, in this order (001_*: all 8).
    pub conditions: Vec<HoldCondition>,
    /// Rise of the co-contraction level within a trial, 1/s (0: constant).
    pub co_contraction_rise_per_s: f64,
    /// Position perturbations per zero-acceleration slot: every slot gets one
    /// (001_*: twice a cycle, 50 per trial).
    pub perturb_every_slot: bool,
}

impl Default for HoldConfig {
    fn default() -> Self {
        use rigtwin_device::config::Axis;
        let mut conditions = Vec::new();
        for axis in [Axis::X, Axis::Y] {
            for force_deg in [0.0, 180.0, 90.0, 270.0] {
                conditions.push(HoldCondition { force_deg, axis });
            }
        }
        HoldConfig {
            hand_m: [0.0, 0.0],
            force_n: 10.0,
            after_s: 1.0,
            conditions,
            co_contraction_rise_per_s: 0.0,
            perturb_every_slot: true,
        }
    }
}

/// The calibrated spring-mass rig of 001_* Appendix B.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CalibrationConfig {
    /// Test mass, kg (1.87).
    pub mass_kg: f64,
    /// Spring stiffness along x and y, N/m (615, 507).
    pub stiffness_n_per_m: [f64; 2],
    /// Repetitions of the task (5 in Appendix B).
    pub repetitions: u32,
}

impl Default for CalibrationConfig {
    fn default() -> Self {
        CalibrationConfig {
            mass_kg: 1.87,
            stiffness_n_per_m: [615.0, 507.0],
            repetitions: 5,
        }
    }
}

/// The plant: the parts of `rigtwin_world::RigConfig` a protocol may set (the handle's
/// start and what holds it follow from the task and the subjects).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantConfig {
    /// Lower (x) cart, kg.
    pub lower_cart_mass_kg: f64,
    /// Upper (y) cart, kg.
    pub upper_cart_mass_kg: f64,
    /// Mass between force sensor and hand, kg.
    pub handle_mass_kg: f64,
    /// Rail end-stops, `[[x_min, x_max], [y_min, y_max]]`, m.
    pub rail_limits_m: [[f64; 2]; 2],
    /// Encoder quantum, m.
    pub encoder_quantum_m: f64,
    /// Force-sensor noise, N RMS per axis at 4 kHz. At 0 the simulated reading repeats
    /// exactly when the handle is still, so the controller's stale-force watchdog is off
    /// in such a rehearsal (it guards a live ADC).
    pub force_noise_rms_n: f64,
    /// rapier solver settings.
    pub solver: SolverConfig,
    /// Non-ideal plant effects (all off by default).
    pub effects: PlantEffects,
    /// The rig's nuisances as realised values; set per trial from the protocol's
    /// `[nuisance]` ranges ([`nuisance::realise`]), off by default.
    #[serde(skip)]
    pub nuisance: rigtwin_world::RigNuisance,
}

impl Default for PlantConfig {
    fn default() -> Self {
        let r = RigConfig::default();
        PlantConfig {
            lower_cart_mass_kg: r.lower_cart_mass_kg,
            upper_cart_mass_kg: r.upper_cart_mass_kg,
            handle_mass_kg: r.handle_mass_kg,
            rail_limits_m: r.rail_limits_m,
            encoder_quantum_m: r.encoder_quantum_m,
            force_noise_rms_n: r.force_noise_rms_n,
            solver: r.solver,
            effects: r.effects,
            nuisance: r.nuisance,
        }
    }
}

impl PlantConfig {
    /// The world's configuration with the handle starting at `initial_handle_m` and
    /// `attachment` holding it.
    #[must_use]
    pub fn rig_config(
        &self,
        initial_handle_m: [f64; 2],
        attachment: rigtwin_world::Attachment,
    ) -> RigConfig {
        RigConfig {
            lower_cart_mass_kg: self.lower_cart_mass_kg,
            upper_cart_mass_kg: self.upper_cart_mass_kg,
            handle_mass_kg: self.handle_mass_kg,
            initial_handle_m,
            rail_limits_m: self.rail_limits_m,
            encoder_quantum_m: self.encoder_quantum_m,
            force_noise_rms_n: self.force_noise_rms_n,
            solver: self.solver,
            attachment,
            effects: self.effects.clone(),
            nuisance: self.nuisance,
            ..RigConfig::default()
        }
    }
}

/// How the variational signals of the Börner estimator are formed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum EstimateMode {
    /// As the seed writes it (000_* section 3.1).
    #[default]
    Seed,
    /// The same filter on force and kinematics (see `rigtwin_device::estimate`).
    Consistent,
}

/// Estimator settings (000_*: SG 5th order 30 Hz, high-pass 1 Hz 5th order, 150 ms).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimateConfig {
    /// Estimation interval after the onset, s.
    pub t_est_s: f64,
    /// Savitzky–Golay cut-off, Hz.
    pub savgol_cutoff_hz: f64,
    /// Savitzky–Golay polynomial order.
    pub savgol_polyorder: usize,
    /// High-pass cut-off of the jerk, Hz.
    pub high_pass_hz: f64,
    /// High-pass Butterworth order.
    pub high_pass_order: usize,
    /// How variational signals are formed.
    pub mode: EstimateMode,
}

impl Default for EstimateConfig {
    fn default() -> Self {
        EstimateConfig {
            t_est_s: 0.150,
            savgol_cutoff_hz: 30.0,
            savgol_polyorder: 5,
            high_pass_hz: 1.0,
            high_pass_order: 5,
            mode: EstimateMode::Seed,
        }
    }
}

impl EstimateConfig {
    /// The device estimator's settings.
    #[must_use]
    pub fn borner(&self) -> rigtwin_device::estimate::BornerConfig {
        use rigtwin_device::estimate::{BornerConfig, HighPass, VariationalMode};
        BornerConfig {
            savgol_polyorder: self.savgol_polyorder,
            savgol_cutoff_hz: self.savgol_cutoff_hz,
            high_pass: (self.high_pass_hz > 0.0).then_some(HighPass {
                cutoff_hz: self.high_pass_hz,
                order: self.high_pass_order,
            }),
            t_est_s: self.t_est_s,
            mode: match self.mode {
                EstimateMode::Seed => VariationalMode::Seed,
                EstimateMode::Consistent => VariationalMode::Consistent,
            },
            ..BornerConfig::default()
        }
    }
}

impl Protocol {
    /// Parses and checks a protocol from TOML text; `path` names it in errors.
    ///
    /// # Errors
    /// [`ProtocolError::Parse`] for bad TOML, unknown keys or wrong types;
    /// [`ProtocolError::Invalid`] naming every out-of-range key.
    pub fn from_toml(text: &str, path: &Path) -> Result<Protocol, ProtocolError> {
        let protocol: Protocol = toml::from_str(text).map_err(|e| ProtocolError::Parse {
            path: path.to_path_buf(),
            message: parse_message(text, &e),
        })?;
        // The document with its spans, parsed once: for the arrays serde cut and for the
        // lines of the keys that fail.
        let root = toml::de::DeTable::parse(text).ok();
        let mut errors = match (&root, toml::Value::try_from(&protocol)) {
            (Some(root), Ok(kept)) => locate::cut_arrays(root, &kept),
            _ => Vec::new(),
        };
        if let Err(e) = protocol.validate() {
            errors.extend(e);
        }
        if errors.is_empty() {
            Ok(protocol)
        } else {
            Err(ProtocolError::Invalid {
                path: path.to_path_buf(),
                lines: locate::lines_of(text, root.as_ref(), &errors),
                errors,
            })
        }
    }

    /// Reads and checks a protocol file. A path that does not exist but is the name of
    /// a shipped protocol (`reach-perturb`, `hold-sinusoid`, `calibration-rig`) gives
    /// the built-in copy.
    ///
    /// # Errors
    /// As [`Protocol::from_toml`]; [`ProtocolError::Read`] if the file cannot be read.
    pub fn load(path: &Path) -> Result<Protocol, ProtocolError> {
        if !path.exists()
            && let Some(p) = path.to_str().and_then(Protocol::builtin_text)
        {
            return Protocol::from_toml(p, path);
        }
        let text = rigtwin_session::files::read_regular_text(
            path,
            rigtwin_session::files::MAX_CONFIG_BYTES,
        )
        .map_err(|source| ProtocolError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Protocol::from_toml(&text, path)
    }

    pub(crate) fn builtin_text(name: &str) -> Option<&'static str> {
        BUILTIN.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
    }

    /// A shipped protocol by name.
    ///
    /// # Errors
    /// [`ProtocolError::Read`] for an unknown name; otherwise as [`Protocol::from_toml`].
    pub fn builtin(name: &str) -> Result<Protocol, ProtocolError> {
        let path = PathBuf::from(format!("<built-in {name}>"));
        match Protocol::builtin_text(name) {
            Some(text) => Protocol::from_toml(text, &path),
            None => Err(ProtocolError::Read {
                path,
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "no built-in protocol of that name",
                ),
            }),
        }
    }

    /// The reach section, with its defaults when absent.
    #[must_use]
    pub fn reach(&self) -> ReachConfig {
        self.reach.clone().unwrap_or_default()
    }

    /// The hold section, with its defaults when absent.
    #[must_use]
    pub fn hold(&self) -> HoldConfig {
        self.hold.clone().unwrap_or_default()
    }

    /// The calibration section, with its defaults when absent.
    #[must_use]
    pub fn calibration(&self) -> CalibrationConfig {
        self.calibration.clone().unwrap_or_default()
    }

    /// The controller's control clock (4 kHz on the Börner rig). A loaded protocol's rate
    /// is validated non-zero; the fallback is the rig's clock.
    #[must_use]
    pub fn control_rate(&self) -> rigtwin_device::Rate {
        self.controller
            .control_rate()
            .unwrap_or(rigtwin_device::Rate::CONTROL)
    }

    /// Trial length, s, by protocol kind, with the key of its largest part (the one to
    /// change when the trial is too long).
    #[must_use]
    pub fn trial_s(&self) -> (f64, &'static str) {
        match self.kind {
            ProtocolKind::ReachPerturb => {
                let r = self.reach();
                let (back_s, back_move_s) =
                    r.back_after_s.map_or((0.0, 0.0), |b| (b, r.movement_s));
                let parts = [
                    (r.still_before_s, "reach.still_before_s"),
                    (r.movement_s, "reach.movement_s"),
                    (back_s, "reach.back_after_s"),
                    (back_move_s, "reach.movement_s"),
                    (r.still_after_s, "reach.still_after_s"),
                ];
                sum_and_largest(&parts)
            }
            ProtocolKind::HoldSinusoid | ProtocolKind::CalibrationRig => {
                let m = &self.controller.imposed_motion;
                let parts = [
                    (2.0 * m.ramp_s, "controller.imposed_motion.ramp_s"),
                    (
                        f64::from(m.cycles) / m.frequency_hz,
                        "controller.imposed_motion.cycles",
                    ),
                    (self.hold().after_s, "hold.after_s"),
                ];
                sum_and_largest(&parts)
            }
        }
    }

    /// Number of trials per subject.
    #[must_use]
    pub fn trials_per_subject(&self) -> usize {
        match self.kind {
            ProtocolKind::ReachPerturb => self.reach().trials as usize,
            ProtocolKind::HoldSinusoid => self.hold().conditions.len(),
            ProtocolKind::CalibrationRig => self.calibration().repetitions as usize,
        }
    }

    /// Checks every key.
    ///
    /// # Errors
    /// Every invalid key, by dotted path.
    pub fn validate(&self) -> Result<(), Vec<InvalidKey>> {
        let mut c = Checker::default();
        if self.name.trim().is_empty()
            || self.name.len() > MAX_NAME_CHARS
            || !self
                .name
                .chars()
                .all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_')
        {
            c.fail(
                "name",
                format!(
                    "must be a folder-safe name of 1 to {MAX_NAME_CHARS} letters, digits, - and _, got {:?}",
                    self.name
                ),
            );
        }
        let rate = self.recording.rate_hz;
        if rate == 0 || !rigtwin_device::Rate::CONTROL.hz().is_multiple_of(rate) {
            c.fail(
                "recording.rate_hz",
                format!("must divide the 4000 Hz control clock, got {rate}"),
            );
        }
        if let Err(e) = self.controller.validate() {
            for k in e.errors {
                c.fail(format!("controller.{}", k.key), k.problem);
            }
        }
        if self.controller.control_rate_hz != 4000 {
            c.fail(
                "controller.control_rate_hz",
                format!(
                    "must be 4000: the simulator steps at 4 kHz, got {}",
                    self.controller.control_rate_hz
                ),
            );
        }
        let wall = self.controller.safety.wall_m;
        let unused = |c: &mut Checker, key: &str| {
            c.fail(
                key,
                format!(
                    "is not used by kind = \"{}\"; remove it",
                    self.kind.as_str()
                ),
            );
        };
        match self.kind {
            ProtocolKind::ReachPerturb => {
                if self.hold.is_some() {
                    unused(&mut c, "hold");
                }
                if self.calibration.is_some() {
                    unused(&mut c, "calibration");
                }
                if self.controller.law != LawKind::Admittance {
                    c.fail("controller.law", "must be \"admittance\" for reach-perturb");
                }
                self.check_reach(&mut c, wall);
            }
            ProtocolKind::HoldSinusoid | ProtocolKind::CalibrationRig => {
                if self.reach.is_some() {
                    unused(&mut c, "reach");
                }
                if self.kind == ProtocolKind::HoldSinusoid && self.calibration.is_some() {
                    unused(&mut c, "calibration");
                }
                if self.controller.law != LawKind::VirtualSpring {
                    c.fail(
                        "controller.law",
                        format!("must be \"virtual-spring\" for {}", self.kind.as_str()),
                    );
                }
                self.check_hold(&mut c, wall);
            }
        }
        self.check_plant(&mut c);
        self.check_sizes(&mut c);
        self.subjects.check(&mut c);
        if let Some(n) = &self.nuisance {
            n.check(&mut c);
        }
        let e = &self.estimate;
        c.positive("estimate.t_est_s", e.t_est_s);
        c.positive("estimate.savgol_cutoff_hz", e.savgol_cutoff_hz);
        c.non_negative("estimate.high_pass_hz", e.high_pass_hz);
        if e.savgol_polyorder < 3 {
            c.fail(
                "estimate.savgol_polyorder",
                format!("must be >= 3 (jerk), got {}", e.savgol_polyorder),
            );
        }
        if e.high_pass_hz > 0.0 && e.high_pass_order == 0 {
            c.fail("estimate.high_pass_order", "must be > 0");
        }
        if c.errors().is_empty() {
            Ok(())
        } else {
            Err(c.into_errors())
        }
    }

    /// Sizes: a trial of at most [`MAX_TRIAL_S`], at most [`MAX_TRIALS`] per subject and
    /// [`MAX_SUBJECTS`] subjects, each refused with what it would cost, before anything
    /// is allocated or simulated.
    fn check_sizes(&self, c: &mut Checker) {
        let (trial_s, key) = self.trial_s();
        // NaN parts are named by their own checks; only a finite excess is a size error.
        if trial_s.is_finite() && trial_s > MAX_TRIAL_S {
            let rate = f64::from(self.recording.rate_hz.max(1));
            c.fail(
                key,
                format!(
                    "makes a trial of {trial_s} s ({:.3e} ticks, {:.3e} recorded rows), more than the {MAX_TRIAL_S} s a trial may last",
                    trial_s * f64::from(rigtwin_device::Rate::CONTROL.hz()),
                    trial_s * rate,
                ),
            );
        }
        let (count, key) = match self.kind {
            ProtocolKind::ReachPerturb => (u64::from(self.reach().trials), "reach.trials"),
            ProtocolKind::HoldSinusoid => (self.hold().conditions.len() as u64, "hold.conditions"),
            ProtocolKind::CalibrationRig => (
                u64::from(self.calibration().repetitions),
                "calibration.repetitions",
            ),
        };
        if count > u64::from(MAX_TRIALS) {
            c.fail(
                key,
                format!(
                    "asks for {count} trials per subject, more than the {MAX_TRIALS} a protocol may have"
                ),
            );
        }
        if self.subjects.count > MAX_SUBJECTS {
            c.fail(
                "subjects.count",
                format!(
                    "asks for {} subjects, more than the {MAX_SUBJECTS} a rehearsal may draw",
                    self.subjects.count
                ),
            );
        }
    }

    fn check_reach(&self, c: &mut Checker, wall: f64) {
        let r = self.reach();
        for i in 0..2 {
            c.inside(&format!("reach.start_m[{i}]"), r.start_m[i], wall);
            c.inside(&format!("reach.goal_m[{i}]"), r.goal_m[i], wall);
        }
        for (key, v) in [
            ("reach.still_before_s", r.still_before_s),
            ("reach.still_after_s", r.still_after_s),
        ] {
            c.non_negative(key, v);
            c.whole_ticks(key, v, CONTROL_RATE);
        }
        c.positive("reach.movement_s", r.movement_s);
        c.whole_ticks("reach.movement_s", r.movement_s, CONTROL_RATE);
        if let Some(b) = r.back_after_s {
            c.non_negative("reach.back_after_s", b);
            c.whole_ticks("reach.back_after_s", b, CONTROL_RATE);
        }
        if r.trials == 0 {
            c.fail("reach.trials", "must be > 0, got 0");
        }
        for (i, a) in r.angles_deg.iter().enumerate() {
            c.finite(&format!("reach.angles_deg[{i}]"), *a);
        }
        if r.perturbed() > r.trials as usize {
            c.fail(
                "reach.repetitions",
                format!(
                    "{} angles x {} repetitions = {} perturbed trials exceed reach.trials = {}",
                    r.angles_deg.len(),
                    r.repetitions,
                    r.perturbed(),
                    r.trials
                ),
            );
        }
        let axis = r.trigger_axis.index();
        let (a, b) = (r.start_m[axis], r.goal_m[axis]);
        let line = r.trigger_position_m;
        if c.finite("reach.trigger_position_m", line)
            && r.perturbed() > 0
            && !(a.min(b) < line && line < a.max(b))
        {
            c.fail(
                "reach.trigger_position_m",
                format!("must lie strictly between start ({a}) and goal ({b}) on the trigger axis, got {line}"),
            );
        }
        // The way from the start to a goal, m.
        let way_m =
            |g: [f64; 2]| ((g[0] - r.start_m[0]).powi(2) + (g[1] - r.start_m[1]).powi(2)).sqrt();
        let dist = way_m(r.goal_m);
        if dist.is_finite() && dist < 1e-3 {
            c.fail("reach.goal_m", "must be at least 1 mm from reach.start_m");
        }
        for (i, g) in r.targets_m.iter().enumerate() {
            let key = format!("reach.targets_m[{i}]");
            for (a, v) in g.iter().enumerate() {
                c.inside(&format!("{key}[{a}]"), *v, wall);
            }
            let way = way_m(*g);
            if way.is_finite() && way < 0.02 {
                c.fail(
                    &key,
                    format!(
                        "must be at least 20 mm from reach.start_m, got {:.1} mm",
                        way * 1e3
                    ),
                );
            }
        }
    }

    fn check_hold(&self, c: &mut Checker, wall: f64) {
        let h = self.hold();
        for i in 0..2 {
            c.inside(&format!("hold.hand_m[{i}]"), h.hand_m[i], wall);
        }
        c.non_negative("hold.force_n", h.force_n);
        c.non_negative("hold.after_s", h.after_s);
        c.whole_ticks("hold.after_s", h.after_s, CONTROL_RATE);
        if self.kind == ProtocolKind::HoldSinusoid && h.conditions.is_empty() {
            c.fail("hold.conditions", "must list at least one condition");
        }
        for (i, cond) in h.conditions.iter().enumerate() {
            c.finite(&format!("hold.conditions[{i}].force_deg"), cond.force_deg);
        }
        c.finite(
            "hold.co_contraction_rise_per_s",
            h.co_contraction_rise_per_s,
        );
        let amp = self.controller.imposed_motion.amplitude_m;
        for i in 0..2 {
            if h.hand_m[i].is_finite() && amp.is_finite() && h.hand_m[i].abs() + amp >= wall {
                c.fail(
                    "controller.imposed_motion.amplitude_m",
                    format!(
                        "hold.hand_m[{i}] = {} plus the amplitude {amp} m reaches the wall at {wall} m",
                        h.hand_m[i]
                    ),
                );
                break;
            }
        }
        if self.kind == ProtocolKind::CalibrationRig {
            let k = self.calibration();
            c.positive("calibration.mass_kg", k.mass_kg);
            c.positive("calibration.stiffness_n_per_m[0]", k.stiffness_n_per_m[0]);
            c.positive("calibration.stiffness_n_per_m[1]", k.stiffness_n_per_m[1]);
            if k.repetitions == 0 {
                c.fail("calibration.repetitions", "must be > 0, got 0");
            }
        }
    }

    fn check_plant(&self, c: &mut Checker) {
        let cfg = self
            .plant
            .rig_config([0.0, 0.0], rigtwin_world::Attachment::None);
        if let Err(e) = cfg.validate() {
            match e {
                rigtwin_world::WorldError::InvalidConfig { key, reason } => {
                    c.fail(format!("plant.{key}"), reason);
                }
                other => c.fail("plant", other.to_string()),
            }
        }
    }
}

/// The sum of `parts` and the key of the largest.
fn sum_and_largest(parts: &[(f64, &'static str)]) -> (f64, &'static str) {
    let total = parts.iter().map(|(v, _)| v).sum();
    let key = parts
        .iter()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map_or("", |(_, k)| k);
    (total, key)
}

/// A TOML error as one line: `line L, column C: message`, the message cut to
/// [`rigtwin_device::check::MAX_QUOTE_CHARS`] (toml's own text quotes the whole line, and
/// serde quotes a bad string whole).
pub(crate) fn parse_message(text: &str, e: &toml::de::Error) -> String {
    let message = rigtwin_device::check::excerpt(e.message().trim_end(), MAX_QUOTE);
    match e.span() {
        Some(span) => {
            let (line, column) = rigtwin_session::files::line_column(text.as_bytes(), span.start);
            match key_at(text, line) {
                Some(key) => format!("line {line}, column {column}: field `{key}`: {message}"),
                None => format!("line {line}, column {column}: {message}"),
            }
        }
        None => message.into_owned(),
    }
}

/// The dotted key written on 1-based `line` (`reach.trials`), from its `key =` and the
/// table header above it; `None` on a line without a key.
fn key_at(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().take(line).collect();
    let here = lines.last()?.trim();
    let key = here
        .split_once('=')
        .map(|(k, _)| k.trim().trim_matches('"'))
        .filter(|k| !k.is_empty() && !k.starts_with('#') && !k.starts_with('['))?;
    let table = lines
        .iter()
        .rev()
        .map(|l| l.trim())
        .find(|l| l.starts_with('['))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']').trim());
    let key = rigtwin_device::check::excerpt(key, 80);
    Some(match table {
        Some(t) if !t.is_empty() => format!("{t}.{key}"),
        _ => key.into_owned(),
    })
}

/// The most characters of a bad value a protocol error quotes.
const MAX_QUOTE: usize = rigtwin_device::check::MAX_QUOTE_CHARS;
