//! One co-simulation step: the rig's controller, the rig it drives, the protocol's
//! driver and the recorder, advanced together by one tick of the 4 kHz clock.
//!
//! ```text
//!  step(n):  driver.before_tick        activation, perturbations armed (the experiment script)
//!            controller.tick(plant, n)  read sensors (state after n−1) → law → write command
//!                                       (recomputed on motor ticks, 2 kHz, held between)
//!            plant.advance(n)           the subject answers the state at n, physics n → n+1;
//!                                       ground truth of n where the plant knows it
//!            recorder.push              block means at the recording rate
//!  hold(n):  a tick whose deadline the loop missed: the controller does not run, the
//!            plant advances under the held command, and the recorder keeps the tick
//!            (the held report), so a missed deadline never drops a recorded sample
//! ```
//!
//! The loops over it differ only in their [`Clock`] and their [`Plant`]: [`run`] with
//! [`LockStep`] and the in-process [`SimPlant`] is the lock-step rehearsal (also
//! `compare`'s re-simulation); with a [`WallClock`] it is the real-time rehearsal; a
//! plant across a wire moves on by itself and reports no ground truth. This is the
//! read → update → write loop of ros2_control's controller manager, with the clock
//! injected as in copper-rs.

pub mod clock;
pub mod driver;
pub mod outcome;
pub mod plant;
pub mod record;
pub mod rt;
pub mod wired;

use rigtwin_device::{Controller, Tick, TickReport};

pub use clock::{Clock, ClockError, LockStep, WallClock};
pub use driver::TrialDriver;
pub use outcome::{Extremes, OnsetTruth, Simulated, track};
pub use plant::{Plant, PlantSample, SimPlant};
use record::Recorder;

/// Why a co-simulation step failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CoSimError {
    /// A lifecycle transition was refused.
    #[error("controller lifecycle: {0}")]
    Lifecycle(#[from] rigtwin_device::LifecycleError),
    /// A perturbation could not be armed.
    #[error("perturbation: {0}")]
    Perturbation(#[from] rigtwin_device::perturb::ArmError),
    /// The arm model refused its parameters, task or state.
    #[error("arm: {0}")]
    Arm(#[from] rigtwin_arm::ArmError),
    /// The plant refused its configuration or diverged.
    #[error("plant: {0}")]
    World(#[from] rigtwin_world::WorldError),
}

/// The controller, its driver, the plant and the recorder of one trial.
#[derive(Debug)]
pub struct CoSim<P> {
    controller: Controller,
    driver: TrialDriver,
    plant: P,
    recorder: Recorder,
    extremes: Extremes,
    pulse_onset: Option<u64>,
    onset_truth: Option<OnsetTruth>,
    push_onsets: Vec<(u64, f64)>,
    held: TickReport,
}

impl<P: Plant> CoSim<P> {
    /// Bundles the parts of one trial; nothing runs until [`CoSim::step`].
    #[must_use]
    pub fn new(controller: Controller, driver: TrialDriver, plant: P, recorder: Recorder) -> Self {
        CoSim {
            controller,
            driver,
            plant,
            recorder,
            extremes: Extremes::default(),
            pulse_onset: None,
            onset_truth: None,
            push_onsets: Vec::with_capacity(64),
            held: TickReport::default(),
        }
    }

    /// The controller.
    #[must_use]
    pub fn controller(&self) -> &Controller {
        &self.controller
    }

    /// The plant.
    #[must_use]
    pub fn plant(&self) -> &P {
        &self.plant
    }

    /// The plant, e.g. to press a simulated e-stop.
    pub fn plant_mut(&mut self) -> &mut P {
        &mut self.plant
    }

    /// One tick: driver, controller (read → update → write), plant, recorder. Returns
    /// the controller's report of the tick.
    ///
    /// # Errors
    /// [`CoSimError`] if the driver's transitions are refused or the plant diverges.
    pub fn step(&mut self, now: Tick) -> Result<TickReport, CoSimError> {
        self.driver.before_tick(&mut self.controller, now)?;
        self.plant.before_tick(self.controller.mode());
        let report = self.controller.tick(&mut self.plant, now);
        track(&mut self.extremes, &report);
        if let Some(angle_deg) = self.driver.push_onset(&report, now) {
            self.push_onsets.push((now.0, angle_deg));
        }
        if report.force_pulse.started_at(now) {
            self.pulse_onset = Some(now.0);
        }
        self.finish_tick(now, &report)?;
        self.held = report;
        Ok(report)
    }

    /// A tick whose deadline was missed: the controller does not run, the plant moves on
    /// under the command it holds, and the tick is recorded with the controller's last
    /// report.
    ///
    /// # Errors
    /// [`CoSimError`] if the plant diverges.
    pub fn hold(&mut self, now: Tick) -> Result<(), CoSimError> {
        let mut report = self.held;
        report.tick = now;
        report.motor_update = false;
        report.trip = None;
        self.finish_tick(now, &report)
    }

    fn finish_tick(&mut self, now: Tick, report: &TickReport) -> Result<(), CoSimError> {
        let sample = self.plant.advance(now, report)?.unwrap_or_default();
        if sample.onset.is_some() {
            self.onset_truth = sample.onset;
        }
        self.recorder.push(report, &sample);
        Ok(())
    }

    /// The recorded trial.
    #[must_use]
    pub fn finish(self) -> Simulated {
        Simulated {
            muscles: self.plant.has_muscles(),
            rows: self.recorder.finish(),
            extremes: self.extremes,
            pulse_onset: self.pulse_onset,
            onset_truth: self.onset_truth,
            push_onsets: self.push_onsets,
        }
    }
}

/// Runs ticks `0..n_ticks` of `cosim` on `clock`: each tick the clock says is due is
/// stepped, the ticks it skipped over are held.
///
/// # Errors
/// [`CoSimError`] from the step.
pub fn run<P: Plant, C: Clock>(
    cosim: &mut CoSim<P>,
    clock: &mut C,
    n_ticks: u64,
) -> Result<(), CoSimError> {
    let mut n = 0;
    while n < n_ticks {
        let due = clock.wait(Tick(n), Tick(n_ticks - 1)).0.max(n);
        let paced = clock.last_wake_latency_ns();
        for k in n..due {
            if paced.is_some() {
                cosim.recorder.set_tick_timing(0.0, true);
            }
            cosim.hold(Tick(k))?;
        }
        if let Some(ns) = paced {
            cosim.recorder.set_tick_timing(ns as f64 / 1000.0, false);
        }
        cosim.step(Tick(due))?;
        n = due + 1;
    }
    Ok(())
}
