//! The protocol's side of the controller in one trial: when the controller is activated
//! and which perturbations are armed, tick by tick. This is what a rig's experiment
//! script does around its real-time controller, so it runs wherever the controller runs
//! (in lock step beside the simulated plant, or across a wire from it).

use rigtwin_device::perturb::force_pulse::PulseTrigger;
use rigtwin_device::perturb::position::PositionTrigger;
use rigtwin_device::perturb::schedule::PlannedPush;
use rigtwin_device::{Controller, Mode, PerturbationStatus, Tick, TickReport};

use super::CoSimError;

/// Activation and perturbation arming for one trial.
#[derive(Debug, Clone)]
pub struct TrialDriver {
    pulse: Option<(f64, PulseTrigger)>,
    pushes: Vec<PlannedPush>,
    next_push: usize,
    armed_angle_deg: f64,
    active: bool,
}

impl TrialDriver {
    /// Activates the controller on the first tick after it has read the sensors once,
    /// then arms `pulse` (direction in radians from +x toward +y, and its trigger) once
    /// and each of `pushes` in turn whenever the position perturbation is idle.
    #[must_use]
    pub fn new(pulse: Option<(f64, PulseTrigger)>, pushes: Vec<PlannedPush>) -> TrialDriver {
        TrialDriver {
            pulse,
            pushes,
            next_push: 0,
            armed_angle_deg: 0.0,
            active: false,
        }
    }

    /// Before the controller's tick `now`: activation and arming.
    ///
    /// # Errors
    /// [`CoSimError`] if the controller refuses a transition or a perturbation.
    pub fn before_tick(&mut self, ctl: &mut Controller, now: Tick) -> Result<(), CoSimError> {
        // The first tick takes the controller from Configured to Inactive (it has read
        // the sensors once); it is activated before the second. A reaching human waits
        // out `still_before_s`; the imposed motion starts at activation.
        if !self.active && now.0 >= 1 && ctl.mode() == Mode::Inactive {
            ctl.activate()?;
            self.active = true;
            if let Some((angle_rad, trigger)) = self.pulse {
                ctl.arm_force_pulse(angle_rad, trigger)?;
            }
        }
        if self.active
            && self.next_push < self.pushes.len()
            && !ctl.position_perturbation_status().is_running()
            && ctl.position_perturbation_status() != PerturbationStatus::Armed
        {
            let p = self.pushes[self.next_push];
            ctl.arm_position_perturbation(p.angle_rad, PositionTrigger::NextZeroAcceleration)?;
            self.armed_angle_deg = p.angle_rad.to_degrees();
            self.next_push += 1;
        }
        Ok(())
    }

    /// After the controller's tick `now`: the direction (degrees) of a position
    /// perturbation that started at it.
    #[must_use]
    pub fn push_onset(&self, report: &TickReport, now: Tick) -> Option<f64> {
        report
            .position_perturbation
            .started_at(now)
            .then_some(self.armed_angle_deg)
    }
}
