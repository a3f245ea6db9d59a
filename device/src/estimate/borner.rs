//! Involuntary impedance by the high-pass-jerk method of Börner, Endo, Hirche
//! (000_*, section 3, eq. 19–32).
//!
//! Per perturbed trial: Savitzky–Golay jerk of the position (5th order, 30 Hz, the
//! seed's sections 4.2 and 5.1), zero-phase Butterworth high-pass of the jerk (1 Hz,
//! 5th order, section 4.3) giving the variational jerk, integration over
//! `[0, T_est]` from the onset (section 3.1) to `Δẍ, Δẋ, Δx`, the variational external
//! force of eq. 21, and, over one or more trials, least squares for `D̄` (full) and
//! a symmetric `K̄` with the a-priori inertia `M̂_BSP` (eq. 30–32).
//!
//! Two ways to obtain the variational signals (see [`VariationalMode`]): the
//! seed's literal one, and a consistent one that applies the identical linear
//! filter to the force and keeps the filtered state at the onset. On a linear
//! system with no nominal movement the seed's way is biased (its high-pass removes
//! part of the response itself when the arm's own modes lie near the cut-off, and
//! the unfiltered force no longer matches the filtered kinematics); the consistent
//! way is exact up to discretisation there. On real reaching the seed's way
//! removes the nominal movement better (the integration restarts at the onset).

use super::Mat2;
use super::error::{EstimateError, check_finite, check_finite_mat2, check_positive};
use super::lsq::{self, CovarianceKind};
use crate::signal::{
    EdgeMode, FilterKind, Sos, butter, cumulative_trapezoid, savgol_filter_planned,
    savgol_window_for_cutoff, sosfiltfilt,
};
use realfft::RealFftPlanner;

/// The device's admittance and handle (000_* eq. 19–21), all in the rig frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Admittance {
    /// Admittance inertia `M_adm`, kg (Börner rig: diag(5, 5)).
    pub m_adm_kg: Mat2,
    /// Admittance damping `D_adm`, N s/m (Börner rig: diag(15, 15)).
    pub d_adm_ns_per_m: Mat2,
    /// Handle inertia `M_handle` beyond the force sensor, kg.
    pub m_handle_kg: Mat2,
}

/// The zero-phase Butterworth high-pass applied to the jerk (000_* section 3.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HighPass {
    /// Cut-off, Hz (seed: 1 Hz, chosen by the PSD comparison of section 4.3).
    pub cutoff_hz: f64,
    /// Butterworth order (seed: 5). Applied forward and backward, so the
    /// magnitude response is the square of this order's.
    pub order: usize,
}

/// How the variational signals are formed from the filtered jerk.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VariationalMode {
    /// The seed's: integration constants zero at the onset (section 3.1) and the
    /// raw perturbation force in eq. 21.
    Seed,
    /// The same linear filter (SG jerk, high-pass, triple integration) applied to
    /// the force as to the position, and integration constants taken from the
    /// filtered signals at the onset. Exact for a linear system at rest.
    Consistent,
}

/// Settings of the involuntary-impedance estimator; [`Default`] is the seed's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BornerConfig {
    /// Savitzky–Golay polynomial order (seed: 5).
    pub savgol_polyorder: usize,
    /// Savitzky–Golay cut-off, Hz (seed: 30); the window follows from
    /// `savgol_window_for_cutoff`.
    pub savgol_cutoff_hz: f64,
    /// High-pass of the jerk; `None` skips it (no nominal movement to remove).
    pub high_pass: Option<HighPass>,
    /// Estimation interval `T_est` after the onset, s (seed: 0.150, section 5.3).
    pub t_est_s: f64,
    /// How variational signals are formed.
    pub mode: VariationalMode,
    /// Largest acceptable condition number of the equilibrated regressor.
    pub max_condition: f64,
}

impl Default for BornerConfig {
    fn default() -> Self {
        Self {
            savgol_polyorder: 5,
            savgol_cutoff_hz: 30.0,
            high_pass: Some(HighPass {
                cutoff_hz: 1.0,
                order: 5,
            }),
            t_est_s: 0.150,
            mode: VariationalMode::Seed,
            max_condition: 1e8,
        }
    }
}

/// One perturbed trial as recorded: positions and the commanded perturbation force
/// on both axes at one sample rate, and the sample at which the perturbation starts.
#[derive(Debug, Clone, Copy)]
pub struct PerturbedTrial<'a> {
    /// Handle position per axis, m.
    pub x_m: [&'a [f64]; 2],
    /// Perturbation force `u_pert` per axis, N (eq. 23).
    pub u_pert_n: [&'a [f64]; 2],
    /// Sample index of the perturbation onset `t₀`.
    pub onset_index: usize,
}

/// The variational dynamics of one trial over `[0, T_est]` (000_* section 3.1).
#[derive(Debug, Clone, PartialEq)]
pub struct VariationalDynamics {
    /// `Δx`, m, per sample from the onset.
    pub dx_m: Vec<[f64; 2]>,
    /// `Δẋ`, m/s.
    pub dv_m_per_s: Vec<[f64; 2]>,
    /// `Δẍ`, m/s².
    pub da_m_per_s2: Vec<[f64; 2]>,
    /// `Δu_ext` of eq. 21, N.
    pub du_ext_n: Vec<[f64; 2]>,
}

/// The involuntary impedance estimate (000_* eq. 29–32).
#[derive(Debug, Clone, PartialEq)]
pub struct InvoluntaryImpedance {
    /// `D̂`, N s/m (full 2x2).
    pub d_ns_per_m: Mat2,
    /// `K̂`, N/m (symmetric by construction, eq. 30).
    pub k_n_per_m: Mat2,
    /// Standard errors of `D̂`, N s/m.
    pub d_std_err_ns_per_m: Mat2,
    /// Standard errors of `K̂`, N/m.
    pub k_std_err_n_per_m: Mat2,
    /// `ζ̄ = [D11, D12, D21, D22, K11, K12, K22]` (eq. 30).
    pub params: [f64; 7],
    /// Covariance of `ζ̄`, in the order of `params`.
    pub covariance: [[f64; 7]; 7],
    /// Where the covariance comes from (jackknife over trials with ≥ 3 trials).
    pub covariance_kind: CovarianceKind,
    /// Condition number of the equilibrated regressor `Ā`.
    pub condition_number: f64,
    /// RMS residual over the largest `|b̄|` (eq. 32).
    pub nrmse: f64,
    /// Residuals `b̄ − X̄ ζ̄`, N, per trial then per sample.
    pub residuals_n: Vec<[f64; 2]>,
    /// The variational dynamics of each trial, in input order.
    pub variational: Vec<VariationalDynamics>,
}

/// Designed filters and sizes for one sample rate.
struct Pipeline {
    window: usize,
    polyorder: usize,
    sos: Option<Sos>,
    dt_s: f64,
    n_est: usize,
    mode: VariationalMode,
}

impl Pipeline {
    fn new(fs_hz: f64, config: &BornerConfig) -> Result<Self, EstimateError> {
        check_positive("fs_hz", fs_hz)?;
        check_positive("t_est_s", config.t_est_s)?;
        let window =
            savgol_window_for_cutoff(config.savgol_polyorder, config.savgol_cutoff_hz, fs_hz)
                .map_err(EstimateError::signal("choosing the Savitzky-Golay window"))?;
        if config.savgol_polyorder < 3 {
            return Err(EstimateError::BadParameter {
                what: "savgol_polyorder",
                value: config.savgol_polyorder as f64,
                why: "jerk is the third derivative: the polynomial needs order >= 3",
            });
        }
        let sos = match config.high_pass {
            Some(hp) => Some(
                butter(hp.order, hp.cutoff_hz, fs_hz, FilterKind::HighPass)
                    .map_err(EstimateError::signal("designing the high-pass"))?,
            ),
            None => None,
        };
        let n_est = (config.t_est_s * fs_hz).round() as usize + 1;
        if n_est < 2 {
            return Err(EstimateError::TooShort {
                what: "estimation interval (samples)",
                needed: 2,
                got: n_est,
            });
        }
        Ok(Self {
            window,
            polyorder: config.savgol_polyorder,
            sos,
            dt_s: 1.0 / fs_hz,
            n_est,
            mode: config.mode,
        })
    }

    /// The linear filter `F`: Savitzky–Golay jerk then the zero-phase high-pass.
    fn filtered_jerk(
        &self,
        planner: &mut RealFftPlanner<f64>,
        y: &[f64],
    ) -> Result<Vec<f64>, EstimateError> {
        check_finite("signal to differentiate", y)?;
        let jerk = savgol_filter_planned(
            planner,
            y,
            self.window,
            self.polyorder,
            3,
            self.dt_s,
            EdgeMode::Interp,
        )
        .map_err(EstimateError::signal(
            "differentiating to jerk (Savitzky-Golay)",
        ))?;
        match &self.sos {
            Some(sos) => sosfiltfilt(sos, &jerk)
                .map_err(EstimateError::signal("high-pass filtering the jerk")),
            None => Ok(jerk),
        }
    }

    /// `F(y)` at sample `k`, where `F` is applied to the `order`-fold running
    /// integral of `y` (so that `F(∫∫∫ y)` is the filtered `y`).
    fn filtered_integral_at(
        &self,
        planner: &mut RealFftPlanner<f64>,
        y: &[f64],
        order: usize,
        k: usize,
    ) -> Result<f64, EstimateError> {
        let mut acc: Vec<f64> = y.to_vec();
        for _ in 0..order {
            acc = cumulative_trapezoid(&acc, self.dt_s);
        }
        Ok(self
            .filtered_jerk(planner, &acc)?
            .get(k)
            .copied()
            .unwrap_or(0.0))
    }

    fn variational(
        &self,
        planner: &mut RealFftPlanner<f64>,
        trial: &PerturbedTrial<'_>,
        adm: &Admittance,
    ) -> Result<VariationalDynamics, EstimateError> {
        let len = trial.x_m[0].len();
        for axis in 0..2 {
            for (what, s) in [
                ("position", trial.x_m[axis]),
                ("perturbation force", trial.u_pert_n[axis]),
            ] {
                if s.len() != len {
                    return Err(EstimateError::LengthMismatch {
                        what,
                        left: len,
                        right: s.len(),
                    });
                }
                check_finite(what, s)?;
            }
        }
        let k0 = trial.onset_index;
        let end = k0.saturating_add(self.n_est);
        if end > len {
            return Err(EstimateError::PerturbationBeyondRecord {
                onset_index: k0,
                needed_end: end,
                len,
            });
        }
        let n = self.n_est;
        let mut dx = vec![[0.0; 2]; n];
        let mut dv = vec![[0.0; 2]; n];
        let mut da = vec![[0.0; 2]; n];
        let mut u = vec![[0.0; 2]; n];
        for axis in 0..2 {
            let x = trial.x_m[axis];
            let jerk = self.filtered_jerk(planner, x)?;
            let seg = &jerk[k0..end];
            let (c0, c1, c2) = match self.mode {
                VariationalMode::Seed => (0.0, 0.0, 0.0),
                VariationalMode::Consistent => {
                    // Remove the offset first: it only adds a cubic that the
                    // jerk filter maps to a constant and the high-pass removes.
                    let x0 = x[0];
                    let centred: Vec<f64> = x.iter().map(|v| v - x0).collect();
                    (
                        self.filtered_integral_at(planner, &centred, 3, k0)?,
                        self.filtered_integral_at(planner, &centred, 2, k0)?,
                        self.filtered_integral_at(planner, &centred, 1, k0)?,
                    )
                }
            };
            let a: Vec<f64> = cumulative_trapezoid(seg, self.dt_s)
                .iter()
                .map(|v| v + c2)
                .collect();
            let v: Vec<f64> = cumulative_trapezoid(&a, self.dt_s)
                .iter()
                .map(|w| w + c1)
                .collect();
            let p: Vec<f64> = cumulative_trapezoid(&v, self.dt_s)
                .iter()
                .map(|w| w + c0)
                .collect();
            let force: Vec<f64> = match self.mode {
                VariationalMode::Seed => trial.u_pert_n[axis][k0..end].to_vec(),
                VariationalMode::Consistent => {
                    let mut acc = trial.u_pert_n[axis].to_vec();
                    for _ in 0..3 {
                        acc = cumulative_trapezoid(&acc, self.dt_s);
                    }
                    self.filtered_jerk(planner, &acc)?[k0..end].to_vec()
                }
            };
            for i in 0..n {
                dx[i][axis] = p[i];
                dv[i][axis] = v[i];
                da[i][axis] = a[i];
                u[i][axis] = force[i];
            }
        }
        // eq. 21: Δu_ext = u_pert − (M_adm + M_handle) Δẍ − D_adm Δẋ.
        let m = add(&adm.m_adm_kg, &adm.m_handle_kg);
        let du_ext = (0..n)
            .map(|i| {
                let ma = mul(&m, &da[i]);
                let dvv = mul(&adm.d_adm_ns_per_m, &dv[i]);
                [u[i][0] - ma[0] - dvv[0], u[i][1] - ma[1] - dvv[1]]
            })
            .collect();
        Ok(VariationalDynamics {
            dx_m: dx,
            dv_m_per_s: dv,
            da_m_per_s2: da,
            du_ext_n: du_ext,
        })
    }
}

fn add(a: &Mat2, b: &Mat2) -> Mat2 {
    [
        [a[0][0] + b[0][0], a[0][1] + b[0][1]],
        [a[1][0] + b[1][0], a[1][1] + b[1][1]],
    ]
}

fn mul(a: &Mat2, v: &[f64; 2]) -> [f64; 2] {
    [
        a[0][0] * v[0] + a[0][1] * v[1],
        a[1][0] * v[0] + a[1][1] * v[1],
    ]
}

/// The variational dynamics `Δx, Δẋ, Δẍ, Δu_ext` of one trial (000_* section 3.1,
/// eq. 19–21).
///
/// # Errors
/// [`EstimateError`] for mismatched lengths, non-finite samples, a perturbation
/// whose `T_est` runs past the record, a record too short for the filters, or bad
/// settings.
pub fn variational_dynamics(
    trial: &PerturbedTrial<'_>,
    fs_hz: f64,
    admittance: &Admittance,
    config: &BornerConfig,
) -> Result<VariationalDynamics, EstimateError> {
    check_admittance(admittance)?;
    Pipeline::new(fs_hz, config)?.variational(&mut RealFftPlanner::new(), trial, admittance)
}

fn check_admittance(adm: &Admittance) -> Result<(), EstimateError> {
    check_finite_mat2("M_adm", &adm.m_adm_kg)?;
    check_finite_mat2("D_adm", &adm.d_adm_ns_per_m)?;
    check_finite_mat2("M_handle", &adm.m_handle_kg)
}

/// Estimates `D̄` and a symmetric `K̄` from one or more perturbed trials with the
/// a-priori inertia `M̂_BSP` (000_* eq. 24–32): the regressor rows of all trials
/// are stacked (eq. 26–27) and solved by least squares (eq. 29).
///
/// Each sample gives two rows (eq. 31), with `ζ̄ = [D11, D12, D21, D22, K11, K12,
/// K22]` (eq. 30):
/// `b̄₁ = D11 Δẋ₁ + D12 Δẋ₂ + K11 Δx₁ + K12 Δx₂`,
/// `b̄₂ = D21 Δẋ₁ + D22 Δẋ₂ + K12 Δx₁ + K22 Δx₂`, with `b̄ = Δu_ext − M̂_BSP Δẍ` (eq. 32).
///
/// A single trial perturbs along one direction and usually cannot separate the
/// seven parameters; expect [`EstimateError::RankDeficient`] then. With three or
/// more trials the standard errors come from the delete-one-trial jackknife.
///
/// # Errors
/// As [`variational_dynamics`]; [`EstimateError::TooShort`] for no trials;
/// [`EstimateError::RankDeficient`] when the regressor does not determine `ζ̄`.
pub fn estimate_involuntary_impedance(
    trials: &[PerturbedTrial<'_>],
    fs_hz: f64,
    admittance: &Admittance,
    m_bsp_kg: &Mat2,
    config: &BornerConfig,
) -> Result<InvoluntaryImpedance, EstimateError> {
    if trials.is_empty() {
        return Err(EstimateError::TooShort {
            what: "set of perturbed trials",
            needed: 1,
            got: 0,
        });
    }
    check_admittance(admittance)?;
    check_finite_mat2("M_BSP", m_bsp_kg)?;
    let pipeline = Pipeline::new(fs_hz, config)?;
    // Trials are independent: split them over the available cores, keep their
    // order (and so the first error and the result) exactly as sequential.
    let n_threads = std::thread::available_parallelism()
        .map_or(1, std::num::NonZeroUsize::get)
        .clamp(1, trials.len());
    let chunk = trials.len().div_ceil(n_threads);
    let variational = std::thread::scope(|scope| {
        let handles: Vec<_> = trials
            .chunks(chunk)
            .map(|part| {
                let pipeline = &pipeline;
                scope.spawn(move || {
                    let mut planner = RealFftPlanner::new();
                    part.iter()
                        .map(|t| pipeline.variational(&mut planner, t, admittance))
                        .collect::<Result<Vec<_>, _>>()
                })
            })
            .collect();
        let mut out = Vec::with_capacity(trials.len());
        for h in handles {
            match h.join() {
                Ok(part) => out.extend(part?),
                Err(payload) => std::panic::resume_unwind(payload),
            }
        }
        Ok::<_, EstimateError>(out)
    })?;
    let rows_per_trial = 2 * pipeline.n_est;
    let n_rows = rows_per_trial * trials.len();
    let mut a = Vec::with_capacity(n_rows * 7);
    let mut b = Vec::with_capacity(n_rows);
    let mut groups = Vec::with_capacity(trials.len());
    for (t, vd) in variational.iter().enumerate() {
        groups.push(t * rows_per_trial..(t + 1) * rows_per_trial);
        for i in 0..pipeline.n_est {
            let [v1, v2] = vd.dv_m_per_s[i];
            let [x1, x2] = vd.dx_m[i];
            let ma = mul(m_bsp_kg, &vd.da_m_per_s2[i]);
            let du = vd.du_ext_n[i];
            a.extend_from_slice(&[v1, v2, 0.0, 0.0, x1, x2, 0.0]);
            b.push(du[0] - ma[0]);
            a.extend_from_slice(&[0.0, 0.0, v1, v2, 0.0, x1, x2]);
            b.push(du[1] - ma[1]);
        }
    }
    let fit = lsq::solve(&a, &b, 7, &groups, config.max_condition)?;
    let mut params = [0.0; 7];
    params.copy_from_slice(&fit.params);
    let mut covariance = [[0.0; 7]; 7];
    for (i, row) in covariance.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = fit.covariance[(i, j)];
        }
    }
    let se: Vec<f64> = (0..7).map(|i| fit.std_err(i)).collect();
    let residuals_n = fit
        .residuals
        .chunks_exact(2)
        .map(|r| [r[0], r[1]])
        .collect();
    Ok(InvoluntaryImpedance {
        d_ns_per_m: [[params[0], params[1]], [params[2], params[3]]],
        k_n_per_m: [[params[4], params[5]], [params[5], params[6]]],
        d_std_err_ns_per_m: [[se[0], se[1]], [se[2], se[3]]],
        k_std_err_n_per_m: [[se[4], se[5]], [se[5], se[6]]],
        params,
        covariance,
        covariance_kind: fit.covariance_kind,
        condition_number: fit.condition_number,
        nrmse: fit.nrmse,
        residuals_n,
        variational,
    })
}
