//! The same plant as [`crate::SimRig`] in closed form, for the accuracy tests and as the
//! speed yardstick of the benchmark.
//!
//! With a rigid grasp the carts, handle and arm form one closed chain with two degrees
//! of freedom. In the arm's joint coordinates `q`, with the carried mass
//! `M_c = diag(m_lower + m_upper + m_handle, m_upper + m_handle)` at the hand:
//!
//! ```text
//! (M(q) + Jᵀ M_c J) q̈ = τ − c(q, q̇) − Jᵀ M_c J̇ q̇ + Jᵀ F_motor
//! ```
//!
//! integrated with classical RK4 at the tick. The spring-mass rig and the bare handle are
//! linear per axis: `(M_c + m_s) ẍ = F_motor − K (x − x₀)`. The plant effects, rail
//! friction and end-stops are not part of this model.
//!
//! The force sensor follows from the handle's equation of motion:
//! `F_sensor = F_hand→handle − m_handle ẍ`, with `F_hand→handle = J⁻ᵀ (τ − M q̈ − c)`.

use nalgebra::{Matrix2, Vector2};
use rigtwin_arm::dynamics::{coriolis, mass_matrix};
use rigtwin_arm::kinematics::{self, Elbow};
use rigtwin_arm::params::ArmParams;

use crate::config::{Attachment, Grasp, RigConfig};
use crate::error::WorldError;
use crate::rig::TICK_S;

/// What the reduced model carries.
#[derive(Debug, Clone)]
enum Load {
    /// Rigid grasp; the state is the arm's joint state.
    Arm {
        params: Box<ArmParams>,
        shoulder_m: Vector2<f64>,
    },
    /// A mass on springs (or nothing, with zero mass and stiffness); the state is the
    /// handle position and velocity.
    Linear {
        mass_kg: f64,
        stiffness_n_per_m: [f64; 2],
        rest_m: Vector2<f64>,
    },
}

/// Closed-form reduced model of the rig.
#[derive(Debug, Clone)]
pub struct ReducedPlant {
    carried_kg: Vector2<f64>,
    handle_kg: f64,
    load: Load,
    /// Joint angles (arm) or handle position (linear), rad or m.
    x: Vector2<f64>,
    /// Their rates.
    xd: Vector2<f64>,
    sensor_n: Vector2<f64>,
}

/// State derivative and sensor force of the reduced model.
struct Eval {
    acc: Vector2<f64>,
    sensor_n: Vector2<f64>,
}

impl ReducedPlant {
    /// The reduced model of `cfg` (rigid grasp, spring-mass or bare handle; a released
    /// arm is modelled as the bare handle).
    pub fn new(cfg: &RigConfig) -> Result<ReducedPlant, WorldError> {
        cfg.validate()?;
        let handle_kg =
            cfg.handle_mass_kg + cfg.effects.handle_mass.map_or(0.0, |h| h.extra_mass_kg);
        let carried_kg = Vector2::new(
            cfg.lower_cart_mass_kg + cfg.upper_cart_mass_kg + handle_kg,
            cfg.upper_cart_mass_kg + handle_kg,
        );
        let p0 = Vector2::new(cfg.initial_handle_m[0], cfg.initial_handle_m[1]);
        let (load, x) = match &cfg.attachment {
            Attachment::Arm {
                shoulder_m,
                arm,
                grasp: Grasp::Held,
            } => {
                let s = Vector2::new(shoulder_m[0], shoulder_m[1]);
                let q = kinematics::inverse(arm, p0 - s, Elbow::Down)?;
                (
                    Load::Arm {
                        params: arm.clone(),
                        shoulder_m: s,
                    },
                    Vector2::new(q[0], q[1]),
                )
            }
            Attachment::SpringMass {
                mass_kg,
                stiffness_n_per_m,
            } => (
                Load::Linear {
                    mass_kg: *mass_kg,
                    stiffness_n_per_m: *stiffness_n_per_m,
                    rest_m: p0,
                },
                p0,
            ),
            Attachment::Arm {
                grasp: Grasp::Released,
                ..
            }
            | Attachment::None => (
                Load::Linear {
                    mass_kg: 0.0,
                    stiffness_n_per_m: [0.0; 2],
                    rest_m: p0,
                },
                p0,
            ),
        };
        Ok(ReducedPlant {
            carried_kg,
            handle_kg,
            load,
            x,
            xd: Vector2::zeros(),
            sensor_n: Vector2::zeros(),
        })
    }

    fn eval(
        &self,
        x: Vector2<f64>,
        xd: Vector2<f64>,
        motor_n: Vector2<f64>,
        tau: Vector2<f64>,
    ) -> Eval {
        match &self.load {
            Load::Arm { params, .. } => {
                let q = [x.x, x.y];
                let qd = [xd.x, xd.y];
                let j = kinematics::jacobian(params, q);
                let jd = kinematics::jacobian_dot(params, q, qd);
                let mc = Matrix2::from_diagonal(&self.carried_kg);
                let m = mass_matrix(params, q);
                let c = coriolis(params, q, qd);
                let jt = j.transpose();
                let lhs = m + jt * mc * j;
                let rhs = tau - c - jt * mc * (jd * xd) + jt * motor_n;
                let qdd = solve2(&lhs, &rhs);
                let hand_acc = j * qdd + jd * xd;
                let hand_on_handle = solve2(&jt, &(tau - m * qdd - c));
                Eval {
                    acc: qdd,
                    sensor_n: hand_on_handle - hand_acc * self.handle_kg,
                }
            }
            Load::Linear {
                mass_kg,
                stiffness_n_per_m,
                rest_m,
            } => {
                let spring = Vector2::new(
                    stiffness_n_per_m[0] * (x.x - rest_m.x),
                    stiffness_n_per_m[1] * (x.y - rest_m.y),
                );
                let total = self.carried_kg.add_scalar(*mass_kg);
                let acc = (motor_n - spring).component_div(&total);
                Eval {
                    acc,
                    sensor_n: -spring - acc * (*mass_kg + self.handle_kg),
                }
            }
        }
    }

    /// One RK4 step of one tick with motor forces (N) and joint torques (N m) held.
    pub fn step(&mut self, motor_n: [f64; 2], arm_torque_nm: [f64; 2]) {
        let (f, t) = (
            Vector2::new(motor_n[0], motor_n[1]),
            Vector2::new(arm_torque_nm[0], arm_torque_nm[1]),
        );
        let h = TICK_S;
        let (x, v) = (self.x, self.xd);
        let k1 = self.eval(x, v, f, t);
        let k2 = self.eval(x + v * (h / 2.0), v + k1.acc * (h / 2.0), f, t);
        let v2 = v + k1.acc * (h / 2.0);
        let v3 = v + k2.acc * (h / 2.0);
        let k3 = self.eval(x + v2 * (h / 2.0), v3, f, t);
        let v4 = v + k3.acc * h;
        let k4 = self.eval(x + v3 * h, v4, f, t);
        self.x = x + (v + v2 * 2.0 + v3 * 2.0 + v4) * (h / 6.0);
        self.xd = v + (k1.acc + k2.acc * 2.0 + k3.acc * 2.0 + k4.acc) * (h / 6.0);
        self.sensor_n = self.eval(self.x, self.xd, f, t).sensor_n;
    }

    /// Handle position, rig frame, m.
    #[must_use]
    pub fn handle_position_m(&self) -> Vector2<f64> {
        match &self.load {
            Load::Arm { params, shoulder_m } => {
                shoulder_m + kinematics::forward(params, [self.x.x, self.x.y])
            }
            Load::Linear { .. } => self.x,
        }
    }

    /// Handle velocity, rig frame, m/s.
    #[must_use]
    pub fn handle_velocity_m_per_s(&self) -> Vector2<f64> {
        match &self.load {
            Load::Arm { params, .. } => {
                kinematics::jacobian(params, [self.x.x, self.x.y]) * self.xd
            }
            Load::Linear { .. } => self.xd,
        }
    }

    /// Arm joint angles and rates, rad and rad/s (`None` without an arm).
    #[must_use]
    pub fn arm_state(&self) -> Option<([f64; 2], [f64; 2])> {
        match &self.load {
            Load::Arm { .. } => Some(([self.x.x, self.x.y], [self.xd.x, self.xd.y])),
            Load::Linear { .. } => None,
        }
    }

    /// Ideal force-sensor reading at the end of the last step, N.
    #[must_use]
    pub fn sensor_n(&self) -> [f64; 2] {
        [self.sensor_n.x, self.sensor_n.y]
    }
}

/// Solve a 2×2 system by Cramer's rule (the matrices here are positive definite or,
/// for Jᵀ, regular away from the straight-arm singularity).
fn solve2(a: &Matrix2<f64>, b: &Vector2<f64>) -> Vector2<f64> {
    let det = a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)];
    Vector2::new(
        (a[(1, 1)] * b.x - a[(0, 1)] * b.y) / det,
        (a[(0, 0)] * b.y - a[(1, 0)] * b.x) / det,
    )
}
