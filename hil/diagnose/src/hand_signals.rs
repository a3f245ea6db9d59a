//! The variational response of the hand to each force pulse, from measured channels
//! only: what the hand balance ([`super::hand`]) is fitted to.
//!
//! For a perturbed trial, the response is the difference between the trial and a
//! reference of what it would have done unperturbed: the mean of the session's
//! unperturbed trials, each aligned at its own crossing of the perturbed trial's
//! position along the reach at the onset (the rig fires the pulse when the measured
//! position along the reach, `y` on the Börner rig, crosses a line, so this is the same
//! moment of the reach; the axis is the one the session's trials span more,
//! [`reach_axis`]; in a session of reaches in several directions, a centre-out task's
//! goals or reaches out and back, the references are the unperturbed trials of the
//! perturbed trial's own reach, [`reach_groups`], along the axis that reach travels
//! along more), and resampled at the perturbed trial's pace: a lab's
//! reaches vary in duration from trial to trial, and a reference that moves at the
//! session's mean pace differs from a faster or slower trial by a velocity and a force
//! that grow over the window, which the balance reads as a reflex's gain. With `κ` the
//! ratio of the trial's speed along the reach to the reference's at the crossing
//! ([`pace_ratio`]), the reference is read at `c + κ (i − k0)` and its velocities are
//! scaled by `κ`, its accelerations by `κ²`, and its hand force as the rig's admittance
//! renders a faster reach: the inertial part by `κ²`, the damping part by `κ`
//! ([`at_pace`]). The device's Börner estimator removes the nominal
//! movement with a high-pass instead and has no alignment to share; its smoothing
//! does not suit a balance either (it differentiates to jerk), so the channels here are
//! smoothed exactly like the cart balance's ([`super::signals`]: cubic Savitzky–Golay,
//! 41 ms, for the kinematics, and the forces through the balance filter, so that a
//! force and the acceleration it causes see the same filter at every frequency).
//!
//! Why the balance filter and not the derivative-0 Savitzky–Golay filter for the force:
//! with the latter, the two filters differ above their pass band, and the hand balance
//! reads that as inertia (an extra handle mass on sessions that hide none).
//!
//! The experiments behind the window, the weights and the odd parts:
//! `hil/docs/notes/2026-12-03-hand-balance-settings.md`.
//!
//! Per sample of the window: `Δx, Δv, Δa` of the handle, `ΔF_hand = Δ(F_sensor + m_h a)`
//! (the sensor is under the handle and reads `F_hand − m_h a`, `m_h` the manifest's
//! `device.handle_mass_kg`) and its rate `ΔḞ_hand`, and the arm's known matrices at the
//! handle position: the endpoint inertia `M_arm = J⁻ᵀ M(q) J⁻¹` and the shape
//! `S = J⁻ᵀ Aᵀ diag(w) A J⁻¹` that any muscle-space position or velocity feedback takes
//! at the hand in the odd part of opposite responses (`A` the moment arms, `w` the
//! muscles' [`odd_part_weights`]), from `rigtwin_arm` with the manifest's segment
//! lengths and shoulder.
//!
//! The window is [`HAND_WINDOW_S`] long from the onset, with [`HAND_LEAD_S`] of history
//! before it for the delayed terms.

use nalgebra::{Matrix2, Vector2};
use rigtwin_arm::dynamics::inverse_dynamics;
use rigtwin_arm::error::ArmError;
use rigtwin_arm::impedance::{endpoint_inertia, joint_to_endpoint};
use rigtwin_arm::kinematics::{Elbow, inverse, jacobian, jacobian_dot};
use rigtwin_arm::muscles::{MUSCLES, MuscleModel};
use rigtwin_arm::params::ArmParams;
use rigtwin_device::signal::{EdgeMode, gradient, savgol_filter};

use super::error::DiscrepancyError;
use super::signals::{
    EVALUATION_RATE_HZ, SMOOTHING_ORDER, filter_force, trial_balance_filter, window_for_rate,
};
use rigtwin_session::{Session, Trial, TrialEntry};

/// Length of the response window after the onset, s. The 150 ms pulse plus 150 ms:
/// the arm's delayed feedback (60 ms in the project's arm, up to ~120 ms in people)
/// answers the pulse within it, and a reflex of up to 50 ms acts twice over. Longer
/// windows add mostly the slow drift between a perturbed trial and its reference
/// (trial-to-trial variability of the reach grows with time since the alignment);
/// a shorter window misses reflexes, a longer one costs hidden masses their held-out
/// gain and puts more reflex delays at the grid's edge.
pub const HAND_WINDOW_S: f64 = 0.3;
/// History kept before the onset for the delayed terms, s (the longest feedback delay
/// of the search plus margin).
pub const HAND_LEAD_S: f64 = 0.13;

/// The arm's known geometry and inertia at the rig.
#[derive(Debug, Clone)]
pub struct HandArm {
    /// Arm parameters (the default arm with the subject's segment lengths and, in
    /// proportion to body mass, segment masses: [`ArmParams::of_subject`]).
    pub params: ArmParams,
    /// Shoulder, rig frame, m.
    pub shoulder_m: [f64; 2],
    /// `Aᵀ diag(w) A` with `w` the `odd_part_weights`, m² (joint space).
    pub ata: Matrix2<f64>,
    /// The arm's six muscles: their moment arms and the torque split that gives each
    /// its activation.
    pub muscles: MuscleModel,
}

impl HandArm {
    /// From the manifest's subject (default lengths and body mass where the manifest
    /// has none).
    ///
    /// # Errors
    /// [`DiscrepancyError::Model`] when the lengths or the body mass are not physical.
    pub fn from_session(session: &Session) -> Result<HandArm, DiscrepancyError> {
        let s = &session.manifest.subject;
        let err = |reason: String| DiscrepancyError::Model {
            path: session.dir.join("session.toml"),
            reason,
        };
        let params =
            ArmParams::of_subject(s.upper_arm_m, s.forearm_m, s.body_mass_kg).map_err(|e| {
                err(format!(
                    "subject.upper_arm_m / forearm_m / body_mass_kg: {e}"
                ))
            })?;
        HandArm::new(params, s.shoulder_m).map_err(|e| err(format!("arm muscles: {e}")))
    }

    /// The arm of `params` with its shoulder at `shoulder_m` (rig frame, m).
    ///
    /// # Errors
    /// [`ArmError`] when the muscles' parameters are not physical.
    pub fn new(params: ArmParams, shoulder_m: [f64; 2]) -> Result<HandArm, ArmError> {
        let model = MuscleModel::new(&params.muscles)?;
        Ok(HandArm {
            ata: model.to_joint(&odd_part_weights(&model)),
            muscles: model,
            params,
            shoulder_m,
        })
    }

    /// The arm at a handle position (rig frame); `None` out of reach or singular.
    #[must_use]
    pub fn at(&self, hand_rig_m: [f64; 2]) -> Option<ArmPosture> {
        let p = Vector2::new(
            hand_rig_m[0] - self.shoulder_m[0],
            hand_rig_m[1] - self.shoulder_m[1],
        );
        let q = inverse(&self.params, p, Elbow::Down).ok()?;
        Some(ArmPosture {
            m_arm: endpoint_inertia(&self.params, q).ok()?,
            s: joint_to_endpoint(&self.params, q, &self.ata).ok()?,
            jinv: jacobian(&self.params, q).try_inverse()?,
        })
    }

    /// The joint torque the muscles hold (shoulder, elbow), N m, for the hand at `x`
    /// (rig frame) moving at `v` and accelerating at `a` while it pushes the handle with
    /// `f`, N: `τ = Jᵀ f + M(q) q̈ + C(q, q̇) q̇`, the arm's rigid-body dynamics from the
    /// tables. `None` out of reach or singular.
    #[must_use]
    pub fn torque(
        &self,
        x: Vector2<f64>,
        v: Vector2<f64>,
        a: Vector2<f64>,
        f: Vector2<f64>,
    ) -> Option<Vector2<f64>> {
        let m = self.joint_motion(x, v, a)?;
        Some(m.j.transpose() * f + inverse_dynamics(&self.params, m.q, m.qd, m.qdd))
    }

    /// The force the hand pushes the handle with, N, at hand motion `x, v, a` while the
    /// muscles hold the joint torque `tau`: `J⁻ᵀ (τ − M(q) q̈ − C(q, q̇) q̇)`, the inverse
    /// of [`HandArm::torque`]. `None` out of reach or singular.
    #[must_use]
    pub fn hand_force(
        &self,
        x: Vector2<f64>,
        v: Vector2<f64>,
        a: Vector2<f64>,
        tau: Vector2<f64>,
    ) -> Option<Vector2<f64>> {
        let m = self.joint_motion(x, v, a)?;
        let rest = tau - inverse_dynamics(&self.params, m.q, m.qd, m.qdd);
        Some(m.j.transpose().try_inverse()? * rest)
    }

    /// `−∂F/∂x` and `−∂F/∂v` of [`HandArm::hand_force`] at the torque `tau` (central
    /// differences of 0.1 mm and 0.1 mm/s), N/m and N s/m: how the hand's force changes
    /// with its motion while the muscles hold their torque (the arm's turning geometry,
    /// its configuration-dependent inertia and its Coriolis and centripetal forces).
    #[must_use]
    pub fn held_torque_impedance(
        &self,
        x: Vector2<f64>,
        v: Vector2<f64>,
        a: Vector2<f64>,
        tau: Vector2<f64>,
    ) -> Option<[Matrix2<f64>; 2]> {
        const H: f64 = 1e-4;
        let mut out = [Matrix2::zeros(); 2];
        for k in 0..2 {
            let e = Vector2::ith(k, H);
            let dx = self.hand_force(x + e, v, a, tau)? - self.hand_force(x - e, v, a, tau)?;
            let dv = self.hand_force(x, v + e, a, tau)? - self.hand_force(x, v - e, a, tau)?;
            out[0].set_column(k, &(-dx / (2.0 * H)));
            out[1].set_column(k, &(-dv / (2.0 * H)));
        }
        Some(out)
    }

    /// The joint motion of a hand motion (position, velocity, acceleration).
    fn joint_motion(
        &self,
        x: Vector2<f64>,
        v: Vector2<f64>,
        a: Vector2<f64>,
    ) -> Option<JointMotion> {
        let p = Vector2::new(x[0] - self.shoulder_m[0], x[1] - self.shoulder_m[1]);
        let q = inverse(&self.params, p, Elbow::Down).ok()?;
        let j = jacobian(&self.params, q);
        let ji = j.try_inverse()?;
        let qd = ji * v;
        let qdd = ji * (a - jacobian_dot(&self.params, q, [qd[0], qd[1]]) * qd);
        Some(JointMotion {
            q,
            qd: [qd[0], qd[1]],
            qdd: [qdd[0], qdd[1]],
            j,
        })
    }

    /// Per muscle pair ([`MUSCLE_PAIRS`]), `J⁻ᵀ Aᵀ diag(a) A J⁻¹` at the hand, N, with `a`
    /// the pair's activations (the other muscles' zero) that the arm's torque split
    /// gives the joint torque `tau` over the co-contraction of level 1.
    #[must_use]
    pub fn pair_activation_shapes(
        &self,
        tau: Vector2<f64>,
        jinv: &Matrix2<f64>,
    ) -> [Matrix2<f64>; MUSCLE_PAIRS] {
        let act = self
            .muscles
            .split([tau[0], tau[1]], &self.muscles.co_contraction(1.0));
        std::array::from_fn(|p| {
            let w: [f64; MUSCLES] = std::array::from_fn(|i| if i / 2 == p { act[i] } else { 0.0 });
            jinv.transpose() * self.muscles.to_joint(&w) * jinv
        })
    }
}

/// The arm's joint angles, rates (rad, rad/s) and accelerations (rad/s²) and its
/// Jacobian (m/rad) for one hand motion.
struct JointMotion {
    q: [f64; 2],
    qd: [f64; 2],
    qdd: [f64; 2],
    j: Matrix2<f64>,
}

/// The arm's muscles in antagonist pairs, in its order: shoulder (SF, SE), elbow (EF,
/// EE), two-joint (BF, BE).
pub const MUSCLE_PAIRS: usize = 3;

/// What the hand balance takes from the arm's tables at one handle position.
#[derive(Debug, Clone, Copy)]
pub struct ArmPosture {
    /// Endpoint inertia `M_arm`, kg.
    pub m_arm: Matrix2<f64>,
    /// Feedback shape `S`, dimensionless.
    pub s: Matrix2<f64>,
    /// `J⁻¹` (joint angles per hand displacement), rad/m.
    pub jinv: Matrix2<f64>,
}

/// The weight of each muscle in the feedback shape `S`: 1 for a muscle the arm keeps
/// toned (positive in its co-contraction pattern), ½ for one it does not.
///
/// Why: a muscle's feedback and reflex change its activation, which cannot go below
/// zero. A toned muscle answers a stretch and a shortening alike; a muscle without tone
/// (the project's arm gives its biarticular muscles none, so the torque split leaves
/// them at or near zero) answers only its stretch, and half of that is the odd part
/// of the responses to opposite pulses ([`odd_parts`]), where the hand balance is
/// fitted. With every weight 1 the fitted reflex gain comes out low; with these weights
/// it centres on the truth.
#[must_use]
pub fn odd_part_weights(model: &MuscleModel) -> [f64; MUSCLES] {
    let co = model.co_contraction(1.0);
    std::array::from_fn(|i| if co[i] > 0.0 { 1.0 } else { 0.5 })
}

/// One perturbed trial's variational response. Vectors are local to the window:
/// index 0 is [`HAND_LEAD_S`] before the onset, `onset` the first sample at or after it.
#[derive(Debug, Clone)]
pub struct HandResponse {
    /// Trial id.
    pub id: u32,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Local index of the onset.
    pub onset: usize,
    /// Perturbation direction, degrees.
    pub angle_deg: f64,
    /// `Δx` of the handle per axis, m.
    pub dx: [Vec<f64>; 2],
    /// `Δv`, m/s.
    pub dv: [Vec<f64>; 2],
    /// `Δa`, m/s².
    pub da: [Vec<f64>; 2],
    /// `ΔF_hand`, N (force of the hand on the handle).
    pub df: [Vec<f64>; 2],
    /// `ΔḞ_hand`, N/s.
    pub dfd: [Vec<f64>; 2],
    /// Endpoint inertia of the arm at each sample, kg.
    pub m_arm: Vec<Matrix2<f64>>,
    /// Feedback shape `S` at each sample, dimensionless.
    pub s: Vec<Matrix2<f64>>,
    /// Per muscle pair ([`MUSCLE_PAIRS`]) and sample, how the pair's activation in the
    /// unperturbed movement shapes an impedance at the hand, less its mean over the
    /// window after the onset, N: [`HandArm::pair_activation_shapes`] of the joint torque
    /// the reference holds ([`HandArm::torque`] of its motion and hand force). A
    /// muscle's stiffness grows with its activation (`K_m = K₀ + K₁ a`), so a stiffness
    /// `κ_p` (1/m) per pair makes `κ_p` times this at the hand, N/m.
    pub activation: [Vec<Matrix2<f64>>; MUSCLE_PAIRS],
    /// Per sample, `−∂F_hand/∂x` (N/m) and `−∂F_hand/∂v` (N s/m) at the torque the
    /// reference holds ([`HandArm::held_torque_impedance`]), less their mean over the
    /// window after the onset.
    pub held: [Vec<Matrix2<f64>>; 2],
    /// Evaluated local indices (from the onset to the end of the window).
    pub rows: Vec<usize>,
    /// Unperturbed trials in the reference (summed over the averaged trials).
    pub references: usize,
    /// The perturbed trials averaged into this response (one unless
    /// `average_by_angle` merged repetitions).
    pub trials: Vec<u32>,
}

/// Fewest distinct pulse directions for which repetitions are averaged (and the folds
/// run over directions); with fewer, every trial is its own unit.
pub const MIN_ANGLES_TO_AVERAGE: usize = 6;

/// Averages the responses of repeated pulses in the same direction (a whole number of
/// degrees apart counts as the same): the balance is linear in every signal, so the
/// average obeys it too, while the arm's motor noise, which is independent between
/// repetitions and dominates a single response (hand-balance NRMSE 0.25 with noise,
/// 0.04 without, on the project's arm), drops by √n. Returns the responses unchanged
/// when they span fewer than [`MIN_ANGLES_TO_AVERAGE`] directions.
#[must_use]
pub fn average_by_angle(responses: Vec<HandResponse>) -> Vec<HandResponse> {
    let key = direction_key;
    let mut keys: Vec<i64> = responses.iter().map(key).collect();
    keys.sort_unstable();
    keys.dedup();
    if keys.len() < MIN_ANGLES_TO_AVERAGE
        || keys.len() == responses.len()
        || !same_shape(&responses)
    {
        return responses;
    }
    keys.iter()
        .filter_map(|k| {
            let group: Vec<&HandResponse> = responses.iter().filter(|r| key(r) == *k).collect();
            let first = *group.first()?;
            let w = 1.0 / group.len() as f64;
            let terms: Vec<(&HandResponse, f64, f64)> = group.iter().map(|r| (*r, w, w)).collect();
            Some(weighted_sum(first.angle_deg, &terms))
        })
        .collect()
}

/// A pulse direction in whole degrees, 0–359 (a whole number of degrees apart, or 360°
/// apart, is the same direction).
fn direction_key(r: &HandResponse) -> i64 {
    r.angle_deg.rem_euclid(360.0).round() as i64 % 360
}

/// Whether the responses share window length, onset and rate, so that they can be
/// combined sample by sample.
fn same_shape(responses: &[HandResponse]) -> bool {
    responses.windows(2).all(|w| {
        w[0].df[0].len() == w[1].df[0].len()
            && w[0].onset == w[1].onset
            && w[0].rate_hz == w[1].rate_hz
    })
}

/// Fewest pairs of opposite pulse directions for [`odd_parts`]; with fewer, the
/// responses are averaged by direction instead ([`average_by_angle`]). Four pairs are
/// four folds, the fewest whose t-test can still pass the family-wise critical value.
pub const MIN_OPPOSITE_PAIRS: usize = 4;

/// How [`odd_parts`] groups the repetitions of a pair of opposite directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OddUnits {
    /// One unit per pair of directions from the mean of every repetition: the least
    /// noise per unit, what the hand balance's gains and parameters are measured on.
    Averaged,
    /// One unit per repetition, the `i`-th response to `θ` with the `i`-th to
    /// `θ + 180°` (unmatched repetitions left out): independent units, what its
    /// significance is tested on.
    Replicates,
    /// `n` units per pair: the matched repetitions as in `Replicates`, the `i`-th in
    /// group `i mod n`, each group's mean ([`odd_groups`]).
    Groups(usize),
}

/// The odd part of the response to each pair of opposite pulse directions: per pair,
/// half the difference between the mean response to `θ` and the mean response to
/// `θ + 180°` (a whole number of degrees apart counts as the same direction).
///
/// The hand balance is linear, so its odd part obeys it; what the odd part removes:
///
/// - Everything even in the pulse: the terms of second order in the response. The
///   arm's tension `a + K(a)(e + τ ė)` has a stiffness that grows with activation, so
///   the feedback's and any reflex's activation change `Δa` multiplies `Δe + τ Δė`;
///   left in, these terms pull a reflex's fitted delay to the search's lower edge.
/// - The reference: every response subtracts the same mean of unperturbed trials, whose
///   own noise does not average out over directions but cancels in the difference.
///
/// The arm matrices are averaged over both directions (the unperturbed posture's, up to
/// the even terms). On reaches in several directions ([`reach_groups`]) the pairs
/// span the reaches: each response is already taken about its own reach, and when
/// every goal gets each direction equally often (a balanced centre-out design) the
/// even terms cancel in the means as on one reach, while each unit still averages
/// every repetition. Pairing within a goal instead leaves one repetition per unit,
/// whose fits the arm's motor noise biases (see [`odd_groups`]; measured in
/// `hil/docs/notes/2026-12-07-centre-out.md`). [`OddUnits`] says whether the repetitions are averaged first or
/// paired one by one. `None` with fewer than [`MIN_OPPOSITE_PAIRS`] pairs of
/// directions, or when the responses differ in shape.
#[must_use]
pub fn odd_parts(responses: &[HandResponse], units: OddUnits) -> Option<Vec<HandResponse>> {
    odd_parts_of(responses, units, MIN_OPPOSITE_PAIRS)
}

/// The odd parts of a session with at least one but fewer than [`MIN_OPPOSITE_PAIRS`]
/// pairs of opposite directions (a lab's four cardinal directions make two): too few
/// pairs to hold one out at a time, so each pair's matched repetitions (the `i`-th at
/// `θ` with the `i`-th at `θ + 180°`) are split into `n = ⌈MIN_OPPOSITE_PAIRS / pairs⌉`
/// groups, the `i`-th into group `i mod n` (so a drift over the session falls on every
/// group alike), and each group's mean responses give one odd part
/// ([`OddUnits::Groups`]). Averaging matters beyond the folds: the arm's motor noise
/// is in the hand force and moves the handle through the rig's admittance, so the
/// regressors carry the noise the target carries, and a fit on single responses is
/// biased (on single odd parts a handle's mass came out up to 25 % low and a reflex's
/// delay at 12–18 ms for 16–35 ms). The groups average as many repetitions as the
/// shared protocol's pairs do (three of six on four directions).
///
/// Returns the groups, the single odd parts (`OddUnits::Replicates`, what the
/// significance is tested on) and `n`; `None` with no pair, with
/// [`MIN_OPPOSITE_PAIRS`] pairs or more ([`odd_parts`] then), or when fewer than
/// [`MIN_OPPOSITE_PAIRS`] groups have a repetition.
#[must_use]
pub fn odd_groups(
    responses: &[HandResponse],
) -> Option<(Vec<HandResponse>, Vec<HandResponse>, usize)> {
    let singles = odd_parts_of(responses, OddUnits::Replicates, 1)?;
    let pairs = opposite_keys(responses).len();
    if pairs >= MIN_OPPOSITE_PAIRS {
        return None;
    }
    let n = MIN_OPPOSITE_PAIRS.div_ceil(pairs);
    let groups = odd_parts_of(responses, OddUnits::Groups(n), 1)?;
    (groups.len() >= MIN_OPPOSITE_PAIRS).then_some((groups, singles, n))
}

/// The directions below 180° (whole degrees) that have an opposite in `responses`.
fn opposite_keys(responses: &[HandResponse]) -> Vec<i64> {
    let key = direction_key;
    let mut keys: Vec<i64> = responses.iter().map(key).filter(|k| *k < 180).collect();
    keys.sort_unstable();
    keys.dedup();
    keys.retain(|k| responses.iter().any(|r| key(r) == k + 180));
    keys
}

/// [`odd_parts`] with at least `min_pairs` pairs of directions.
fn odd_parts_of(
    responses: &[HandResponse],
    units: OddUnits,
    min_pairs: usize,
) -> Option<Vec<HandResponse>> {
    let key = direction_key;
    if !same_shape(responses) {
        return None;
    }
    let keys = opposite_keys(responses);
    if keys.len() < min_pairs {
        return None;
    }
    let mut out = Vec::new();
    for &k in &keys {
        let a: Vec<&HandResponse> = responses.iter().filter(|r| key(r) == k).collect();
        let b: Vec<&HandResponse> = responses.iter().filter(|r| key(r) == k + 180).collect();
        match units {
            OddUnits::Averaged => out.push(odd_unit(k as f64, &a, &b)),
            OddUnits::Replicates => out.extend(
                a.iter()
                    .zip(&b)
                    .map(|(ra, rb)| odd_unit(k as f64, &[ra], &[rb])),
            ),
            OddUnits::Groups(n) => {
                for g in 0..n {
                    let (ga, gb): (Vec<&HandResponse>, Vec<&HandResponse>) = a
                        .iter()
                        .zip(&b)
                        .skip(g)
                        .step_by(n)
                        .map(|(ra, rb)| (*ra, *rb))
                        .unzip();
                    if !ga.is_empty() {
                        out.push(odd_unit(k as f64, &ga, &gb));
                    }
                }
            }
        }
    }
    Some(out)
}

/// Half the difference of the mean responses `a` (at `θ`) and `b` (at `θ + 180°`), both
/// non-empty and of one shape; the arm matrices are the mean over both.
fn odd_unit(angle_deg: f64, a: &[&HandResponse], b: &[&HandResponse]) -> HandResponse {
    // +1/(2 n_a) on θ, −1/(2 n_b) on θ + 180°; the matrices take 1/(2 n) on both.
    let (wa, wb) = (0.5 / a.len() as f64, 0.5 / b.len() as f64);
    let terms: Vec<(&HandResponse, f64, f64)> = a
        .iter()
        .map(|r| (*r, wa, wa))
        .chain(b.iter().map(|r| (*r, -wb, wb)))
        .collect();
    weighted_sum(angle_deg, &terms)
}

/// `Σ w r` over `terms = (r, w, w_matrices)`, all of one shape and at least one: the
/// signals weighted by `w`, the arm matrices by `w_matrices`; id, rate, onset and rows
/// of the first, the trials and reference counts of all.
fn weighted_sum(angle_deg: f64, terms: &[(&HandResponse, f64, f64)]) -> HandResponse {
    let first = terms[0].0;
    // The signals take the first weight, the arm's matrices the second.
    let sum = |f: &dyn Fn(&HandResponse) -> &Vec<f64>| weighted(terms, false, f);
    let sum_mat = |f: &dyn Fn(&HandResponse) -> &Vec<Matrix2<f64>>| weighted(terms, true, f);
    HandResponse {
        id: first.id,
        rate_hz: first.rate_hz,
        onset: first.onset,
        angle_deg,
        dx: [sum(&|r| &r.dx[0]), sum(&|r| &r.dx[1])],
        dv: [sum(&|r| &r.dv[0]), sum(&|r| &r.dv[1])],
        da: [sum(&|r| &r.da[0]), sum(&|r| &r.da[1])],
        df: [sum(&|r| &r.df[0]), sum(&|r| &r.df[1])],
        dfd: [sum(&|r| &r.dfd[0]), sum(&|r| &r.dfd[1])],
        m_arm: sum_mat(&|r| &r.m_arm),
        s: sum_mat(&|r| &r.s),
        activation: std::array::from_fn(|p| sum_mat(&|r| &r.activation[p])),
        held: std::array::from_fn(|k| sum_mat(&|r| &r.held[k])),
        rows: first.rows.clone(),
        references: terms.iter().map(|(r, _, _)| r.references).sum(),
        trials: terms
            .iter()
            .flat_map(|(r, _, _)| r.trials.clone())
            .collect(),
    }
}

/// `Σ w f(r)` sample by sample over `terms = (r, w, w_arm)`, with `w_arm` for `arm`.
fn weighted<T>(
    terms: &[(&HandResponse, f64, f64)],
    arm: bool,
    f: impl Fn(&HandResponse) -> &Vec<T>,
) -> Vec<T>
where
    T: Copy + Default + std::ops::Mul<f64, Output = T> + std::ops::AddAssign,
{
    let mut out = vec![T::default(); f(terms[0].0).len()];
    for (r, w, w_arm) in terms {
        let w = if arm { *w_arm } else { *w };
        for (o, v) in out.iter_mut().zip(f(r)) {
            *o += *v * w;
        }
    }
    out
}

/// One trial's smoothed channels.
struct Smoothed {
    /// The recorded position along the session's reach axis ([`reach_axis`]), m.
    along_raw: Vec<f64>,
    /// x, y, vx, vy, ax, ay, Fx, Fy (hand), Ḟx, Ḟy.
    ch: [Vec<f64>; 10],
}

fn smooth(
    entry: &TrialEntry,
    trial: &Trial,
    rate_hz: f64,
    handle_mass_kg: f64,
    axis: usize,
) -> Result<Smoothed, DiscrepancyError> {
    let window = window_for_rate(rate_hz);
    if trial.len() < 2 * window + 2 {
        return Err(DiscrepancyError::TrialTooShort {
            trial: entry.id,
            samples: trial.len(),
            window: 2 * window + 2,
        });
    }
    let dt = 1.0 / rate_hz;
    let sg = |x: &[f64], deriv: usize| {
        savgol_filter(x, window, SMOOTHING_ORDER, deriv, dt, EdgeMode::Interp).map_err(|source| {
            DiscrepancyError::Signal {
                trial: entry.id,
                source,
            }
        })
    };
    let taps = trial_balance_filter(window, dt, entry.id)?;
    let force = |x: &[f64]| filter_force(&taps, x, entry.id);
    let [ax, ay] = [sg(&trial.x_m, 2)?, sg(&trial.y_m, 2)?];
    let hand = |f: Vec<f64>, a: &[f64]| -> Vec<f64> {
        f.iter()
            .zip(a)
            .map(|(f, a)| f + handle_mass_kg * a)
            .collect()
    };
    let fx = hand(force(&trial.fx_n)?, &ax);
    let fy = hand(force(&trial.fy_n)?, &ay);
    // The rate of the filtered hand force by central differences: the filter passes
    // little above 30 Hz, where the difference is within 0.6 % of the derivative, and the
    // rate is then the one of the very signal the balance uses.
    let (fdx, fdy) = (gradient(&fx, dt), gradient(&fy, dt));
    Ok(Smoothed {
        along_raw: if axis == 0 {
            trial.x_m.clone()
        } else {
            trial.y_m.clone()
        },
        ch: [
            sg(&trial.x_m, 0)?,
            sg(&trial.y_m, 0)?,
            sg(&trial.x_m, 1)?,
            sg(&trial.y_m, 1)?,
            ax,
            ay,
            fx,
            fy,
            fdx,
            fdy,
        ],
    })
}

/// Linear interpolation of `x` at fractional index `t`; `None` outside.
fn interp(x: &[f64], t: f64) -> Option<f64> {
    if t.is_nan() || t < 0.0 || t > (x.len() - 1) as f64 {
        return None;
    }
    let k = t.floor() as usize;
    let w = t - k as f64;
    match x.get(k + 1) {
        Some(b) => Some(x[k] + w * (b - x[k])),
        None => Some(x[k]),
    }
}

/// The axis the session's reaches travel along, 0 for `x`, 1 for `y`: the one whose
/// position spans more, summed over the trials (ties to `y`, the Börner rig's). A rig
/// triggers its pulses on one axis's crossing of a line; that axis is the one the
/// reach travels along, and the references are aligned on it.
#[must_use]
pub fn reach_axis(session: &Session) -> usize {
    let span = |v: &[f64]| {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        if hi >= lo { hi - lo } else { 0.0 }
    };
    let (x, y) = session
        .trials
        .iter()
        .fold((0.0, 0.0), |(x, y), t| (x + span(&t.x_m), y + span(&t.y_m)));
    usize::from(x <= y)
}

/// Reaches whose directions lie within this angle of a reach's mean direction are
/// one reach (one goal of a centre-out task), degrees. A lab's reach scatters its
/// direction by a few degrees (the generator's end points by up to 5 mm over 0.2–0.25 m:
/// under 3°); centre-out goals lie 30° or more apart.
pub const SAME_REACH_DEG: f64 = 15.0;
/// Shortest way from a trial's first sample to the farthest it goes for it to be a
/// reach, m: shorter ones (a trial held in place) go to no reach.
pub const MIN_REACH_M: f64 = 0.02;

/// Which reach each of the session's trials made, in the order of [`Session::iter`]:
/// the direction of its way from its first recorded position to the recorded position
/// farthest from it, grouped with the first reach whose mean direction is within
/// [`SAME_REACH_DEG`] of it (`None` for a trial whose farthest point is nearer than
/// [`MIN_REACH_M`]). A one-way reach's farthest point is its end (an overshoot lies on
/// the same line); a trial that goes out and comes back in one recording (a
/// centre-out task that logs the return) is put in the reach of its way out. A
/// centre-out session gives one reach per goal, and reaches out and back logged as
/// separate trials give two. Returns the reach of each trial and the unit vector of
/// each reach's mean direction.
#[must_use]
pub fn reach_groups(session: &Session) -> (Vec<Option<usize>>, Vec<[f64; 2]>) {
    let cos_same = SAME_REACH_DEG.to_radians().cos();
    let mut sums: Vec<[f64; 2]> = Vec::new();
    let unit = |v: [f64; 2]| {
        let n = v[0].hypot(v[1]);
        [v[0] / n, v[1] / n]
    };
    let of_trial: Vec<Option<usize>> = session
        .iter()
        .map(|(_, t)| {
            let (x0, y0) = (*t.x_m.first()?, *t.y_m.first()?);
            let way = t
                .x_m
                .iter()
                .zip(&t.y_m)
                .map(|(x, y)| [x - x0, y - y0])
                .filter(|w| w[0].is_finite() && w[1].is_finite())
                .max_by(|a, b| a[0].hypot(a[1]).total_cmp(&b[0].hypot(b[1])))?;
            let length = way[0].hypot(way[1]);
            if !(length.is_finite() && length >= MIN_REACH_M) {
                return None;
            }
            let u = unit(way);
            let found = sums.iter().position(|s| {
                let m = unit(*s);
                m[0] * u[0] + m[1] * u[1] >= cos_same
            });
            let g = found.unwrap_or_else(|| {
                sums.push([0.0; 2]);
                sums.len() - 1
            });
            sums[g] = [sums[g][0] + u[0], sums[g][1] + u[1]];
            Some(g)
        })
        .collect();
    (of_trial, sums.into_iter().map(unit).collect())
}

/// First crossing of `level` by `y` in direction `dir` (sign of the rate), as a
/// fractional index.
fn crossing(y: &[f64], level: f64, dir: f64) -> Option<f64> {
    y.windows(2).enumerate().find_map(|(i, w)| {
        let (a, b) = (w[0] - level, w[1] - level);
        let rising = (b - a) * dir > 0.0;
        (rising && a * b <= 0.0 && a != b).then(|| i as f64 + a / (a - b))
    })
}

/// Range of the pace ratio `κ` a reference is resampled at (the perturbed trial's
/// speed over the reference's, both along the reach where they cross the onset's level). A
/// lab's reaches vary in duration by ±10–20 % (the generator's `movement_spread` is
/// 13 %); outside 0.7–1.4 the two reaches are not the same movement at another pace
/// and the ratio is held at the edge.
pub const PACE_RANGE: (f64, f64) = (0.7, 1.4);
/// Slowest speed along the reach at the crossing for which the pace ratio is taken, m/s.
/// Below it (an onset near a reach's start or end, where the speed is a few cm/s and
/// the ratio of two small numbers is noise) the reference keeps its own pace.
pub const PACE_MIN_SPEED_M_S: f64 = 0.05;

/// How fast the perturbed trial moves against a reference at the same point of the
/// reach: the ratio of their speeds along it, within [`PACE_RANGE`]; 1 when either is slower than
/// [`PACE_MIN_SPEED_M_S`] or they move in opposite directions.
#[must_use]
pub fn pace_ratio(v_trial_m_s: f64, v_reference_m_s: f64) -> f64 {
    let ratio = v_trial_m_s / v_reference_m_s;
    if v_trial_m_s.abs() < PACE_MIN_SPEED_M_S
        || v_reference_m_s.abs() < PACE_MIN_SPEED_M_S
        || !ratio.is_finite()
        || ratio <= 0.0
    {
        return 1.0;
    }
    ratio.clamp(PACE_RANGE.0, PACE_RANGE.1)
}

/// Channel `c` of [`Smoothed::ch`] of a reference resampled at pace `κ`, from the
/// reference's own channels at the resampled time (`read(ch)`; `None` outside it).
///
/// A reach run `κ` times faster, `x'(t) = x(κ t)`, has its velocities `κ` times and its
/// accelerations `κ²` times the reference's. Its hand force follows from the rig's
/// admittance `M a + D v = F_hand` (manifest `[device]`, per axis): the inertial part
/// scales with `κ²` and the damping part with `κ`, so
/// `F' = κ² F + (κ − κ²) D v` and, differentiated, `Ḟ' = κ³ Ḟ + (κ² − κ³) D a`. What the
/// admittance does not render (the rig's own errors) is scaled as inertia.
fn at_pace(
    c: usize,
    kappa: f64,
    damping_n_s_per_m: [f64; 2],
    read: impl Fn(usize) -> Option<f64>,
) -> Option<f64> {
    let k2 = kappa * kappa;
    Some(match c {
        0 | 1 => read(c)?,
        2 | 3 => kappa * read(c)?,
        4 | 5 => k2 * read(c)?,
        6 | 7 => k2 * read(c)? + (kappa - k2) * damping_n_s_per_m[c - 6] * read(c - 4)?,
        _ => k2 * kappa * read(c)? + (k2 - k2 * kappa) * damping_n_s_per_m[c - 8] * read(c - 4)?,
    })
}

/// Why a session's human side cannot be judged, or the responses.
#[derive(Debug)]
pub enum HandData {
    /// The responses of the perturbed trials, and how many reaches the session's
    /// trials make ([`reach_groups`]: 1 when every reach goes one way).
    Responses {
        /// One per perturbed trial with a whole response window.
        responses: Vec<HandResponse>,
        /// The reaches found over every trial, perturbed or not.
        reaches: usize,
    },
    /// Why not.
    Missing(String),
}

/// Fewest unperturbed trials for a reference, and perturbed trials for the folds.
pub const MIN_REFERENCES: usize = 2;
/// Fewest perturbed trials with a response.
pub const MIN_PERTURBED: usize = 8;

/// The variational responses of every perturbed trial of a session.
///
/// # Errors
/// A signal-processing error or unphysical subject lengths.
pub fn hand_responses(session: &Session, arm: &HandArm) -> Result<HandData, DiscrepancyError> {
    let rate = session.manifest.rate_hz;
    if !(rate.is_finite() && rate >= 200.0) {
        return Err(DiscrepancyError::RateTooLow { rate_hz: rate });
    }
    let m_h = session.manifest.device.handle_mass_kg.unwrap_or(0.0);
    // Each trial with the reach it made ([`reach_groups`]).
    let (reach_of, directions) = reach_groups(session);
    let trials: Vec<(&TrialEntry, &Trial, Option<usize>)> = session
        .iter()
        .zip(reach_of)
        .map(|((e, t), g)| (e, t, g))
        .collect();
    let has_pulse = |t: &Trial| t.pert_fx_n.iter().chain(&t.pert_fy_n).any(|v| *v != 0.0);
    let perturbed: Vec<&(&TrialEntry, &Trial, Option<usize>)> = trials
        .iter()
        .filter(|(e, t, _)| e.perturbation.is_some() && has_pulse(t))
        .collect();
    let unperturbed: Vec<&(&TrialEntry, &Trial, Option<usize>)> = trials
        .iter()
        .filter(|(e, t, _)| e.perturbation.is_none() && !has_pulse(t))
        .collect();
    if perturbed.len() < MIN_PERTURBED || unperturbed.len() < MIN_REFERENCES {
        return Ok(HandData::Missing(format!(
            "needs the response to force pulses: at least {MIN_PERTURBED} perturbed trials (with onset in \
             session.toml and the pulse in pert_fx_n, pert_fy_n) and {MIN_REFERENCES} unperturbed ones to \
             align a reference on; the session has {} and {}",
            perturbed.len(),
            unperturbed.len()
        )));
    }
    use rayon::prelude::*;
    // Each reach's references are its own unperturbed trials, aligned along the axis it
    // travels along more; with one reach, every unperturbed trial along the session's.
    let one_reach = directions.len() <= 1;
    let session_axis = reach_axis(session);
    let axis_of = |g: Option<usize>| match g.and_then(|g| directions.get(g)) {
        Some(u) if !one_reach => usize::from(u[0].abs() <= u[1].abs()),
        _ => session_axis,
    };
    let refs: Vec<(Option<usize>, Smoothed)> = unperturbed
        .par_iter()
        .map(|(e, t, g)| smooth(e, t, rate, m_h, axis_of(*g)).map(|s| (*g, s)))
        .collect::<Result<_, _>>()?;
    let damping = session.manifest.device.damping_n_s_per_m;
    let lead = (HAND_LEAD_S * rate).ceil() as usize;
    let len = (HAND_WINDOW_S * rate).round() as usize + 1;
    let decim = ((rate / EVALUATION_RATE_HZ).round() as usize).max(1);
    let half = window_for_rate(rate) / 2;
    let out: Vec<Option<HandResponse>> = perturbed
        .par_iter()
        .map(
            |(e, t, g)| -> Result<Option<HandResponse>, DiscrepancyError> {
                let Some(pert) = &e.perturbation else {
                    return Ok(None);
                };
                let g = *g;
                if !one_reach && g.is_none() {
                    return Ok(None);
                }
                let axis = axis_of(g);
                // The smoothed velocity along it.
                let speed = 2 + axis;
                let p = smooth(e, t, rate, m_h, axis)?;
                let t0 = t.t_s.first().copied().unwrap_or(0.0);
                let k0f = (pert.onset_s - t0) * rate;
                let k0 = k0f.ceil().max(0.0) as usize;
                if k0 < lead + half || k0 + len + half >= t.len() {
                    return Ok(None);
                }
                let Some(level) = interp(&p.along_raw, k0f) else {
                    return Ok(None);
                };
                let dir = p.ch[speed][k0].signum();
                let v_trial = interp(&p.ch[speed], k0f).unwrap_or(0.0);
                let n = lead + len;
                // Each reference: where it crosses the onset's level, and its pace ratio.
                // Sample `i` of the trial reads the reference at `c + κ (i − k0f)`.
                let aligned: Vec<(usize, f64, f64)> = refs
                    .iter()
                    .enumerate()
                    .filter(|(_, (rg, _))| one_reach || *rg == g)
                    .filter_map(|(u, (_, r))| crossing(&r.along_raw, level, dir).map(|c| (u, c)))
                    .map(|(u, c)| {
                        let kappa =
                            pace_ratio(v_trial, interp(&refs[u].1.ch[speed], c).unwrap_or(0.0));
                        (u, c, kappa)
                    })
                    .filter(|(u, c, kappa)| {
                        let last = refs[*u].1.along_raw.len() as f64 - 1.0;
                        let first = c - kappa * lead as f64;
                        first >= 0.0 && c + kappa * len as f64 <= last
                    })
                    .collect();
                if aligned.len() < MIN_REFERENCES {
                    return Ok(None);
                }
                let mut d: [Vec<f64>; 10] = std::array::from_fn(|_| vec![0.0; n]);
                // The reference's own acceleration and hand force (channels 4–7).
                let mut reference = vec![[0.0; 4]; n];
                for (c, dc) in d.iter_mut().enumerate() {
                    for (j, v) in dc.iter_mut().enumerate() {
                        let i = k0 - lead + j;
                        let at = i as f64 - k0f;
                        let mean = aligned
                            .iter()
                            .filter_map(|(u, cu, kappa)| {
                                let read = |ch: usize| interp(&refs[*u].1.ch[ch], cu + kappa * at);
                                at_pace(c, *kappa, damping, read)
                            })
                            .sum::<f64>()
                            / aligned.len() as f64;
                        *v = p.ch[c][i] - mean;
                        if (4..8).contains(&c) {
                            reference[j][c - 4] = mean;
                        }
                    }
                }
                let mut m_arm = Vec::with_capacity(n);
                let mut s = Vec::with_capacity(n);
                let mut activation: [Vec<Matrix2<f64>>; MUSCLE_PAIRS] =
                    std::array::from_fn(|_| Vec::with_capacity(n));
                let mut held: [Vec<Matrix2<f64>>; 2] =
                    std::array::from_fn(|_| Vec::with_capacity(n));
                for (j, rf) in reference.iter().enumerate() {
                    let i = k0 - lead + j;
                    let Some(ArmPosture {
                        m_arm: m,
                        s: sh,
                        jinv: ji,
                        ..
                    }) = arm.at([p.ch[0][i], p.ch[1][i]])
                    else {
                        return Ok(None);
                    };
                    // The reference's own motion and hand force at this sample.
                    let x = Vector2::new(p.ch[0][i] - d[0][j], p.ch[1][i] - d[1][j]);
                    let v = Vector2::new(p.ch[2][i] - d[2][j], p.ch[3][i] - d[3][j]);
                    let a = Vector2::new(rf[0], rf[1]);
                    let f = Vector2::new(rf[2], rf[3]);
                    let Some(tau) = arm.torque(x, v, a, f) else {
                        return Ok(None);
                    };
                    let Some(g) = arm.held_torque_impedance(x, v, a, tau) else {
                        return Ok(None);
                    };
                    for (out, shape) in activation
                        .iter_mut()
                        .zip(arm.pair_activation_shapes(tau, &ji))
                    {
                        out.push(shape);
                    }
                    for (out, g) in held.iter_mut().zip(g) {
                        out.push(g);
                    }
                    m_arm.push(m);
                    s.push(sh);
                }
                for series in activation.iter_mut().chain(held.iter_mut()) {
                    let mean = series[lead..].iter().sum::<Matrix2<f64>>() / (n - lead) as f64;
                    series.iter_mut().for_each(|e| *e -= mean);
                }
                let [x, y, vx, vy, ax, ay, fx, fy, fdx, fdy] = d;
                Ok(Some(HandResponse {
                    id: e.id,
                    rate_hz: rate,
                    onset: lead,
                    angle_deg: pert.angle_deg,
                    dx: [x, y],
                    dv: [vx, vy],
                    da: [ax, ay],
                    df: [fx, fy],
                    dfd: [fdx, fdy],
                    m_arm,
                    s,
                    activation,
                    held,
                    rows: (lead..n).step_by(decim).collect(),
                    references: aligned.len(),
                    trials: vec![e.id],
                }))
            },
        )
        .collect::<Result<_, _>>()?;
    let responses: Vec<HandResponse> = out.into_iter().flatten().collect();
    if responses.len() < MIN_PERTURBED {
        return Ok(HandData::Missing(format!(
            "only {} perturbed trials have a whole response window ({} s after the onset, {} s before) and \
             at least {MIN_REFERENCES} unperturbed trials crossing the same point of the reach; needs {MIN_PERTURBED}",
            responses.len(),
            HAND_WINDOW_S,
            HAND_LEAD_S
        )));
    }
    Ok(HandData::Responses {
        responses,
        reaches: directions.len(),
    })
}

/// Value of a local vector at `j − lag` samples (fractional lag, linear interpolation).
#[must_use]
pub fn lagged(x: &[f64], j: usize, lag: f64) -> f64 {
    interp(x, j as f64 - lag).unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pace_ratio_is_the_speed_ratio_within_its_range() {
        // A trial 10 % faster than its reference: κ = 1.1 (exact to rounding).
        assert!((pace_ratio(0.33, 0.30) - 1.1).abs() < 1e-12);
        assert!((pace_ratio(-0.27, -0.30) - 0.9).abs() < 1e-12);
        // Twice as fast or half as fast is not the same reach: held at the range's edge.
        assert_eq!(pace_ratio(0.6, 0.3), PACE_RANGE.1);
        assert_eq!(pace_ratio(0.1, 0.3), PACE_RANGE.0);
        // Too slow to compare, opposite directions or no speed at all: its own pace.
        assert_eq!(pace_ratio(0.04, 0.3), 1.0);
        assert_eq!(pace_ratio(0.3, -0.3), 1.0);
        assert_eq!(pace_ratio(0.3, 0.0), 1.0);
    }

    #[test]
    fn a_reference_at_another_pace_is_resampled_to_the_trial() {
        // The same reach y(t) = sin(ω t) at two paces: the trial at ω, the reference at
        // ω / κ. Read at c + κ (i − k0) (its velocity scaled by κ), the reference's
        // position and velocity equal the trial's, to the linear interpolation's error.
        let rate = 1000.0;
        let omega = 3.0;
        let kappa = 1.15;
        let n = 2000;
        let trial_y: Vec<f64> = (0..n).map(|i| (omega * i as f64 / rate).sin()).collect();
        let trial_v: Vec<f64> = (0..n)
            .map(|i| omega * (omega * i as f64 / rate).cos())
            .collect();
        let w = omega / kappa;
        let ref_y: Vec<f64> = (0..n).map(|i| (w * i as f64 / rate).sin()).collect();
        let ref_v: Vec<f64> = (0..n).map(|i| w * (w * i as f64 / rate).cos()).collect();
        let k0 = 100.0;
        let level = trial_y[100];
        let c = crossing(&ref_y, level, 1.0).unwrap_or(f64::NAN);
        let found = pace_ratio(trial_v[100], interp(&ref_v, c).unwrap_or(0.0));
        assert!((found - kappa).abs() < 1e-3, "κ {found}");
        for i in [100usize, 200, 300, 400] {
            let at = c + found * (i as f64 - k0);
            let y = interp(&ref_y, at).unwrap_or(f64::NAN);
            let v = interp(&ref_v, at).unwrap_or(f64::NAN) * found;
            // 1e-4 of a unit-amplitude sine: the interpolation's error and κ's 1e-3.
            assert!(
                (y - trial_y[i]).abs() < 1e-3,
                "y at {i}: {y} against {}",
                trial_y[i]
            );
            assert!(
                (v - trial_v[i]).abs() < 3e-3 * omega,
                "v at {i}: {v} against {}",
                trial_v[i]
            );
        }
    }

    #[test]
    fn a_faster_reach_under_the_admittance_needs_the_force_at_pace() {
        // A reach x(t) = sin(ω t) on an admittance M a + D v = F, and the same reach κ
        // times faster. The hand force the faster one needs, M κ² a + D κ v, and its
        // rate, from the reference's channels at the resampled time: exact (the same
        // algebra), to rounding.
        let (m, d, omega, kappa) = (5.0, 15.0, 4.0, 1.2);
        let t = 0.3_f64;
        let (x, v, a, j) = (
            (omega * t).sin(),
            omega * (omega * t).cos(),
            -omega * omega * (omega * t).sin(),
            -omega.powi(3) * (omega * t).cos(),
        );
        let ch = [
            x,
            x,
            v,
            v,
            a,
            a,
            m * a + d * v,
            m * a + d * v,
            m * j + d * a,
            m * j + d * a,
        ];
        let read = |c: usize| Some(ch[c]);
        let want = [
            x,
            x,
            kappa * v,
            kappa * v,
            kappa * kappa * a,
            kappa * kappa * a,
            m * kappa * kappa * a + d * kappa * v,
            m * kappa * kappa * a + d * kappa * v,
            m * kappa.powi(3) * j + d * kappa * kappa * a,
            m * kappa.powi(3) * j + d * kappa * kappa * a,
        ];
        for (c, w) in want.iter().enumerate() {
            let got = at_pace(c, kappa, [d, d], read).unwrap_or(f64::NAN);
            assert!(
                (got - w).abs() < 1e-9 * (1.0 + w.abs()),
                "channel {c}: {got} against {w}"
            );
        }
        // Outside the reference: nothing.
        assert!(at_pace(6, kappa, [d, d], |c| (c == 6).then_some(1.0)).is_none());
    }

    #[test]
    fn crossing_is_interpolated_and_directed() {
        let y = [0.0, 1.0, 2.0, 1.0, 0.0];
        // Rising through 1.5 between samples 1 and 2; falling between 2 and 3.
        assert!((crossing(&y, 1.5, 1.0).unwrap_or(f64::NAN) - 1.5).abs() < 1e-12);
        assert!((crossing(&y, 1.5, -1.0).unwrap_or(f64::NAN) - 2.5).abs() < 1e-12);
        assert!(crossing(&y, 3.0, 1.0).is_none());
    }

    fn response(id: u32, angle_deg: f64, value: f64) -> HandResponse {
        let v = vec![value; 4];
        HandResponse {
            id,
            rate_hz: 1000.0,
            onset: 1,
            angle_deg,
            dx: [v.clone(), v.clone()],
            dv: [v.clone(), v.clone()],
            da: [v.clone(), v.clone()],
            df: [v.clone(), v.clone()],
            dfd: [v.clone(), v],
            m_arm: vec![Matrix2::identity() * value; 4],
            s: vec![Matrix2::identity(); 4],
            activation: std::array::from_fn(|_| vec![Matrix2::identity() * value; 4]),
            held: std::array::from_fn(|_| vec![Matrix2::identity() * value; 4]),
            rows: vec![1, 2, 3],
            references: 2,
            trials: vec![id],
        }
    }

    /// Repetitions of a direction become their mean (the balance is linear, so the mean
    /// obeys it); with fewer directions than the threshold nothing is merged.
    #[test]
    fn repetitions_of_a_direction_are_averaged() {
        let mut rs = Vec::new();
        for k in 0..MIN_ANGLES_TO_AVERAGE {
            let angle = 30.0 + 45.0 * k as f64;
            rs.push(response(2 * k as u32, angle, 1.0));
            rs.push(response(2 * k as u32 + 1, angle + 360.0, 3.0));
        }
        let avg = average_by_angle(rs.clone());
        assert_eq!(avg.len(), MIN_ANGLES_TO_AVERAGE);
        for a in &avg {
            assert_eq!(a.trials.len(), 2);
            assert_eq!(a.references, 4);
            // Mean of 1 and 3, exactly representable.
            assert!(a.df[1].iter().all(|v| *v == 2.0));
            assert!(a.m_arm.iter().all(|m| m[(0, 0)] == 2.0 && m[(0, 1)] == 0.0));
        }
        let few: Vec<HandResponse> = rs.into_iter().take(4).collect();
        assert_eq!(average_by_angle(few).len(), 4);
    }

    /// A response `±L + Q` (odd part `L` flipping with the pulse, even part `Q` not)
    /// gives back exactly `L`, whatever `Q` and however many repetitions each side has;
    /// 359.6° and 180° count as opposite to 0°; fewer than [`MIN_OPPOSITE_PAIRS`] pairs
    /// give `None`.
    #[test]
    fn opposite_pulses_keep_the_odd_part_only() {
        let (odd, even) = (1.5, 4.0);
        let mut rs = Vec::new();
        for k in 0..MIN_OPPOSITE_PAIRS {
            let angle = 45.0 * k as f64;
            let id = 10 * k as u32;
            // Two repetitions on one side (one written as θ − 0.4°), one on the other.
            rs.push(response(id, angle, even + odd));
            rs.push(response(id + 1, angle - 0.4, even + odd));
            rs.push(response(id + 2, angle + 180.0, even - odd));
        }
        let Some(units) = odd_parts(&rs, OddUnits::Averaged) else {
            panic!("{MIN_OPPOSITE_PAIRS} opposite pairs are enough");
        };
        assert_eq!(units.len(), MIN_OPPOSITE_PAIRS);
        for u in &units {
            assert_eq!(u.trials.len(), 3);
            assert!(u.angle_deg < 180.0);
            for ch in [&u.dx, &u.dv, &u.da, &u.df, &u.dfd] {
                assert!(ch.iter().flatten().all(|v| (v - odd).abs() < 1e-12));
            }
            // The matrices: the mean over both sides, (2 (Q + L) / 2 + (Q − L)) / 2 = Q.
            assert!(u.m_arm.iter().all(|m| (m[(0, 0)] - even).abs() < 1e-12));
        }
        // One replicate per pair (the second repetition at θ has no partner), the same value.
        let Some(reps) = odd_parts(&rs, OddUnits::Replicates) else {
            panic!("the same pairs make replicates");
        };
        assert_eq!(reps.len(), MIN_OPPOSITE_PAIRS);
        assert!(
            reps.iter()
                .all(|u| u.trials.len() == 2 && u.df[0][0] == odd)
        );
        let unpaired: Vec<HandResponse> = rs.iter().filter(|r| r.id % 10 != 2).cloned().collect();
        assert!(odd_parts(&unpaired, OddUnits::Averaged).is_none());
        let few: Vec<HandResponse> = rs.into_iter().skip(3).collect();
        assert!(odd_parts(&few, OddUnits::Replicates).is_none());
    }

    /// Four cardinal directions (two opposite pairs, too few for `odd_parts`), `reps`
    /// repetitions each, the `i`-th at `θ` `even + odd + i` and at `θ + 180°`
    /// `even − odd − i`: two groups per pair, the `i`-th repetition in group `i mod 2`,
    /// so each group's odd part is `odd` plus the mean of its `i`, and its arm
    /// matrices `even`; the singles are every matched pair. One or too few repetitions
    /// to make four groups, no opposite pair, or four pairs give `None`.
    #[test]
    fn few_opposite_pairs_are_split_into_groups_of_repetitions() {
        let (odd, even) = (1.5, 4.0);
        let session = |reps: u32, angles: &[f64]| -> Vec<HandResponse> {
            let mut rs = Vec::new();
            for (k, angle) in angles.iter().enumerate() {
                let sign = if *angle < 180.0 { 1.0 } else { -1.0 };
                for i in 0..reps {
                    let value = even + sign * (odd + f64::from(i));
                    rs.push(response(100 * k as u32 + i, *angle, value));
                }
            }
            rs
        };
        let cardinal = [0.0, 90.0, 180.0, 270.0];
        let rs = session(6, &cardinal);
        assert!(odd_parts(&rs, OddUnits::Averaged).is_none());
        let Some((groups, singles, n)) = odd_groups(&rs) else {
            panic!("two pairs of six repetitions make four groups");
        };
        assert_eq!((groups.len(), singles.len(), n), (4, 12, 2));
        for (u, (angle, first)) in groups
            .iter()
            .zip([(0.0, 0), (0.0, 1), (90.0, 0), (90.0, 1)])
        {
            assert_eq!(u.angle_deg, angle);
            let mine: Vec<u32> = [first, first + 2, first + 4].to_vec();
            let base = if angle == 0.0 { 0 } else { 100 };
            let mut expected: Vec<u32> = mine
                .iter()
                .flat_map(|i| [base + i, base + 200 + i])
                .collect();
            let mut trials = u.trials.clone();
            expected.sort_unstable();
            trials.sort_unstable();
            assert_eq!(trials, expected);
            let value = odd + f64::from(first + 2);
            for ch in [&u.dx, &u.dv, &u.da, &u.df, &u.dfd] {
                assert!(ch.iter().flatten().all(|v| (v - value).abs() < 1e-12));
            }
            assert!(u.m_arm.iter().all(|m| (m[(0, 0)] - even).abs() < 1e-12));
        }
        // One pair of four repetitions: four groups of one.
        let Some((one, _, n)) = odd_groups(&session(4, &[30.0, 210.0])) else {
            panic!("one pair of four repetitions makes four groups");
        };
        assert_eq!((one.len(), n), (4, 4));
        assert!(odd_groups(&session(3, &[30.0, 210.0])).is_none());
        assert!(odd_groups(&session(1, &cardinal)).is_none());
        assert!(odd_groups(&session(6, &[0.0, 90.0, 120.0, 200.0])).is_none());
        let eight = [30.0, 60.0, 120.0, 150.0, 210.0, 240.0, 300.0, 330.0];
        assert!(odd_groups(&session(3, &eight)).is_none());
    }

    fn default_arm() -> HandArm {
        let Ok(arm) = HandArm::new(ArmParams::default(), [0.0, -0.425]) else {
            panic!("the default muscles are valid");
        };
        arm
    }

    #[test]
    fn endpoint_inertia_is_symmetric_and_positive() {
        let arm = default_arm();
        let Some(ArmPosture { m_arm: m, s, .. }) = arm.at([0.0, 0.0]) else {
            panic!("the workspace centre is reachable");
        };
        // Symmetric to round-off, positive definite (physical inertia and a Gram matrix).
        assert!((m[(0, 1)] - m[(1, 0)]).abs() < 1e-12);
        assert!((s[(0, 1)] - s[(1, 0)]).abs() < 1e-12);
        assert!(m.determinant() > 0.0 && m[(0, 0)] > 0.0);
        assert!(s.determinant() > 0.0 && s[(0, 0)] > 0.0);
        // An arm of 3.45 kg cannot feel heavier than its mass at the hand in every direction.
        assert!(m.symmetric_eigenvalues().min() < 3.45);
    }

    /// The torque a hand motion and force need, and the force that torque makes at that
    /// motion, are each other's inverse (to 1e-9 N, round-off of two 2×2 solves), on a
    /// fast reach's motion (0.6 m/s, 4 m/s², 12 N).
    #[test]
    fn the_held_torque_gives_the_hand_force_back() {
        let arm = default_arm();
        let (x, v, a, f) = (
            Vector2::new(0.03, -0.02),
            Vector2::new(0.1, 0.6),
            Vector2::new(-1.0, 4.0),
            Vector2::new(2.0, 12.0),
        );
        let Some(tau) = arm.torque(x, v, a, f) else {
            panic!("reachable");
        };
        let Some(back) = arm.hand_force(x, v, a, tau) else {
            panic!("reachable");
        };
        assert!((back - f).norm() < 1e-9, "{back} vs {f}");
    }

    /// At rest the hand force is `J⁻ᵀ τ`, so the held torque's stiffness is
    /// `−Σ_m ∂(J⁻ᵀ)/∂q_m τ (J⁻¹)_m·` with `∂(J⁻ᵀ)/∂q_m = −J⁻ᵀ (∂J/∂q_m)ᵀ J⁻ᵀ` from
    /// the two-link Jacobian's closed-form partials; the central difference of 0.1 mm
    /// agrees to 1e-5 N/m (its truncation error, O(h²) of a term of ~50 N/m). Its damping
    /// at rest is zero: the Coriolis and centripetal torques are quadratic in `q̇`.
    #[test]
    fn the_held_torque_stiffness_at_rest_is_the_turning_jacobian() {
        let arm = default_arm();
        let x = Vector2::new(0.02, 0.05);
        let tau = Vector2::new(4.0, -2.5);
        let z = Vector2::zeros();
        let Some([gx, gv]) = arm.held_torque_impedance(x, z, z, tau) else {
            panic!("reachable");
        };
        let p = &arm.params;
        let (l1, l2) = (p.upper.length_m, p.fore.length_m);
        let Ok(q) = inverse(p, x - Vector2::from(arm.shoulder_m), Elbow::Down) else {
            panic!("reachable");
        };
        let (s1, c1) = q[0].sin_cos();
        let (s12, c12) = (q[0] + q[1]).sin_cos();
        let dj = [
            Matrix2::new(
                -l1 * c1 - l2 * c12,
                -l2 * c12,
                -l1 * s1 - l2 * s12,
                -l2 * s12,
            ),
            Matrix2::new(-l2 * c12, -l2 * c12, -l2 * s12, -l2 * s12),
        ];
        let Some(ji) = jacobian(p, q).try_inverse() else {
            panic!("not singular");
        };
        let jit = ji.transpose();
        let mut want = Matrix2::zeros();
        for (m, djm) in dj.iter().enumerate() {
            let d_jit_tau = -(jit * djm.transpose() * jit) * tau;
            for k in 0..2 {
                want[(0, k)] -= d_jit_tau[0] * ji[(m, k)];
                want[(1, k)] -= d_jit_tau[1] * ji[(m, k)];
            }
        }
        assert!((gx - want).abs().max() < 1e-5, "{gx} vs {want}");
        assert!(want.abs().max() > 1.0, "a test of something: {want}");
        assert!(gv.abs().max() < 1e-6, "{gv}");
    }

    /// The default arm tones its four monoarticular muscles (shoulder and elbow flexors
    /// and extensors) and not its two biarticular ones: weights 1, 1, 1, 1, ½, ½.
    #[test]
    fn untoned_muscles_weigh_half_in_the_feedback_shape() {
        let Ok(model) = MuscleModel::new(&ArmParams::default().muscles) else {
            panic!("the default muscles are valid");
        };
        assert_eq!(odd_part_weights(&model), [1.0, 1.0, 1.0, 1.0, 0.5, 0.5]);
    }
}
