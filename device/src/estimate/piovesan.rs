//! Windowed stiffness and damping regression of Piovesan et al. (001_*, "Impedance
//! Estimation"): per position perturbation, a linear baseline from the onset to
//! 0.7 s later, the error `e` and its derivatives, the force change `ΔF`; per window
//! of `N_w` cycles sliding by one cycle, `[K B] = (ΔF − M̂ ë) [e; ė]^#` by the
//! Moore–Penrose pseudoinverse, and the canonical correlation `r²` of eq. 8.

use super::Mat2;
use super::ellipse::{CurlTest, curl_test};
use super::error::{EstimateError, check_finite, check_finite_mat2, check_positive};
use super::lsq::{self, CovarianceKind};
use crate::signal::{
    EdgeMode, cumulative_trapezoid, gradient, savgol_filter, savgol_window_for_cutoff,
};
use nalgebra::{Matrix2, Matrix2x4, Matrix4};

/// Settings of the windowed regression; [`Default`] is the seed's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PiovesanConfig {
    /// Baseline from the onset `t₀` to `t_f = t₀ + baseline_s`, s (seed: 0.7).
    pub baseline_s: f64,
    /// Data used per perturbation, from `t₀` to `t_p = t₀ + regression_s`, s
    /// (seed: 0.30).
    pub regression_s: f64,
    /// Savitzky–Golay order (seed: 6).
    pub savgol_polyorder: usize,
    /// Savitzky–Golay cut-off, Hz (seed: 23.4).
    pub savgol_cutoff_hz: f64,
    /// Cycles per window `N_w` (seed: 10); windows slide by one cycle, giving
    /// `N_WT = N_c − N_w + 1` estimates.
    pub window_cycles: usize,
    /// Remove each perturbation's mean (seed: "we subtracted the mean force to avoid
    /// bias"). Removing a constant from the force alone would bias a regression
    /// without intercept, so the mean is removed from the force and the kinematics
    /// alike — the same as a per-perturbation intercept.
    pub remove_mean: bool,
    /// Pass position and force through one identical filter: the Savitzky–Golay
    /// second-derivative filter applied to the (fourth-order) double running integral of the
    /// force and of the position (giving `F` and `x`), to the single integral of
    /// the position (`ẋ`) and to the position (`ẍ`). The regression then sees the
    /// same linear filter on both sides of `F = K x + B ẋ + M ẍ`. With `false`,
    /// `x` and `F` are smoothed and `ẋ, ẍ` are the smoother's first and second
    /// derivatives (the seed's description), whose gains differ slightly near the
    /// cut-off; on the seed's 100 ms transitions that mismatch biases `B` by ~10 %.
    pub consistent_filtering: bool,
    /// Largest acceptable condition number of the equilibrated regressor.
    pub max_condition: f64,
}

impl Default for PiovesanConfig {
    fn default() -> Self {
        Self {
            baseline_s: 0.7,
            regression_s: 0.30,
            savgol_polyorder: 6,
            savgol_cutoff_hz: 23.4,
            window_cycles: 10,
            remove_mean: true,
            consistent_filtering: true,
            max_condition: 1e8,
        }
    }
}

/// Where and in which movement cycle a position perturbation starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PositionPerturbation {
    /// Sample index of the onset `t₀ⁱ`.
    pub onset_index: usize,
    /// Movement cycle (0-based) the perturbation belongs to.
    pub cycle: usize,
}

/// One imposed-motion trial: handle position and the force the subject applies to
/// the handle on both axes, and the perturbations.
#[derive(Debug, Clone, Copy)]
pub struct ImposedMotionTrial<'a> {
    /// Position per axis, m.
    pub x_m: [&'a [f64]; 2],
    /// Force on the handle per axis, N.
    pub force_n: [&'a [f64]; 2],
    /// The perturbations, in any order.
    pub perturbations: &'a [PositionPerturbation],
    /// Number of movement cycles `N_c` (seed: 25).
    pub n_cycles: usize,
}

/// The response to one perturbation over `[t₀, t_p]`.
#[derive(Debug, Clone, PartialEq)]
pub struct PerturbationResponse {
    /// Onset sample.
    pub onset_index: usize,
    /// Movement cycle.
    pub cycle: usize,
    /// Position error `e` from the baseline, m.
    pub e_m: Vec<[f64; 2]>,
    /// `ė`, m/s.
    pub de_m_per_s: Vec<[f64; 2]>,
    /// `ë`, m/s².
    pub dde_m_per_s2: Vec<[f64; 2]>,
    /// `ΔF`, force minus its baseline, N.
    pub df_n: Vec<[f64; 2]>,
}

/// Stiffness and damping of one window (001_*, the regression below Fig. 4).
#[derive(Debug, Clone, PartialEq)]
pub struct WindowEstimate {
    /// First cycle of the window (0-based).
    pub first_cycle: usize,
    /// Perturbations used, `N_Pw`.
    pub n_perturbations: usize,
    /// `K`, N/m (full 2x2).
    pub k_n_per_m: Mat2,
    /// `B`, N s/m (full 2x2).
    pub b_ns_per_m: Mat2,
    /// Standard errors of `K`, N/m.
    pub k_std_err_n_per_m: Mat2,
    /// Standard errors of `B`, N s/m.
    pub b_std_err_ns_per_m: Mat2,
    /// `[K11, K12, K21, K22, B11, B12, B21, B22]`.
    pub params: [f64; 8],
    /// Covariance of `params`.
    pub covariance: [[f64; 8]; 8],
    /// Jackknife over perturbations when there are ≥ 3, else ordinary.
    pub covariance_kind: CovarianceKind,
    /// Canonical correlation `r²` of eq. 8 between `ΔF − M̂ë` and `[e; ė]`.
    pub canonical_r2: f64,
    /// Condition number of the equilibrated kinematic regressor.
    pub condition_number: f64,
    /// RMS residual over the largest `|ΔF − M̂ë|`.
    pub nrmse: f64,
}

impl WindowEstimate {
    /// Tests whether `K` has curl (`K₁₂ ≠ K₂₁`) at level `alpha` (seed: 0.01).
    ///
    /// # Errors
    /// As [`curl_test`].
    pub fn stiffness_curl(&self, alpha: f64) -> Result<CurlTest, EstimateError> {
        let c = &self.covariance;
        curl_test(&self.k_n_per_m, c[1][1], c[2][2], c[1][2], alpha)
    }

    /// Tests whether `B` has curl (`B₁₂ ≠ B₂₁`) at level `alpha`.
    ///
    /// # Errors
    /// As [`curl_test`].
    pub fn damping_curl(&self, alpha: f64) -> Result<CurlTest, EstimateError> {
        let c = &self.covariance;
        curl_test(&self.b_ns_per_m, c[5][5], c[6][6], c[5][6], alpha)
    }
}

/// Extracts the response to every perturbation of a trial (001_*, Fig. 4 and the
/// paragraph before the regression): signals smoothed by Savitzky–Golay, velocity
/// and acceleration as its first and second derivatives; the baseline of position
/// and force is the straight line from `t₀` to `t₀ + 0.7 s`, and the same
/// straight-line baseline is removed from the velocity and acceleration:
/// `e = x − baseline`, `ė = ẋ − its baseline`, `ë = ẍ − its baseline`,
/// `ΔF = F − baseline`; means removed if asked.
///
/// Only a segment around each perturbation is filtered (the filter's half window
/// beyond its ends), so long trials cost in proportion to the perturbations.
///
/// # Errors
/// [`EstimateError::LengthMismatch`], [`EstimateError::NonFinite`],
/// [`EstimateError::PerturbationBeyondRecord`] when a baseline runs past the
/// record, [`EstimateError::BadParameter`] for bad settings (including a regression
/// interval longer than the baseline), [`EstimateError::Signal`] for a segment
/// shorter than the filter window.
pub fn perturbation_responses(
    trial: &ImposedMotionTrial<'_>,
    fs_hz: f64,
    config: &PiovesanConfig,
) -> Result<Vec<PerturbationResponse>, EstimateError> {
    check_positive("fs_hz", fs_hz)?;
    check_positive("baseline_s", config.baseline_s)?;
    check_positive("regression_s", config.regression_s)?;
    let len = trial.x_m[0].len();
    for axis in 0..2 {
        for (what, s) in [
            ("position", trial.x_m[axis]),
            ("force", trial.force_n[axis]),
        ] {
            if s.len() != len {
                return Err(EstimateError::LengthMismatch {
                    what,
                    left: len,
                    right: s.len(),
                });
            }
        }
    }
    let dt = 1.0 / fs_hz;
    let window = savgol_window_for_cutoff(config.savgol_polyorder, config.savgol_cutoff_hz, fs_hz)
        .map_err(EstimateError::signal("choosing the Savitzky-Golay window"))?;
    let n_base = (config.baseline_s * fs_hz).round() as usize;
    let n_reg = (config.regression_s * fs_hz).round() as usize + 1;
    if n_base < 2 || n_reg < 2 || n_reg > n_base + 1 {
        return Err(EstimateError::BadParameter {
            what: "regression_s",
            value: config.regression_s,
            why: "needs >= 2 samples and must not exceed the baseline interval",
        });
    }
    let half = window / 2;
    let mut out = Vec::with_capacity(trial.perturbations.len());
    for p in trial.perturbations {
        let k0 = p.onset_index;
        let kf = k0.saturating_add(n_base);
        if kf >= len {
            return Err(EstimateError::PerturbationBeyondRecord {
                onset_index: k0,
                needed_end: kf.saturating_add(1),
                len,
            });
        }
        if p.cycle >= trial.n_cycles {
            return Err(EstimateError::BadParameter {
                what: "perturbation cycle",
                value: p.cycle as f64,
                why: "must be below n_cycles",
            });
        }
        let s0 = k0.saturating_sub(half);
        let s1 = (kf + half + 1).min(len);
        let (i0, i_f) = (k0 - s0, kf - s0);
        let mut e = vec![[0.0; 2]; n_reg];
        let mut de = vec![[0.0; 2]; n_reg];
        let mut dde = vec![[0.0; 2]; n_reg];
        let mut df = vec![[0.0; 2]; n_reg];
        for axis in 0..2 {
            let xs = &trial.x_m[axis][s0..s1];
            let fs = &trial.force_n[axis][s0..s1];
            check_finite("position", xs)?;
            check_finite("force", fs)?;
            let sg = |y: &[f64], d: usize| {
                savgol_filter(y, window, config.savgol_polyorder, d, dt, EdgeMode::Interp).map_err(
                    EstimateError::signal("smoothing around a perturbation (Savitzky-Golay)"),
                )
            };
            let (x0, v, a, f0) = if config.consistent_filtering {
                let ix = integrate(xs, dt);
                let iix = integrate(&ix, dt);
                let iif = integrate(&integrate(fs, dt), dt);
                (sg(&iix, 2)?, sg(&ix, 2)?, sg(xs, 2)?, sg(&iif, 2)?)
            } else {
                (sg(xs, 0)?, sg(xs, 1)?, sg(xs, 2)?, sg(fs, 0)?)
            };
            // The same straight-line baseline, t₀ to t_f, is removed from every
            // signal: the force baseline is K·(x baseline) + B·(ẋ baseline) +
            // M·(ẍ baseline), so only this keeps the regression exact. (The
            // smoothed ẋ and ẍ are not zero at t₀: the smoother's window reaches
            // into the perturbation.)
            let base = |y: &[f64], k: usize| {
                let frac = (k - i0) as f64 / n_base as f64;
                y[i0] + (y[i_f] - y[i0]) * frac
            };
            for i in 0..n_reg {
                let k = i0 + i;
                e[i][axis] = x0[k] - base(&x0, k);
                de[i][axis] = v[k] - base(&v, k);
                dde[i][axis] = a[k] - base(&a, k);
                df[i][axis] = f0[k] - base(&f0, k);
            }
        }
        if config.remove_mean {
            for sig in [&mut e, &mut de, &mut dde, &mut df] {
                remove_mean(sig);
            }
        }
        out.push(PerturbationResponse {
            onset_index: k0,
            cycle: p.cycle,
            e_m: e,
            de_m_per_s: de,
            dde_m_per_s2: dde,
            df_n: df,
        });
    }
    Ok(out)
}

/// Running integral with the trapezoid rule's end correction (`−dt²/12 · Δy'`,
/// Euler–Maclaurin), fourth-order accurate: plain trapezoids leave a relative error
/// of `(ω dt)²/6` in the double integral of the acceleration, ~1 % of the inertial
/// force at 10 Hz and 250 Hz, which leaked into K.
fn integrate(y: &[f64], dt: f64) -> Vec<f64> {
    let slope = gradient(y, dt);
    let g0 = slope.first().copied().unwrap_or(0.0);
    cumulative_trapezoid(y, dt)
        .into_iter()
        .zip(&slope)
        .map(|(s, g)| s - dt * dt / 12.0 * (g - g0))
        .collect()
}

fn remove_mean(sig: &mut [[f64; 2]]) {
    let n = sig.len() as f64;
    for axis in 0..2 {
        let mean = sig.iter().map(|s| s[axis]).sum::<f64>() / n;
        for s in sig.iter_mut() {
            s[axis] -= mean;
        }
    }
}

/// `[K B]` from a set of perturbation responses (001_*, the regression equation
/// below Fig. 4): `ΔF − M̂ ë = [K B] [e; ė]`, solved with the pseudoinverse, plus
/// the canonical correlation of eq. 8.
///
/// # Errors
/// [`EstimateError::TooShort`] for no responses, [`EstimateError::RankDeficient`]
/// when the perturbations do not span both axes, [`EstimateError::NonFinite`] for a
/// bad `m_hat_kg`, [`EstimateError::SingularCovariance`] for constant signals.
pub fn estimate_window(
    responses: &[&PerturbationResponse],
    m_hat_kg: &Mat2,
    max_condition: f64,
) -> Result<WindowEstimate, EstimateError> {
    check_finite_mat2("inertia estimate", m_hat_kg)?;
    if responses.is_empty() {
        return Err(EstimateError::TooShort {
            what: "window (perturbations)",
            needed: 1,
            got: 0,
        });
    }
    let n_rows: usize = responses.iter().map(|r| 2 * r.e_m.len()).sum();
    let mut a = Vec::with_capacity(n_rows * 8);
    let mut b = Vec::with_capacity(n_rows);
    let mut groups = Vec::with_capacity(responses.len());
    let mut force = Vec::with_capacity(n_rows / 2);
    let mut kin = Vec::with_capacity(n_rows / 2);
    for r in responses {
        let start = b.len();
        for i in 0..r.e_m.len() {
            let [e1, e2] = r.e_m[i];
            let [v1, v2] = r.de_m_per_s[i];
            let acc = r.dde_m_per_s2[i];
            let m = m_hat_kg;
            let y = [
                r.df_n[i][0] - (m[0][0] * acc[0] + m[0][1] * acc[1]),
                r.df_n[i][1] - (m[1][0] * acc[0] + m[1][1] * acc[1]),
            ];
            a.extend_from_slice(&[e1, e2, 0.0, 0.0, v1, v2, 0.0, 0.0]);
            b.push(y[0]);
            a.extend_from_slice(&[0.0, 0.0, e1, e2, 0.0, 0.0, v1, v2]);
            b.push(y[1]);
            force.push(y);
            kin.push([e1, e2, v1, v2]);
        }
        groups.push(start..b.len());
    }
    let fit = lsq::solve(&a, &b, 8, &groups, max_condition)?;
    let canonical_r2 = canonical_correlation(&force, &kin)?;
    let p = &fit.params;
    let mut params = [0.0; 8];
    params.copy_from_slice(p);
    let se: Vec<f64> = (0..8).map(|i| fit.std_err(i)).collect();
    let mut covariance = [[0.0; 8]; 8];
    for (i, row) in covariance.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = fit.covariance[(i, j)];
        }
    }
    Ok(WindowEstimate {
        first_cycle: responses.iter().map(|r| r.cycle).min().unwrap_or(0),
        n_perturbations: responses.len(),
        k_n_per_m: [[p[0], p[1]], [p[2], p[3]]],
        b_ns_per_m: [[p[4], p[5]], [p[6], p[7]]],
        k_std_err_n_per_m: [[se[0], se[1]], [se[2], se[3]]],
        b_std_err_ns_per_m: [[se[4], se[5]], [se[6], se[7]]],
        params,
        covariance,
        covariance_kind: fit.covariance_kind,
        canonical_r2,
        condition_number: fit.condition_number,
        nrmse: fit.nrmse,
    })
}

/// Canonical correlation `r² = max eig(S_FF⁻¹ S_FX S_XX⁻¹ S_XF)` (001_* eq. 8)
/// between a 2-D force and 4-D kinematics (`[e₁, e₂, ė₁, ė₂]`), sample by sample,
/// with the sample means removed.
///
/// # Errors
/// [`EstimateError::TooShort`] for fewer than 6 samples, [`EstimateError::LengthMismatch`],
/// [`EstimateError::NonFinite`], [`EstimateError::SingularCovariance`] when either
/// covariance cannot be inverted.
pub fn canonical_correlation(
    force: &[[f64; 2]],
    kinematics: &[[f64; 4]],
) -> Result<f64, EstimateError> {
    let n = force.len();
    if n != kinematics.len() {
        return Err(EstimateError::LengthMismatch {
            what: "force vs kinematics",
            left: n,
            right: kinematics.len(),
        });
    }
    if n < 6 {
        return Err(EstimateError::TooShort {
            what: "canonical correlation (samples)",
            needed: 6,
            got: n,
        });
    }
    let mf = force
        .iter()
        .fold([0.0; 2], |acc, f| [acc[0] + f[0], acc[1] + f[1]]);
    let mk = kinematics
        .iter()
        .fold([0.0; 4], |acc, k| std::array::from_fn(|i| acc[i] + k[i]));
    let nf = n as f64;
    let mf = mf.map(|v| v / nf);
    let mk = mk.map(|v| v / nf);
    let mut sff = Matrix2::<f64>::zeros();
    let mut sfx = Matrix2x4::<f64>::zeros();
    let mut sxx = Matrix4::<f64>::zeros();
    for (f, k) in force.iter().zip(kinematics) {
        let fc = nalgebra::Vector2::new(f[0] - mf[0], f[1] - mf[1]);
        let kc = nalgebra::Vector4::new(k[0] - mk[0], k[1] - mk[1], k[2] - mk[2], k[3] - mk[3]);
        sff += fc * fc.transpose();
        sfx += fc * kc.transpose();
        sxx += kc * kc.transpose();
    }
    if !(sff.iter().all(|v| v.is_finite())
        && sxx.iter().all(|v| v.is_finite())
        && sfx.iter().all(|v| v.is_finite()))
    {
        return Err(EstimateError::NonFinite {
            what: "canonical correlation input",
            index: 0,
        });
    }
    let sxx_inv = sxx
        .try_inverse()
        .ok_or(EstimateError::SingularCovariance { what: "kinematics" })?;
    let sff_inv = sff
        .try_inverse()
        .ok_or(EstimateError::SingularCovariance { what: "force" })?;
    let c = sff_inv * sfx * sxx_inv * sfx.transpose();
    // Eigenvalues of C are real (C is similar to a symmetric PSD matrix).
    let tr = c.trace();
    let det = c.determinant();
    let disc = (0.25 * tr * tr - det).max(0.0);
    let r2 = 0.5 * tr + disc.sqrt();
    if !r2.is_finite() {
        return Err(EstimateError::SingularCovariance { what: "force" });
    }
    // r² lies in [0, 1]; an exactly linear relation can round a few ulps above 1.
    Ok(r2.clamp(0.0, 1.0))
}

/// The sliding-window estimates of a trial: windows of `N_w` cycles starting at
/// cycles `0, 1, …, N_c − N_w`, each using the perturbations of its cycles
/// (001_*: 25 cycles and `N_w = 10` give 16 estimates).
///
/// # Errors
/// As [`perturbation_responses`] and [`estimate_window`];
/// [`EstimateError::TooShort`] when the trial has fewer cycles than a window.
pub fn windowed_impedance(
    trial: &ImposedMotionTrial<'_>,
    fs_hz: f64,
    m_hat_kg: &Mat2,
    config: &PiovesanConfig,
) -> Result<Vec<WindowEstimate>, EstimateError> {
    if config.window_cycles == 0 || trial.n_cycles < config.window_cycles {
        return Err(EstimateError::TooShort {
            what: "trial (cycles) for one window",
            needed: config.window_cycles.max(1),
            got: trial.n_cycles,
        });
    }
    let responses = perturbation_responses(trial, fs_hz, config)?;
    let n_windows = trial.n_cycles - config.window_cycles + 1;
    (0..n_windows)
        .map(|j| {
            let members: Vec<&PerturbationResponse> = responses
                .iter()
                .filter(|r| (j..j + config.window_cycles).contains(&r.cycle))
                .collect();
            let mut w = estimate_window(&members, m_hat_kg, config.max_condition)?;
            w.first_cycle = j;
            Ok(w)
        })
        .collect()
}
