//! The controller's configuration: serde types whose defaults reproduce the Börner rig
//! (000_* section 5.1) and the Piovesan virtual spring and imposed motion (001_*), with a
//! [`ControllerConfig::validate`] that names the offending key.
//!
//! Every table uses `deny_unknown_fields` so a misspelt key is an error, and `default`
//! so a file only needs the keys it changes.

use serde::{Deserialize, Serialize};

use crate::calib::ForceCalibration;
pub use crate::check::{Checker, ConfigError, InvalidKey, join_invalid_keys};
use crate::time::Rate;

/// Which control law turns the measured force into the position reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LawKind {
    /// Börner admittance, 000_* eq. 20: `M_adm ẍ_r + D_adm ẋ_r = F_meas + u_pert`.
    #[default]
    Admittance,
    /// Piovesan virtual spring, 001_* eq. 4, anchored to the imposed sinusoid.
    VirtualSpring,
}

/// A rig axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Axis {
    /// The lower cart, rig-frame `x` (to the subject's right).
    X,
    /// The upper cart, rig-frame `y` (away from the subject).
    #[default]
    Y,
}

impl Axis {
    /// 0 for `x`, 1 for `y`.
    #[must_use]
    pub const fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
        }
    }
}

/// The whole controller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControllerConfig {
    /// Control clock, Hz (4000 on the Börner rig). Must be > 0.
    pub control_rate_hz: u32,
    /// Motor command rate, Hz (2000 on the Börner rig: the Thrusttube inputs are
    /// downsampled). Must be > 0 and divide `control_rate_hz`.
    pub motor_rate_hz: u32,
    /// The control law.
    pub law: LawKind,
    /// Encoders, force-sensor calibration and the velocity filter.
    pub sensors: SensorConfig,
    /// The admittance of 000_* eq. 20.
    pub admittance: AdmittanceConfig,
    /// The virtual spring of 001_* eq. 4.
    pub virtual_spring: VirtualSpringConfig,
    /// The sinusoid the virtual spring is anchored to.
    pub imposed_motion: ImposedMotionConfig,
    /// Position rendering (PD plus feed-forward).
    pub render: RenderConfig,
    /// The force pulse of 000_* eq. 22–23.
    pub force_pulse: ForcePulseConfig,
    /// The position perturbation of 001_*.
    pub position_perturbation: PositionPerturbationConfig,
    /// The safety layer (always on).
    pub safety: SafetyConfig,
}

impl Default for ControllerConfig {
    fn default() -> Self {
        ControllerConfig {
            control_rate_hz: Rate::CONTROL.hz(),
            motor_rate_hz: 2000,
            law: LawKind::Admittance,
            sensors: SensorConfig::default(),
            admittance: AdmittanceConfig::default(),
            virtual_spring: VirtualSpringConfig::default(),
            imposed_motion: ImposedMotionConfig::default(),
            render: RenderConfig::default(),
            force_pulse: ForcePulseConfig::default(),
            position_perturbation: PositionPerturbationConfig::default(),
            safety: SafetyConfig::default(),
        }
    }
}

/// Encoders, force sensor and velocity estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// Metres per encoder count per axis (1 µm on the Börner rig). Non-zero; a negative
    /// value flips the axis.
    pub encoder_m_per_count: [f64; 2],
    /// Raw force-sensor reading → rig frame.
    pub force_calibration: ForceCalibration,
    /// Cut-off of the first-order low-pass applied to the encoder backward difference,
    /// Hz. 500 Hz keeps the phase lag at the 50 Hz rendering bandwidth near 6° while
    /// dividing the 4 mm/s-per-count quantisation noise of a raw 4 kHz difference.
    pub velocity_filter_hz: f64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        SensorConfig {
            encoder_m_per_count: [1e-6, 1e-6],
            force_calibration: ForceCalibration::default(),
            velocity_filter_hz: 500.0,
        }
    }
}

/// 000_* eq. 20 per axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdmittanceConfig {
    /// Admittance inertia `M_adm`, kg per axis (5, 5 on the Börner rig). > 0.
    pub mass_kg: [f64; 2],
    /// Admittance damping `D_adm`, N s/m per axis (15, 15 on the Börner rig). >= 0.
    pub damping_n_s_per_m: [f64; 2],
}

impl Default for AdmittanceConfig {
    fn default() -> Self {
        AdmittanceConfig {
            mass_kg: [5.0, 5.0],
            damping_n_s_per_m: [15.0, 15.0],
        }
    }
}

/// 001_* eq. 4 per axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VirtualSpringConfig {
    /// Virtual mass `M_e`, kg (5 in 001_*). > 0.
    pub mass_kg: [f64; 2],
    /// Spring `K_e`, N/m (10 kN/m in 001_*). >= 0.
    pub stiffness_n_per_m: [f64; 2],
    /// Damper `B_e`, N s/m (447.21, critical for 5 kg and 10 kN/m, in 001_*). >= 0.
    pub damping_n_s_per_m: [f64; 2],
}

impl Default for VirtualSpringConfig {
    fn default() -> Self {
        VirtualSpringConfig {
            mass_kg: [5.0, 5.0],
            stiffness_n_per_m: [10_000.0, 10_000.0],
            damping_n_s_per_m: [447.21, 447.21],
        }
    }
}

/// The imposed sinusoid of 001_*: `a(t) · A · sin(2π f t)` along one axis about the
/// handle position at activation, where the envelope `a(t)` rises as a raised cosine
/// `½(1 − cos(π t / T_r))` over `ramp_s`, stays 1 for `cycles` full cycles and falls
/// symmetrically, so position, velocity and acceleration start and end at zero.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImposedMotionConfig {
    /// Axis of the motion.
    pub axis: Axis,
    /// Semi-amplitude `A`, m (0.10 in 001_*). >= 0 and inside the walls.
    pub amplitude_m: f64,
    /// Frequency `f`, Hz (0.125 in 001_*). > 0.
    pub frequency_hz: f64,
    /// Full-amplitude cycles (25 in 001_*). > 0.
    pub cycles: u32,
    /// Envelope ramp at each end, s (default 4 s = half a cycle at 0.125 Hz, so the
    /// full-amplitude part starts at a zero crossing). >= 0.
    pub ramp_s: f64,
}

impl Default for ImposedMotionConfig {
    fn default() -> Self {
        ImposedMotionConfig {
            axis: Axis::Y,
            amplitude_m: 0.10,
            frequency_hz: 0.125,
            cycles: 25,
            ramp_s: 4.0,
        }
    }
}

/// Position rendering: `F = m_ff ẍ_ref + K_p (x_ref − x) + K_d (ẋ_ref − ẋ)` per axis.
///
/// Defaults place a critically damped 50 Hz closed loop on carts of 4 kg (x: both carts
/// and handle) and 2 kg (y: upper cart and handle): `K_p = m ω²`, `K_d = 2 m ω` with
/// `ω = 2π·50 rad/s`. The simulator's cart masses should replace these.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderConfig {
    /// Feed-forward mass multiplying the reference acceleration, kg. >= 0.
    pub feedforward_mass_kg: [f64; 2],
    /// Proportional gain, N/m. >= 0.
    pub kp_n_per_m: [f64; 2],
    /// Derivative gain, N s/m. >= 0.
    pub kd_n_s_per_m: [f64; 2],
}

impl Default for RenderConfig {
    fn default() -> Self {
        let w = 2.0 * core::f64::consts::PI * 50.0;
        RenderConfig {
            feedforward_mass_kg: [4.0, 2.0],
            kp_n_per_m: [4.0 * w * w, 2.0 * w * w],
            kd_n_s_per_m: [2.0 * 4.0 * w, 2.0 * 2.0 * w],
        }
    }
}

/// The force pulse of 000_* eq. 22–23.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ForcePulseConfig {
    /// `T_pert`, s (0.150 in 000_*): a whole number of ticks, at least 3.
    pub duration_s: f64,
    /// `A_pert`, N (15 in 000_*). >= 0.
    pub amplitude_n: f64,
}

impl Default for ForcePulseConfig {
    fn default() -> Self {
        ForcePulseConfig {
            duration_s: 0.150,
            amplitude_n: 15.0,
        }
    }
}

/// Shape of the two transitions of a position perturbation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TransitionShape {
    /// 001_* as written: sixth-degree polynomial `20τ³ − 45τ⁴ + 36τ⁵ − 10τ⁶`, zero
    /// velocity and acceleration at both ends and zero jerk at the end.
    #[default]
    Degree6,
    /// Rest-to-rest minimum snap, `35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷`: also zero jerk at the start.
    MinimumSnap7,
}

/// The position perturbation of 001_*: out along a direction, hold, back.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PositionPerturbationConfig {
    /// Displacement, m (0.008 in 001_*). >= 0.
    pub amplitude_m: f64,
    /// Total duration, s (0.300 in 001_*): a whole number of ticks.
    pub duration_s: f64,
    /// Duration of each transition, s (0.100 in 001_*): whole ticks, `2 ·` it `<= duration_s`.
    pub transition_s: f64,
    /// Transition polynomial.
    pub shape: TransitionShape,
}

impl Default for PositionPerturbationConfig {
    fn default() -> Self {
        PositionPerturbationConfig {
            amplitude_m: 0.008,
            duration_s: 0.300,
            transition_s: 0.100,
            shape: TransitionShape::Degree6,
        }
    }
}

/// The safety layer. It is always on: these limits hold in every mode.
///
/// Three watchdogs look for a part of the loop that has stopped working while
/// reporting nothing wrong; each is on by default, counts in ticks of the control clock
/// (4 kHz: one tick is 250 µs) and is switched off by setting its count to 0:
///
/// | key | trips when | default |
/// |---|---|---|
/// | `stale_force_ticks` | the raw force reading is bit-identical this many readings in a row | 40 (10 ms) |
/// | `encoder_stall_ticks`, `encoder_stall_force_n` | an axis was commanded at least the force for this many readings and its encoder did not change by one count | 80 (20 ms), 50 N |
/// | `deadline_window_ticks`, `max_deadline_overruns` | more active ticks than allowed arrived late (after skipped deadlines) within the window | 64 (16 ms), 4 |
///
/// A simulated sensor without noise repeats its readings legitimately (the simulator
/// at rest, or `force_noise_rms_n = 0`): a protocol or a test that drives the controller
/// with one states `stale_force_ticks = 0`. A scripted rig whose carts never move is a
/// dead encoder to the stall watchdog: [`crate::testing::scripted`] says so for tests.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SafetyConfig {
    /// Motor force is clamped to ±this per axis, N. > 0. A non-finite command is never
    /// clamped: it trips a fault and zero is written.
    pub force_limit_n: [f64; 2],
    /// Filtered encoder velocity beyond ±this on any axis trips a fault, m/s. > 0.
    pub velocity_limit_m_per_s: f64,
    /// Soft walls at ±this on both axes, m (0.15 on the Börner rig). > 0.
    pub wall_m: f64,
    /// Wall spring acting on the virtual dynamics beyond a wall, N/m. >= 0.
    pub wall_stiffness_n_per_m: f64,
    /// Wall damper (only pushes inward), N s/m. >= 0.
    pub wall_damping_n_s_per_m: f64,
    /// A measured position beyond `wall_m + position_trip_margin_m` trips a fault, m. >= 0.
    pub position_trip_margin_m: f64,
    /// This many consecutive non-finite force readings trip a fault (the last finite
    /// reading is held meanwhile). > 0.
    pub nonfinite_force_ticks: u32,
    /// This many consecutive bit-identical raw force readings (the first and its
    /// repeats) trip a fault; 0 switches the watchdog off; 1 is refused (every reading
    /// is a run of one). A live strain-gauge ADC always moves its last bits: with noise
    /// of one LSB RMS two successive readings agree with probability ≈ 0.28, so 40 in a
    /// row happen by chance once in ~10²¹ readings, while a frozen bus or amplifier
    /// repeats its last word for ever. Default 40 = 10 ms at 4 kHz, which bounds what a
    /// frozen reading does before the trip: 30 N frozen while the hand has let go drives
    /// the default 5 kg admittance 6 cm/s and 0.3 mm. A noiseless simulated sensor
    /// repeats readings legitimately and must set 0.
    pub stale_force_ticks: u32,
    /// The force an axis must be commanded (at least, either sign) for the encoder-stall
    /// watchdog to count, N. > 0 and at most the smaller `force_limit_n`. Default 50 N:
    /// on the heaviest axis of the shipped plant (x: both carts and the handle,
    /// 12.35 kg) that is 4.0 m/s², ½ · 4.0 · (20 ms)² = 0.8 mm = 800 counts of a 1 µm
    /// encoder in 20 ms from rest (y, 4.35 kg: 2.3 mm); and a quarter of the default
    /// force limit, well above what holding a handle still needs on a gravity-free
    /// rig (the hold protocol's 10 N).
    pub encoder_stall_force_n: f64,
    /// This many consecutive readings with the axis commanded at least
    /// `encoder_stall_force_n` (the command written at the reading before) and its
    /// encoder count not changed at all trip an encoder-stall fault on that axis;
    /// 0 switches the watchdog off. A cut encoder cable freezes the count: the position
    /// loop sees a constant error, pushes harder and harder, and the velocity and
    /// position watchdogs, which read the same dead encoder, never fire. Default 80 =
    /// 20 ms: 200 N (the default limit) on the 4.35 kg y cart reaches 0.9 m/s and 9 mm in
    /// that time; a free cart under 50 N stays within one count of a turning point for
    /// ~1.4 ms (1 µm at 4 m/s²). The contract: under that force the count must move
    /// within 20 ms. A hand holding the handle against a stiff virtual spring moves it
    /// through the small wobble of its force (in `tests/safety_watchdogs.rs`, 0.2 N at
    /// 10 Hz on a 55 N hold against 10 kN/m is enough); a hold steadier than that, an
    /// end stop, a clamp or a dead encoder are a stall. A set-up that holds the handle
    /// still under large forces on purpose sets 0.
    pub encoder_stall_ticks: u32,
    /// Length of the loop-deadline watchdog's sliding window, ticks; 0 switches it off;
    /// at most 64 (the window is one 64-bit word). Default 64 = 16 ms at 4 kHz.
    pub deadline_window_ticks: u32,
    /// An active tick that arrives after one or more skipped ticks is a deadline
    /// overrun; more than this many within the last `deadline_window_ticks` ticks trip
    /// a fault. Below `ceil(deadline_window_ticks / 2)`, the most a window can hold (a
    /// late tick follows at least one skipped one). Where `max_consecutive_misses`
    /// bounds how long one stall may be, this bounds how often the loop may be late: a
    /// loop that keeps its period is late rarely, in single stalls (0.07–0.8 % of the
    /// deadlines in the README's real-time runs on a shared VM, ~0.05–0.5 per 64 ticks).
    /// Five late ticks in 16 ms is a loop that no longer keeps its period. The worst
    /// such loop the clock-skip allowance lets through runs every other tick: on odd
    /// ticks only it never reaches a motor tick (`tick % (control_rate_hz /
    /// motor_rate_hz) == 0`), so the motor holds one command while the law moves on;
    /// with the default 4 it trips at its fifth late tick, 11 ticks (2.75 ms) after the
    /// last motor update. Default 4.
    pub max_deadline_overruns: u32,
    /// An encoder step larger than this between consecutive ticks trips a fault, m
    /// (default 1 mm per 250 µs = 4 m/s, far above any hand speed). > 0.
    pub encoder_jump_m: f64,
    /// An active tick may follow the previous one after at most this many skipped ticks
    /// (deadlines a real-time loop missed and skipped instead of bursting to catch up);
    /// a longer gap trips a clock-skip fault. 0: every skipped tick trips. The default
    /// is 0, the lock-step contract; a real-time protocol sets a few ticks (4 = 1 ms at
    /// 4 kHz), as a rig's real-time layer tolerates a few overruns but not a stall.
    pub max_consecutive_misses: u32,
}

/// Most ticks the loop-deadline watchdog's window can span (one `u64` of history).
pub const MAX_DEADLINE_WINDOW_TICKS: u32 = 64;

impl Default for SafetyConfig {
    fn default() -> Self {
        SafetyConfig {
            force_limit_n: [200.0, 200.0],
            velocity_limit_m_per_s: 1.0,
            wall_m: 0.15,
            wall_stiffness_n_per_m: 20_000.0,
            wall_damping_n_s_per_m: 400.0,
            position_trip_margin_m: 0.02,
            nonfinite_force_ticks: 4,
            stale_force_ticks: 40,
            encoder_stall_force_n: 50.0,
            encoder_stall_ticks: 80,
            deadline_window_ticks: 64,
            max_deadline_overruns: 4,
            encoder_jump_m: 0.001,
            max_consecutive_misses: 0,
        }
    }
}

impl ControllerConfig {
    /// The control clock, if `control_rate_hz` is non-zero.
    #[must_use]
    pub fn control_rate(&self) -> Option<Rate> {
        Rate::new(self.control_rate_hz)
    }

    /// Ticks per motor update, if the rates are valid.
    #[must_use]
    pub fn motor_divisor(&self) -> Option<u32> {
        self.control_rate()?
            .divisor_of(Rate::new(self.motor_rate_hz)?)
    }

    /// Check every key; the error lists each invalid key by its dotted path.
    ///
    /// # Errors
    /// [`ConfigError`] naming every invalid key, e.g.
    /// `admittance.mass_kg[0] must be > 0, got -1`.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let mut c = Checker::default();
        let rate = self.control_rate();
        if rate.is_none() {
            c.fail("control_rate_hz", "must be > 0, got 0".to_owned());
        }
        if self.motor_rate_hz == 0 {
            c.fail("motor_rate_hz", "must be > 0, got 0".to_owned());
        } else if rate.is_some() && self.motor_divisor().is_none() {
            c.fail(
                "motor_rate_hz",
                format!(
                    "must divide control_rate_hz = {} exactly, got {}",
                    self.control_rate_hz, self.motor_rate_hz
                ),
            );
        }

        let s = &self.sensors;
        for (i, m) in s.encoder_m_per_count.iter().enumerate() {
            let key = format!("sensors.encoder_m_per_count[{i}]");
            if c.finite(&key, *m) && *m == 0.0 {
                c.fail(&key, "must be non-zero, got 0".to_owned());
            }
        }
        s.force_calibration
            .check("sensors.force_calibration", &mut c);
        c.positive("sensors.velocity_filter_hz", s.velocity_filter_hz);

        c.positive2("admittance.mass_kg", self.admittance.mass_kg);
        c.non_negative2(
            "admittance.damping_n_s_per_m",
            self.admittance.damping_n_s_per_m,
        );

        let v = &self.virtual_spring;
        c.positive2("virtual_spring.mass_kg", v.mass_kg);
        c.non_negative2("virtual_spring.stiffness_n_per_m", v.stiffness_n_per_m);
        c.non_negative2("virtual_spring.damping_n_s_per_m", v.damping_n_s_per_m);

        let m = &self.imposed_motion;
        c.non_negative("imposed_motion.amplitude_m", m.amplitude_m);
        c.positive("imposed_motion.frequency_hz", m.frequency_hz);
        if m.cycles == 0 {
            c.fail("imposed_motion.cycles", "must be > 0, got 0".to_owned());
        }
        c.non_negative("imposed_motion.ramp_s", m.ramp_s);
        if m.amplitude_m.is_finite()
            && self.safety.wall_m.is_finite()
            && m.amplitude_m >= self.safety.wall_m
        {
            c.fail(
                "imposed_motion.amplitude_m",
                format!(
                    "must be < safety.wall_m = {}, got {}",
                    self.safety.wall_m, m.amplitude_m
                ),
            );
        }

        let r = &self.render;
        c.non_negative2("render.feedforward_mass_kg", r.feedforward_mass_kg);
        c.non_negative2("render.kp_n_per_m", r.kp_n_per_m);
        c.non_negative2("render.kd_n_s_per_m", r.kd_n_s_per_m);

        let f = &self.force_pulse;
        c.positive("force_pulse.duration_s", f.duration_s);
        c.whole_ticks("force_pulse.duration_s", f.duration_s, rate);
        if let Some(rate) = rate
            && f.duration_s.is_finite()
            && f.duration_s > 0.0
            && (f.duration_s * f64::from(rate.hz())).round() < 3.0
        {
            c.fail(
                "force_pulse.duration_s",
                format!("must span at least 3 ticks, got {} s", f.duration_s),
            );
        }
        c.non_negative("force_pulse.amplitude_n", f.amplitude_n);

        let p = &self.position_perturbation;
        c.non_negative("position_perturbation.amplitude_m", p.amplitude_m);
        c.positive("position_perturbation.duration_s", p.duration_s);
        c.whole_ticks("position_perturbation.duration_s", p.duration_s, rate);
        c.positive("position_perturbation.transition_s", p.transition_s);
        c.whole_ticks("position_perturbation.transition_s", p.transition_s, rate);
        if p.transition_s.is_finite()
            && p.duration_s.is_finite()
            && 2.0 * p.transition_s > p.duration_s + 1e-12
        {
            c.fail(
                "position_perturbation.transition_s",
                format!(
                    "must be <= duration_s / 2 = {}, got {}",
                    p.duration_s / 2.0,
                    p.transition_s
                ),
            );
        }

        let sa = &self.safety;
        c.positive2("safety.force_limit_n", sa.force_limit_n);
        c.positive("safety.velocity_limit_m_per_s", sa.velocity_limit_m_per_s);
        c.positive("safety.wall_m", sa.wall_m);
        c.non_negative("safety.wall_stiffness_n_per_m", sa.wall_stiffness_n_per_m);
        c.non_negative("safety.wall_damping_n_s_per_m", sa.wall_damping_n_s_per_m);
        c.non_negative("safety.position_trip_margin_m", sa.position_trip_margin_m);
        if sa.nonfinite_force_ticks == 0 {
            c.fail(
                "safety.nonfinite_force_ticks",
                "must be > 0, got 0".to_owned(),
            );
        }
        if sa.stale_force_ticks == 1 {
            c.fail(
                "safety.stale_force_ticks",
                "must be 0 (off) or >= 2 (every reading is a run of one), got 1".to_owned(),
            );
        }
        c.positive("safety.encoder_stall_force_n", sa.encoder_stall_force_n);
        let limit = sa.force_limit_n[0].min(sa.force_limit_n[1]);
        if sa.encoder_stall_ticks > 0
            && sa.encoder_stall_force_n.is_finite()
            && limit.is_finite()
            && sa.encoder_stall_force_n > limit
        {
            c.fail(
                "safety.encoder_stall_force_n",
                format!(
                    "must be <= the smaller safety.force_limit_n = {limit} (a clamped command never reaches it), got {}",
                    sa.encoder_stall_force_n
                ),
            );
        }
        let window = sa.deadline_window_ticks;
        if window > MAX_DEADLINE_WINDOW_TICKS {
            c.fail(
                "safety.deadline_window_ticks",
                format!("must be 0 (off) or <= {MAX_DEADLINE_WINDOW_TICKS}, got {window}"),
            );
        } else if window > 0 && sa.max_deadline_overruns >= window.div_ceil(2) {
            c.fail(
                "safety.max_deadline_overruns",
                format!(
                    "must be < {} (a {window}-tick window holds at most that many late ticks, so the watchdog could never trip), got {}",
                    window.div_ceil(2),
                    sa.max_deadline_overruns
                ),
            );
        }
        c.positive("safety.encoder_jump_m", sa.encoder_jump_m);
        c.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_are_the_boerner_rig() {
        let c = ControllerConfig::default();
        assert_eq!(c.validate(), Ok(()));
        // 4 kHz loop, motor inputs at 2 kHz (000_* section 5.1): divisor exactly 2.
        assert_eq!(c.motor_divisor(), Some(2));
        // Critical damping of 001_*: B = 2 sqrt(K M) = 447.2136, stated to 0.01 N s/m.
        let v = &c.virtual_spring;
        assert!(
            (2.0 * (v.stiffness_n_per_m[0] * v.mass_kg[0]).sqrt() - v.damping_n_s_per_m[0]).abs()
                < 0.01
        );
    }

    #[test]
    fn every_bad_key_is_named() {
        let mut c = ControllerConfig::default();
        c.admittance.mass_kg[0] = -1.0;
        c.motor_rate_hz = 3000;
        let e = c
            .validate()
            .err()
            .unwrap_or(ConfigError { errors: Vec::new() });
        assert!(e.names("admittance.mass_kg[0]"));
        assert!(e.names("motor_rate_hz"));
        assert!(
            e.to_string()
                .contains("admittance.mass_kg[0] must be > 0, got -1"),
            "{e}"
        );
    }
}
