//! # rigtwin-world — the plant
//!
//! A rapier2d-f64 world of the Börner manipulandum (000_* section 5.1) and the arm or
//! calibration rig that holds its handle, behind the rig's own boundary:
//! [`SimRig`] implements [`rigtwin_device::RigIo`] in rig units (encoder counts, raw
//! force-sensor reading, e-stop; motor force commands). Beside `RigIo` the runtime
//! drives it with [`SimRig::set_arm_torques`] and [`SimRig::step`] (one 4 kHz tick) and
//! reads ground truth: [`SimRig::arm_state`], [`SimRig::handle_position_m`],
//! [`SimRig::handle_velocity_m_per_s`], [`SimRig::cart_positions_m`], [`SimRig::truth`]
//! (motor, friction, end-stop, true sensor and hand forces of the last tick).
//!
//! ## Frames and units
//!
//! SI, `f64`. Rig frame (recording spec): origin at the workspace centre, `x` to the
//! subject's right, `y` away from the subject, horizontal plane, so there is no gravity.
//! The shoulder frame has its origin at the shoulder and axes parallel to the rig frame;
//! `q[0]` is the upper arm's angle from `+x`, `q[1]` the elbow angle relative to it
//! (the arm crate's convention). Cart positions are those of the handle (the handle sits
//! on the upper cart's origin): the lower cart carries `x`, the upper cart `y`.
//!
//! ## Bodies
//!
//! | body | type | mass | pose at start |
//! |---|---|---|---|
//! | base | fixed | — | rig origin |
//! | lower cart | dynamic | 8 kg (**assumed**) | `(x₀, 0)` |
//! | upper cart | dynamic | 4 kg (**assumed**) | `(x₀, y₀)` |
//! | handle | dynamic | 0.35 kg (+ `handle_mass` effect) | `(x₀, y₀)` = `initial_handle_m` |
//! | upper arm | dynamic | segment mass, CoM, inertia of [`rigtwin_arm::params::ArmParams`] | origin at the shoulder, angle `q[0]` |
//! | forearm | dynamic | as above | origin at the elbow, angle `q[0] + q[1]` |
//! | test mass (Appendix B rig) | dynamic | 1.87 kg | at the handle |
//!
//! The arm starts in the elbow-down (human right arm) inverse-kinematics posture of the
//! initial handle position. All bodies have `can_sleep(false)`.
//!
//! ## Joints and forces
//!
//! | between | kind | role |
//! |---|---|---|
//! | base – lower cart | prismatic along `x`, as locked body axes (y, rotation) | x rail |
//! | lower cart – upper cart | prismatic along `y` (generic joint, x row) | y rail, riding the x rail |
//! | upper cart – handle | fixed (generic joint, x and y rows) | **the force sensor** |
//! | base – upper arm | revolute at the shoulder | shoulder; torque `τ₀` on the upper arm |
//! | upper arm – forearm | revolute at the elbow | elbow; `+τ₁` on the forearm, `−τ₁` on the upper arm |
//! | forearm – handle | revolute at the hand | rigid grasp (absent when released or with `grip_compliance`) |
//! | handle – test mass | revolute | Appendix B rig; springs `−K(p − p₀)` from the base on the mass |
//!
//! Motor force `x` acts on the lower cart; motor force `y` on the upper cart with its
//! reaction on the lower cart. Rail end-stops are parry2d boxes at `rail_limits_m`
//! ([`endstop`]); their rubber-bumper force is applied by this crate, not by rapier
//! contacts, so that the sensor accounting below knows it.
//!
//! **Force sensor.** The reading is the force the handle exerts on the upper cart
//! through the fixed joint, from the carts' momentum balance over the tick:
//! `F_x = (m_l Δv_lx + m_u Δv_ux)/dt − F_applied,x`, `F_y = m_u Δv_uy/dt − F_applied,y`.
//! It therefore contains the handle's inertia like a real sensor:
//! `F_sensor = F_hand→handle − m_handle · a`. rapier's own joint impulses are not used:
//! in 0.36 they are the last substep's, so they match only with one substep or at rest
//! ([`SimRig::sensor_joint_impulses_n_s`] exposes them for that comparison). `tests/accuracy.rs`
//! checks the reading against the arm's inverse dynamics through `J⁻ᵀ`.
//!
//! ## Plant effects ([`config::PlantEffects`], each off by default)
//!
//! | key | law | changes |
//! |---|---|---|
//! | `rail_friction { coulomb_n, viscous_n_s_per_m, smooth_velocity_m_per_s }` | `F = −(F_c tanh(v/v_s) + b v)` on each cart by its own rail velocity at the start of the tick | cart motion |
//! | `force_ripple { amplitude_n, pitch_m, phase_rad }` | additive cogging `A_i sin(2π q_i/pitch + φ_i)` on axis `i` by its cart's rail position `q_i`, whatever the command; amplitude and phase per axis (each motor its own magnet track), one pitch | motor force |
//! | `actuation_delay { delay_ms }` | motor force = command of `round(delay/250 µs)` ticks earlier (zero before) | motor force timing |
//! | `sensor { rotation_deg, offset_n, lowpass_hz }` | `raw = R(θ) · lowpass(F) + offset`; first-order lag, exact discretisation | the reading only |
//! | `handle_mass { extra_mass_kg }` | mass added to the handle, between sensor and hand | inertia the sensor sees |
//! | `grip_compliance { stiffness_n_per_m, damping_n_s_per_m }` | spring-damper between hand and handle instead of the pin | hand–handle coupling |
//! | `cable_spring { stiffness_n_per_m, rest_m }` | a cable carrier's pull `−k_i (q_i − rest_i)` on each cart by its rail position (not in the diagnosis's catalog) | cart motion |
//!
//! Also always present: encoder quantisation `floor(x / 1 µm)`, white Gaussian force
//! noise (0.05 N RMS by default) from the seeded [`rand_chacha::ChaCha8Rng`] passed in.
//!
//! ## Solver settings
//!
//! `dt` = 250 µs (one tick), 1 substep, 1 PGS and 1 stabilisation iteration, joint
//! warm-starting on: the cheapest settings with which every accuracy test passes with
//! margin (free arm 1.7e-4 rad over 1 s against a 1e-3 bound, first-order convergence;
//! sensor 0.01 % of range against 1 %). The allowed linear error is 1e-7 m (rapier's
//! 5 mm default is far above the encoder quantum); CCD is off and no collider takes part
//! in the step. Turning the stabilisation pass and joint warm-start off did not make the
//! step cheaper (`benches/plant.rs`: 7.2 µs against 5.5 µs, same run), so they stay on.
//!
//! Measured (`cargo bench -p rigtwin-world -- --warm-up-time 1 --measurement-time 3`, 2
//! shared cores, so ±50 % between runs under load): full plant step (arm torques, motor
//! command, rapier step, sensors) 5.5 µs quiet, 10 µs under load; the closed-form
//! [`ReducedPlant`] 0.66–1.2 µs, 8–9× faster.
//!
//! ## Reduced model
//!
//! [`ReducedPlant`] is the same plant in closed form (rigid grasp in joint coordinates,
//! spring-mass per axis), RK4 at the tick: the accuracy reference and the speed
//! yardstick of `benches/plant.rs`.

pub mod config;
pub mod effects;
pub mod endstop;
pub mod error;
pub mod reduced;
pub mod rig;

pub use config::{Attachment, Grasp, PlantEffects, RigConfig, RigNuisance, SolverConfig};
pub use error::WorldError;
pub use reduced::ReducedPlant;
pub use rig::{SimRig, StepTruth, TICK_S};
