//! rigtwin-arm: the simulated human arm holding the manipulandum.
//!
//! # Frames and units
//!
//! SI units and `f64` throughout. The **shoulder frame** has its origin at the shoulder
//! joint and axes parallel to the rig frame: x to the subject's right, y away from the
//! subject. `q[0]` is the shoulder angle of the upper arm measured counter-clockwise
//! from +x; `q[1]` is the elbow angle relative to the upper arm (0 = straight, positive
//! = flexion). The human right-arm posture is [`kinematics::Elbow::Down`] (`q[1] > 0`).
//! Rig-frame positions are shoulder-frame positions plus the shoulder position in the
//! rig frame.
//!
//! # Modules
//!
//! - [`params`]: segments (Shadmehr & Mussa-Ivaldi 1994 by default) and their per-subject scaling.
//! - [`kinematics`]: forward/inverse kinematics, Jacobian and its derivative.
//! - [`dynamics`]: two-link rigid-body dynamics and an RK4 integrator.

pub mod dynamics;
pub mod error;
pub mod kinematics;
pub mod params;

pub use error::ArmError;
