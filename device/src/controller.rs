//! The rig's real-time controller: lifecycle, the per-tick read → update → write, and
//! the per-tick report for the recorder and the viewer.
//!
//! Every tick (4 kHz): read the sensors, convert them (encoders → m, force calibration →
//! rig frame, filtered-difference velocity), run the safety checks, and in `Active`
//! advance perturbations and the control law (admittance or virtual spring) by one
//! exact step. On motor ticks (`tick % divisor == 0`, 2 kHz by default) the renderer
//! computes a new motor command; in between the last one is held. Any trip makes the
//! command written at that same tick zero, a non-finite command included (it trips
//! before it is clamped). `tick` does not allocate, lock or block.
//!
//! The safety layer sees every reading (force, encoder counts), every command written
//! and every tick number the loop passes in; its watchdogs (stale force, encoder stall,
//! loop deadline, see [`crate::safety`]) count from those alone. Time is only what the
//! loop says `now` is: a tick after skipped ones is judged by its gap (a clock skip,
//! `safety.max_consecutive_misses`) and by how often it happens (a deadline overrun).

use crate::admittance::Admittance;
use crate::calib::{ForceCalibration, counts_to_m};
use crate::config::{ConfigError, ControllerConfig, LawKind};
use crate::io::{MotorCommand, RigIo, RigIoError, SensorFrame};
use crate::motion::ImposedMotion;
use crate::perturb::force_pulse::{ForcePulse, PulseTrigger};
use crate::perturb::position::{PositionPerturbation, PositionTrigger};
use crate::perturb::{ArmError, PerturbationStatus};
use crate::render::Renderer;
use crate::safety::{EventLog, IoStage, SafetyEvent, SafetyMonitor, TripReason};
use crate::spring::VirtualSpring;
use crate::time::{Rate, Tick};
use crate::velocity::VelocityEstimator;

/// The controller's lifecycle state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Built from a valid config; no sensor frame read yet. Commands zero.
    #[default]
    Configured,
    /// Reading sensors (the safety layer watches them) and commanding zero force.
    Inactive,
    /// Rendering the control law.
    Active,
    /// Tripped: zero force, latched until [`Controller::reset`].
    Fault,
}

/// Why a lifecycle transition was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LifecycleError {
    /// The transition is not allowed from this mode.
    #[error("cannot {action} from mode {mode:?}")]
    WrongMode {
        /// What was asked.
        action: &'static str,
        /// The mode the controller is in.
        mode: Mode,
    },
    /// A fault cannot be reset while the e-stop is pressed.
    #[error("cannot reset while the e-stop is pressed")]
    EStopPressed,
}

/// Everything the recorder and the viewer need from one tick. Rig frame, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TickReport {
    /// The tick.
    pub tick: Tick,
    /// Mode after this tick.
    pub mode: Mode,
    /// The control law selected.
    pub law: LawKind,
    /// Handle position from the encoders, m.
    pub position_m: [f64; 2],
    /// Filtered-difference encoder velocity, m/s.
    pub velocity_m_per_s: [f64; 2],
    /// Calibrated hand force on the handle, rig frame, N (last finite reading if this
    /// one was not finite).
    pub force_n: [f64; 2],
    /// Force-pulse perturbation added to the law's input (`u_pert`), N.
    pub pert_force_n: [f64; 2],
    /// Position-perturbation offset added to the reference, m.
    pub pert_position_m: [f64; 2],
    /// Soft-wall force added to the law's input, N.
    pub wall_force_n: [f64; 2],
    /// Virtual-spring anchor (imposed motion), m; in admittance mode equal to the
    /// admittance reference.
    pub anchor_position_m: [f64; 2],
    /// Reference the carts are driven to at this tick (the law's state at this tick's
    /// time, from the inputs up to the previous tick, plus the position perturbation), m.
    pub ref_position_m: [f64; 2],
    /// Reference velocity, m/s.
    pub ref_velocity_m_per_s: [f64; 2],
    /// Reference acceleration (feed-forward), m/s².
    pub ref_acceleration_m_per_s2: [f64; 2],
    /// Motor force written at this tick, N.
    pub command_n: [f64; 2],
    /// True if a new command was computed at this tick (motor tick).
    pub motor_update: bool,
    /// Per axis: the last computed command hit the force limit.
    pub saturated: [bool; 2],
    /// The e-stop input as read.
    pub estop: bool,
    /// Force-pulse generator status.
    pub force_pulse: PerturbationStatus,
    /// Position-perturbation generator status.
    pub position_perturbation: PerturbationStatus,
    /// The trip detected at this tick, if any.
    pub trip: Option<TripReason>,
}

/// The rig's controller, generic over the hardware at each call.
#[derive(Debug, Clone)]
pub struct Controller {
    config: ControllerConfig,
    rate: Rate,
    divisor: u64,
    mode: Mode,
    law: LawKind,
    calibration: ForceCalibration,
    velocity: VelocityEstimator,
    admittance: Admittance,
    spring: VirtualSpring,
    motion: ImposedMotion,
    renderer: Renderer,
    pulse: ForcePulse,
    push: PositionPerturbation,
    safety: SafetyMonitor,
    events: EventLog,
    last_tick: Option<Tick>,
    position_m: [f64; 2],
    prev_position_m: [f64; 2],
    force_n: [f64; 2],
    estop: bool,
    held_n: [f64; 2],
    saturated: [bool; 2],
    motion_start: Option<Tick>,
    center_m: [f64; 2],
    clock: Tick,
    report: TickReport,
}

impl Controller {
    /// A controller in [`Mode::Configured`].
    ///
    /// # Errors
    /// [`ConfigError`] naming every invalid key.
    pub fn new(config: ControllerConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        let (Some(rate), Some(divisor)) = (config.control_rate(), config.motor_divisor()) else {
            // validate() has rejected both cases; keep the error path total anyway.
            return Err(ConfigError {
                errors: vec![crate::config::InvalidKey {
                    key: "control_rate_hz".to_owned(),
                    problem: "and motor_rate_hz must be non-zero, the motor rate dividing the control rate".to_owned(),
                }],
            });
        };
        let h = rate.period_s();
        let a = &config.admittance;
        let v = &config.virtual_spring;
        Ok(Controller {
            rate,
            divisor: u64::from(divisor),
            mode: Mode::Configured,
            law: config.law,
            calibration: config.sensors.force_calibration,
            velocity: VelocityEstimator::new(config.sensors.velocity_filter_hz, h),
            admittance: Admittance::new(a.mass_kg, a.damping_n_s_per_m, h),
            spring: VirtualSpring::new(v.mass_kg, v.stiffness_n_per_m, v.damping_n_s_per_m, h),
            motion: ImposedMotion::new(&config.imposed_motion, rate),
            renderer: Renderer::new(&config.render),
            pulse: ForcePulse::new(&config.force_pulse, rate),
            push: PositionPerturbation::new(&config.position_perturbation, rate),
            safety: SafetyMonitor::new(&config.safety),
            events: EventLog::default(),
            last_tick: None,
            position_m: [0.0; 2],
            prev_position_m: [0.0; 2],
            force_n: [0.0; 2],
            estop: false,
            held_n: [0.0; 2],
            saturated: [false; 2],
            motion_start: None,
            center_m: [0.0; 2],
            clock: Tick(0),
            report: TickReport {
                law: config.law,
                ..TickReport::default()
            },
            config,
        })
    }

    /// The config it was built from.
    #[must_use]
    pub fn config(&self) -> &ControllerConfig {
        &self.config
    }

    /// The control clock.
    #[must_use]
    pub fn rate(&self) -> Rate {
        self.rate
    }

    /// Control ticks per motor update.
    #[must_use]
    pub fn motor_divisor(&self) -> u64 {
        self.divisor
    }

    /// The lifecycle state.
    #[must_use]
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The selected law.
    #[must_use]
    pub fn law(&self) -> LawKind {
        self.law
    }

    /// The last tick's report.
    #[must_use]
    pub fn report(&self) -> &TickReport {
        &self.report
    }

    /// The safety events (latest [`crate::safety::EVENT_CAPACITY`]).
    #[must_use]
    pub fn events(&self) -> &EventLog {
        &self.events
    }

    /// The imposed motion of the virtual-spring law.
    #[must_use]
    pub fn imposed_motion(&self) -> &ImposedMotion {
        &self.motion
    }

    /// The force-pulse generator (profile, duration).
    #[must_use]
    pub fn force_pulse(&self) -> &ForcePulse {
        &self.pulse
    }

    /// The position-perturbation generator (profile, duration).
    #[must_use]
    pub fn position_perturbation(&self) -> &PositionPerturbation {
        &self.push
    }

    /// The tick the imposed motion started (first active tick), if active.
    #[must_use]
    pub fn motion_start(&self) -> Option<Tick> {
        self.motion_start
    }

    /// True once the imposed motion has run its course (virtual-spring law only).
    #[must_use]
    pub fn motion_finished(&self) -> bool {
        match (self.motion_start, self.last_tick) {
            (Some(s), Some(t)) => self.motion.finished(t.0.saturating_sub(s.0)),
            _ => false,
        }
    }

    /// Switch law; refused while active.
    ///
    /// # Errors
    /// [`LifecycleError::WrongMode`] in [`Mode::Active`].
    pub fn set_law(&mut self, law: LawKind) -> Result<(), LifecycleError> {
        if self.mode == Mode::Active {
            return Err(LifecycleError::WrongMode {
                action: "switch law",
                mode: self.mode,
            });
        }
        self.law = law;
        Ok(())
    }

    /// Inactive → Active. The law starts at rest at the measured handle position; the
    /// imposed motion is centred there and starts at the next tick.
    ///
    /// # Errors
    /// [`LifecycleError::WrongMode`] unless [`Mode::Inactive`].
    pub fn activate(&mut self) -> Result<(), LifecycleError> {
        if self.mode != Mode::Inactive {
            return Err(LifecycleError::WrongMode {
                action: "activate",
                mode: self.mode,
            });
        }
        self.admittance.reset(self.position_m, [0.0; 2]);
        self.spring.reset(self.position_m, [0.0; 2]);
        self.center_m = self.position_m;
        self.motion_start = None;
        self.held_n = [0.0; 2];
        self.mode = Mode::Active;
        Ok(())
    }

    /// Active → Inactive (zero force); running perturbations are aborted.
    ///
    /// # Errors
    /// [`LifecycleError::WrongMode`] unless [`Mode::Active`].
    pub fn deactivate(&mut self) -> Result<(), LifecycleError> {
        if self.mode != Mode::Active {
            return Err(LifecycleError::WrongMode {
                action: "deactivate",
                mode: self.mode,
            });
        }
        self.stop_law();
        self.mode = Mode::Inactive;
        Ok(())
    }

    /// Fault → Inactive, if the e-stop was released at the last read.
    ///
    /// # Errors
    /// [`LifecycleError::WrongMode`] unless [`Mode::Fault`];
    /// [`LifecycleError::EStopPressed`] while the e-stop is pressed.
    pub fn reset(&mut self) -> Result<(), LifecycleError> {
        if self.mode != Mode::Fault {
            return Err(LifecycleError::WrongMode {
                action: "reset",
                mode: self.mode,
            });
        }
        if self.estop {
            return Err(LifecycleError::EStopPressed);
        }
        self.safety.reset();
        self.velocity.reset();
        self.last_tick = None;
        self.mode = Mode::Inactive;
        Ok(())
    }

    /// Arm a force pulse (000_* eq. 22–23) at `angle_rad` from +x toward +y.
    ///
    /// # Errors
    /// [`ArmError`] for a non-finite angle or line, or while a pulse runs.
    pub fn arm_force_pulse(
        &mut self,
        angle_rad: f64,
        trigger: PulseTrigger,
    ) -> Result<(), ArmError> {
        self.pulse.arm(angle_rad, trigger)
    }

    /// Arm a position perturbation (001_*) at `angle_rad` from +x toward +y.
    ///
    /// # Errors
    /// [`ArmError`] for a non-finite angle, while one runs, or for a zero-acceleration
    /// trigger without the virtual-spring law.
    pub fn arm_position_perturbation(
        &mut self,
        angle_rad: f64,
        trigger: PositionTrigger,
    ) -> Result<(), ArmError> {
        if trigger == PositionTrigger::NextZeroAcceleration && self.law != LawKind::VirtualSpring {
            return Err(ArmError::NoImposedMotion);
        }
        self.push.arm(angle_rad, trigger)
    }

    /// Disarm or cut short both perturbations.
    pub fn abort_perturbations(&mut self) {
        self.pulse.abort();
        self.push.abort();
    }

    /// Force-pulse status and onset.
    #[must_use]
    pub fn force_pulse_status(&self) -> PerturbationStatus {
        self.pulse.status()
    }

    /// Position-perturbation status and onset.
    #[must_use]
    pub fn position_perturbation_status(&self) -> PerturbationStatus {
        self.push.status()
    }

    fn stop_law(&mut self) {
        self.abort_perturbations();
        self.held_n = [0.0; 2];
        self.saturated = [false; 2];
        self.motion_start = None;
    }

    fn trip(&mut self, now: Tick, reason: TripReason) {
        if self.mode == Mode::Fault {
            return;
        }
        self.events.push(SafetyEvent { tick: now, reason });
        self.report.trip = Some(reason);
        self.stop_law();
        self.mode = Mode::Fault;
    }

    /// One control period on the controller's own clock: the tick after the last one
    /// passed to [`Controller::tick`] or `step` (tick 0 first). For lock-step loops
    /// that keep no clock of their own.
    pub fn step<I: RigIo>(&mut self, io: &mut I) -> TickReport {
        self.tick(io, self.clock)
    }

    /// One control period at tick `now`: read → update → write. Returns this tick's
    /// report. Never allocates.
    pub fn tick<I: RigIo>(&mut self, io: &mut I, now: Tick) -> TickReport {
        self.report.trip = None;
        self.report.motor_update = false;
        let consecutive = self.last_tick.is_some_and(|t| now == t.next());
        let frame = match io.read(now) {
            Ok(f) => Some(f),
            Err(e) => {
                self.trip(
                    now,
                    TripReason::Io {
                        stage: IoStage::Read,
                        kind: e.kind(),
                    },
                );
                None
            }
        };
        if let Some(frame) = frame {
            self.sense(now, &frame, consecutive);
        }
        let command = if self.mode == Mode::Active {
            self.update(now)
        } else {
            [0.0; 2]
        };
        self.safety.observe_command(command);
        if let Err(e) = io.write(now, MotorCommand { force_n: command }) {
            self.trip(
                now,
                TripReason::Io {
                    stage: IoStage::Write,
                    kind: e.kind(),
                },
            );
        }
        self.last_tick = Some(now);
        self.clock = now.next();
        let r = &mut self.report;
        r.tick = now;
        r.mode = self.mode;
        r.law = self.law;
        r.command_n = command;
        r.saturated = self.saturated;
        r.force_pulse = self.pulse.status();
        r.position_perturbation = self.push.status();
        if self.mode != Mode::Active {
            // Nothing is rendered: the reference is where the handle is, at rest.
            r.ref_position_m = r.position_m;
            r.ref_velocity_m_per_s = [0.0; 2];
            r.ref_acceleration_m_per_s2 = [0.0; 2];
            r.anchor_position_m = r.position_m;
            r.pert_force_n = [0.0; 2];
            r.pert_position_m = [0.0; 2];
            r.wall_force_n = [0.0; 2];
        }
        self.report
    }

    /// Convert the frame, update velocity, run the safety checks.
    fn sense(&mut self, now: Tick, frame: &SensorFrame, consecutive: bool) {
        let position = counts_to_m(
            frame.encoder_counts,
            self.config.sensors.encoder_m_per_count,
        );
        if self.safety.observe_force(frame) {
            self.force_n = self.calibration.apply(frame.force_raw_n);
        }
        let step = if consecutive {
            [
                position[0] - self.position_m[0],
                position[1] - self.position_m[1],
            ]
        } else {
            self.velocity.reset();
            [0.0; 2]
        };
        let velocity = self.velocity.update(position);
        self.report.position_m = position;
        self.report.velocity_m_per_s = velocity;
        self.report.force_n = self.force_n;
        self.report.estop = frame.estop;
        self.estop = frame.estop;
        let before = if consecutive {
            self.position_m
        } else {
            position
        };
        self.position_m = position;
        self.prev_position_m = before;
        if self.mode == Mode::Active
            && let Some(last) = self.last_tick
            && !consecutive
            && !(now > last
                && now.0 - last.0 - 1 <= u64::from(self.config.safety.max_consecutive_misses))
        {
            self.trip(
                now,
                TripReason::ClockSkip {
                    expected: last.next(),
                    got: now,
                },
            );
        }
        self.safety.observe_encoders(frame);
        self.safety
            .observe_clock(now, self.last_tick, self.mode == Mode::Active);
        if let Some(reason) = self.safety.check(frame, position, step, velocity) {
            self.trip(now, reason);
        }
        if self.mode == Mode::Configured {
            self.mode = Mode::Inactive;
        }
    }

    /// One active tick of perturbations, law and rendering; returns the command to write.
    fn update(&mut self, now: Tick) -> [f64; 2] {
        let start = *self.motion_start.get_or_insert(now);
        let k = now.0.saturating_sub(start.0);
        let pert = self
            .pulse
            .update(now, self.prev_position_m, self.position_m);
        if self.push.armed_trigger() == Some(PositionTrigger::NextZeroAcceleration) {
            match self.motion.next_zero_acceleration(k) {
                Some(kz) => self
                    .push
                    .retarget(PositionTrigger::AtTick(Tick(start.0 + kz))),
                // No zero-acceleration point left in the motion: nothing to fire.
                None => self.push.abort(),
            }
        }
        let p = self.push.update(now);
        let add = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| [a[0] + b[0] + c[0], a[1] + b[1] + c[1]];
        // The reference for this tick is the law's state at t_n (time-aligned with the
        // encoder reading); the input read now is then held over [t_n, t_n+1) to advance
        // the state to t_n+1 for the next tick.
        let (pos, vel, acc, anchor, wall) = match self.law {
            LawKind::Admittance => {
                let (pos, vel) = (self.admittance.position_m, self.admittance.velocity_m_per_s);
                let wall = self.safety.wall_force(pos, vel);
                let u = add(self.force_n, pert, wall);
                let acc = self.admittance.acceleration(u);
                self.admittance.step(u);
                (pos, vel, acc, pos, wall)
            }
            LawKind::VirtualSpring => {
                let axis = self.motion.axis().index();
                let h = self.rate.period_s();
                let along = |offset: f64| {
                    let mut p = self.center_m;
                    p[axis] += offset;
                    p
                };
                let on_axis = |v: f64| {
                    let mut p = [0.0; 2];
                    p[axis] = v;
                    p
                };
                let now_k = self.motion.at(k);
                let (a_now, v_now) = (along(now_k.position_m), on_axis(now_k.velocity_m_per_s));
                // The anchor is held over the tick at its mid-period value (second-order
                // accurate for the moving anchor; exact for a still one).
                let mid = self.motion.at_seconds((k as f64 + 0.5) * h);
                let (a_mid, v_mid) = (along(mid.position_m), on_axis(mid.velocity_m_per_s));
                let (pos, vel) = (self.spring.position_m, self.spring.velocity_m_per_s);
                let wall = self.safety.wall_force(pos, vel);
                let f = add(self.force_n, pert, wall);
                let acc = self.spring.acceleration(f, a_now, v_now);
                self.spring.step(f, a_mid, v_mid);
                (pos, vel, acc, a_now, wall)
            }
        };
        let ref_pos = [pos[0] + p[0].position_m, pos[1] + p[1].position_m];
        let ref_vel = [
            vel[0] + p[0].velocity_m_per_s,
            vel[1] + p[1].velocity_m_per_s,
        ];
        let ref_acc = [
            acc[0] + p[0].acceleration_m_per_s2,
            acc[1] + p[1].acceleration_m_per_s2,
        ];
        if now.0.is_multiple_of(self.divisor) {
            let cmd = self.renderer.command(
                ref_pos,
                ref_vel,
                ref_acc,
                self.position_m,
                self.report.velocity_m_per_s,
            );
            if let Some(reason) = SafetyMonitor::nonfinite_command(cmd) {
                // The law's state is broken: nothing it computes now can be sent.
                self.trip(now, reason);
                return [0.0; 2];
            }
            let (clamped, saturated) = self.safety.clamp(cmd);
            self.held_n = clamped;
            self.saturated = saturated;
            self.report.motor_update = true;
        }
        let r = &mut self.report;
        r.pert_force_n = pert;
        r.pert_position_m = [p[0].position_m, p[1].position_m];
        r.wall_force_n = wall;
        r.anchor_position_m = anchor;
        r.ref_position_m = ref_pos;
        r.ref_velocity_m_per_s = ref_vel;
        r.ref_acceleration_m_per_s2 = ref_acc;
        self.held_n
    }
}
