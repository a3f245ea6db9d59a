//! One trial in lock step, tick by tick on the integer 4 kHz clock:
//!
//! ```text
//!  tick n:  controller.tick(rig, n)     sensors (state after step n−1) → law → motor command
//!                                       (recomputed on motor ticks, 2 kHz, held between)
//!           human.update(n, joint state) neural update on its own divisor, muscle torques
//!           rig.set_arm_torques, rig.step()   physics from n·h to (n+1)·h
//!           recorder.push(n)            block means at the recording rate (the muscle
//!                                       activations too, for the viewer)
//! ```
//!
//! The controller is `rigtwin_device`'s, driven through `RigIo` exactly as on the rig.
//! Nothing here reads a clock or an unseeded generator, so a trial is a pure function
//! of its plan.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigtwin_arm::dynamics::JointState;
use rigtwin_arm::human::{Admittance, HoldTask, ImposedSinusoid, ReachTask};
use rigtwin_arm::muscles::MUSCLES;
use rigtwin_arm::{Human, HumanConfig, Task};
use rigtwin_device::config::Axis;
use rigtwin_device::perturb::Crossing;
use rigtwin_device::perturb::force_pulse::PulseTrigger;
use rigtwin_device::perturb::position::PositionTrigger;
use rigtwin_device::{Controller, Mode, PerturbationStatus, Tick, TickReport};
use rigtwin_world::{Attachment, Grasp, SimRig};

use super::record::{Block, Recorder};
use super::seed::{Stream, trial_seed};
use super::{RehearseError, TICK_HZ};
use crate::protocol::{HoldCondition, Protocol, ProtocolKind, VirtualSubject};

/// What one trial does.
#[derive(Debug, Clone, PartialEq)]
pub enum TrialTask {
    /// A reach, with a force pulse at this angle (degrees) or none.
    Reach {
        /// Pulse direction, degrees from +x toward +y.
        angle_deg: Option<f64>,
    },
    /// Force holding during the imposed motion (001_*).
    Hold {
        /// Force direction and motion axis.
        condition: HoldCondition,
    },
    /// The spring-mass rig under the same imposed motion and perturbations.
    Calibration,
}

/// The plan of one trial.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialPlan {
    /// 0-based index in the session; the trial id is `index + 1`.
    pub index: u32,
    /// What is done.
    pub task: TrialTask,
}

/// Ground truth at the onset of a force pulse.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OnsetTruth {
    /// Onset tick.
    pub tick: u64,
    /// Arm endpoint inertia `J⁻ᵀ M_q J⁻¹`, kg (the a-priori `M_BSP`).
    pub mass_kg: [[f64; 2]; 2],
    /// Intrinsic endpoint damping of the muscles, N s/m.
    pub damping_n_s_per_m: [[f64; 2]; 2],
    /// Intrinsic endpoint stiffness of the muscles, N/m.
    pub stiffness_n_per_m: [[f64; 2]; 2],
    /// Hand position, rig frame, m.
    pub hand_m: [f64; 2],
}

/// Per-tick extremes of a trial, for the safety and workspace parts of the report.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Extremes {
    /// Largest |hand force| as the controller measured it, N.
    pub peak_force_n: f64,
    /// Largest handle speed from the drive's velocity, m/s.
    pub peak_speed_m_per_s: f64,
    /// Largest |motor command| per axis, N.
    pub peak_command_n: [f64; 2],
    /// Largest |position| per axis, m.
    pub peak_position_m: [f64; 2],
    /// Ticks with a saturated motor command.
    pub saturated_ticks: u64,
    /// Ticks with a soft-wall force acting.
    pub wall_ticks: u64,
    /// First safety trip: tick and reason.
    pub trip: Option<(u64, String)>,
}

/// The raw result of simulating one trial.
#[derive(Debug, Clone)]
pub struct Simulated {
    /// Block-mean rows at the recording rate.
    pub rows: Vec<Block>,
    /// Whether a simulated arm held the handle, so that the rows' activation channels
    /// (`record::ch::ACTIVATION`) hold its muscles' (false for the spring-mass rig).
    pub muscles: bool,
    /// Extremes over all ticks.
    pub extremes: Extremes,
    /// Onset tick of the force pulse, if one fired.
    pub pulse_onset: Option<u64>,
    /// Ground truth at the pulse onset.
    pub onset_truth: Option<OnsetTruth>,
    /// Onset tick and direction (degrees) of each position perturbation.
    pub push_onsets: Vec<(u64, f64)>,
}

/// Ticks of a duration in seconds (validated to be whole).
pub(crate) fn ticks(s: f64) -> u64 {
    (s * TICK_HZ as f64).round().max(0.0) as u64
}

fn mat(m: &nalgebra::Matrix2<f64>) -> [[f64; 2]; 2] {
    [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]]
}

/// Trial length in ticks.
#[must_use]
pub fn trial_ticks(protocol: &Protocol) -> u64 {
    match protocol.kind {
        ProtocolKind::ReachPerturb => ticks(protocol.reach().trial_s()),
        ProtocolKind::HoldSinusoid | ProtocolKind::CalibrationRig => {
            let h = protocol.hold();
            let m = &protocol.controller.imposed_motion;
            let motion_s = 2.0 * m.ramp_s + f64::from(m.cycles) / m.frequency_hz;
            1 + ticks(motion_s).max(1) + ticks(h.after_s)
        }
    }
}

/// Simulates one trial of `subject`. `pulse` may be overridden to `None` to run the
/// unperturbed twin of a perturbed reach with the very same random streams.
///
/// # Errors
/// [`RehearseError`] if the controller, the arm or the plant refuse their
/// configuration or the simulation diverges.
pub fn simulate(
    protocol: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    plan: &TrialPlan,
    with_perturbation: bool,
) -> Result<Simulated, RehearseError> {
    let seed = |s: Stream| trial_seed(session_seed, subject.index, plan.index, s);
    let ctl_cfg = protocol.controller.clone();
    let rate_div = (TICK_HZ / u64::from(protocol.recording.rate_hz)).max(1);
    let n_ticks = trial_ticks(protocol);
    let handle_mass = protocol.plant.handle_mass_kg;

    let mut ctl_cfg = ctl_cfg;
    let (start_m, attachment, task) = match &plan.task {
        TrialTask::Reach { .. } => {
            let r = protocol.reach();
            let adm = &ctl_cfg.admittance;
            let task = Task::Reach(ReachTask {
                start_rig_m: r.start_m,
                goal_rig_m: r.goal_m,
                start_tick: ticks(r.still_before_s),
                duration_ticks: ticks(r.movement_s),
                admittance: Admittance {
                    mass_kg: adm.mass_kg,
                    damping_n_s_per_m: adm.damping_n_s_per_m,
                    handle_mass_kg: handle_mass,
                },
            });
            (r.start_m, arm_attachment(subject), Some(task))
        }
        TrialTask::Hold { condition } => {
            let h = protocol.hold();
            ctl_cfg.imposed_motion.axis = condition.axis;
            let (s, c) = condition.force_deg.to_radians().sin_cos();
            let task = Task::Hold(HoldTask {
                hand_rig_m: h.hand_m,
                force_n: [h.force_n * c, h.force_n * s],
                imposed: Some(human_sinusoid(protocol, condition.axis)),
                co_contraction_rise_per_s: h.co_contraction_rise_per_s,
            });
            (h.hand_m, arm_attachment(subject), Some(task))
        }
        TrialTask::Calibration => {
            let k = protocol.calibration();
            let att = Attachment::SpringMass {
                mass_kg: k.mass_kg,
                stiffness_n_per_m: k.stiffness_n_per_m,
            };
            (protocol.hold().hand_m, att, None)
        }
    };
    let rig_cfg = protocol.plant.rig_config(start_m, attachment);
    let mut rig = SimRig::new(rig_cfg, ChaCha8Rng::seed_from_u64(seed(Stream::Plant)))?;
    let mut ctl = Controller::new(ctl_cfg.clone())?;
    let mut human = match task {
        Some(task) => Some(Human::new(
            subject.arm.clone(),
            task,
            HumanConfig {
                shoulder_rig_m: subject.shoulder_m,
                neural_divisor: 4,
                trial_index: plan.index,
                co_contraction_level: subject.co_contraction_level,
            },
            ChaCha8Rng::seed_from_u64(seed(Stream::Arm)),
        )?),
        None => None,
    };

    // Position perturbations: one per zero-acceleration slot, directions drawn from
    // the trial's own stream (001_*: k π/4, k = 1..8).
    let mut pushes = Vec::new();
    if with_perturbation && !matches!(plan.task, TrialTask::Reach { .. }) {
        let slots = 2 * protocol.controller.imposed_motion.cycles;
        let mut rng = ChaCha8Rng::seed_from_u64(seed(Stream::Schedule));
        pushes = rigtwin_device::perturb::schedule::position_schedule(slots, &mut rng);
    }
    let mut next_push = 0usize;

    let mut recorder = Recorder::new(rate_div, n_ticks);
    let mut extremes = Extremes::default();
    let mut pulse_onset = None;
    let mut onset_truth = None;
    let mut push_onsets = Vec::new();
    let mut armed_angle_deg = 0.0;
    let mut last_hand_n = [0.0; 2];
    let mut last_acc = [0.0; 2];
    let mut activations_n = [0.0; MUSCLES];
    let mut active = false;
    for n in 0..n_ticks {
        let now = Tick(n);
        // The first tick takes the controller from Configured to Inactive (it has read
        // the sensors once); it is activated before the second. A reaching human waits
        // out `still_before_s`; the imposed motion starts at activation.
        if !active && n >= 1 && ctl.mode() == Mode::Inactive {
            ctl.activate()?;
            active = true;
            if let TrialTask::Reach { angle_deg: Some(a) } = plan.task
                && with_perturbation
            {
                let r = protocol.reach();
                let axis = r.trigger_axis.index();
                let dir = if r.goal_m[axis] >= r.start_m[axis] {
                    Crossing::Rising
                } else {
                    Crossing::Falling
                };
                ctl.arm_force_pulse(
                    a.to_radians(),
                    PulseTrigger::LineCrossing {
                        axis: r.trigger_axis,
                        position_m: r.trigger_position_m,
                        direction: dir,
                    },
                )?;
            }
        }
        if active
            && next_push < pushes.len()
            && !ctl.position_perturbation_status().is_running()
            && ctl.position_perturbation_status() != PerturbationStatus::Armed
        {
            let p = pushes[next_push];
            ctl.arm_position_perturbation(p.angle_rad, PositionTrigger::NextZeroAcceleration)?;
            armed_angle_deg = p.angle_rad.to_degrees();
            next_push += 1;
        }
        let true_pos = rig.handle_position_m();
        let true_vel = rig.handle_velocity_m_per_s();
        let report = ctl.tick(&mut rig, now);
        track(&mut extremes, &report);
        if let PerturbationStatus::Running { onset } = report.position_perturbation
            && onset == now
        {
            push_onsets.push((n, armed_angle_deg));
        }
        let state = rig.arm_state();
        if let (Some(h), Some(state)) = (human.as_mut(), state) {
            let tau = h.update(n, &state);
            activations_n = h.activations_n();
            rig.set_arm_torques(tau)?;
            if let PerturbationStatus::Running { onset } = report.force_pulse
                && onset == now
            {
                pulse_onset = Some(n);
                onset_truth = Some(onset_truth_at(h, &state, &rig, n)?);
            }
        } else if let PerturbationStatus::Running { onset } = report.force_pulse
            && onset == now
        {
            pulse_onset = Some(n);
        }
        recorder.push(
            &report,
            true_pos,
            true_vel,
            last_hand_n,
            last_acc,
            &activations_n,
        );
        rig.step()?;
        let truth = rig.truth();
        last_hand_n = truth.hand_on_handle_n;
        last_acc = truth.handle_acc_m_per_s2;
    }
    Ok(Simulated {
        rows: recorder.finish(),
        muscles: human.is_some(),
        extremes,
        pulse_onset,
        onset_truth,
        push_onsets,
    })
}

fn arm_attachment(subject: &VirtualSubject) -> Attachment {
    Attachment::Arm {
        shoulder_m: subject.shoulder_m,
        arm: Box::new(subject.arm.clone()),
        grasp: Grasp::Held,
    }
}

/// The imposed motion as the subject knows it: the controller's own, `e(t) A sin(2π f t)`
/// from activation (the tick after the handle is placed, centred there) with the same
/// raised-cosine envelope `e` over the ramp, the full cycles and the ramp out.
fn human_sinusoid(protocol: &Protocol, axis: Axis) -> ImposedSinusoid {
    let m = &protocol.controller.imposed_motion;
    let mut amplitude_m = [0.0; 2];
    amplitude_m[axis.index()] = m.amplitude_m;
    ImposedSinusoid {
        amplitude_m,
        frequency_hz: m.frequency_hz,
        start_tick: 1,
        ramp_s: m.ramp_s,
        cycles: Some(m.cycles),
    }
}

fn onset_truth_at(
    human: &Human,
    state: &JointState,
    rig: &SimRig,
    n: u64,
) -> Result<OnsetTruth, RehearseError> {
    let gt = human.ground_truth(state.q)?;
    let hand = rig.hand_position_m().map_or([0.0; 2], |p| [p.x, p.y]);
    Ok(OnsetTruth {
        tick: n,
        mass_kg: mat(&gt.mass_kg),
        damping_n_s_per_m: mat(&gt.damping_n_s_per_m),
        stiffness_n_per_m: mat(&gt.stiffness_n_per_m),
        hand_m: hand,
    })
}

fn track(e: &mut Extremes, r: &TickReport) {
    e.peak_force_n = e.peak_force_n.max(r.force_n[0].hypot(r.force_n[1]));
    e.peak_speed_m_per_s = e
        .peak_speed_m_per_s
        .max(r.velocity_m_per_s[0].hypot(r.velocity_m_per_s[1]));
    for i in 0..2 {
        e.peak_command_n[i] = e.peak_command_n[i].max(r.command_n[i].abs());
        e.peak_position_m[i] = e.peak_position_m[i].max(r.position_m[i].abs());
    }
    if r.saturated[0] || r.saturated[1] {
        e.saturated_ticks += 1;
    }
    if r.wall_force_n[0] != 0.0 || r.wall_force_n[1] != 0.0 {
        e.wall_ticks += 1;
    }
    if e.trip.is_none()
        && let Some(t) = r.trip
    {
        e.trip = Some((r.tick.0, format!("{t:?}")));
    }
}
