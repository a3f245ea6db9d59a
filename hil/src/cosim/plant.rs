//! The simulated plant of a co-simulation: the rapier rig ([`SimRig`]) and the subject
//! holding its handle ([`Human`]), advanced together by one tick.
//!
//! To the controller it is a [`RigIo`] like any rig (the rig's sensors and motors); to
//! the loop it is a [`Plant`] that, once the controller has written its command for tick
//! `n`, lets the subject answer the state at `n` and moves physics on to `n + 1`. What
//! it reports of tick `n` (the true handle state, the hand's force and the handle's
//! acceleration over the step that ended at `n`, the muscle activations, and the arm's
//! impedance at a pulse onset) is ground truth that no rig measures.

use rand_chacha::ChaCha8Rng;
use rigtwin_arm::Human;
use rigtwin_arm::dynamics::JointState;
use rigtwin_arm::muscles::MUSCLES;
use rigtwin_device::{MotorCommand, RigIo, SensorFrame, Tick, TickReport};
use rigtwin_world::{RigConfig, SimRig, WorldError};

use super::{CoSimError, OnsetTruth};

/// Ground truth of one tick: the plant's state at the tick, before it moved on.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlantSample {
    /// True handle position, rig frame, m.
    pub position_m: [f64; 2],
    /// True handle velocity, m/s.
    pub velocity_m_per_s: [f64; 2],
    /// Force of the hand on the handle over the step that ended at this tick, N.
    pub hand_n: [f64; 2],
    /// Handle acceleration over the step that ended at this tick, m/s².
    pub acceleration_m_per_s2: [f64; 2],
    /// The arm's six muscle activations after its update at this tick, N (zero without
    /// an arm).
    pub activations_n: [f64; MUSCLES],
    /// The arm's endpoint inertia, damping and stiffness, when a force pulse started at
    /// this tick and an arm holds the handle.
    pub onset: Option<OnsetTruth>,
}

/// What the loop needs of a plant beyond the rig's I/O.
pub trait Plant: RigIo {
    /// Before the controller's tick: the controller's mode, for a plant that tells it to
    /// the other side (a wire carries it with every command). Nothing by default.
    fn before_tick(&mut self, mode: rigtwin_device::Mode) {
        let _ = mode;
    }

    /// Ends tick `now`, after the controller wrote its command (`report`): the plant
    /// moves on by one period under the command it holds. Returns the ground truth of
    /// `now` where the plant knows it (a simulated plant), `None` where it does not (a
    /// rig across a wire, which moves on by itself).
    ///
    /// # Errors
    /// [`CoSimError`] if the plant diverges or the subject refuses its state.
    fn advance(
        &mut self,
        now: Tick,
        report: &TickReport,
    ) -> Result<Option<PlantSample>, CoSimError>;

    /// Whether a simulated subject's muscles take part (their activations are in the
    /// samples).
    fn has_muscles(&self) -> bool {
        false
    }
}

/// The rapier rig and, where one holds the handle, the simulated subject.
#[derive(Debug)]
pub struct SimPlant {
    rig: SimRig,
    human: Option<Human>,
}

impl SimPlant {
    /// The plant of `config` (seeded by `rng`) held by `human` (`None`: no arm, e.g. the
    /// spring-mass calibration rig).
    ///
    /// # Errors
    /// [`WorldError`] if the rig refuses its configuration.
    pub fn new(
        config: RigConfig,
        rng: ChaCha8Rng,
        human: Option<Human>,
    ) -> Result<SimPlant, WorldError> {
        Ok(SimPlant {
            rig: SimRig::new(config, rng)?,
            human,
        })
    }

    /// The rapier rig.
    #[must_use]
    pub fn rig(&self) -> &SimRig {
        &self.rig
    }

    /// The rapier rig, e.g. to press its e-stop.
    pub fn rig_mut(&mut self) -> &mut SimRig {
        &mut self.rig
    }

    /// The simulated subject, if one holds the handle.
    #[must_use]
    pub fn human(&self) -> Option<&Human> {
        self.human.as_ref()
    }

    /// Ends tick `now`: the subject answers the state at `now`, physics moves to
    /// `now + 1`. `onset`: a force pulse started at `now` (the arm's impedance is then
    /// sampled). Returns the ground truth of `now`.
    ///
    /// # Errors
    /// [`CoSimError`] if the arm refuses its state or the plant diverges.
    pub fn advance_with(&mut self, now: Tick, onset: bool) -> Result<PlantSample, CoSimError> {
        let p = self.rig.handle_position_m();
        let v = self.rig.handle_velocity_m_per_s();
        let mut onset_truth = None;
        if let (Some(h), Some(state)) = (self.human.as_mut(), self.rig.arm_state()) {
            let tau = h.update(now.0, &state);
            self.rig.set_arm_torques(tau)?;
            if onset {
                onset_truth = Some(onset_truth_at(h, &state, &self.rig, now.0)?);
            }
        }
        // The rig's truth is still the last step's (zeros before the first).
        let last = self.rig.truth();
        let sample = PlantSample {
            position_m: [p.x, p.y],
            velocity_m_per_s: [v.x, v.y],
            hand_n: last.hand_on_handle_n,
            acceleration_m_per_s2: last.handle_acc_m_per_s2,
            activations_n: self
                .human
                .as_ref()
                .map_or([0.0; MUSCLES], Human::activations_n),
            onset: onset_truth,
        };
        self.rig.step()?;
        Ok(sample)
    }
}

impl RigIo for SimPlant {
    type Error = WorldError;

    fn read(&mut self, now: Tick) -> Result<SensorFrame, WorldError> {
        self.rig.read(now)
    }

    fn write(&mut self, now: Tick, command: MotorCommand) -> Result<(), WorldError> {
        self.rig.write(now, command)
    }
}

impl Plant for SimPlant {
    fn advance(
        &mut self,
        now: Tick,
        report: &TickReport,
    ) -> Result<Option<PlantSample>, CoSimError> {
        self.advance_with(now, report.force_pulse.started_at(now))
            .map(Some)
    }

    fn has_muscles(&self) -> bool {
        self.human.is_some()
    }
}

fn mat(m: &nalgebra::Matrix2<f64>) -> [[f64; 2]; 2] {
    [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]]
}

fn onset_truth_at(
    human: &Human,
    state: &JointState,
    rig: &SimRig,
    n: u64,
) -> Result<OnsetTruth, CoSimError> {
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
