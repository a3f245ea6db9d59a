//! One trial: its plan, the co-simulation it builds ([`build`]: controller, driver,
//! rig and arm seeded from the trial's streams, recorder), and the lock-step run
//! ([`simulate`]) that is a loop over [`crate::cosim::CoSim::step`] on the integer 4 kHz
//! clock. Nothing here reads a clock or an unseeded generator, so a lock-step trial is
//! a pure function of its plan.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigtwin_arm::human::{Admittance, HoldTask, ImposedSinusoid, ReachTask};
use rigtwin_arm::{Human, HumanConfig, Task};
use rigtwin_device::Controller;
use rigtwin_device::config::Axis;
use rigtwin_device::perturb::Crossing;
use rigtwin_device::perturb::force_pulse::PulseTrigger;
use rigtwin_world::{Attachment, Grasp};

use super::record::Recorder;
use super::seed::{Stream, trial_seed};
use super::{RehearseError, TICK_HZ};
use crate::cosim::{self, Clock, CoSim, CoSimError, LockStep, SimPlant, TrialDriver};
pub use crate::cosim::{Extremes, OnsetTruth, Simulated};
use crate::protocol::{HoldCondition, Protocol, ProtocolKind, VirtualSubject};

/// What one trial does.
#[derive(Debug, Clone, PartialEq)]
pub enum TrialTask {
    /// A reach, with a force pulse at this angle (degrees) or none.
    Reach {
        /// Pulse direction, degrees from +x toward +y.
        angle_deg: Option<f64>,
        /// The centre-out goal (an index into `reach.targets_m`); `None`, the
        /// protocol's `goal_m`.
        target: Option<usize>,
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

/// The protocol `plan`'s trial runs with: `protocol` itself, or, for a reach to a
/// centre-out goal, a copy whose reach is the one to that goal
/// ([`crate::protocol::ReachConfig::toward`]), which is also what its manifest entry
/// records as the trial's goal.
#[must_use]
pub fn for_plan<'a>(protocol: &'a Protocol, plan: &TrialPlan) -> std::borrow::Cow<'a, Protocol> {
    use std::borrow::Cow;
    let TrialTask::Reach {
        target: Some(target),
        ..
    } = plan.task
    else {
        return Cow::Borrowed(protocol);
    };
    match protocol.reach.as_ref().and_then(|r| r.toward(target)) {
        Some(reach) => {
            let mut p = protocol.clone();
            p.reach = Some(reach);
            Cow::Owned(p)
        }
        None => Cow::Borrowed(protocol),
    }
}

/// Ticks of a duration in seconds (validated to be whole).
pub(crate) fn ticks(s: f64) -> u64 {
    (s * TICK_HZ as f64).round().max(0.0) as u64
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

/// Simulates one trial of `subject` in lock step. `with_perturbation` false runs the
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
    simulate_on(
        protocol,
        subject,
        session_seed,
        plan,
        with_perturbation,
        &mut LockStep,
    )
}

/// [`simulate`] paced by `clock` (a [`crate::cosim::WallClock`] for real time).
///
/// # Errors
/// As [`simulate`].
pub fn simulate_on<C: Clock>(
    protocol: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    plan: &TrialPlan,
    with_perturbation: bool,
    clock: &mut C,
) -> Result<Simulated, RehearseError> {
    let mut cosim = build(protocol, subject, session_seed, plan, with_perturbation)?;
    cosim::run(&mut cosim, clock, trial_ticks(protocol))?;
    Ok(cosim.finish())
}

/// The co-simulation of one trial, ready for its first tick: the controller of the
/// protocol (its imposed motion on the trial's axis), the driver with the trial's
/// perturbations, the rig with the subject's arm (or the spring-mass rig) seeded from
/// the trial's streams, and a recorder sized for the trial.
///
/// # Errors
/// [`RehearseError`] if the controller, the arm or the plant refuse their
/// configuration.
pub fn build(
    protocol: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    plan: &TrialPlan,
    with_perturbation: bool,
) -> Result<CoSim<SimPlant>, RehearseError> {
    let p = parts(protocol, subject, session_seed, plan, with_perturbation)?;
    Ok(CoSim::new(p.controller, p.driver, p.plant, p.recorder))
}

/// The parts of one trial's co-simulation, for a runner that puts something between the
/// controller and the plant (a wire).
#[derive(Debug)]
pub struct Parts {
    /// The protocol's controller (the trial's imposed-motion axis set).
    pub controller: Controller,
    /// Activation and the trial's perturbations.
    pub driver: TrialDriver,
    /// The rig and the subject, seeded from the trial's streams.
    pub plant: SimPlant,
    /// A recorder sized for the trial.
    pub recorder: Recorder,
}

/// What runs on the controller's side of one trial: the controller, its driver and a
/// recorder. A runner whose plant is across a wire builds only these.
#[derive(Debug)]
pub struct ControllerParts {
    /// The protocol's controller (the trial's imposed-motion axis set).
    pub controller: Controller,
    /// Activation and the trial's perturbations.
    pub driver: TrialDriver,
    /// A recorder sized for the trial.
    pub recorder: Recorder,
}

/// The parts [`build`] bundles: [`controller_parts`] and [`plant`] of the same trial.
///
/// # Errors
/// As [`build`].
pub fn parts(
    protocol: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    plan: &TrialPlan,
    with_perturbation: bool,
) -> Result<Parts, RehearseError> {
    let c = controller_parts(protocol, subject, session_seed, plan, with_perturbation)?;
    Ok(Parts {
        controller: c.controller,
        driver: c.driver,
        plant: plant(protocol, subject, session_seed, plan)?,
        recorder: c.recorder,
    })
}

/// The simulated plant of one trial: the rig at the trial's start with the subject's
/// arm given the trial's task (or the spring-mass rig), seeded from the trial's streams.
/// It is the same whether the controller runs beside it or across a wire.
///
/// # Errors
/// [`RehearseError`] if the arm or the plant refuse their configuration.
pub fn plant(
    protocol: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    plan: &TrialPlan,
) -> Result<SimPlant, RehearseError> {
    let seed = |s: Stream| trial_seed(session_seed, subject.index, plan.index, s);
    let mut ctl_cfg = protocol.controller.clone();
    let (start_m, attachment, task) = trial_task(protocol, subject, plan, &mut ctl_cfg);
    let rig_cfg = protocol.plant.rig_config(start_m, attachment);
    let human = match task {
        Some(task) => Some(
            Human::new(
                subject.arm.clone(),
                task,
                HumanConfig {
                    shoulder_rig_m: subject.shoulder_m,
                    neural_divisor: 4,
                    trial_index: plan.index,
                    co_contraction_level: subject.co_contraction_level,
                },
                ChaCha8Rng::seed_from_u64(seed(Stream::Arm)),
            )
            .map_err(CoSimError::from)?,
        ),
        None => None,
    };
    Ok(SimPlant::new(
        rig_cfg,
        ChaCha8Rng::seed_from_u64(seed(Stream::Plant)),
        human,
    )
    .map_err(CoSimError::from)?)
}

/// The controller's side of one trial: the protocol's controller (a hold trial's
/// imposed motion on its axis), the driver with the trial's perturbations, and a
/// recorder sized for the trial.
///
/// # Errors
/// [`RehearseError`] if the controller refuses its configuration.
pub fn controller_parts(
    protocol: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    plan: &TrialPlan,
    with_perturbation: bool,
) -> Result<ControllerParts, RehearseError> {
    let seed = |s: Stream| trial_seed(session_seed, subject.index, plan.index, s);
    let mut ctl_cfg = protocol.controller.clone();
    // The stale-force watchdog guards a live strain-gauge ADC, whose last bits always
    // move; a simulated sensor without noise repeats its reading exactly whenever the
    // handle is still (the calibration rig at rest tripped it), so it is off there.
    if protocol.plant.force_noise_rms_n == 0.0 {
        ctl_cfg.safety.stale_force_ticks = 0;
    }
    let rate_div = (TICK_HZ / u64::from(protocol.recording.rate_hz)).max(1);
    trial_task(protocol, subject, plan, &mut ctl_cfg);
    let controller = Controller::new(ctl_cfg)?;
    let pulse = match plan.task {
        TrialTask::Reach {
            angle_deg: Some(a), ..
        } if with_perturbation => {
            let r = protocol.reach();
            let axis = r.trigger_axis.index();
            let direction = if r.goal_m[axis] >= r.start_m[axis] {
                Crossing::Rising
            } else {
                Crossing::Falling
            };
            Some((
                a.to_radians(),
                PulseTrigger::LineCrossing {
                    axis: r.trigger_axis,
                    position_m: r.trigger_position_m,
                    direction,
                },
            ))
        }
        _ => None,
    };
    // Position perturbations: one per zero-acceleration slot, directions drawn from
    // the trial's own stream (001_*: k π/4, k = 1..8).
    let mut pushes = Vec::new();
    if with_perturbation && !matches!(plan.task, TrialTask::Reach { .. }) {
        let slots = 2 * protocol.controller.imposed_motion.cycles;
        let mut rng = ChaCha8Rng::seed_from_u64(seed(Stream::Schedule));
        pushes = rigtwin_device::perturb::schedule::position_schedule(slots, &mut rng);
    }
    Ok(ControllerParts {
        controller,
        driver: TrialDriver::new(pulse, pushes),
        recorder: Recorder::new(rate_div, trial_ticks(protocol)),
    })
}

/// Where the handle starts, what holds it and what the subject does in `plan`'s trial;
/// a hold trial moves the controller's imposed motion onto its axis.
fn trial_task(
    protocol: &Protocol,
    subject: &VirtualSubject,
    plan: &TrialPlan,
    ctl_cfg: &mut rigtwin_device::ControllerConfig,
) -> ([f64; 2], Attachment, Option<Task>) {
    let handle_mass = protocol.plant.handle_mass_kg;
    match &plan.task {
        TrialTask::Reach { .. } => {
            let r = protocol.reach();
            let adm = &ctl_cfg.admittance;
            let task = Task::Reach(ReachTask {
                start_rig_m: r.start_m,
                goal_rig_m: r.goal_m,
                start_tick: ticks(r.still_before_s),
                duration_ticks: ticks(r.movement_s),
                back_after_ticks: r.back_after_s.map(ticks),
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
    }
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
