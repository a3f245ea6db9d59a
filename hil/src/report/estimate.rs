//! The device's estimators applied to sessions, measured or simulated: Börner
//! involuntary impedance (000_*) on force-pulse trials, with the subject's endpoint
//! inertia as the a-priori `M_BSP`.

use nalgebra::Vector2;
use rigtwin_arm::kinematics::{Elbow, inverse};
use rigtwin_arm::params::ArmParams;
use rigtwin_device::estimate::{
    Admittance, EstimateError, InvoluntaryImpedance, Mat2, PerturbedTrial,
    estimate_involuntary_impedance,
};
use serde::Serialize;

use crate::protocol::EstimateConfig;
use crate::session::{Manifest, PerturbationKind, Session, Trial};

/// Why a session could not be estimated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionEstimateError {
    /// No trial has a perturbation the estimator uses.
    #[error(
        "no trial has a force-pulse (or, for the windowed regression, a position) perturbation: nothing to estimate"
    )]
    NoPerturbedTrials,
    /// The subject's arm cannot be built from the manifest.
    #[error("subject arm from the manifest: {0}")]
    Arm(#[from] rigtwin_arm::ArmError),
    /// The estimator failed.
    #[error("estimator: {0}")]
    Estimate(#[from] EstimateError),
}

/// The Börner estimate of a set of trials, with what went into it.
#[derive(Debug, Clone, Serialize)]
pub struct BornerResult {
    /// Number of perturbed trials used.
    pub trials: usize,
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// The a-priori inertia used, kg.
    pub m_bsp_kg: Mat2,
    /// `D̂`, N s/m.
    pub d_ns_per_m: Mat2,
    /// `K̂` (symmetric), N/m.
    pub k_n_per_m: Mat2,
    /// Standard errors of `D̂` (jackknife over trials), N s/m.
    pub d_std_err_ns_per_m: Mat2,
    /// Standard errors of `K̂`, N/m.
    pub k_std_err_n_per_m: Mat2,
    /// Condition number of the regressor.
    pub condition_number: f64,
    /// Relative RMS residual.
    pub nrmse: f64,
    /// Onset row of each trial used.
    #[serde(skip)]
    pub onsets: Vec<usize>,
    /// The estimator's full output (variational dynamics per trial).
    #[serde(skip)]
    pub raw: Option<InvoluntaryImpedance>,
}

/// The admittance of a session's `[device]` and handle.
#[must_use]
pub fn admittance_of(m: &Manifest) -> Admittance {
    let d = &m.device;
    let h = d.handle_mass_kg.unwrap_or(0.0);
    Admittance {
        m_adm_kg: [[d.mass_kg[0], 0.0], [0.0, d.mass_kg[1]]],
        d_adm_ns_per_m: [[d.damping_n_s_per_m[0], 0.0], [0.0, d.damping_n_s_per_m[1]]],
        m_handle_kg: [[h, 0.0], [0.0, h]],
    }
}

/// Endpoint inertia of `arm` with the hand at `hand_m` (rig frame) and the shoulder
/// at `shoulder_m`, kg.
///
/// # Errors
/// [`rigtwin_arm::ArmError`] when the hand is out of reach or at a singularity.
pub fn endpoint_inertia(
    arm: &ArmParams,
    shoulder_m: [f64; 2],
    hand_m: [f64; 2],
) -> Result<Mat2, rigtwin_arm::ArmError> {
    let rel = Vector2::new(hand_m[0] - shoulder_m[0], hand_m[1] - shoulder_m[1]);
    let q = inverse(arm, rel, Elbow::Down)?;
    let m = rigtwin_arm::impedance::endpoint_inertia(arm, q)?;
    Ok([[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]])
}

/// Runs the Börner estimator on `trials` (table, onset row) with inertia `m_bsp`.
///
/// # Errors
/// As [`estimate_involuntary_impedance`].
pub fn borner(
    trials: &[(&Trial, usize)],
    rate_hz: f64,
    admittance: &Admittance,
    m_bsp_kg: &Mat2,
    config: &EstimateConfig,
) -> Result<BornerResult, SessionEstimateError> {
    if trials.is_empty() {
        return Err(SessionEstimateError::NoPerturbedTrials);
    }
    let inputs: Vec<PerturbedTrial<'_>> = trials
        .iter()
        .map(|(t, i0)| PerturbedTrial {
            x_m: [&t.x_m, &t.y_m],
            u_pert_n: [&t.pert_fx_n, &t.pert_fy_n],
            onset_index: *i0,
        })
        .collect();
    let est =
        estimate_involuntary_impedance(&inputs, rate_hz, admittance, m_bsp_kg, &config.borner())?;
    Ok(BornerResult {
        trials: trials.len(),
        rate_hz,
        m_bsp_kg: *m_bsp_kg,
        d_ns_per_m: est.d_ns_per_m,
        k_n_per_m: est.k_n_per_m,
        d_std_err_ns_per_m: est.d_std_err_ns_per_m,
        k_std_err_n_per_m: est.k_std_err_n_per_m,
        condition_number: est.condition_number,
        nrmse: est.nrmse,
        onsets: trials.iter().map(|(_, i)| *i).collect(),
        raw: Some(est),
    })
}

/// The onset row of a perturbation at `onset_s` in a table at `rate_hz`.
#[must_use]
pub fn onset_index(onset_s: f64, rate_hz: f64) -> usize {
    (onset_s * rate_hz).round().max(0.0) as usize
}

/// Börner estimate of every force-pulse trial of a session, with `M_BSP` the mean
/// endpoint inertia at the onset postures of the default arm rescaled to the
/// subject's segment lengths (000_*: anthropometric data and inverse kinematics).
///
/// # Errors
/// [`SessionEstimateError`].
pub fn borner_on_session(
    session: &Session,
    config: &EstimateConfig,
) -> Result<BornerResult, SessionEstimateError> {
    let m = &session.manifest;
    let arm = ArmParams::of_subject(
        m.subject.upper_arm_m,
        m.subject.forearm_m,
        m.subject.body_mass_kg,
    )?;
    let mut trials = Vec::new();
    let mut m_sum = [[0.0; 2]; 2];
    for (entry, table) in session.iter() {
        let Some(p) = &entry.perturbation else {
            continue;
        };
        if p.kind != PerturbationKind::ForcePulse {
            continue;
        }
        let i0 = onset_index(p.onset_s, m.rate_hz);
        let hand = [
            table.x_m.get(i0).copied().unwrap_or(0.0),
            table.y_m.get(i0).copied().unwrap_or(0.0),
        ];
        let mi = endpoint_inertia(&arm, m.subject.shoulder_m, hand)?;
        for r in 0..2 {
            for c in 0..2 {
                m_sum[r][c] += mi[r][c];
            }
        }
        trials.push((table, i0));
    }
    if trials.is_empty() {
        return Err(SessionEstimateError::NoPerturbedTrials);
    }
    let n = trials.len() as f64;
    let m_bsp = m_sum.map(|row| row.map(|v| v / n));
    borner(&trials, m.rate_hz, &admittance_of(m), &m_bsp, config)
}

/// The windowed regression (001_*) of one hold trial: window estimates averaged.
#[derive(Debug, Clone, Serialize)]
pub struct PiovesanTrial {
    /// Trial id.
    pub id: u32,
    /// Position perturbations found.
    pub perturbations: usize,
    /// Windows estimated.
    pub windows: usize,
    /// Mean `K` over windows, N/m.
    pub k_n_per_m: Mat2,
    /// Mean `B` over windows, N s/m.
    pub b_ns_per_m: Mat2,
    /// Mean canonical r².
    pub r2: f64,
    /// Each window's estimate, in order (window `j` spans cycles `j .. j + windows`).
    #[serde(skip)]
    pub window_estimates: Vec<rigtwin_device::estimate::WindowEstimate>,
    /// Onset row of each position perturbation (perturbation `i` is in cycle `i / 2`).
    #[serde(skip)]
    pub onsets: Vec<usize>,
}

/// Onsets of the position perturbations of a table, from its `pert_x_m, pert_y_m`
/// columns: rows where the offset leaves zero.
#[must_use]
pub fn push_onsets(table: &Trial) -> Vec<usize> {
    let (Some(px), Some(py)) = (table.column("pert_x_m"), table.column("pert_y_m")) else {
        return Vec::new();
    };
    let off = |i: usize| px[i] != 0.0 || py[i] != 0.0;
    (0..px.len().min(py.len()))
        .filter(|&i| off(i) && (i == 0 || !off(i - 1)))
        .collect()
}

/// The windowed regression of 001_* on every trial with position perturbations
/// (`pert_x_m, pert_y_m` columns). Perturbations are taken to come twice per cycle,
/// as in 001_*, so perturbation `i` belongs to cycle `i / 2`; windows are 10 cycles.
/// `M̂` is `m_hat_kg` (isotropic) when given, else the subject's arm endpoint inertia
/// at the trial's first position plus the handle mass.
///
/// # Errors
/// [`SessionEstimateError::NoPerturbedTrials`] without position perturbations; arm
/// errors when `M̂` comes from the arm.
pub fn piovesan_on_session(
    session: &Session,
    m_hat_kg: Option<f64>,
) -> Result<Vec<Result<PiovesanTrial, String>>, SessionEstimateError> {
    use rigtwin_device::estimate::{
        ImposedMotionTrial, PiovesanConfig, PositionPerturbation, windowed_impedance,
    };
    let m = &session.manifest;
    let h = m.device.handle_mass_kg.unwrap_or(0.0);
    let arm = ArmParams::of_subject(
        m.subject.upper_arm_m,
        m.subject.forearm_m,
        m.subject.body_mass_kg,
    )?;
    let mut out = Vec::new();
    for (entry, table) in session.iter() {
        let onsets = push_onsets(table);
        if onsets.is_empty() {
            continue;
        }
        let m_hat = match m_hat_kg {
            Some(mk) => [[mk + h, 0.0], [0.0, mk + h]],
            None => {
                let hand = [table.x_m[0], table.y_m[0]];
                let mi = endpoint_inertia(&arm, m.subject.shoulder_m, hand)?;
                [[mi[0][0] + h, mi[0][1]], [mi[1][0], mi[1][1] + h]]
            }
        };
        let pushes: Vec<PositionPerturbation> = onsets
            .iter()
            .enumerate()
            .map(|(i, &onset_index)| PositionPerturbation {
                onset_index,
                cycle: i / 2,
            })
            .collect();
        let n_cycles = pushes.len().div_ceil(2);
        let config = PiovesanConfig {
            window_cycles: PiovesanConfig::default().window_cycles.min(n_cycles),
            ..PiovesanConfig::default()
        };
        let fx: Vec<f64> = table.fx_n.iter().map(|v| -v).collect();
        let fy: Vec<f64> = table.fy_n.iter().map(|v| -v).collect();
        let trial = ImposedMotionTrial {
            x_m: [&table.x_m, &table.y_m],
            force_n: [&fx, &fy],
            perturbations: &pushes,
            n_cycles,
        };
        out.push(
            windowed_impedance(&trial, m.rate_hz, &m_hat, &config)
                .map_err(|e| format!("trial {}: {e}", entry.id))
                .map(|w| {
                    let n = w.len().max(1) as f64;
                    let mut k = [[0.0; 2]; 2];
                    let mut b = [[0.0; 2]; 2];
                    for e in &w {
                        for r in 0..2 {
                            for c in 0..2 {
                                k[r][c] += e.k_n_per_m[r][c] / n;
                                b[r][c] += e.b_ns_per_m[r][c] / n;
                            }
                        }
                    }
                    PiovesanTrial {
                        id: entry.id,
                        perturbations: pushes.len(),
                        windows: w.len(),
                        k_n_per_m: k,
                        b_ns_per_m: b,
                        r2: w.iter().map(|e| e.canonical_r2).sum::<f64>() / n,
                        window_estimates: w,
                        onsets: onsets.clone(),
                    }
                }),
        );
    }
    if out.is_empty() {
        return Err(SessionEstimateError::NoPerturbedTrials);
    }
    Ok(out)
}
