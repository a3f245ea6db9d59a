//! Ground truth: the arm's endpoint inertia, intrinsic stiffness and damping.
//!
//! `M = J⁻ᵀ M_q J⁻¹`, `K = J⁻ᵀ K_q J⁻¹`, `D = J⁻ᵀ D_q J⁻¹` (000_* eq. 16–18) with
//! `K_q = Aᵀ diag(K_m) A` and `D_q = Aᵀ diag(D_m) A` from the muscle model. Like the
//! seed's eq. 18 and the reference table, the stiffness leaves out the geometric term
//! `−J⁻ᵀ (∂Jᵀ/∂q · F) J⁻¹` that a hand force F adds; it is the *intrinsic* (muscle)
//! stiffness. Feedback and reflexes are not included either. Axes of the returned
//! matrices are the shoulder (= rig) frame axes.

use nalgebra::{Matrix2, SymmetricEigen};

use crate::dynamics::mass_matrix;
use crate::error::ArmError;
use crate::kinematics::jacobian;
use crate::muscles::{MUSCLES, MuscleModel};
use crate::params::ArmParams;

/// Endpoint impedance in the shoulder/rig frame axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndpointImpedance {
    /// Apparent endpoint inertia \[kg\].
    pub mass_kg: Matrix2<f64>,
    /// Intrinsic endpoint damping \[N s/m\].
    pub damping_n_s_per_m: Matrix2<f64>,
    /// Intrinsic endpoint stiffness \[N/m\].
    pub stiffness_n_per_m: Matrix2<f64>,
}

/// `J⁻ᵀ X J⁻¹`: a joint-space matrix (N m/rad, N m s/rad, kg m²) at the hand
/// (N/m, N s/m, kg). Errors at a kinematic singularity.
pub fn joint_to_endpoint(
    p: &ArmParams,
    q: [f64; 2],
    joint: &Matrix2<f64>,
) -> Result<Matrix2<f64>, ArmError> {
    let j = jacobian(p, q);
    let det = j.determinant();
    // Below 1e-9 m² the arm is within ~µrad of straight; the mapping is meaningless.
    if det.is_nan() || det.abs() <= 1e-9 {
        return Err(ArmError::Singular { det_m2: det });
    }
    let ji = j.try_inverse().ok_or(ArmError::Singular { det_m2: det })?;
    Ok(ji.transpose() * joint * ji)
}

/// The arm's inertia at the hand, `J⁻ᵀ M(q) J⁻¹` (operational-space inertia), kg: the
/// one definition every room uses. Errors at a kinematic singularity.
pub fn endpoint_inertia(p: &ArmParams, q: [f64; 2]) -> Result<Matrix2<f64>, ArmError> {
    joint_to_endpoint(p, q, &crate::dynamics::mass_matrix(p, q))
}

/// Endpoint impedance with stiffness scale `scale` (see [`crate::params::StiffnessDrift`]).
pub fn endpoint_impedance_scaled(
    p: &ArmParams,
    model: &MuscleModel,
    q: [f64; 2],
    activations_n: &[f64; MUSCLES],
    scale: f64,
) -> Result<EndpointImpedance, ArmError> {
    Ok(EndpointImpedance {
        mass_kg: joint_to_endpoint(p, q, &mass_matrix(p, q))?,
        damping_n_s_per_m: joint_to_endpoint(p, q, &model.joint_damping(activations_n, scale))?,
        stiffness_n_per_m: joint_to_endpoint(p, q, &model.joint_stiffness(activations_n, scale))?,
    })
}

/// The arm's endpoint inertia and intrinsic stiffness and damping at posture `q` \[rad\]
/// and muscle activations \[N\] (order SF, SE, EF, EE, BF, BE), without stiffness drift.
pub fn endpoint_impedance(
    p: &ArmParams,
    q: [f64; 2],
    activations_n: &[f64; MUSCLES],
) -> Result<EndpointImpedance, ArmError> {
    let model = MuscleModel::new(&p.muscles)?;
    endpoint_impedance_scaled(p, &model, q, activations_n, 1.0)
}

/// Principal axes of a symmetric 2×2 matrix (its symmetric part if not symmetric):
/// (major eigenvalue, minor eigenvalue, direction of the major axis in degrees from +x,
/// in [0, 180)).
pub fn principal_axes(m: &Matrix2<f64>) -> (f64, f64, f64) {
    let sym = (m + m.transpose()) * 0.5;
    let eig = SymmetricEigen::new(sym);
    let (imax, imin) = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let v = eig.eigenvectors.column(imax);
    let deg = v[1].atan2(v[0]).to_degrees().rem_euclid(180.0);
    (eig.eigenvalues[imax], eig.eigenvalues[imin], deg)
}
