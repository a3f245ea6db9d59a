//! The simulated human: plans, feed-forward, delayed feedback, reflex, noise, and the
//! muscles that turn them into joint torques. The runtime calls [`Human::update`] once
//! per 4 kHz tick, in order.
//!
//! Per neural tick (every `neural_divisor` ticks) the activations \[N\] are recomputed:
//!
//! `a = max(0, a_FF + a_FB + a_SR + a_N)`, with
//! - `a_FF`: the feed-forward torque (inverse dynamics of the planned joint motion,
//!   plus `Jᵀ F` with `F = (M_adm + m_handle) ẍ_plan + D_adm ẋ_plan` to push the rig's
//!   admittance along the plan) split over the muscles by [`MuscleModel::split`] on top
//!   of the co-contraction;
//! - `a_FB = G_p e(t − δ) + G_d ė(t − δ)`, δ = 60 ms (whole neural ticks);
//! - `a_SR` the optional stretch reflex; `a_N` the signal-dependent noise.
//!
//! Every tick the muscle impedance acts on the current state:
//! `m = a + K_m (e + τ_d ė)`, torque `Aᵀ m`. The muscle error is taken against the
//! planned joint trajectory (the reach plan, or for holding the imposed motion shifted
//! by the force bias).
//!
//! **Force holding** (001_* eq. 5–7, classical impedance control, F_ref = 0): the
//! reference posture is displaced by `Δq = K_tot⁻¹ Jᵀ F_cmd` with `K_tot` the joint
//! stiffness of muscles plus position feedback, so that the arm's own spring presses
//! the handle with `F_cmd` when the hand is on the imposed path (`v₀` of eq. 7 is the
//! bias). The bias follows the co-contraction level, which may rise during a trial.

use nalgebra::Vector2;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::delay::DelayLine;
use crate::dynamics::{JointState, inverse_dynamics};
use crate::error::ArmError;
use crate::impedance::{EndpointImpedance, endpoint_impedance_scaled};
use crate::kinematics::{Elbow, inverse, jacobian, joint_rates};
use crate::muscles::{MUSCLES, MuscleModel};
use crate::noise::MotorNoise;
use crate::params::ArmParams;
use crate::plan::ReachPlan;
use crate::time::{TICK_HZ, ms_to_periods, ticks_to_s};

/// The rig's admittance as felt at the handle (diagonal in the rig frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Admittance {
    /// Virtual mass (x, y) \[kg\].
    pub mass_kg: [f64; 2],
    /// Virtual damping (x, y) \[N s/m\].
    pub damping_n_s_per_m: [f64; 2],
    /// Physical handle mass moved with the hand \[kg\].
    pub handle_mass_kg: f64,
}

impl Admittance {
    /// Börner's rig: M = diag(5, 5) kg, D = diag(15, 15) N s/m (000_* section 5.1),
    /// handle mass left to the caller (0 here).
    pub const BORNER: Admittance = Admittance {
        mass_kg: [5.0, 5.0],
        damping_n_s_per_m: [15.0, 15.0],
        handle_mass_kg: 0.0,
    };

    /// Force \[N\] the hand must apply to move the admittance with velocity `v` \[m/s\] and
    /// acceleration `acc` \[m/s²\].
    pub fn force_n(&self, v: Vector2<f64>, acc: Vector2<f64>) -> Vector2<f64> {
        Vector2::new(
            (self.mass_kg[0] + self.handle_mass_kg) * acc.x + self.damping_n_s_per_m[0] * v.x,
            (self.mass_kg[1] + self.handle_mass_kg) * acc.y + self.damping_n_s_per_m[1] * v.y,
        )
    }
}

/// A point-to-point reach (000_*: (0, 0.30) → (0, 0.55) m in the shoulder frame, 3 s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReachTask {
    /// Start of the hand \[m, rig frame\].
    pub start_rig_m: [f64; 2],
    /// Goal of the hand \[m, rig frame\].
    pub goal_rig_m: [f64; 2],
    /// Movement onset \[tick\].
    pub start_tick: u64,
    /// Movement duration \[ticks\].
    pub duration_ticks: u64,
    /// The admittance the hand pushes along the plan.
    pub admittance: Admittance,
    /// Reaches out and back in one trial (a centre-out task that logs the return):
    /// ticks the hand stays at the goal before it goes back to the start along the
    /// same line in the same duration; `None`, the default, stays at the goal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub back_after_ticks: Option<u64>,
}

/// A motion the rig imposes on the hand, known to the subject:
/// `x(t) = centre + e(t) · amplitude · sin(2π f (t − t₀))` for t ≥ t₀, the centre before,
/// with the device's envelope `e`: a raised-cosine ramp `½(1 − cos(π τ / T_r))` over
/// `T_r = ramp_s` in, 1 for `cycles` full cycles, the mirror ramp out, then 0 (no ramp
/// when `ramp_s` is 0; no end when `cycles` is `None`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImposedSinusoid {
    /// Amplitude (x, y) \[m\].
    pub amplitude_m: [f64; 2],
    /// Frequency \[Hz\] (0.125 Hz in 001_*).
    pub frequency_hz: f64,
    /// Onset \[tick\].
    pub start_tick: u64,
    /// Raised-cosine ramp in and out \[s\] (0 = none).
    #[serde(default)]
    pub ramp_s: f64,
    /// Full-amplitude cycles between the ramps (`None` = the motion never ends).
    #[serde(default)]
    pub cycles: Option<u32>,
}

impl ImposedSinusoid {
    /// Envelope and its first two time derivatives at `t` s since the onset.
    fn envelope(&self, t: f64) -> (f64, f64, f64) {
        let r = self.ramp_s.max(0.0);
        let full_s = self
            .cycles
            .map_or(f64::INFINITY, |n| f64::from(n) / self.frequency_hz);
        let end = 2.0 * r + full_s;
        if t < 0.0 || t >= end {
            return (0.0, 0.0, 0.0);
        }
        let ramp = |tau: f64, sign: f64| {
            let k = std::f64::consts::PI / r;
            (
                0.5 * (1.0 - (k * tau).cos()),
                sign * 0.5 * k * (k * tau).sin(),
                0.5 * k * k * (k * tau).cos(),
            )
        };
        if t < r {
            ramp(t, 1.0)
        } else if t <= r + full_s {
            (1.0, 0.0, 0.0)
        } else {
            ramp(end - t, -1.0)
        }
    }

    /// Offset from the centre, its velocity and acceleration at `t` s since the onset.
    fn offset(&self, t: f64) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
        let amp = Vector2::new(self.amplitude_m[0], self.amplitude_m[1]);
        let (e, de, dde) = self.envelope(t);
        let w = std::f64::consts::TAU * self.frequency_hz;
        let (s, c) = (w * t).sin_cos();
        (
            amp * (e * s),
            amp * (de * s + e * w * c),
            amp * (dde * s + 2.0 * de * w * c - e * w * w * s),
        )
    }
}

/// Holding a contact force on the handle (001_*).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoldTask {
    /// Where the hand holds the handle, centre of any imposed motion \[m, rig frame\].
    pub hand_rig_m: [f64; 2],
    /// Force the hand is to exert on the handle \[N, rig frame\].
    pub force_n: [f64; 2],
    /// Motion imposed by the rig, if any.
    pub imposed: Option<ImposedSinusoid>,
    /// Rise of the co-contraction level within the trial \[1/s\] (0 = constant).
    pub co_contraction_rise_per_s: f64,
}

/// What the human is doing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Task {
    /// Point-to-point reach.
    Reach(ReachTask),
    /// Force holding.
    Hold(HoldTask),
}

/// How the human sits at the rig and runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HumanConfig {
    /// Shoulder position \[m, rig frame\]. Default (0, −0.425): the reach midpoint of
    /// 000_* at the rig origin.
    pub shoulder_rig_m: [f64; 2],
    /// Neural update every this many ticks; divides 4000. Default 4 (1 kHz).
    pub neural_divisor: u32,
    /// 0-based trial number in the session (drives [`crate::params::StiffnessDrift`]).
    pub trial_index: u32,
    /// Co-contraction level at the start of the trial \[-\] (1 = the params' default).
    pub co_contraction_level: f64,
}

impl Default for HumanConfig {
    fn default() -> Self {
        HumanConfig {
            shoulder_rig_m: [0.0, -0.425],
            neural_divisor: 4,
            trial_index: 0,
            co_contraction_level: 1.0,
        }
    }
}

/// Planned joint motion and the torque that realises it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointRef {
    /// Planned angles \[rad\].
    pub q: [f64; 2],
    /// Planned rates \[rad/s\].
    pub qd: [f64; 2],
    /// Feed-forward torque \[N m\].
    pub tau_ff_n_m: [f64; 2],
}

/// The simulated human. See the module docs for the model.
#[derive(Debug, Clone)]
pub struct Human {
    params: ArmParams,
    model: MuscleModel,
    task: Task,
    config: HumanConfig,
    /// The reach plan (None when holding).
    plan: Option<ReachPlan>,
    shoulder: Vector2<f64>,
    scale: f64,
    fb_lag: usize,
    sr_lag: Option<usize>,
    delay: DelayLine<([f64; MUSCLES], [f64; MUSCLES])>,
    noise: MotorNoise,
    activations_n: [f64; MUSCLES],
    tensions_n: [f64; MUSCLES],
    bias_rad: [f64; 2],
    last_ref: JointRef,
}

/// Checks that the straight segment a→b (shoulder frame) stays in the workspace with a
/// margin from the singular boundaries: 2 % inside the outer circle, 2 cm outside the
/// inner one.
fn check_path(p: &ArmParams, a: Vector2<f64>, b: Vector2<f64>) -> Result<(), ArmError> {
    let (l1, l2) = (p.upper.length_m, p.fore.length_m);
    let (min_m, max_m) = ((l1 - l2).abs() + 0.02, 0.98 * (l1 + l2));
    let d = b - a;
    let t = if d.norm_squared() > 0.0 {
        (-a.dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let nearest = (a + d * t).norm();
    let farthest = a.norm().max(b.norm());
    if nearest < min_m || farthest > max_m {
        return Err(ArmError::Unreachable {
            distance_m: if farthest > max_m { farthest } else { nearest },
            min_m,
            max_m,
        });
    }
    Ok(())
}

impl Human {
    /// A human for one trial. `rng` drives the motor noise and nothing else.
    pub fn new(
        params: ArmParams,
        task: Task,
        config: HumanConfig,
        rng: ChaCha8Rng,
    ) -> Result<Human, ArmError> {
        params.validate()?;
        let model = MuscleModel::new(&params.muscles)?;
        let div = config.neural_divisor;
        if div == 0 || !TICK_HZ.is_multiple_of(u64::from(div)) {
            return Err(ArmError::InvalidParameter {
                key: "neural_divisor",
                reason: format!("must divide {TICK_HZ}, got {div}"),
            });
        }
        if !(config.co_contraction_level.is_finite() && config.co_contraction_level >= 0.0) {
            return Err(ArmError::InvalidParameter {
                key: "co_contraction_level",
                reason: format!(
                    "must be finite and >= 0, got {}",
                    config.co_contraction_level
                ),
            });
        }
        let shoulder = Vector2::new(config.shoulder_rig_m[0], config.shoulder_rig_m[1]);
        if !shoulder.iter().all(|x| x.is_finite()) {
            return Err(ArmError::NonFinite {
                what: "shoulder_rig_m",
            });
        }
        let whole = |key: &'static str, ms: f64| {
            ms_to_periods(ms, div).map(|n| n as usize).ok_or_else(|| ArmError::InvalidParameter {
                key,
                reason: format!("{ms} ms is not a whole number of neural ticks of {div} ticks at {TICK_HZ} Hz"),
            })
        };
        let fb_lag = whole("feedback.delay_ms", params.feedback.delay_ms)?;
        let sr_lag = match &params.stretch_reflex {
            Some(r) => Some(whole("stretch_reflex.delay_ms", r.delay_ms)?),
            None => None,
        };
        let plan = match &task {
            Task::Reach(r) => {
                let a = Vector2::new(r.start_rig_m[0], r.start_rig_m[1]);
                let b = Vector2::new(r.goal_rig_m[0], r.goal_rig_m[1]);
                let plan =
                    ReachPlan::new(a, b, r.start_tick, r.duration_ticks, r.back_after_ticks)?;
                check_path(&params, a - shoulder, b - shoulder)?;
                let adm = &r.admittance;
                if !adm
                    .mass_kg
                    .iter()
                    .chain(&adm.damping_n_s_per_m)
                    .chain([&adm.handle_mass_kg])
                    .all(|x| x.is_finite())
                {
                    return Err(ArmError::NonFinite { what: "admittance" });
                }
                Some(plan)
            }
            Task::Hold(h) => {
                let c = Vector2::new(h.hand_rig_m[0], h.hand_rig_m[1]) - shoulder;
                let amp = h.imposed.map_or(Vector2::zeros(), |s| {
                    Vector2::new(s.amplitude_m[0], s.amplitude_m[1])
                });
                check_path(&params, c - amp, c + amp)?;
                let finite = h
                    .force_n
                    .iter()
                    .chain([&h.co_contraction_rise_per_s])
                    .all(|x| x.is_finite())
                    && h.imposed.is_none_or(|s| {
                        s.frequency_hz.is_finite() && s.ramp_s.is_finite() && s.ramp_s >= 0.0
                    });
                if !finite {
                    return Err(ArmError::NonFinite { what: "hold task" });
                }
                None
            }
        };
        let scale = params.stiffness_scale(config.trial_index);
        let max_lag = fb_lag.max(sr_lag.unwrap_or(0));
        let noise = MotorNoise::new(&params.noise, f64::from(div) / TICK_HZ as f64, rng);
        let mut human = Human {
            params,
            model,
            task,
            config,
            plan,
            shoulder,
            scale,
            fb_lag,
            sr_lag,
            delay: DelayLine::new(max_lag, ([0.0; MUSCLES], [0.0; MUSCLES])),
            noise,
            activations_n: [0.0; MUSCLES],
            tensions_n: [0.0; MUSCLES],
            bias_rad: [0.0; 2],
            last_ref: JointRef {
                q: [0.0; 2],
                qd: [0.0; 2],
                tau_ff_n_m: [0.0; 2],
            },
        };
        // Validated paths are reachable, so this succeeds; it also seeds the fallback.
        human.last_ref = human.base_reference(0)?;
        let co = human.model.co_contraction(human.co_contraction_level(0));
        human.activations_n = human.model.split(human.last_ref.tau_ff_n_m, &co);
        Ok(human)
    }

    /// The parameters.
    pub fn params(&self) -> &ArmParams {
        &self.params
    }

    /// The muscle model.
    pub fn muscle_model(&self) -> &MuscleModel {
        &self.model
    }

    /// The task.
    pub fn task(&self) -> &Task {
        &self.task
    }

    /// Feedback delay in neural ticks.
    pub fn feedback_delay_periods(&self) -> usize {
        self.fb_lag
    }

    /// Stiffness-drift scale of this trial \[-\].
    pub fn stiffness_scale(&self) -> f64 {
        self.scale
    }

    /// Activations held since the last neural tick \[N\], order SF, SE, EF, EE, BF, BE.
    pub fn activations_n(&self) -> [f64; MUSCLES] {
        self.activations_n
    }

    /// Tensions of the last update \[N\].
    pub fn tensions_n(&self) -> [f64; MUSCLES] {
        self.tensions_n
    }

    /// Joint-space bias of the force-holding reference \[rad\] (zero when reaching).
    pub fn bias_rad(&self) -> [f64; 2] {
        self.bias_rad
    }

    /// Co-contraction level at a tick \[-\].
    pub fn co_contraction_level(&self, tick: u64) -> f64 {
        let rise = match &self.task {
            Task::Hold(h) => h.co_contraction_rise_per_s * ticks_to_s(tick),
            Task::Reach(_) => 0.0,
        };
        (self.config.co_contraction_level + rise).max(0.0)
    }

    /// Planned hand position, velocity, acceleration at a tick in the shoulder frame.
    fn hand_plan(&self, tick: u64) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
        if let Some(plan) = &self.plan {
            let h = plan.at(tick);
            return (h.pos_m - self.shoulder, h.vel_m_s, h.acc_m_s2);
        }
        let (centre, imposed) = match &self.task {
            Task::Hold(h) => (Vector2::new(h.hand_rig_m[0], h.hand_rig_m[1]), h.imposed),
            // `new` gives every reach a plan; this arm only keeps the match total.
            Task::Reach(r) => (Vector2::new(r.start_rig_m[0], r.start_rig_m[1]), None),
        };
        let c = centre - self.shoulder;
        match imposed {
            Some(s) if tick >= s.start_tick => {
                let (x, v, acc) = s.offset(ticks_to_s(tick - s.start_tick));
                (c + x, v, acc)
            }
            _ => (c, Vector2::zeros(), Vector2::zeros()),
        }
    }

    /// The planned joint motion at a tick, without the force bias.
    pub fn base_reference(&self, tick: u64) -> Result<JointRef, ArmError> {
        let (x, v, acc) = self.hand_plan(tick);
        let p = &self.params;
        let q = inverse(p, x, Elbow::Down)?;
        let (qd, qdd) = joint_rates(p, q, v, acc)?;
        let mut tau = inverse_dynamics(p, q, qd, qdd);
        if let Task::Reach(r) = &self.task {
            tau += jacobian(p, q).transpose() * r.admittance.force_n(v, acc);
        }
        Ok(JointRef {
            q,
            qd,
            tau_ff_n_m: [tau.x, tau.y],
        })
    }

    /// Joint state on the plan at tick 0 (the natural initial condition of a trial).
    pub fn initial_state(&self) -> JointState {
        let r = self.base_reference(0).unwrap_or(self.last_ref);
        JointState { q: r.q, qd: r.qd }
    }

    /// Joint bias that makes muscles plus feedback press `force_n` at posture `q`.
    ///
    /// Solves `Aᵀ(a(Δq) + K_m(a) ∘ e) − Aᵀ a_FF = Jᵀ F` with `e = A Δq` and
    /// `a = max(0, a_FF + G_p e)` (the settled feedback; a muscle at zero activation
    /// cannot relax further, so its feedback is rectified) by Newton's method on this
    /// piecewise-smooth map, starting from zero. Six iterations reach round-off for the
    /// forces of 001_*; the human's internal model is taken to be exact.
    fn hold_bias(&self, q: [f64; 2], force_n: [f64; 2], a_ff: &[f64; MUSCLES]) -> [f64; 2] {
        let target = jacobian(&self.params, q).transpose() * Vector2::new(force_n[0], force_n[1]);
        let gp = self.params.feedback.position_gain_n_per_m;
        let mp = self.model.params();
        let mut bias = Vector2::zeros();
        for _ in 0..6 {
            let e = self.model.stretch([0.0; 2], [bias.x, bias.y]);
            let a: [f64; MUSCLES] = std::array::from_fn(|i| (a_ff[i] + gp * e[i]).max(0.0));
            let km = self.model.stiffness(&a, self.scale);
            let extra: [f64; MUSCLES] = std::array::from_fn(|i| a[i] - a_ff[i] + km[i] * e[i]);
            let t = self.model.joint_torque(&extra);
            let residual = target - Vector2::new(t[0], t[1]);
            // d(extra_i)/d(e_i): K_m plus, where the feedback is not rectified, the
            // feedback gain and the stiffness it adds.
            let slope: [f64; MUSCLES] = std::array::from_fn(|i| {
                let active = a_ff[i] + gp * e[i] > 0.0;
                km[i]
                    + if active {
                        gp * (1.0 + self.scale * mp.stiffness_per_activation_per_m[i] * e[i])
                    } else {
                        0.0
                    }
            });
            let Some(ki) = self.model.to_joint(&slope).try_inverse() else {
                break;
            };
            bias += ki * residual;
        }
        [bias.x, bias.y]
    }

    /// Ground truth at posture `q` with the activations currently held.
    pub fn ground_truth(&self, q: [f64; 2]) -> Result<EndpointImpedance, ArmError> {
        endpoint_impedance_scaled(
            &self.params,
            &self.model,
            q,
            &self.activations_n,
            self.scale,
        )
    }

    /// Joint torques (shoulder, elbow) \[N m\] from the muscles at `tick` for the joint
    /// state the plant reports. Call once per tick, in increasing tick order.
    pub fn update(&mut self, tick: u64, state: &JointState) -> [f64; 2] {
        // Reachability was checked at construction; a failure here could only come from
        // round-off at the margin, where the previous reference is the best estimate.
        let base = self.base_reference(tick).unwrap_or(self.last_ref);
        self.last_ref = base;
        let neural = tick.is_multiple_of(u64::from(self.config.neural_divisor));
        let mut a_ff = [0.0; MUSCLES];
        if neural {
            let co = self.model.co_contraction(self.co_contraction_level(tick));
            a_ff = self.model.split(base.tau_ff_n_m, &co);
            if let Task::Hold(h) = &self.task {
                self.bias_rad = self.hold_bias(base.q, h.force_n, &a_ff);
            }
        }
        let q_ref = [base.q[0] + self.bias_rad[0], base.q[1] + self.bias_rad[1]];
        let e = self.model.stretch(state.q, q_ref);
        let ed = self.model.stretch(state.qd, base.qd);
        if neural {
            self.delay.push((e, ed));
            let (e_fb, ed_fb) = self.delay.get(self.fb_lag);
            let fb = &self.params.feedback;
            let sr = self
                .sr_lag
                .zip(self.params.stretch_reflex)
                .map(|(lag, r)| (self.delay.get(lag).1, r.gain_n_s_per_m));
            let pre: [f64; MUSCLES] = std::array::from_fn(|i| {
                let reflex = sr.map_or(0.0, |(ed_sr, g)| g * ed_sr[i]);
                a_ff[i]
                    + fb.position_gain_n_per_m * e_fb[i]
                    + fb.velocity_gain_n_s_per_m * ed_fb[i]
                    + reflex
            });
            let n = self.noise.step(&pre);
            self.activations_n = std::array::from_fn(|i| (pre[i] + n[i]).max(0.0));
        }
        self.tensions_n = self
            .model
            .tensions(&self.activations_n, &e, &ed, self.scale);
        self.model.joint_torque(&self.tensions_n)
    }
}
