//! [`SimRig`]: the rapier2d-f64 plant behind the rig's [`RigIo`] boundary.
//!
//! See the crate docs for the bodies, joints and frames. The force sensor is read from
//! the momentum balance of the carts: over one tick the carts' momentum changes by the
//! impulses of the forces this module applies (motors, friction, end-stops) plus the
//! impulse that the handle transmits through the sensor, so
//! `F_sensor = (Σ mᵢ Δvᵢ)/dt − ΣF_applied` (x: both carts; y: upper cart, whose other
//! constraint, the y-rail, has no y component). This is the step-averaged force of the
//! handle–cart fixed joint, exact for rapier's integrator, and it contains the handle's
//! inertia as a real sensor does. rapier's own joint impulses are not used: in 0.36
//! they are the last substep's, so `impulse / (dt / substeps)` equals this reading with
//! one substep or at rest but not while the load changes within a substepped tick
//! (`tests/rigio.rs` measures up to 0.44 N apart with four substeps).

use nalgebra::Vector2;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rapier2d_f64::prelude::{
    GenericJointBuilder, ImpulseJointHandle, IntegrationParameters, JointAxesMask, LockedAxes,
    MassProperties, PhysicsWorld, RevoluteJointBuilder, RigidBodyBuilder, RigidBodyHandle, Vector,
};
use rigtwin_arm::dynamics::JointState;
use rigtwin_arm::kinematics::{self, Elbow};
use rigtwin_arm::params::ArmParams;
use rigtwin_device::{MotorCommand, Rate, RigIo, SensorFrame, Tick};

use crate::config::{Attachment, Grasp, GripCompliance, RigConfig};
use crate::effects::{DelayLine, SensorModel, cable_force_n, friction_force_n, ripple_force_n};
use crate::endstop::RailStops;
use crate::error::WorldError;

/// The control tick, s: the period of [`Rate::CONTROL`] (4 kHz, 000_* section 5.1).
pub const TICK_S: f64 = 1.0 / Rate::CONTROL.hz() as f64;

/// Rotational inertia given to the carts and the handle, kg m². Their rotation is
/// locked by the rails, so the value only conditions the solver.
const CART_INERTIA_KG_M2: f64 = 0.05;
const HANDLE_INERTIA_KG_M2: f64 = 1.0e-3;

/// The arm's two links in the rapier world.
#[derive(Debug, Clone)]
struct ArmLinks {
    params: Box<ArmParams>,
    shoulder_m: Vector2<f64>,
    upper: RigidBodyHandle,
    fore: RigidBodyHandle,
    pin: Option<ImpulseJointHandle>,
    grip: Option<GripCompliance>,
    /// Unwrapped joint angles at the last step, rad.
    q: [f64; 2],
    torque_nm: [f64; 2],
}

/// The Appendix B test mass in the rapier world.
#[derive(Debug, Clone, Copy)]
struct SpringMass {
    body: RigidBodyHandle,
    stiffness_n_per_m: [f64; 2],
    rest_m: [f64; 2],
}

/// Ground truth of the last step, for recording and tests. Forces in N, rig frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepTruth {
    /// Motor force that acted on each axis (after delay and ripple), N.
    pub motor_n: [f64; 2],
    /// Rail friction on the lower cart (x) and the upper cart (y), N.
    pub friction_n: [f64; 2],
    /// Cable carriers' pull on the lower cart (x) and the upper cart (y), N.
    pub cable_n: [f64; 2],
    /// End-stop force on the lower cart (x) and the upper cart (y), N.
    pub end_stop_n: [f64; 2],
    /// Force the handle exerted on the cart through the sensor (what an ideal sensor
    /// reads), N.
    pub sensor_n: [f64; 2],
    /// Force the hand (or the test mass) exerted on the handle, N.
    pub hand_on_handle_n: [f64; 2],
    /// Handle acceleration over the step, m/s².
    pub handle_acc_m_per_s2: [f64; 2],
}

/// The current loop's noise on both motors: white Gaussian noise through a first-order
/// low-pass, scaled so that its stationary RMS is the configured one and started from
/// its stationary distribution. Off (no draws) when the RMS is 0.
#[derive(Debug, Clone)]
struct MotorNoise {
    rng: Option<ChaCha8Rng>,
    /// `y += α (x − y)`.
    alpha: f64,
    /// Standard deviation of the white input giving the stationary RMS.
    input_sd: f64,
    rms: f64,
    state: [f64; 2],
}

impl MotorNoise {
    fn new(n: &crate::config::RigNuisance, dt_s: f64, rng: &mut ChaCha8Rng) -> MotorNoise {
        let alpha = 1.0 - (-2.0 * std::f64::consts::PI * n.motor_noise_bw_hz * dt_s).exp();
        // Stationary variance of y_{k+1} = (1 − α) y_k + α x_k with var x = s²:
        // α² s² / (1 − (1 − α)²) = α s² / (2 − α).
        let input_sd = n.motor_noise_rms_n * ((2.0 - alpha) / alpha).sqrt();
        let mut noise = MotorNoise {
            rng: (n.motor_noise_rms_n > 0.0).then(|| ChaCha8Rng::seed_from_u64(rng.next_u64())),
            alpha,
            input_sd,
            rms: n.motor_noise_rms_n,
            state: [0.0; 2],
        };
        if let Some(r) = &mut noise.rng {
            for s in &mut noise.state {
                let z: f64 = StandardNormal.sample(r);
                *s = noise.rms * z;
            }
        }
        noise
    }

    fn sample(&mut self) -> [f64; 2] {
        let Some(r) = &mut self.rng else {
            return [0.0; 2];
        };
        for s in &mut self.state {
            let z: f64 = StandardNormal.sample(r);
            *s += self.alpha * (self.input_sd * z - *s);
        }
        self.state
    }
}

/// The simulated manipulandum with its arm (or calibration rig).
pub struct SimRig {
    cfg: RigConfig,
    world: PhysicsWorld,
    lower: RigidBodyHandle,
    upper: RigidBodyHandle,
    handle: RigidBodyHandle,
    sensor_joint: ImpulseJointHandle,
    arm: Option<ArmLinks>,
    spring_mass: Option<SpringMass>,
    stops: [RailStops; 2],
    delay: DelayLine,
    sensor: SensorModel,
    rng: ChaCha8Rng,
    motor_noise: MotorNoise,
    tick: u64,
    command_n: [f64; 2],
    estop: bool,
    reading_n: [f64; 2],
    truth: StepTruth,
}

impl std::fmt::Debug for SimRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // rapier's PhysicsWorld has no Debug; show the state a person wants to see.
        f.debug_struct("SimRig")
            .field("tick", &self.tick)
            .field("handle_m", &self.handle_position_m())
            .field("command_n", &self.command_n)
            .field("reading_n", &self.reading_n)
            .field("arm", &self.arm)
            .finish_non_exhaustive()
    }
}

fn v(a: [f64; 2]) -> Vector {
    Vector::new(a[0], a[1])
}

/// Wrap an angle difference to (−π, π].
fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(2.0 * std::f64::consts::PI);
    if w > std::f64::consts::PI {
        w - 2.0 * std::f64::consts::PI
    } else {
        w
    }
}

/// A dynamic body at `pos` that never sleeps, with its mass and rotational inertia at
/// its origin.
fn dynamic_body(pos: [f64; 2], mass: f64, inertia: f64) -> RigidBodyBuilder {
    RigidBodyBuilder::dynamic()
        .translation(v(pos))
        .additional_mass_properties(MassProperties::new(Vector::ZERO, mass, inertia))
        .can_sleep(false)
}

/// The manipulandum's bodies on their rails: the fixed base, the lower (x) cart, the
/// upper (y) cart on it, and the handle on the force sensor.
struct Carriage {
    base: RigidBodyHandle,
    lower: RigidBodyHandle,
    upper: RigidBodyHandle,
    handle: RigidBodyHandle,
    sensor_joint: ImpulseJointHandle,
}

/// Builds the carriage with the handle at `cfg.initial_handle_m`.
fn carriage(world: &mut PhysicsWorld, cfg: &RigConfig) -> Carriage {
    let p0 = cfg.initial_handle_m;
    let base = world.bodies.insert(RigidBodyBuilder::fixed());
    // Carts and handle never rotate: the rails hold them. Their rotation is removed
    // as a body degree of freedom instead of by angular joint rows, which costs the
    // solver nothing (rapier's step time grows with every constraint row).
    let lower = world.bodies.insert(
        dynamic_body([p0[0], 0.0], cfg.lower_cart_mass_kg, CART_INERTIA_KG_M2)
            // x rail: the prismatic joint to the fixed base, as locked body axes.
            .locked_axes(LockedAxes::TRANSLATION_LOCKED_Y | LockedAxes::ROTATION_LOCKED),
    );
    let upper = world.bodies.insert(
        dynamic_body(p0, cfg.upper_cart_mass_kg, CART_INERTIA_KG_M2)
            .locked_axes(LockedAxes::ROTATION_LOCKED),
    );
    let handle_mass = cfg.handle_mass_kg + cfg.effects.handle_mass.map_or(0.0, |h| h.extra_mass_kg);
    let handle = world.bodies.insert(
        dynamic_body(p0, handle_mass, HANDLE_INERTIA_KG_M2)
            .locked_axes(LockedAxes::ROTATION_LOCKED),
    );
    // y rail: prismatic along y from the lower cart; its angular row is redundant
    // with the locked rotations, so only the x row remains.
    world.impulse_joints.insert(
        lower,
        upper,
        GenericJointBuilder::new(JointAxesMask::LIN_X).local_anchor2(Vector::new(0.0, -p0[1])),
        true,
    );
    // The force sensor: the handle fixed on the upper cart (translation rows; the
    // rotation row is again redundant).
    let sensor_joint = world.impulse_joints.insert(
        upper,
        handle,
        GenericJointBuilder::new(JointAxesMask::LIN_X | JointAxesMask::LIN_Y),
        true,
    );
    Carriage {
        base,
        lower,
        upper,
        handle,
        sensor_joint,
    }
}

/// The two-link arm: links at the posture that puts the hand at `p0` (elbow down),
/// jointed to the base at the shoulder and to each other, and held to the handle by a
/// pin (or, with a compliant `grip`, by the spring-damper the step applies).
///
/// # Errors
/// [`WorldError`] when the hand's start is out of the arm's reach.
fn attach_arm(
    world: &mut PhysicsWorld,
    c: &Carriage,
    p0: [f64; 2],
    shoulder_m: [f64; 2],
    params: &ArmParams,
    grasp: Grasp,
    grip: Option<GripCompliance>,
) -> Result<ArmLinks, WorldError> {
    let (base, handle) = (c.base, c.handle);
    let shoulder = Vector2::new(shoulder_m[0], shoulder_m[1]);
    let hand = Vector2::new(p0[0], p0[1]) - shoulder;
    let q = kinematics::inverse(params, hand, Elbow::Down)?;
    let elbow = shoulder + kinematics::elbow(params, q);
    let link = |origin: Vector2<f64>, angle: f64, seg: &rigtwin_arm::params::Segment| {
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(origin.x, origin.y))
            .rotation(angle)
            .additional_mass_properties(MassProperties::new(
                Vector::new(seg.com_m, 0.0),
                seg.mass_kg,
                seg.inertia_kg_m2,
            ))
            .can_sleep(false)
    };
    let ub = world.bodies.insert(link(shoulder, q[0], &params.upper));
    let fb = world.bodies.insert(link(elbow, q[0] + q[1], &params.fore));
    world.impulse_joints.insert(
        base,
        ub,
        RevoluteJointBuilder::new().local_anchor1(Vector::new(shoulder.x, shoulder.y)),
        true,
    );
    world.impulse_joints.insert(
        ub,
        fb,
        RevoluteJointBuilder::new().local_anchor1(Vector::new(params.upper.length_m, 0.0)),
        true,
    );
    let pin = if grasp == Grasp::Held && grip.is_none() {
        Some(world.impulse_joints.insert(
            fb,
            handle,
            RevoluteJointBuilder::new().local_anchor1(Vector::new(params.fore.length_m, 0.0)),
            true,
        ))
    } else {
        None
    };
    Ok(ArmLinks {
        params: Box::new(params.clone()),
        shoulder_m: shoulder,
        upper: ub,
        fore: fb,
        pin,
        grip: if grasp == Grasp::Held { grip } else { None },
        q,
        torque_nm: [0.0; 2],
    })
}

/// A point mass pinned to the handle, pulled towards `p0` by a spring.
fn attach_spring_mass(
    world: &mut PhysicsWorld,
    handle: RigidBodyHandle,
    p0: [f64; 2],
    mass_kg: f64,
    stiffness_n_per_m: [f64; 2],
) -> SpringMass {
    // A compact block: radius of gyration 3 cm.
    let body = world
        .bodies
        .insert(dynamic_body(p0, mass_kg, mass_kg * 0.03 * 0.03));
    world
        .impulse_joints
        .insert(handle, body, RevoluteJointBuilder::new(), true);
    SpringMass {
        body,
        stiffness_n_per_m,
        rest_m: p0,
    }
}

impl SimRig {
    /// Build the plant from `cfg`, with its random stream seeded by `rng`.
    pub fn new(cfg: RigConfig, rng: ChaCha8Rng) -> Result<SimRig, WorldError> {
        cfg.validate()?;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::ZERO;
        world.integration_parameters = integration_parameters(&cfg);
        // Bodies and joints are inserted in one fixed order (carriage, then what is
        // attached to the handle): rapier's handles, and so its results, follow it.
        let c = carriage(&mut world, &cfg);
        let p0 = cfg.initial_handle_m;
        let mut arm = None;
        let mut spring_mass = None;
        match &cfg.attachment {
            Attachment::Arm {
                shoulder_m,
                arm: params,
                grasp,
            } => {
                let effect = cfg.effects.grip_compliance;
                arm = Some(attach_arm(
                    &mut world,
                    &c,
                    p0,
                    *shoulder_m,
                    params,
                    *grasp,
                    effect,
                )?);
            }
            Attachment::SpringMass {
                mass_kg,
                stiffness_n_per_m,
            } => {
                spring_mass = Some(attach_spring_mass(
                    &mut world,
                    c.handle,
                    p0,
                    *mass_kg,
                    *stiffness_n_per_m,
                ));
            }
            Attachment::None => {}
        }
        let stops = [
            RailStops::new(
                0,
                cfg.rail_limits_m[0],
                cfg.end_stop_stiffness_n_per_m,
                cfg.end_stop_damping_n_s_per_m,
            ),
            RailStops::new(
                1,
                cfg.rail_limits_m[1],
                cfg.end_stop_stiffness_n_per_m,
                cfg.end_stop_damping_n_s_per_m,
            ),
        ];
        let delay_ticks = cfg
            .effects
            .actuation_delay
            .map_or(0, |d| (d.delay_ms * 1e-3 / TICK_S).round() as usize);
        let sensor = SensorModel::new(cfg.effects.sensor.as_ref(), TICK_S);
        let mut rng = rng;
        // The motor noise has its own stream, split off only when it is on, so that a
        // rig without it draws its sensor noise exactly as before.
        let motor_noise = MotorNoise::new(&cfg.nuisance, TICK_S, &mut rng);
        let mut rig = SimRig {
            world,
            lower: c.lower,
            upper: c.upper,
            handle: c.handle,
            sensor_joint: c.sensor_joint,
            arm,
            spring_mass,
            stops,
            delay: DelayLine::new(delay_ticks),
            sensor,
            rng,
            motor_noise,
            tick: 0,
            command_n: [0.0; 2],
            estop: false,
            reading_n: [0.0; 2],
            truth: StepTruth::default(),
            cfg,
        };
        rig.reading_n = rig.sample_sensor([0.0; 2]);
        Ok(rig)
    }

    /// A rig with the default configuration and the given seed.
    pub fn with_seed(cfg: RigConfig, seed: u64) -> Result<SimRig, WorldError> {
        SimRig::new(cfg, ChaCha8Rng::seed_from_u64(seed))
    }

    /// The configuration this rig was built from.
    #[must_use]
    pub fn config(&self) -> &RigConfig {
        &self.cfg
    }

    /// Ticks stepped since construction.
    #[must_use]
    pub fn tick(&self) -> Tick {
        Tick(self.tick)
    }

    /// Set the muscle torques at shoulder and elbow, N m, held until the next call.
    /// The shoulder torque acts between base and upper arm, the elbow torque between
    /// upper arm and forearm, each equal and opposite. Ignored without an arm.
    pub fn set_arm_torques(&mut self, torque_nm: [f64; 2]) -> Result<(), WorldError> {
        if !(torque_nm[0].is_finite() && torque_nm[1].is_finite()) {
            return Err(WorldError::NonFinite { what: "arm torque" });
        }
        if let Some(a) = &mut self.arm {
            a.torque_nm = torque_nm;
        }
        Ok(())
    }

    /// Press (`true`) or release the emergency-stop button.
    pub fn set_estop(&mut self, pressed: bool) {
        self.estop = pressed;
    }

    /// The hand lets go of the handle (no-op when already released or without an arm).
    pub fn release_hand(&mut self) {
        if let Some(a) = &mut self.arm {
            if let Some(pin) = a.pin.take() {
                self.world.impulse_joints.remove(pin, true);
            }
            a.grip = None;
        }
    }

    /// The motor command as last written, N.
    #[must_use]
    pub fn command_n(&self) -> [f64; 2] {
        self.command_n
    }

    /// Advance the plant by one 250 µs tick.
    pub fn step(&mut self) -> Result<(), WorldError> {
        let dt = TICK_S;
        let (lo_pos, lo_vel, up_pos, up_vel) = {
            let b = &self.world.bodies;
            let (lo, up) = (&b[self.lower], &b[self.upper]);
            (lo.translation(), lo.linvel(), up.translation(), up.linvel())
        };
        let handle_v0 = self.world.bodies[self.handle].linvel();
        let y_rel = up_pos.y - lo_pos.y;
        let y_rel_vel = up_vel.y - lo_vel.y;

        // Motor: delay, the force constant's tolerance and the current loop's noise,
        // then cogging by each cart's own rail position.
        let mut motor = self.delay.push(self.command_n);
        let noise = self.motor_noise.sample();
        for a in 0..2 {
            motor[a] = motor[a] * self.cfg.nuisance.motor_gain[a] + noise[a];
        }
        if let Some(r) = &self.cfg.effects.force_ripple {
            motor[0] += ripple_force_n(r, 0, lo_pos.x);
            motor[1] += ripple_force_n(r, 1, y_rel);
        }
        let friction = match &self.cfg.effects.rail_friction {
            Some(f) => [
                friction_force_n(f, lo_vel.x),
                friction_force_n(f, y_rel_vel),
            ],
            None => [0.0; 2],
        };
        let cable = match &self.cfg.effects.cable_spring {
            Some(c) => [cable_force_n(c, 0, lo_pos.x), cable_force_n(c, 1, y_rel)],
            None => [0.0; 2],
        };
        let stop = [
            self.stops[0].force_n(lo_pos.x, lo_vel.x),
            self.stops[1].force_n(y_rel, y_rel_vel),
        ];
        let fx = motor[0] + friction[0] + cable[0] + stop[0];
        let fy = motor[1] + friction[1] + cable[1] + stop[1];

        let bodies = &mut self.world.bodies;
        // The y motor, y friction and y stops act between the carts.
        let lo = &mut bodies[self.lower];
        lo.reset_forces(false);
        lo.add_force(Vector::new(fx, -fy), false);
        let up = &mut bodies[self.upper];
        up.reset_forces(false);
        up.add_force(Vector::new(0.0, fy), false);
        bodies[self.handle].reset_forces(false);

        if let Some(a) = &self.arm {
            let [t_s, t_e] = a.torque_nm;
            let ub = &mut bodies[a.upper];
            ub.reset_torques(false);
            ub.add_torque(t_s - t_e, false);
            let fb = &mut bodies[a.fore];
            fb.reset_forces(false);
            fb.reset_torques(false);
            fb.add_torque(t_e, false);
            if let Some(g) = &a.grip {
                let fb = &bodies[a.fore];
                let tip = fb
                    .position()
                    .transform_point(Vector::new(a.params.fore.length_m, 0.0));
                let tip_v = fb.velocity_at_point(tip);
                let h = &bodies[self.handle];
                let f_on_hand = (h.translation() - tip) * g.stiffness_n_per_m
                    + (h.linvel() - tip_v) * g.damping_n_s_per_m;
                bodies[a.fore].add_force_at_point(f_on_hand, tip, false);
                bodies[self.handle].add_force(-f_on_hand, false);
            }
        }
        if let Some(s) = &self.spring_mass {
            let b = &mut bodies[s.body];
            let p = b.translation();
            let f = Vector::new(
                -s.stiffness_n_per_m[0] * (p.x - s.rest_m[0]),
                -s.stiffness_n_per_m[1] * (p.y - s.rest_m[1]),
            );
            b.reset_forces(false);
            b.add_force(f, false);
        }

        self.world.step();
        self.tick += 1;

        let b = &self.world.bodies;
        let (lo, up, h) = (&b[self.lower], &b[self.upper], &b[self.handle]);
        let (dlo, dup) = (lo.linvel() - lo_vel, up.linvel() - up_vel);
        let sensor = [
            (lo.mass() * dlo.x + up.mass() * dup.x) / dt - fx,
            up.mass() * dup.y / dt - fy,
        ];
        let acc = (h.linvel() - handle_v0) / dt;
        let hand = [h.mass() * acc.x + sensor[0], h.mass() * acc.y + sensor[1]];
        if !(sensor[0].is_finite() && sensor[1].is_finite() && h.translation().is_finite()) {
            return Err(WorldError::Diverged { tick: self.tick });
        }
        self.truth = StepTruth {
            motor_n: motor,
            friction_n: friction,
            cable_n: cable,
            end_stop_n: stop,
            sensor_n: sensor,
            hand_on_handle_n: hand,
            handle_acc_m_per_s2: [acc.x, acc.y],
        };
        if let Some(a) = &mut self.arm {
            let (ua, fa) = (b[a.upper].rotation().angle(), b[a.fore].rotation().angle());
            let q0 = a.q[0] + wrap(ua - a.q[0]);
            let q1 = a.q[1] + wrap(fa - ua - a.q[1]);
            a.q = [q0, q1];
        }
        self.reading_n = self.sample_sensor(sensor);
        Ok(())
    }

    fn sample_sensor(&mut self, true_n: [f64; 2]) -> [f64; 2] {
        let mut r = self.sensor.sample(true_n);
        for (x, o) in r.iter_mut().zip(self.cfg.nuisance.sensor_offset_n) {
            *x += o;
        }
        if self.cfg.force_noise_rms_n > 0.0 {
            for x in &mut r {
                let z: f64 = StandardNormal.sample(&mut self.rng);
                *x += self.cfg.force_noise_rms_n * z;
            }
        }
        r
    }

    /// rapier's own linear impulses of the sensor joint after the last step, N s, in the
    /// joint frame (= rig axes here). Diagnostic only: in rapier 0.36 these are the last
    /// substep's accumulated impulses, so `impulse / (dt / substeps)` approximates the
    /// force only when the load is steady; the sensor reading does not use them
    /// (`tests/rigio.rs` compares the two).
    #[must_use]
    pub fn sensor_joint_impulses_n_s(&self) -> [f64; 2] {
        self.world
            .impulse_joints
            .get(self.sensor_joint)
            .map_or([0.0; 2], |j| [j.impulses[0], j.impulses[1]])
    }

    /// Ground truth of the last step.
    #[must_use]
    pub fn truth(&self) -> &StepTruth {
        &self.truth
    }

    /// The raw force-sensor reading that the next `read` returns, N (sensor frame).
    #[must_use]
    pub fn force_reading_n(&self) -> [f64; 2] {
        self.reading_n
    }

    /// True handle position, rig frame, m.
    #[must_use]
    pub fn handle_position_m(&self) -> Vector2<f64> {
        let p = self.world.bodies[self.handle].translation();
        Vector2::new(p.x, p.y)
    }

    /// True handle velocity, rig frame, m/s.
    #[must_use]
    pub fn handle_velocity_m_per_s(&self) -> Vector2<f64> {
        let p = self.world.bodies[self.handle].linvel();
        Vector2::new(p.x, p.y)
    }

    /// Lower-cart x and upper-cart y positions along their rails, m.
    #[must_use]
    pub fn cart_positions_m(&self) -> [f64; 2] {
        let b = &self.world.bodies;
        let (lo, up) = (b[self.lower].translation(), b[self.upper].translation());
        [lo.x, up.y - lo.y]
    }

    /// Lower-cart x and upper-cart y velocities along their rails, m/s.
    #[must_use]
    pub fn cart_velocities_m_per_s(&self) -> [f64; 2] {
        let b = &self.world.bodies;
        let (lo, up) = (b[self.lower].linvel(), b[self.upper].linvel());
        [lo.x, up.y - lo.y]
    }

    /// The arm's joint state from the rapier links (`None` without an arm): `q` unwrapped,
    /// rad; `qd` rad/s. The arm model's feedback reads this.
    #[must_use]
    pub fn arm_state(&self) -> Option<JointState> {
        self.arm.as_ref().map(|a| {
            let b = &self.world.bodies;
            let (wu, wf) = (b[a.upper].angvel(), b[a.fore].angvel());
            JointState {
                q: a.q,
                qd: [wu, wf - wu],
            }
        })
    }

    /// The arm's parameters and shoulder position in the rig frame, m.
    #[must_use]
    pub fn arm_params(&self) -> Option<(&ArmParams, Vector2<f64>)> {
        self.arm.as_ref().map(|a| (&*a.params, a.shoulder_m))
    }

    /// The hand position from the forearm link, rig frame, m.
    #[must_use]
    pub fn hand_position_m(&self) -> Option<Vector2<f64>> {
        self.arm.as_ref().map(|a| {
            let fb = &self.world.bodies[a.fore];
            let tip = fb
                .position()
                .transform_point(Vector::new(a.params.fore.length_m, 0.0));
            Vector2::new(tip.x, tip.y)
        })
    }

    /// Mass that moves with the handle along x and y when the carts are free and nothing
    /// is attached: `[m_lower + m_upper + m_handle, m_upper + m_handle]`, kg (handle
    /// including the `handle_mass` effect).
    #[must_use]
    pub fn carried_mass_kg(&self) -> [f64; 2] {
        let c = &self.cfg;
        let mh = c.handle_mass_kg + c.effects.handle_mass.map_or(0.0, |h| h.extra_mass_kg);
        [
            c.lower_cart_mass_kg + c.upper_cart_mass_kg + mh,
            c.upper_cart_mass_kg + mh,
        ]
    }

    /// The attached test mass, kg (spring-mass rig only).
    #[must_use]
    pub fn test_mass_kg(&self) -> Option<f64> {
        match &self.cfg.attachment {
            Attachment::SpringMass { mass_kg, .. } => Some(*mass_kg),
            _ => None,
        }
    }

    /// Encoder counts of the current cart positions: `floor(x / quantum)`, so the count
    /// changes exactly when the cart crosses a multiple of the quantum (an incremental
    /// encoder counts edges) and the quantisation error lies in `[0, quantum)`.
    #[must_use]
    pub fn encoder_counts(&self) -> [i64; 2] {
        let [x, y] = self.cart_positions_m();
        let q = self.cfg.encoder_quantum_m;
        // Positions are bounded by the rail stops, so the cast cannot saturate.
        [(x / q).floor() as i64, (y / q).floor() as i64]
    }
}

fn integration_parameters(cfg: &RigConfig) -> IntegrationParameters {
    IntegrationParameters {
        dt: TICK_S,
        num_solver_iterations: cfg.solver.substeps,
        num_internal_pgs_iterations: cfg.solver.pgs_iterations,
        num_internal_stabilization_iterations: cfg.solver.stabilization_iterations,
        warmstart_joints: cfg.solver.warmstart_joints,
        // No colliders take part in the step (end-stops are queried with parry
        // directly), but keep rapier's length tolerances far below the encoder quantum.
        normalized_allowed_linear_error: 1.0e-7,
        normalized_prediction_distance: 1.0e-6,
        max_ccd_substeps: 0,
        ..IntegrationParameters::default()
    }
}

impl RigIo for SimRig {
    type Error = WorldError;

    fn read(&mut self, _now: Tick) -> Result<SensorFrame, WorldError> {
        Ok(SensorFrame {
            encoder_counts: self.encoder_counts(),
            force_raw_n: self.reading_n,
            estop: self.estop,
        })
    }

    fn write(&mut self, _now: Tick, command: MotorCommand) -> Result<(), WorldError> {
        if !(command.force_n[0].is_finite() && command.force_n[1].is_finite()) {
            return Err(WorldError::NonFinite {
                what: "motor command",
            });
        }
        self.command_n = command.force_n;
        Ok(())
    }
}
