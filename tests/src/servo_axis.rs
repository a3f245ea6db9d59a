//! An emulated linear servo axis, the kind a lab puts on a test bench: one carriage on
//! a rail, driven by a linear motor through a current amplifier (command in volts),
//! under a digital position loop at 1 kHz, logged as one long recording of time,
//! position, reference and drive command. Its physics is written here, independently
//! of the diagnosis, and is not the diagnosis's law:
//!
//! ```text
//! m ẍ = K_a · u(t − τ) + f₀ + A sin(2π x / p + φ) − F_c · sgn(ẋ) − b ẋ,   stiction at ẋ = 0
//! ```
//!
//! - **Friction** is Karnopp's stick–slip model: at rest the carriage sticks while the
//!   other forces stay within `F_c`, and moves off as soon as they exceed it; in motion
//!   the force is `F_c sgn(ẋ) + b ẋ`. No smoothing: the diagnosis's friction law has a
//!   knee, the axis has none.
//! - `f₀` is a constant force (a cable chain's pull, a slightly tilted rail).
//! - `A sin(2π x / p + φ)` is the motor's cogging along its magnet track.
//! - `τ` is the loop's transport delay: the command computed from the sample at `k`
//!   acts over `[k + d, k + d + 1)` ticks (`delay_ticks = d`; the bench's `d = 1` is a
//!   real-time loop that writes its output at the next tick). Seen in the sampled
//!   balance, the second difference of the positions at `k` holds the forces over
//!   `[k − 1, k + 1)` equally, so the command acts `d + 0.5` ticks late.
//!
//! The loop is a PID with velocity and acceleration feed-forward on a minimum-jerk
//! reference; the encoder quantises position to `encoder_m`; the amplifier adds white
//! current noise. The carriage is integrated at 20 kHz (semi-implicit Euler,
//! 20 substeps a sample), far above every time constant of the loop.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rigtwin::session::{
    Axes, Channels, Device, Manifest, Sample, SessionError, SessionWriter, Source, Subject,
    TrialKind, TrialMeta,
};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The axis's physics and its controller.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoAxis {
    /// Moving mass (carriage, motor coil, payload), kg.
    pub mass_kg: f64,
    /// Coulomb friction, N.
    pub coulomb_n: f64,
    /// Viscous friction, N s/m.
    pub viscous_n_s_per_m: f64,
    /// Stribeck excess of static over Coulomb friction, N (0: none): the friction in
    /// motion is `(F_c + F_s e^{−(v/v_s)²}) sgn(v) + b v`, and at rest the carriage sticks
    /// while the other forces stay within `F_c + F_s`. Not in the diagnosis's catalog.
    pub stribeck_n: f64,
    /// Stribeck speed `v_s`, m/s.
    pub stribeck_speed_m_per_s: f64,
    /// Constant force on the carriage, N.
    pub offset_n: f64,
    /// Cogging amplitude, N (0: none).
    pub cogging_n: f64,
    /// Cogging pitch (the magnet track's pole pitch), m.
    pub cogging_pitch_m: f64,
    /// Amplifier and motor: force per volt of command, N/V.
    pub force_per_volt: f64,
    /// Amplifier current noise as a force, N RMS per sample.
    pub noise_n: f64,
    /// Encoder resolution, m.
    pub encoder_m: f64,
    /// Loop rate, Hz.
    pub rate_hz: f64,
    /// Ticks between the sample a command is computed from and the tick it starts to
    /// act (0: within the same tick; 1: written at the next tick).
    pub delay_ticks: usize,
    /// Position gain, N/m.
    pub kp: f64,
    /// Velocity gain, N s/m.
    pub kd: f64,
    /// Integral gain, N/(m s).
    pub ki: f64,
}

impl ServoAxis {
    /// A linear-motor stage of the size labs use for haptic and motor-control benches
    /// (moving mass 3.2 kg, 4.5 N Coulomb, 12 N s/m viscous, a 1.5 N cable pull,
    /// 0.8 N cogging at a 32 mm pole pitch, 20 N/V amplifier, 1 µm encoder), under a
    /// loop of ~25 Hz bandwidth at 1 kHz.
    #[must_use]
    pub fn bench() -> ServoAxis {
        let mass_kg = 3.2;
        let w = 2.0 * std::f64::consts::PI * 25.0;
        ServoAxis {
            mass_kg,
            coulomb_n: 4.5,
            viscous_n_s_per_m: 12.0,
            stribeck_n: 0.0,
            stribeck_speed_m_per_s: 0.005,
            offset_n: -1.5,
            cogging_n: 0.8,
            cogging_pitch_m: 0.032,
            force_per_volt: 20.0,
            noise_n: 0.3,
            encoder_m: 1e-6,
            rate_hz: 1000.0,
            delay_ticks: 1,
            kp: mass_kg * w * w,
            kd: 2.0 * 0.7 * w * mass_kg,
            ki: 0.0,
        }
    }
}

/// One long recording, sampled at the loop rate.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoLog {
    /// Time, s, from 0.
    pub t_s: Vec<f64>,
    /// Encoder position, m.
    pub pos_m: Vec<f64>,
    /// Position reference, m.
    pub ref_m: Vec<f64>,
    /// Drive command, V.
    pub cmd_v: Vec<f64>,
    /// Onset of each move of the reference, s.
    pub move_onsets_s: Vec<f64>,
}

/// Minimum-jerk position, velocity and acceleration at phase `s` ∈ [0, 1] of a move
/// of length `d` over `t` seconds.
fn min_jerk(s: f64, d: f64, t: f64) -> (f64, f64, f64) {
    let s = s.clamp(0.0, 1.0);
    let p = 10.0 * s.powi(3) - 15.0 * s.powi(4) + 6.0 * s.powi(5);
    let v = (30.0 * s.powi(2) - 60.0 * s.powi(3) + 30.0 * s.powi(4)) / t;
    let a = (60.0 * s - 180.0 * s.powi(2) + 120.0 * s.powi(3)) / (t * t);
    (d * p, d * v, d * a)
}

/// Runs `moves` point-to-point moves between seeded targets within ±`half_range_m`,
/// each of a seeded duration (0.3–1.6 s, so that speeds span a decade) followed by a
/// seeded dwell (0.3–0.8 s), after 0.5 s at rest.
///
/// # Panics
/// Never: the noise distribution's deviation is a finite constant.
#[must_use]
pub fn run(axis: &ServoAxis, moves: usize, half_range_m: f64, seed: u64) -> ServoLog {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Reference plan: (start time, start pos, length, duration).
    let mut plan = Vec::with_capacity(moves);
    let (mut t, mut at) = (0.5, 0.0);
    for _ in 0..moves {
        let mut to: f64 = rng.random_range(-half_range_m..half_range_m);
        if (to - at).abs() < 0.2 * half_range_m {
            to = -to.signum() * half_range_m * 0.6;
        }
        let dur = rng.random_range(0.3..1.6);
        plan.push((t, at, to - at, dur));
        t += dur + rng.random_range(0.3..0.8);
        at = to;
    }
    let total_s = t + 0.5;
    let dt = 1.0 / axis.rate_hz;
    let n = (total_s * axis.rate_hz).round() as usize;
    let substeps = 20;
    let h = dt / f64::from(substeps);
    #[allow(clippy::expect_used)]
    let noise = Normal::new(0.0, axis.noise_n).expect("finite deviation");
    let reference = |t: f64| -> (f64, f64, f64) {
        let mut out = (0.0, 0.0, 0.0);
        for &(t0, x0, d, dur) in &plan {
            if t >= t0 {
                out = if t < t0 + dur {
                    let (p, v, a) = min_jerk((t - t0) / dur, d, dur);
                    (x0 + p, v, a)
                } else {
                    (x0 + d, 0.0, 0.0)
                };
            }
        }
        out
    };
    let mut log = ServoLog {
        t_s: Vec::with_capacity(n),
        pos_m: Vec::with_capacity(n),
        ref_m: Vec::with_capacity(n),
        cmd_v: Vec::with_capacity(n),
        move_onsets_s: plan.iter().map(|p| p.0).collect(),
    };
    let (mut x, mut v) = (0.0f64, 0.0f64);
    let (mut integral, mut last_enc) = (0.0, 0.0);
    // Commands computed but not yet acting, oldest first.
    let mut pending = std::collections::VecDeque::from(vec![0.0; axis.delay_ticks]);
    let phase = 0.7;
    for k in 0..n {
        let tk = k as f64 * dt;
        let enc = (x / axis.encoder_m).round() * axis.encoder_m;
        let vel_est = if k == 0 { 0.0 } else { (enc - last_enc) / dt };
        last_enc = enc;
        let (r, rv, ra) = reference(tk);
        let e = r - enc;
        integral += e * dt;
        let force = axis.kp * e + axis.kd * (rv - vel_est) + axis.ki * integral + axis.mass_kg * ra;
        let cmd = force / axis.force_per_volt;
        log.t_s.push(tk);
        log.pos_m.push(enc);
        log.ref_m.push(r);
        log.cmd_v.push(cmd);
        // The carriage over the next sample, under the command of `delay_ticks` ago.
        pending.push_back(cmd);
        let applied_v = pending.pop_front().unwrap_or(cmd);
        let drive = axis.force_per_volt * applied_v + axis.offset_n + noise.sample(&mut rng);
        for _ in 0..substeps {
            let cog = axis.cogging_n
                * (2.0 * std::f64::consts::PI * x / axis.cogging_pitch_m + phase).sin();
            let f = drive + cog;
            if v == 0.0 && f.abs() <= axis.coulomb_n + axis.stribeck_n {
                continue; // stuck
            }
            let dir = if v == 0.0 { f.signum() } else { v.signum() };
            let sliding = axis.coulomb_n
                + axis.stribeck_n * (-(v / axis.stribeck_speed_m_per_s).powi(2)).exp();
            let a = (f - sliding * dir - axis.viscous_n_s_per_m * v) / axis.mass_kg;
            let v_new = v + a * h;
            // Friction cannot reverse the motion within a substep: it stops it.
            v = if v != 0.0 && v_new.signum() != v.signum() {
                0.0
            } else {
                v_new
            };
            x += v * h;
        }
    }
    log
}

/// The log as a lab's continuous CSV: `time_s,pos_mm,ref_mm,drive_V` (millimetres
/// and volts, as a bench logger writes them), one row a sample.
#[must_use]
pub fn log_csv(log: &ServoLog) -> String {
    let mut out = String::from("time_s,pos_mm,ref_mm,drive_V\n");
    for k in 0..log.t_s.len() {
        let _ = writeln!(
            out,
            "{},{},{},{}",
            log.t_s[k],
            log.pos_m[k] * 1e3,
            log.ref_m[k] * 1e3,
            log.cmd_v[k]
        );
    }
    out
}

/// Writes the log as a one-axis session in `dir` (`axes = ["x"]`, no handle sensor:
/// force columns zero; the command in newtons at the amplifier's nominal `N/V`), one
/// trial per move from 0.25 s before its onset to 0.25 s before the next. `dir` must
/// not hold a session.
///
/// # Errors
/// The session writer's.
pub fn write_session(log: &ServoLog, axis: &ServoAxis, dir: &Path) -> Result<(), SessionError> {
    let manifest = Manifest {
        source: Source::Rig,
        rate_hz: axis.rate_hz,
        axes: Axes::X,
        created: "2026-12-03T00:00:00Z".into(),
        device: Device {
            kind: "position-servo".into(),
            mass_kg: [axis.mass_kg, axis.mass_kg],
            damping_n_s_per_m: [0.0, 0.0],
            handle_mass_kg: None,
            workspace_half_width_m: None,
        },
        subject: Subject {
            id: "servo-axis".into(),
            shoulder_m: [0.0, 0.0],
            upper_arm_m: None,
            forearm_m: None,
            body_mass_kg: None,
            extra: BTreeMap::new(),
        },
        sim: None,
        timing: None,
        trials: Vec::new(),
    };
    let mut w = SessionWriter::create(dir, manifest)?;
    let n = log.t_s.len();
    let at = |t: f64| ((t * axis.rate_hz).round().max(0.0) as usize).min(n);
    let channels = Channels {
        velocity: false,
        reference: true,
        command: true,
        extra: Vec::new(),
    };
    for (i, &onset) in log.move_onsets_s.iter().enumerate() {
        let from = at(onset - 0.25);
        let to = log
            .move_onsets_s
            .get(i + 1)
            .map_or(n, |next| at(next - 0.25));
        let meta = TrialMeta {
            id: u32::try_from(i + 1).unwrap_or(u32::MAX),
            kind: TrialKind::Reach,
            start_m: None,
            goal_m: None,
            perturbation: None,
        };
        w.begin_trial(meta, channels.clone())?;
        for k in from..to {
            w.push(&Sample {
                pos_m: [log.pos_m[k], 0.0],
                force_n: [0.0; 2],
                pert_force_n: [0.0; 2],
                vel_m_per_s: None,
                ref_m: Some([log.ref_m[k], 0.0]),
                cmd_n: Some([log.cmd_v[k] * axis.force_per_volt, 0.0]),
            })?;
        }
        w.finish_trial()?;
    }
    w.finish()?;
    Ok(())
}
