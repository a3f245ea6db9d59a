//! Measured-style sessions with one hidden plant effect, for testing `diagnose` on data
//! whose cause is known.
//!
//! The session comes from the project's own runtime (`rigtwin::rehearse`) running the
//! shipped `reach-perturb` protocol (000_*: 3 s reaches, 15 N force pulses at eight
//! angles) against a drawn virtual subject (not the nominal one), with the world's
//! sensor noise and encoder quantum, recorded at 1 kHz as 4-tick block means like the
//! shared emulated rig, without ground-truth columns. The hidden effect is drawn from
//! the catalog, plant side or human side, with parameters in realistic ranges ([`draw`]).
//! Every session has, by default, the nuisances of a lab's rig and subject
//! ([`Design::nuisance`]: sensor offset and drift, motor gain tolerance and current
//! noise, reaches varying in reaction time, duration and end points, impedance drifting
//! over the session), `none` included, so that a diagnosis is tested on sessions like a
//! lab's. The layout ([`Design`]) is the shared sessions' by default (32 reaches, 24 pulses of
//! 150 ms); more and briefer pulses make a session like a lab's reflex study
//! ([`Design::reflex_study`]), to measure how the diagnosis gains with them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigtwin::protocol::Protocol;
use rigtwin::protocol::nuisance::NuisanceConfig;
use rigtwin::rehearse::{self, Options};
use rigtwin_arm::params::StretchReflex;
use rigtwin_device::config::ForcePulseConfig;
use rigtwin_diagnose::EffectKind;
use rigtwin_world::PlantEffects;
use rigtwin_world::config::{
    ActuationDelay, CableSpring, ForceRipple, GripCompliance, HandleMass, RailFriction,
    SensorEffect,
};

/// The effects a generated session may hide: `none` (nothing), then the diagnosis's
/// whole catalog, by its names.
pub const EFFECTS: [&str; EffectKind::ALL.len() + 1] = {
    let mut out = ["none"; EffectKind::ALL.len() + 1];
    let mut i = 0;
    while i < EffectKind::ALL.len() {
        out[i + 1] = EffectKind::ALL[i].name();
        i += 1;
    }
    out
};

/// The control tick, s (the world rounds delays to whole ticks).
const TICK_S: f64 = rigtwin_world::TICK_S;

/// Effects outside the diagnosis's catalog a generated session may hide ([`draw`]): a
/// diagnosis must not name a catalog effect for them but report the residual as
/// unexplained.
pub const OUT_OF_CATALOG: [&str; 3] = ["cable-spring", "sensor-lowpass", "late-feedback"];

/// Pairs of effects a generated session may hide together ([`draw`] with `a+b`): two
/// plant-side effects on one rig (friction and cogging, friction and a latency), one
/// of each side (friction and a heavier handle; a rotated sensor and a
/// heavier handle, the shared rig's), a delay with a rotated sensor (both reshape
/// the balance rather than add to it), and two human-side effects on one subject and
/// handle (a heavier handle with a reflex or a soft grip, a soft grip with a reflex).
pub const PAIRS: [&str; 8] = [
    "rail-friction+force-ripple",
    "rail-friction+actuation-delay",
    "actuation-delay+sensor-rotation",
    "rail-friction+handle-mass",
    "sensor-rotation+handle-mass",
    "stretch-reflex+handle-mass",
    "grip-compliance+handle-mass",
    "grip-compliance+stretch-reflex",
];

/// A hidden effect (or several): its catalog name (`a+b` for several), the parameters a
/// diagnosis should recover (units in the names) and the world configuration that
/// produces it.
#[derive(Debug, Clone, PartialEq)]
pub struct Hidden {
    /// Catalog name, `a+b` for several, or `none`.
    pub effect: String,
    /// Each hidden effect's catalog name and the parameters to recover, in the order of
    /// the name (empty for `none`).
    pub each: Vec<(String, BTreeMap<String, f64>)>,
    /// The parameters to recover, all effects' together (for one effect, its own).
    pub parameters: BTreeMap<String, f64>,
    /// What the world simulates.
    pub effects: PlantEffects,
    /// The subject's stretch reflex (`stretch-reflex`), put into the protocol's arm.
    pub stretch_reflex: Option<StretchReflex>,
    /// The subject's feedback delay, ms (`late-feedback`), put into the protocol's arm
    /// instead of its 60 ms.
    pub feedback_delay_ms: Option<f64>,
}

impl Hidden {
    /// A rail friction of `coulomb_n` N and `viscous_n_s_per_m` on both rails, its knee
    /// at 1 mm/s, and nothing else, for [`generate_hidden`]: frictions outside
    /// [`draw`]'s range (a viscous friction without a Coulomb force).
    #[must_use]
    pub fn friction(coulomb_n: f64, viscous_n_s_per_m: f64) -> Hidden {
        Hidden::plant_alone(
            EffectKind::RailFriction,
            &[
                ("coulomb_n", coulomb_n),
                ("viscous_n_s_per_m", viscous_n_s_per_m),
            ],
            PlantEffects {
                rail_friction: Some(RailFriction {
                    coulomb_n,
                    viscous_n_s_per_m,
                    smooth_velocity_m_per_s: 1e-3,
                }),
                ..PlantEffects::default()
            },
        )
    }

    /// A grip of `stiffness_n_per_m` with `damping_n_s_per_m` and nothing else, for
    /// [`generate_hidden`]: grips outside [`draw`]'s range.
    #[must_use]
    pub fn grip(stiffness_n_per_m: f64, damping_n_s_per_m: f64) -> Hidden {
        Hidden::plant_alone(
            EffectKind::GripCompliance,
            &[("stiffness_n_per_m", stiffness_n_per_m)],
            PlantEffects {
                grip_compliance: Some(GripCompliance {
                    stiffness_n_per_m,
                    damping_n_s_per_m,
                }),
                ..PlantEffects::default()
            },
        )
    }

    /// The catalog effect `kind` alone, simulated by `effects`, with `parameters` to
    /// recover.
    fn plant_alone(kind: EffectKind, parameters: &[(&str, f64)], effects: PlantEffects) -> Hidden {
        let name = kind.name();
        let p: BTreeMap<String, f64> = parameters
            .iter()
            .map(|(k, v)| ((*k).to_string(), *v))
            .collect();
        Hidden {
            effect: name.to_string(),
            each: vec![(name.to_string(), p.clone())],
            parameters: p,
            effects,
            stretch_reflex: None,
            feedback_delay_ms: None,
        }
    }
}

/// Draws the parameters of `effect` from realistic ranges; `None` for an unknown name.
///
/// - `rail-friction`: `Fc` 1–4 N, `b` 2–10 N s/m, smoothing 0.5–2 mm/s (linear-stage
///   rails with preloaded carriages).
/// - `force-ripple`: amplitude 1–3 N per axis, pitch 10–50 mm (iron-core linear
///   motors), each axis's phase uniform (its magnet track starts anywhere).
/// - `actuation-delay`: 0.75–1.5 ms in whole ticks (drive/bus latency; much beyond
///   ~2 ms the project's stiff position loop is no longer stable).
/// - `sensor-rotation`: ±10–25° (a sensor mounted one bolt hole off its index; a few
///   degrees of misalignment are found too, but explain less than half of the
///   plant's residual floor, see `tests/tests/hidden_effect.rs`).
/// - `stretch-reflex`: delay 15–35 ms in whole milliseconds (the arm's neural tick at
///   its default divisor; short-latency reflexes of the upper limb lie at 20–50 ms
///   from stretch to EMG, the lumped model has no separate EMG-to-force lag), gain
///   100–250 N of activation per m/s of muscle stretch velocity: the same order as the
///   muscles' own damping `τ_d K_m` (≈ 100–300 N s/m at the default co-contraction),
///   which is what makes the reflex a material part of the perturbation response
///   (the arm's `StretchReflex::TYPICAL` 50 N s/m adds only a few percent to it).
/// - `grip-compliance`: stiffness 2–6 kN/m, damping `k · τ` with τ 2–6 ms
///   (4–36 N s/m; a firm grasp on a handle through skin and soft tissue). Only the
///   stiffness is a catalog parameter and so in [`Hidden::parameters`].
/// - `handle-mass`: 0.3–1.0 kg (an unlisted adapter, a heavier handle or grip tube).
///
/// Outside the catalog ([`OUT_OF_CATALOG`]):
/// - `cable-spring`: a cable carrier on each rail pulling its cart with 20–60 N/m
///   towards a rest position within ±5 cm of the workspace's centre (2–6 N over a
///   10 cm reach: an energy chain's bending force).
/// - `sensor-lowpass`: the force sensor's reading through a first-order low-pass at
///   10–30 Hz (an amplifier's anti-alias or a DSP filter set low: 5–16 ms of lag).
/// - `late-feedback`: a subject whose delayed feedback (the arm's PD on the muscles'
///   stretch) acts after 110–160 ms in whole milliseconds instead of the model's
///   60 ms: a slow responder, whose corrections are long-latency or voluntary ones
///   (those begin 100–150 ms after a perturbation).
///
/// `a+b` draws each named effect in turn from the same generator and hides them
/// together; `None` when a name is unknown or repeated, or one of them is `none`.
#[must_use]
pub fn draw(effect: &str, rng: &mut ChaCha8Rng) -> Option<Hidden> {
    if !effect.contains('+') {
        return draw_one(effect, rng);
    }
    let names: Vec<&str> = effect.split('+').collect();
    let mut all = Hidden {
        effect: effect.to_string(),
        each: Vec::new(),
        parameters: BTreeMap::new(),
        effects: PlantEffects::default(),
        stretch_reflex: None,
        feedback_delay_ms: None,
    };
    for (i, name) in names.iter().enumerate() {
        if *name == "none" || names[..i].contains(name) {
            return None;
        }
        let h = draw_one(name, rng)?;
        let e = h.effects;
        let w = &mut all.effects;
        w.rail_friction = w.rail_friction.or(e.rail_friction);
        w.force_ripple = w.force_ripple.or(e.force_ripple);
        w.actuation_delay = w.actuation_delay.or(e.actuation_delay);
        w.sensor = w.sensor.or(e.sensor);
        w.handle_mass = w.handle_mass.or(e.handle_mass);
        w.grip_compliance = w.grip_compliance.or(e.grip_compliance);
        w.cable_spring = w.cable_spring.or(e.cable_spring);
        all.stretch_reflex = all.stretch_reflex.or(h.stretch_reflex);
        all.feedback_delay_ms = all.feedback_delay_ms.or(h.feedback_delay_ms);
        all.parameters.extend(h.parameters.clone());
        all.each.extend(h.each);
    }
    Some(all)
}

fn draw_one(effect: &str, rng: &mut ChaCha8Rng) -> Option<Hidden> {
    let mut effects = PlantEffects::default();
    let mut stretch_reflex = None;
    let mut feedback_delay_ms = None;
    let mut p = BTreeMap::new();
    match (effect, EffectKind::from_name(effect)) {
        ("none", _) => {}
        // Every catalog effect has its draw: a new one does not compile until it has.
        (_, Some(kind)) => match kind {
            EffectKind::RailFriction => {
                let f = RailFriction {
                    coulomb_n: rng.random_range(1.0..4.0),
                    viscous_n_s_per_m: rng.random_range(2.0..10.0),
                    smooth_velocity_m_per_s: rng.random_range(0.5e-3..2e-3),
                };
                p.insert("coulomb_n".into(), f.coulomb_n);
                p.insert("viscous_n_s_per_m".into(), f.viscous_n_s_per_m);
                effects.rail_friction = Some(f);
            }
            EffectKind::ForceRipple => {
                let r = ForceRipple {
                    amplitude_n: [rng.random_range(1.0..3.0), rng.random_range(1.0..3.0)],
                    pitch_m: rng.random_range(0.01..0.05),
                    phase_rad: [
                        rng.random_range(0.0..std::f64::consts::TAU),
                        rng.random_range(0.0..std::f64::consts::TAU),
                    ],
                };
                p.insert("amplitude_x_n".into(), r.amplitude_n[0]);
                p.insert("amplitude_y_n".into(), r.amplitude_n[1]);
                p.insert("pitch_m".into(), r.pitch_m);
                effects.force_ripple = Some(r);
            }
            EffectKind::ActuationDelay => {
                let ticks = (rng.random_range(0.75e-3..1.5e-3) / TICK_S).round();
                let d = ActuationDelay {
                    delay_ms: ticks * TICK_S * 1e3,
                };
                p.insert("delay_ms".into(), d.delay_ms);
                effects.actuation_delay = Some(d);
            }
            EffectKind::SensorRotation => {
                let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                let s = SensorEffect {
                    rotation_deg: sign * rng.random_range(10.0..25.0),
                    offset_n: [0.0; 2],
                    lowpass_hz: 0.0,
                };
                p.insert("angle_deg".into(), s.rotation_deg);
                effects.sensor = Some(s);
            }
            EffectKind::StretchReflex => {
                let r = StretchReflex {
                    delay_ms: rng.random_range(15.0_f64..35.0).round(),
                    gain_n_s_per_m: rng.random_range(100.0..250.0),
                };
                p.insert("delay_ms".into(), r.delay_ms);
                p.insert("gain".into(), r.gain_n_s_per_m);
                stretch_reflex = Some(r);
            }
            EffectKind::GripCompliance => {
                let k = rng.random_range(2000.0..6000.0);
                let g = GripCompliance {
                    stiffness_n_per_m: k,
                    damping_n_s_per_m: k * rng.random_range(2e-3..6e-3),
                };
                p.insert("stiffness_n_per_m".into(), g.stiffness_n_per_m);
                effects.grip_compliance = Some(g);
            }
            EffectKind::HandleMass => {
                let h = HandleMass {
                    extra_mass_kg: rng.random_range(0.3..1.0),
                };
                p.insert("extra_mass_kg".into(), h.extra_mass_kg);
                effects.handle_mass = Some(h);
            }
        },
        ("cable-spring", None) => {
            let c = CableSpring {
                stiffness_n_per_m: [rng.random_range(20.0..60.0), rng.random_range(20.0..60.0)],
                rest_m: [rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05)],
            };
            p.insert("stiffness_x_n_per_m".into(), c.stiffness_n_per_m[0]);
            p.insert("stiffness_y_n_per_m".into(), c.stiffness_n_per_m[1]);
            effects.cable_spring = Some(c);
        }
        ("sensor-lowpass", None) => {
            let s = SensorEffect {
                rotation_deg: 0.0,
                offset_n: [0.0; 2],
                lowpass_hz: rng.random_range(10.0..30.0),
            };
            p.insert("lowpass_hz".into(), s.lowpass_hz);
            effects.sensor = Some(s);
        }
        ("late-feedback", None) => {
            let ms: f64 = rng.random_range(110.0_f64..160.0).round();
            p.insert("feedback_delay_ms".into(), ms);
            feedback_delay_ms = Some(ms);
        }
        _ => return None,
    }
    Some(Hidden {
        effect: effect.to_string(),
        each: if effect == "none" {
            Vec::new()
        } else {
            vec![(effect.to_string(), p.clone())]
        },
        parameters: p,
        effects,
        stretch_reflex,
        feedback_delay_ms,
    })
}

/// A generated session.
#[derive(Debug, Clone, PartialEq)]
pub struct Generated {
    /// The session directory.
    pub dir: PathBuf,
    /// What it hides.
    pub hidden: Hidden,
}

/// The four cardinal pulse directions, degrees from `+x` toward `+y` ([`Design::cardinal`]).
pub const CARDINAL_DEG: [f64; 4] = [0.0, 90.0, 180.0, 270.0];

/// The goals of [`Design::centre_out`], rig frame, m: 0.18 m from the protocol's start
/// `[0, −0.125]` at 45°, 90° and 135° from `+x`, to 0.01 mm (a fan in front of the body,
/// inside the rig's ±0.15 m along `x`).
pub const CENTRE_OUT_M: [[f64; 2]; 3] = [[0.127_28, 0.002_28], [0.0, 0.055], [-0.127_28, 0.002_28]];

/// How a generated session is laid out: its length, how many force pulses it carries
/// and of what shape, and whether the arm has its motor noise.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// Reaches recorded.
    pub trials: usize,
    /// Pulses per angle (the protocol's 8 angles, or [`Self::angles_deg`]): 3 on the
    /// shared sessions. A lab measuring a reflex against the arm's motor noise gives it
    /// more.
    pub repetitions: u32,
    /// The arm's signal-dependent motor noise; off, only the sensor noise and encoder
    /// quantum remain: the same subject and effect, to see what a balance's model
    /// leaves when the noise floor is gone.
    pub motor_noise: bool,
    /// The force pulse; `None` keeps the protocol's (000_*: 150 ms, 15 N).
    pub pulse: Option<ForcePulseConfig>,
    /// The rig's and subject's nuisances (sensor offset and drift, motor gain and
    /// noise, reaches varying in time and place, impedance drifting): a lab's rig by
    /// default ([`NuisanceConfig::REALISTIC`]); `None` is the ideal rig.
    pub nuisance: Option<NuisanceConfig>,
    /// The recording rate, Hz (a divisor of the 4 kHz control rate): 1000 on the
    /// shared sessions; labs log at 500 Hz to 4 kHz.
    pub rate_hz: u32,
    /// The factor on the simulated arm's segment masses and moments of inertia (1: the
    /// tables the diagnosis assumes; the manifest does not say it): a subject whose arm
    /// is heavier or lighter than the anthropometric model, to measure what the hand
    /// balance makes of it.
    pub arm_inertia_scale: f64,
    /// The reach's duration, s; `None` keeps the protocol's (000_*: 3 s for 0.25 m).
    /// Most reaching studies move about three times faster.
    pub movement_s: Option<f64>,
    /// Reaches along `x` instead of `y`: the protocol's 0.25 m from `[−0.125, 0]` to
    /// `[0.125, 0]` m, the pulse fired where the measured `x` crosses −0.025 m, as a lab
    /// that studies lateral reaches lays them out.
    pub lateral: bool,
    /// The pulse directions, degrees from `+x` toward `+y`, `repetitions` pulses each;
    /// `None` keeps the protocol's eight (30, 60, 120, … 330°, none along an axis).
    /// Many labs pulse in the four cardinal directions ([`Design::cardinal`]: two pairs
    /// of opposite directions) or only across the reach (one pair).
    pub angles_deg: Option<Vec<f64>>,
    /// Centre-out goals (the protocol's `reach.targets_m`), rig frame, m; `None`: every
    /// reach to the protocol's goal. [`Design::centre_out`] is a fan of three.
    pub targets_m: Option<Vec<[f64; 2]>>,
    /// Reaches out and back in one trial (the protocol's `reach.back_after_s`): the time
    /// at the goal, s, before the hand goes back to its start in the reach's duration,
    /// as a centre-out task that logs the return; `None`, one way.
    pub back_after_s: Option<f64>,
}

impl Design {
    /// The shared sessions' layout: 32 reaches of which 24 perturbed (8 angles × 3),
    /// motor noise on.
    pub const SHARED: Design = Design {
        trials: 32,
        repetitions: 3,
        motor_noise: true,
        pulse: None,
        nuisance: Some(NuisanceConfig::REALISTIC),
        rate_hz: 1000,
        arm_inertia_scale: 1.0,
        movement_s: None,
        lateral: false,
        angles_deg: None,
        targets_m: None,
        back_after_s: None,
    };

    /// The shared layout on the ideal rig and without the arm's motor noise: what is
    /// left is the balance's own structural floor.
    pub const QUIET: Design = Design {
        motor_noise: false,
        nuisance: None,
        ..Design::SHARED
    };

    /// `repetitions` pulses per angle in a session of the shared proportion (a quarter
    /// of the reaches unperturbed): 9 gives 72 pulses in 96 reaches.
    #[must_use]
    pub const fn with_pulses(repetitions: u32) -> Design {
        let perturbed = 8 * repetitions as usize;
        Design {
            trials: perturbed + perturbed / 3,
            repetitions,
            motor_noise: true,
            pulse: None,
            nuisance: Some(NuisanceConfig::REALISTIC),
            rate_hz: 1000,
            arm_inertia_scale: 1.0,
            movement_s: None,
            lateral: false,
            angles_deg: None,
            targets_m: None,
            back_after_s: None,
        }
    }

    /// `repetitions` pulses in each of `angles_deg` (degrees from `+x` toward `+y`), in a
    /// session of the shared proportion (a quarter of the reaches unperturbed).
    #[must_use]
    pub fn with_angles(angles_deg: &[f64], repetitions: u32) -> Design {
        let perturbed = angles_deg.len() * repetitions as usize;
        Design {
            trials: perturbed + perturbed / 3,
            repetitions,
            angles_deg: Some(angles_deg.to_vec()),
            ..Design::SHARED
        }
    }

    /// The shared layout's 24 pulses on centre-out reaches to the three goals of
    /// [`CENTRE_OUT_M`] (45°, 90° and 135° from the start, 0.18 m away): each goal gets
    /// one pulse in each of the protocol's eight directions, and a third of the
    /// unperturbed reaches.
    #[must_use]
    pub fn centre_out() -> Design {
        Design {
            targets_m: Some(CENTRE_OUT_M.to_vec()),
            ..Design::SHARED
        }
    }

    /// The shared layout's 24 pulses in the four cardinal directions (0, 90, 180, 270°,
    /// six each, in 32 reaches): the layout of many labs.
    #[must_use]
    pub fn cardinal() -> Design {
        Design::with_angles(&CARDINAL_DEG, 6)
    }

    /// A session laid out to measure a short-latency reflex, as reflex studies do: 72
    /// brief pulses (9 per angle, in 96 reaches), 50 ms long instead of the seed's
    /// 150 ms so that their power reaches the 10–30 Hz where a 15–35 ms delay turns the
    /// response (`ωδ` towards π/2), and 30 N instead of 15 N to keep two thirds of the
    /// seed pulse's impulse (1.5 against 2.25 N s for the same shape), so the hand moves
    /// about as far.
    #[must_use]
    pub fn reflex_study() -> Design {
        Design {
            pulse: Some(ForcePulseConfig {
                duration_s: 0.05,
                amplitude_n: 30.0,
            }),
            ..Design::with_pulses(9)
        }
    }
}

/// Two numbers from `A,B`, each named (`what` and `names`) in its error, `form` saying
/// what is wanted.
fn two_numbers(v: &str, what: &str, names: [&str; 2], form: &str) -> Result<(f64, f64), String> {
    let parts: Vec<&str> = v.split(',').collect();
    let [a, b] = parts.as_slice() else {
        return Err(format!("{what} {v:?}: want {form}"));
    };
    let number = |x: &str, name: &str| {
        x.trim()
            .parse::<f64>()
            .map_err(|e| format!("{what} {name} {x:?}: {e}"))
    };
    Ok((number(a, names[0])?, number(b, names[1])?))
}

/// A force pulse from `SECONDS,NEWTONS` (e.g. `0.05,30`), as the example's `--pulse`
/// and the sweep's `SWEEP_PULSE` take it.
///
/// # Errors
/// Not two numbers, a duration not above 0 s or an amplitude below 0 N, said with `v`.
pub fn parse_pulse(v: &str) -> Result<ForcePulseConfig, String> {
    let (duration_s, amplitude_n) = two_numbers(
        v,
        "pulse",
        ["duration", "amplitude"],
        "SECONDS,NEWTONS, e.g. 0.05,30",
    )?;
    if !(duration_s > 0.0 && amplitude_n >= 0.0) {
        return Err(format!(
            "pulse {v:?}: the duration must be > 0 s and the amplitude >= 0 N"
        ));
    }
    Ok(ForcePulseConfig {
        duration_s,
        amplitude_n,
    })
}

/// A grip's stiffness and damping from `N_PER_M,N_S_PER_M` (e.g. `1000,10`), as the
/// example's `--grip` takes it.
///
/// # Errors
/// Not two numbers, a stiffness not above 0 N/m or a damping below 0 N s/m, said with `v`.
pub fn parse_grip(v: &str) -> Result<(f64, f64), String> {
    let (k, b) = two_numbers(
        v,
        "grip",
        ["stiffness", "damping"],
        "N_PER_M,N_S_PER_M, e.g. 1000,10",
    )?;
    if !(k > 0.0 && k.is_finite() && b >= 0.0 && b.is_finite()) {
        return Err(format!(
            "grip {v:?}: the stiffness must be > 0 N/m and the damping >= 0 N s/m"
        ));
    }
    Ok((k, b))
}

/// Writes a session of `trials` reaches hiding `effect` (parameters and subject drawn
/// from `seed`) under `out` (which must not exist or be empty), with the shared
/// sessions' 24 pulses.
///
/// # Errors
/// An unknown effect name, or the runtime's error.
pub fn generate(
    effect: &str,
    seed: u64,
    trials: usize,
    out: &Path,
) -> Result<Generated, Box<dyn std::error::Error + Send + Sync>> {
    let design = Design {
        trials,
        ..Design::SHARED
    };
    generate_design(effect, seed, &design, out)
}

/// [`generate`] with the session laid out by `design`. The effect and subject depend on
/// `seed` alone, so one seed under two designs hides the same thing in the same arm.
///
/// # Errors
/// An unknown effect name, or the runtime's error.
pub fn generate_design(
    effect: &str,
    seed: u64,
    design: &Design,
    out: &Path,
) -> Result<Generated, Box<dyn std::error::Error + Send + Sync>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let hidden = draw(effect, &mut rng).ok_or_else(|| {
        format!("unknown effect {effect:?}; known: {EFFECTS:?}, or two of them joined by +")
    })?;
    generate_hidden(hidden, seed, design, out)
}

/// [`generate_design`] hiding `hidden` as given instead of drawn: parameters outside
/// [`draw`]'s ranges. The subject depends on `seed` alone, as there.
///
/// # Errors
/// The runtime's error.
pub fn generate_hidden(
    mut hidden: Hidden,
    seed: u64,
    design: &Design,
    out: &Path,
) -> Result<Generated, Box<dyn std::error::Error + Send + Sync>> {
    let mut protocol = Protocol::builtin("reach-perturb")?;
    protocol.recording.rate_hz = design.rate_hz;
    // The pulses in random order among the reaches, all of them within the recorded
    // ones (the first 32 of the seed's 100-trial schedule hold only ~8 of the 24): the
    // hand balance needs the perturbed trials.
    let trials = design.trials;
    let mut reach = protocol.reach();
    reach.repetitions = design.repetitions;
    if let Some(s) = design.movement_s {
        reach.movement_s = s;
    }
    if let Some(angles) = &design.angles_deg {
        reach.angles_deg.clone_from(angles);
    }
    if design.lateral {
        reach.start_m = [-0.125, 0.0];
        reach.goal_m = [0.125, 0.0];
        reach.trigger_axis = rigtwin_device::config::Axis::X;
        reach.trigger_position_m = -0.025;
    }
    if let Some(t) = &design.targets_m {
        reach.targets_m.clone_from(t);
    }
    reach.back_after_s = design.back_after_s;
    let perturbed = reach.repetitions as usize * reach.angles_deg.len();
    reach.trials = u32::try_from(trials.max(perturbed + 2)).unwrap_or(u32::MAX);
    protocol.reach = Some(reach);
    protocol.recording.truth_columns = false;
    protocol.plant.effects = hidden.effects.clone();
    protocol.subjects.arm.stretch_reflex = hidden.stretch_reflex;
    if let Some(ms) = hidden.feedback_delay_ms {
        protocol.subjects.arm.feedback.delay_ms = ms;
    }
    protocol.subjects.first_is_nominal = false;
    protocol.subjects.arm = protocol
        .subjects
        .arm
        .clone()
        .with_mass_scale(design.arm_inertia_scale);
    if let Some(p) = &design.pulse {
        protocol.controller.force_pulse = p.clone();
    }
    if !design.motor_noise {
        protocol.subjects.arm.noise.activation_cv = 0.0;
    }
    protocol.nuisance = design.nuisance;
    let options = Options {
        subjects: 1,
        seed,
        out_dir: out.to_path_buf(),
        jobs: 2,
        max_trials: Some(trials),
    };
    let r = rehearse::rehearse(&protocol, &options, &|_| {}, &AtomicBool::new(false))?;
    let subject = r.subjects.first().ok_or("the rehearsal wrote no session")?;
    // A late feedback's gain is the subject's own (the protocol draws it): recorded with
    // the delay as what a diagnosis should recover.
    if hidden.feedback_delay_ms.is_some() {
        let gain = subject.subject.arm.feedback.position_gain_n_per_m;
        for map in
            std::iter::once(&mut hidden.parameters).chain(hidden.each.iter_mut().map(|(_, p)| p))
        {
            map.insert("feedback_position_gain_n_per_m".into(), gain);
        }
    }
    Ok(Generated {
        dir: subject.dir.clone(),
        hidden,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reflex study's pulse reads back exactly; a missing field, a zero duration, a
    /// negative amplitude or a word are refused with the value in the message.
    #[test]
    fn pulse_reads_seconds_and_newtons() {
        assert_eq!(
            parse_pulse("0.05,30"),
            Ok(ForcePulseConfig {
                duration_s: 0.05,
                amplitude_n: 30.0
            })
        );
        for bad in ["0.05", "0,30", "0.05,-1", "short,30", "0.05,30,1"] {
            let Err(e) = parse_pulse(bad) else {
                panic!("{bad:?} was accepted");
            };
            assert!(e.contains("pulse"), "{e}");
        }
    }

    /// A grip reads back exactly; a zero or infinite stiffness, a negative damping, a
    /// word or a third number are refused with the value in the message.
    #[test]
    fn grip_reads_stiffness_and_damping() {
        assert_eq!(parse_grip("1000, 10"), Ok((1000.0, 10.0)));
        for bad in ["1000", "0,10", "inf,10", "1000,-1", "soft,10", "1000,10,1"] {
            let Err(e) = parse_grip(bad) else {
                panic!("{bad:?} was accepted");
            };
            assert!(e.contains("grip"), "{e}");
        }
    }
}
