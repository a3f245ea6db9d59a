//! rigtwin-arm: the simulated human arm holding the manipulandum.
//!
//! # Frames and units
//!
//! SI units and `f64` throughout; every public item states its unit. The **shoulder
//! frame** has its origin at the shoulder joint and axes parallel to the rig frame:
//! x to the subject's right, y away from the subject. `q[0]` is the shoulder angle of
//! the upper arm measured counter-clockwise from +x; `q[1]` is the elbow angle relative
//! to the upper arm (0 = straight, positive = flexion). The human right-arm posture is
//! [`kinematics::Elbow::Down`] (`q[1] > 0`, elbow out to the subject's right). Rig-frame
//! positions are shoulder-frame positions plus the shoulder position in the rig frame
//! ([`human::HumanConfig::shoulder_rig_m`]). Time is whole 4 kHz ticks ([`time`]).
//!
//! # Mechanics
//!
//! Two rigid links in the horizontal plane ([`dynamics`]): `M(q) q̈ + C(q, q̇) q̇ = τ`,
//! segments of Shadmehr & Mussa-Ivaldi (1994) by default, rescaled per subject by
//! [`params::Segment::scaled_to_length`] (CoM ∝ length, inertia ∝ length², mass kept).
//!
//! # Muscle model (000_* section 4, eq. 33–35)
//!
//! Six lumped muscles SF, SE, EF, EE, BF, BE with constant moment arms `A` \[m\]
//! (Selen, Franklin & Wolpert 2009). Length `l = l₀ − A q`; tension
//! `m = a + D_m ė + K_m e` with `e = −A (q − q_plan)` the stretch beyond the planned
//! length, `K_m = K₀ + K₁ a`, `D_m = K_m / 12`; joint torque `τ = Aᵀ m` ([`muscles`]).
//! Activations `a ≥ 0` \[N\] are feed-forward (inverse dynamics of a minimum-jerk plan
//! plus the force that moves the rig's admittance, split over the muscles with a
//! torque-free co-contraction), delayed PD feedback at muscle level (60 ms), optional
//! stretch reflex, and signal-dependent noise from a seeded ChaCha8 stream ([`human`],
//! [`noise`]).
//!
//! ## Chosen stiffness levels
//!
//! `K₀ = 450 N/m` (Katayama & Kawato's 810.8 N/m scaled by their/our moment arm ratio
//! squared), `K₁ = 100 /m`, co-contraction of 1.0 N m at the shoulder and 2.6 N m at the
//! elbow. During the default Börner reach this puts the intrinsic endpoint stiffness at
//! x₂ = 0.4 m within one standard deviation of Table 1 of 000_*: K ≈ [[128, −75],
//! [−75, 306]] N/m against [[110.5 ± 48.5, −106 ± 63], [·, 313.8 ± 77.5]] N/m. With the
//! seed's `D_m = K_m/12` the damping is `K/12` ≈ [[10.7, −6.2], [−6.2, 25.5]] N s/m,
//! which matches Table 1's D₁₁, D₁₂ but not its small D₂₂ (6.75 ± 4.27 N s/m);
//! [`muscles::MuscleParams::table1_damping`] lowers the elbow monoarticulars' damping
//! time to 10 ms and fits all of D (≈ [[10.7, −6.2], [−6.2, 8.3]] N s/m). The levels are
//! the parameters `co_contraction_n_m`, `stiffness_passive_n_per_m`,
//! `stiffness_per_activation_per_m`, `damping_time_s`, and the per-trial
//! [`human::HumanConfig::co_contraction_level`].
//!
//! # Ground truth
//!
//! [`impedance::endpoint_impedance`]: endpoint inertia `J⁻ᵀ M_q J⁻¹` and intrinsic
//! stiffness/damping `J⁻ᵀ Aᵀ diag(K_m) A J⁻¹`, without the geometric `∂Jᵀ/∂q · F` term.
//!
//! # Extensions (off by default)
//!
//! `stretch_reflex { delay_ms, gain_n_s_per_m }` and `stiffness_drift { scale_per_trial }`
//! in [`params::ArmParams`].

pub mod delay;
pub mod dynamics;
pub mod error;
pub mod human;
pub mod impedance;
pub mod kinematics;
pub mod muscles;
pub mod noise;
pub mod params;
pub mod plan;
pub mod time;

pub use error::ArmError;
pub use human::{Human, HumanConfig, Task};
