//! Shared test helpers: the arm coupled at the hand to a point-mass admittance, the
//! analytic stand-in for the world's rig (the arm crate must not depend on rapier).

#![allow(dead_code)]

use nalgebra::{Matrix2, Vector2};
use rigtwin_arm::dynamics::{JointState, coriolis, mass_matrix};
use rigtwin_arm::kinematics::{jacobian, jacobian_dot};
use rigtwin_arm::params::ArmParams;

/// Admittance felt at the hand: diagonal mass [kg] and damping [N s/m].
#[derive(Debug, Clone, Copy)]
pub struct Load {
    pub mass_kg: [f64; 2],
    pub damping_n_s_per_m: [f64; 2],
}

/// Joint acceleration of the arm whose hand drags `load` and feels an extra hand force
/// `f_ext` [N]: (M_q + Jᵀ M_a J) q̈ = τ − C q̇ − Jᵀ (M_a J̇ q̇ + D_a J q̇) + Jᵀ f_ext.
pub fn loaded_accel(
    p: &ArmParams,
    s: &JointState,
    tau: [f64; 2],
    load: &Load,
    f_ext: Vector2<f64>,
) -> Vector2<f64> {
    let j = jacobian(p, s.q);
    let jd = jacobian_dot(p, s.q, s.qd);
    let qd = Vector2::new(s.qd[0], s.qd[1]);
    let ma = Matrix2::new(load.mass_kg[0], 0.0, 0.0, load.mass_kg[1]);
    let da = Matrix2::new(
        load.damping_n_s_per_m[0],
        0.0,
        0.0,
        load.damping_n_s_per_m[1],
    );
    let m = mass_matrix(p, s.q) + j.transpose() * ma * j;
    let rhs = Vector2::new(tau[0], tau[1])
        - coriolis(p, s.q, s.qd)
        - j.transpose() * (ma * jd * qd + da * j * qd)
        + j.transpose() * f_ext;
    m.try_inverse().map_or(Vector2::zeros(), |mi| mi * rhs)
}

/// One RK4 step of the loaded arm with τ and f_ext held.
pub fn loaded_rk4(
    p: &ArmParams,
    s: &JointState,
    tau: [f64; 2],
    load: &Load,
    f_ext: Vector2<f64>,
    dt: f64,
) -> JointState {
    let f = |st: &JointState| {
        let a = loaded_accel(p, st, tau, load, f_ext);
        (st.qd, [a.x, a.y])
    };
    let add = |st: &JointState, d: &([f64; 2], [f64; 2]), h: f64| JointState {
        q: [st.q[0] + h * d.0[0], st.q[1] + h * d.0[1]],
        qd: [st.qd[0] + h * d.1[0], st.qd[1] + h * d.1[1]],
    };
    let k1 = f(s);
    let k2 = f(&add(s, &k1, dt / 2.0));
    let k3 = f(&add(s, &k2, dt / 2.0));
    let k4 = f(&add(s, &k3, dt));
    let c = |a: f64, b: f64, cc: f64, d: f64| dt / 6.0 * (a + 2.0 * b + 2.0 * cc + d);
    JointState {
        q: [
            s.q[0] + c(k1.0[0], k2.0[0], k3.0[0], k4.0[0]),
            s.q[1] + c(k1.0[1], k2.0[1], k3.0[1], k4.0[1]),
        ],
        qd: [
            s.qd[0] + c(k1.1[0], k2.1[0], k3.1[0], k4.1[0]),
            s.qd[1] + c(k1.1[1], k2.1[1], k3.1[1], k4.1[1]),
        ],
    }
}
