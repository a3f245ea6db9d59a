//! # rigtwin-device — the rig's own real-time code
//!
//! Everything in this crate runs on the real manipulandum at 4 kHz and, unchanged,
//! against the simulator. It never depends on the physics engine, the viewer, the arm
//! model or the runtime: the only way in and out is [`io::RigIo`], in rig units.
//!
//! ## Units and frames
//!
//! Units are SI throughout (m, s, N, kg) unless a name says otherwise; positions are in
//! the rig frame (origin at the workspace centre, `x` to the subject's right, `y` away
//! from the subject, horizontal plane). Angles of perturbations are radians from `+x`
//! toward `+y`. The hardware speaks encoder counts and the force sensor's raw reading
//! in its own frame; [`calib`] converts them (`F_rig = R (F_raw − offset)`). Forces
//! `force_n` are what the hand exerts on the handle. Time is the integer [`Tick`] of the
//! 4 kHz clock; the motor command is recomputed every `control_rate_hz /
//! motor_rate_hz` ticks (2 kHz) and held in between.
//!
//! ## The controller
//!
//! [`Controller::tick`] does read → update → write once per tick:
//!
//! ```text
//!  sensors ─▶ counts→m, calibrate force, filtered-difference velocity
//!          ─▶ safety checks (e-stop, I/O, non-finite/stale force, encoder jump,
//!             position, velocity, encoder stall, missed or
//!             too often late ticks)                      ── trip ─▶ Fault, zero force
//!          ─▶ perturbations: force pulse u_pert (000_* eq. 22-23),
//!             position offset p (001_*, min-snap transitions)
//!          ─▶ law, exact step for the held input:
//!               admittance    M ẍ_r + D ẋ_r = F + u_pert + F_wall      (000_* eq. 20)
//!               virtual spring M_e ẍ_e + B_e(ẋ_e − ẋ_a) + K_e(x_e − x_a) = F + …
//!                             anchored to the imposed sinusoid x_a     (001_* eq. 4)
//!          ─▶ render (motor ticks): F_cmd = m ẍ_ref + K_p e + K_d ė,
//!             non-finite ── trip ─▶ Fault, zero force; else clamped
//!          ─▶ write (the safety layer notes the command for the stall watchdog)
//! ```
//!
//! ## Lifecycle
//!
//! ```text
//!        Controller::new(config)
//!                 │
//!                 ▼
//!          ┌────────────┐ first tick  ┌──────────┐  activate()   ┌────────┐
//!          │ Configured │────────────▶│ Inactive │──────────────▶│ Active │
//!          │  0 force   │             │ 0 force  │◀──────────────│        │
//!          └────────────┘             └──────────┘  deactivate() └────────┘
//!                 │                     ▲      │                     │
//!                 │  trip     reset()   │      │ trip                │ trip
//!                 │      (e-stop off)   │      ▼                     │
//!                 │                   ┌──────────────────┐           │
//!                 └──────────────────▶│ Fault: 0 force,  │◀──────────┘
//!                                     │ latched          │
//!                                     └──────────────────┘
//! ```
//!
//! A trip is an e-stop, an I/O error, a non-finite or frozen force sensor, an encoder
//! jump, a velocity or position limit, a stalled encoder (a large command and not one
//! count of motion), a non-finite motor command, or (while active) a missed tick or too
//! many late ticks in a short window. The three watchdogs that look for a part gone
//! quiet (stale force, encoder stall, loop deadline) are on by default; a noiseless
//! simulated sensor, which repeats its readings legitimately, is run with
//! `safety.stale_force_ticks = 0` ([`config::SafetyConfig`]).
//!
//! `Configured`, `Inactive` and `Fault` command zero force; the safety layer watches in
//! every mode. A trip records a [`safety::SafetyEvent`] `{tick, reason}` in a
//! fixed-capacity log and the command written at that very tick is zero.
//!
//! ## Example
//!
//! ```
//! use rigtwin_device::perturb::force_pulse::PulseTrigger;
//! use rigtwin_device::testing::PointMassRig;
//! use rigtwin_device::{Controller, ControllerConfig, Mode, Rate, Tick};
//!
//! // Point-mass carts and a hand pushing 2 N along x; or world's SimRig, or a replay.
//! let mut rig = PointMassRig::new([4.0, 2.0], Rate::CONTROL);
//! rig.hand_force_n = [2.0, 0.0];
//! let mut ctl = Controller::new(ControllerConfig::default())?; // the Börner rig
//! ctl.tick(&mut rig, Tick(0)); // Configured → Inactive
//! ctl.activate()?;
//! ctl.arm_force_pulse(30f64.to_radians(), PulseTrigger::AtTick(Tick(100)))?;
//! for n in 1..=1000 {
//!     let report = ctl.tick(&mut rig, Tick(n));
//!     assert_eq!(report.mode, Mode::Active);
//! }
//! assert_eq!(ctl.force_pulse_status().onset(), Some(Tick(100)));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Real time
//!
//! `tick` never allocates, locks or does I/O beyond the [`RigIo`] calls; everything is
//! precomputed in [`Controller::new`] (discretizations, the pulse's closed form). A
//! counting-allocator test proves it.

pub mod admittance;
pub mod calib;
pub mod check;
pub mod config;
pub mod controller;
pub mod estimate;
pub mod io;
pub mod motion;
pub mod perturb;
pub mod render;
pub mod safety;
pub mod signal;
pub mod spring;
pub mod testing;
pub mod time;
pub mod velocity;

pub use config::{ConfigError, ControllerConfig, LawKind};
pub use controller::{Controller, LifecycleError, Mode, TickReport};
pub use io::{ErrorKind, MotorCommand, RigIo, RigIoError, SensorFrame};
pub use perturb::PerturbationStatus;
pub use time::{Rate, Tick};
