//! The six lumped muscles and their impedance (000_* eq. 33–35).
//!
//! Muscles, always in this order: shoulder flexor (SF), shoulder extensor (SE), elbow
//! flexor (EF), elbow extensor (EE), biarticular flexor (BF), biarticular extensor (BE).
//!
//! - **Lengths** from constant moment arms: `l = l₀ − A q` with `A` the 6×2 moment-arm
//!   matrix \[m\] (row = muscle, columns = shoulder, elbow). Only length *differences*
//!   enter the model, so `l₀` cancels and is not a parameter.
//! - **Activation** `a ≥ 0` \[N\] is the active tension (the seed sets m_A = a).
//! - **Tension** `m = a + D_m ė + K_m e` \[N\], with `e = l − l_ref = −A (q − q_ref)` the
//!   muscle stretch beyond the planned length, `K_m = s (K₀ + K₁ a)` \[N/m\],
//!   `D_m = τ_d K_m` \[N s/m\] (`τ_d` = 1/12 s in the seed), `s` the stiffness-drift
//!   scale (1 unless [`crate::params::StiffnessDrift`] is on). The law is linear, as in
//!   the seed: tension is not clipped at zero, so a muscle stretched far below its
//!   planned length can "push"; with the default co-contraction this needs errors of
//!   centimetres.
//! - **Joint torque** `τ = Aᵀ m` \[N m\]; so the intrinsic joint stiffness is
//!   `K_q = Aᵀ diag(K_m) A` and the damping `D_q = Aᵀ diag(D_m) A`.

use nalgebra::{Matrix2, SMatrix, Vector2};
use serde::{Deserialize, Serialize};

use crate::error::ArmError;

/// Number of lumped muscles.
pub const MUSCLES: usize = 6;

/// Names in the order used by every `[_; 6]` array of this crate.
pub const MUSCLE_NAMES: [&str; MUSCLES] = ["SF", "SE", "EF", "EE", "BF", "BE"];

/// Parameters of the six muscles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MuscleParams {
    /// Moment arms (shoulder, elbow) \[m\], rows SF, SE, EF, EE, BF, BE.
    /// Default: Selen, Franklin & Wolpert 2009, Table 1.
    pub moment_arms_m: [[f64; 2]; MUSCLES],
    /// `K₀`, stiffness of the passive muscle \[N/m\]. Default 450 N/m for every muscle:
    /// Katayama & Kawato's k₀ = 810.8 N/m scaled by (their moment arm / ours)² ≈ 0.56 so
    /// that the joint stiffness per muscle is kept.
    pub stiffness_passive_n_per_m: [f64; MUSCLES],
    /// `K₁`, stiffness added per newton of activation \[N/m per N = 1/m\]. Default 100 /m:
    /// tension/stiffness = 1 cm, within the range of short-range muscle stiffness.
    pub stiffness_per_activation_per_m: [f64; MUSCLES],
    /// `τ_d` in `D_m = τ_d K_m` \[s\]. Default 1/12 s (000_* eq. 35).
    pub damping_time_s: [f64; MUSCLES],
    /// Co-contraction as a torque each monoarticular pair pulls against itself
    /// (shoulder, elbow) \[N m\]: the shoulder pair then carries c/|r| N each, the elbow
    /// flexor c/r_EF, the extensor c/|r_EE|, so the net torque is zero. Scaled at run
    /// time by the task's co-contraction level. Defaults are chosen so that the
    /// endpoint stiffness during the Börner reach lands on Table 1 (see the crate docs).
    pub co_contraction_n_m: [f64; 2],
}

impl Default for MuscleParams {
    fn default() -> Self {
        MuscleParams {
            moment_arms_m: [
                [0.0536, 0.0],
                [-0.0536, 0.0],
                [0.0, 0.0316],
                [0.0, -0.0267],
                [0.0386, 0.0427],
                [-0.0388, -0.0300],
            ],
            stiffness_passive_n_per_m: [450.0; MUSCLES],
            stiffness_per_activation_per_m: [100.0; MUSCLES],
            damping_time_s: [1.0 / 12.0; MUSCLES],
            co_contraction_n_m: [1.0, 2.6],
        }
    }
}

impl MuscleParams {
    /// The default muscles with the damping refitted to Börner's Table 1 (000_*).
    ///
    /// With one damping/stiffness ratio for all muscles the endpoint damping is K/12,
    /// and Table 1's large K₂₂ (313.75 N/m) with small D₂₂ (6.75 N s/m) cannot both be
    /// met: the default gives D₂₂ ≈ 25 N s/m, 4 std high. K₂₂ comes almost entirely from
    /// the co-contracted elbow monoarticulars, so this preset lowers only their
    /// `damping_time_s` to 10 ms (EF, EE) and keeps the seed's 1/12 s elsewhere; during
    /// the default reach at x₂ = 0.4 m, D then lies within one std of every entry of
    /// Table 1 while K is unchanged. A departure from eq. 35, hence not the default.
    pub fn table1_damping() -> MuscleParams {
        let mut m = MuscleParams::default();
        m.damping_time_s[2] = 0.01;
        m.damping_time_s[3] = 0.01;
        m
    }
}

/// The muscle model with its derived matrices, built once from [`MuscleParams`].
#[derive(Debug, Clone, PartialEq)]
pub struct MuscleModel {
    params: MuscleParams,
    /// A \[m\], 6×2.
    arms: SMatrix<f64, MUSCLES, 2>,
    /// A (AᵀA)⁻¹ \[1/m\], 6×2: the minimum-norm split of a torque over the muscles.
    split: SMatrix<f64, MUSCLES, 2>,
    /// Positive torque-free pattern used to lift a split to non-negative activations.
    lift: [f64; MUSCLES],
    /// Torque-free co-contraction pattern for one unit of the params' co-contraction \[N\].
    co_pattern_n: [f64; MUSCLES],
}

/// Projects `v` onto the null space of Aᵀ (torque-free tension patterns).
fn torque_free(
    arms: &SMatrix<f64, MUSCLES, 2>,
    split: &SMatrix<f64, MUSCLES, 2>,
    v: [f64; MUSCLES],
) -> [f64; MUSCLES] {
    let v = SMatrix::<f64, MUSCLES, 1>::from_column_slice(&v);
    let p = v - split * (arms.transpose() * v);
    let mut out = [0.0; MUSCLES];
    out.copy_from_slice(p.as_slice());
    out
}

impl MuscleModel {
    /// Checks the parameters and precomputes the torque split.
    pub fn new(params: &MuscleParams) -> Result<MuscleModel, ArmError> {
        let finite_nonneg = |xs: &[f64]| xs.iter().all(|x| x.is_finite() && *x >= 0.0);
        if !params.moment_arms_m.iter().flatten().all(|x| x.is_finite()) {
            return Err(ArmError::InvalidParameter {
                key: "moment_arms_m",
                reason: "must be finite".into(),
            });
        }
        for (key, xs) in [
            (
                "stiffness_passive_n_per_m",
                &params.stiffness_passive_n_per_m[..],
            ),
            (
                "stiffness_per_activation_per_m",
                &params.stiffness_per_activation_per_m[..],
            ),
            ("damping_time_s", &params.damping_time_s[..]),
            ("co_contraction_n_m", &params.co_contraction_n_m[..]),
        ] {
            if !finite_nonneg(xs) {
                return Err(ArmError::InvalidParameter {
                    key,
                    reason: format!("must be finite and >= 0, got {xs:?}"),
                });
            }
        }
        let mut arms = SMatrix::<f64, MUSCLES, 2>::zeros();
        for (i, row) in params.moment_arms_m.iter().enumerate() {
            arms[(i, 0)] = row[0];
            arms[(i, 1)] = row[1];
        }
        let ata_inv =
            (arms.transpose() * arms)
                .try_inverse()
                .ok_or_else(|| ArmError::InvalidParameter {
                    key: "moment_arms_m",
                    reason: "the muscles cannot produce every joint torque (AᵀA singular)".into(),
                })?;
        let split = arms * ata_inv;
        let lift = torque_free(&arms, &split, [1.0; MUSCLES]);
        if lift.iter().any(|x| *x <= 1e-6) {
            return Err(ArmError::InvalidParameter {
                key: "moment_arms_m",
                reason: format!(
                    "no torque-free pattern with all muscles active (got {lift:?}); antagonists are missing"
                ),
            });
        }
        let [cs, ce] = params.co_contraction_n_m;
        let r = &params.moment_arms_m;
        let inv = |x: f64| if x.abs() > 1e-9 { 1.0 / x.abs() } else { 0.0 };
        let co_raw = [
            cs * inv(r[0][0]),
            cs * inv(r[1][0]),
            ce * inv(r[2][1]),
            ce * inv(r[3][1]),
            0.0,
            0.0,
        ];
        let co_pattern_n = torque_free(&arms, &split, co_raw);
        if co_pattern_n.iter().any(|x| *x < -1e-9) {
            return Err(ArmError::InvalidParameter {
                key: "co_contraction_n_m",
                reason: "the monoarticular moment arms do not allow a torque-free co-contraction"
                    .into(),
            });
        }
        Ok(MuscleModel {
            params: params.clone(),
            arms,
            split,
            lift,
            co_pattern_n: co_pattern_n.map(|x| x.max(0.0)),
        })
    }

    /// The parameters this model was built from.
    pub fn params(&self) -> &MuscleParams {
        &self.params
    }

    /// The moment-arm matrix A \[m\] (6×2).
    pub fn moment_arms(&self) -> &SMatrix<f64, MUSCLES, 2> {
        &self.arms
    }

    /// Muscle stretch beyond the reference, `e = −A (q − q_ref)` \[m\]; also valid for
    /// rates: `ė = −A (q̇ − q̇_ref)` \[m/s\].
    pub fn stretch(&self, q: [f64; 2], q_ref: [f64; 2]) -> [f64; MUSCLES] {
        let d = [q[0] - q_ref[0], q[1] - q_ref[1]];
        let mut e = [0.0; MUSCLES];
        for (i, ei) in e.iter_mut().enumerate() {
            *ei = -(self.arms[(i, 0)] * d[0] + self.arms[(i, 1)] * d[1]);
        }
        e
    }

    /// Muscle stiffness `K_m = scale (K₀ + K₁ a)` \[N/m\] at activations `a` \[N\].
    pub fn stiffness(&self, activations_n: &[f64; MUSCLES], scale: f64) -> [f64; MUSCLES] {
        let p = &self.params;
        std::array::from_fn(|i| {
            scale
                * (p.stiffness_passive_n_per_m[i]
                    + p.stiffness_per_activation_per_m[i] * activations_n[i])
        })
    }

    /// Muscle tensions `m = a + D_m ė + K_m e` \[N\].
    pub fn tensions(
        &self,
        activations_n: &[f64; MUSCLES],
        stretch_m: &[f64; MUSCLES],
        stretch_rate_m_s: &[f64; MUSCLES],
        scale: f64,
    ) -> [f64; MUSCLES] {
        let k = self.stiffness(activations_n, scale);
        std::array::from_fn(|i| {
            activations_n[i]
                + k[i] * (stretch_m[i] + self.params.damping_time_s[i] * stretch_rate_m_s[i])
        })
    }

    /// Joint torques `Aᵀ m` \[N m\] of muscle tensions `m` \[N\].
    pub fn joint_torque(&self, tensions_n: &[f64; MUSCLES]) -> [f64; 2] {
        let mut tau = [0.0; 2];
        for (i, m) in tensions_n.iter().enumerate() {
            tau[0] += self.arms[(i, 0)] * m;
            tau[1] += self.arms[(i, 1)] * m;
        }
        tau
    }

    /// `Aᵀ diag(w) A` for per-muscle weights `w` \[N/m → N m/rad, N s/m → N m s/rad\].
    pub fn to_joint(&self, per_muscle: &[f64; MUSCLES]) -> Matrix2<f64> {
        let mut k = Matrix2::zeros();
        for (i, w) in per_muscle.iter().enumerate() {
            let r = Vector2::new(self.arms[(i, 0)], self.arms[(i, 1)]);
            k += *w * r * r.transpose();
        }
        k
    }

    /// Intrinsic joint stiffness `K_q = Aᵀ diag(K_m) A` \[N m/rad\].
    pub fn joint_stiffness(&self, activations_n: &[f64; MUSCLES], scale: f64) -> Matrix2<f64> {
        self.to_joint(&self.stiffness(activations_n, scale))
    }

    /// Intrinsic joint damping `D_q = Aᵀ diag(τ_d K_m) A` \[N m s/rad\].
    pub fn joint_damping(&self, activations_n: &[f64; MUSCLES], scale: f64) -> Matrix2<f64> {
        let k = self.stiffness(activations_n, scale);
        let d: [f64; MUSCLES] = std::array::from_fn(|i| k[i] * self.params.damping_time_s[i]);
        self.to_joint(&d)
    }

    /// Co-contraction activations \[N\] for a level (1 = the params' `co_contraction_n_m`).
    /// Torque-free: `Aᵀ c = 0`.
    pub fn co_contraction(&self, level: f64) -> [f64; MUSCLES] {
        self.co_pattern_n.map(|x| x * level.max(0.0))
    }

    /// Non-negative activations \[N\] that produce joint torque `tau` \[N m\] on top of a
    /// torque-free co-contraction `co_n` \[N\] (e.g. from [`MuscleModel::co_contraction`]).
    ///
    /// Closed form: the minimum-norm split `a₀ = A (AᵀA)⁻¹ τ`, lifted by the smallest
    /// multiple λ ≥ 0 of the positive torque-free pattern `n` (the projection of (1,…,1)
    /// onto the null space of Aᵀ) that makes every entry non-negative, plus `co_n`:
    /// `a = a₀ + λ n + co_n`. Since `Aᵀ n = 0`, `Aᵀ a = τ` exactly; the lift is the
    /// co-contraction a larger torque unavoidably brings (stiffness rises with load).
    pub fn split(&self, tau: [f64; 2], co_n: &[f64; MUSCLES]) -> [f64; MUSCLES] {
        let a0 = self.split * Vector2::new(tau[0], tau[1]);
        let lambda = (0..MUSCLES)
            .map(|i| -a0[i] / self.lift[i])
            .fold(0.0_f64, f64::max);
        std::array::from_fn(|i| (a0[i] + lambda * self.lift[i] + co_n[i]).max(0.0))
    }
}
