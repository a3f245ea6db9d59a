//! Force-error and skill-gain measures of Piovesan et al. (001_* eq. 9–13): per-cycle
//! mean force and mean absolute error outside the perturbations (eq. 9), their
//! window averages (eq. 10), the skill gain (eq. 11), the stiffness change
//! (eq. 12) and the sign correlation between skill gain and stiffness change
//! (eq. 13).

use std::ops::Range;

use super::error::{EstimateError, check_finite};

/// Per-cycle force measures along one direction `s` (001_* eq. 9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleForce {
    /// `φ_sᵏ`: mean force over the cycle's samples outside perturbations, N (eq. 9a).
    pub mean_n: f64,
    /// `e_sᵏ`: mean `|F_s − F_ref,s|` over the same samples, N (eq. 9b).
    pub abs_error_n: f64,
    /// `N`: samples counted (the cycle's samples not in `P`).
    pub n_samples: usize,
}

/// Per-window force errors along one direction (001_* eq. 10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowForceError {
    /// `Ξ_sⁱ`: mean of the window's `φ` minus `F_ref,s`, N (eq. 10a).
    pub signed_n: f64,
    /// `E_sⁱ`: mean of the window's `e`, N (eq. 10b).
    pub abs_n: f64,
}

/// Eq. 9 for each cycle. `cycle_bounds` holds `N_c + 1` ascending sample indices
/// (cycle `k` is `cycle_bounds[k]..cycle_bounds[k+1]`); `excluded` lists the sample
/// ranges `P` of the perturbations; `f_ref_n` is the constant reference force.
///
/// # Errors
/// [`EstimateError::TooShort`] for fewer than two bounds or a cycle with no sample
/// left, [`EstimateError::BadParameter`] for descending bounds or bounds past the
/// record, [`EstimateError::NonFinite`] for a bad sample or reference.
pub fn cycle_force_measures(
    force_n: &[f64],
    f_ref_n: f64,
    cycle_bounds: &[usize],
    excluded: &[Range<usize>],
) -> Result<Vec<CycleForce>, EstimateError> {
    if !f_ref_n.is_finite() {
        return Err(EstimateError::BadParameter {
            what: "f_ref_n",
            value: f_ref_n,
            why: "must be finite",
        });
    }
    if cycle_bounds.len() < 2 {
        return Err(EstimateError::TooShort {
            what: "cycle bounds",
            needed: 2,
            got: cycle_bounds.len(),
        });
    }
    check_finite("force", force_n)?;
    let mut out = Vec::with_capacity(cycle_bounds.len() - 1);
    for w in cycle_bounds.windows(2) {
        let (start, end) = (w[0], w[1]);
        if start > end || end > force_n.len() {
            return Err(EstimateError::BadParameter {
                what: "cycle bound",
                value: end as f64,
                why: "bounds must ascend and stay within the record",
            });
        }
        let (mut sum, mut abs, mut n) = (0.0, 0.0, 0usize);
        for (i, f) in force_n.iter().enumerate().take(end).skip(start) {
            if excluded.iter().any(|r| r.contains(&i)) {
                continue;
            }
            sum += f;
            abs += (f - f_ref_n).abs();
            n += 1;
        }
        if n == 0 {
            return Err(EstimateError::TooShort {
                what: "cycle (samples outside perturbations)",
                needed: 1,
                got: 0,
            });
        }
        out.push(CycleForce {
            mean_n: sum / n as f64,
            abs_error_n: abs / n as f64,
            n_samples: n,
        });
    }
    Ok(out)
}

/// Eq. 10 for the windows `i = 1..N_WT` of `window_cycles` consecutive cycles,
/// sliding by one cycle.
///
/// # Errors
/// [`EstimateError::TooShort`] when there are fewer cycles than one window (or the
/// window is empty), [`EstimateError::BadParameter`] for a non-finite reference.
pub fn window_force_errors(
    cycles: &[CycleForce],
    f_ref_n: f64,
    window_cycles: usize,
) -> Result<Vec<WindowForceError>, EstimateError> {
    if !f_ref_n.is_finite() {
        return Err(EstimateError::BadParameter {
            what: "f_ref_n",
            value: f_ref_n,
            why: "must be finite",
        });
    }
    if window_cycles == 0 || cycles.len() < window_cycles {
        return Err(EstimateError::TooShort {
            what: "cycles for one window",
            needed: window_cycles.max(1),
            got: cycles.len(),
        });
    }
    let nw = window_cycles as f64;
    Ok(cycles
        .windows(window_cycles)
        .map(|w| WindowForceError {
            signed_n: w.iter().map(|c| c.mean_n).sum::<f64>() / nw - f_ref_n,
            abs_n: w.iter().map(|c| c.abs_error_n).sum::<f64>() / nw,
        })
        .collect())
}

/// Skill gain `G_s = E_s¹ − E_s^{N_WT}` (eq. 11), N: positive when the absolute
/// force error fell from the first window to the last.
///
/// # Errors
/// [`EstimateError::TooShort`] for no windows.
pub fn skill_gain(windows: &[WindowForceError]) -> Result<f64, EstimateError> {
    match (windows.first(), windows.last()) {
        (Some(first), Some(last)) => Ok(first.abs_n - last.abs_n),
        _ => Err(EstimateError::TooShort {
            what: "windows",
            needed: 1,
            got: 0,
        }),
    }
}

/// Stiffness change `ΔK = K_{N_WT} − K₁` (eq. 12) of one stiffness component, N/m,
/// from the per-window estimates in order.
///
/// # Errors
/// [`EstimateError::TooShort`] for no estimates.
pub fn stiffness_change(per_window_n_per_m: &[f64]) -> Result<f64, EstimateError> {
    match (per_window_n_per_m.first(), per_window_n_per_m.last()) {
        (Some(first), Some(last)) => Ok(last - first),
        _ => Err(EstimateError::TooShort {
            what: "window estimates",
            needed: 1,
            got: 0,
        }),
    }
}

/// Sign correlation `R = (1/N_T) Σ sgn(G_i) sgn(ΔK_i)` (eq. 13) over trials;
/// `sgn(0) = 0`, so `−1 ≤ R ≤ 1`.
///
/// # Errors
/// [`EstimateError::TooShort`] for no trials, [`EstimateError::LengthMismatch`],
/// [`EstimateError::NonFinite`].
pub fn sign_correlation(gains: &[f64], delta_k: &[f64]) -> Result<f64, EstimateError> {
    if gains.len() != delta_k.len() {
        return Err(EstimateError::LengthMismatch {
            what: "skill gains vs stiffness changes",
            left: gains.len(),
            right: delta_k.len(),
        });
    }
    if gains.is_empty() {
        return Err(EstimateError::TooShort {
            what: "trials",
            needed: 1,
            got: 0,
        });
    }
    check_finite("skill gains", gains)?;
    check_finite("stiffness changes", delta_k)?;
    let sgn = |v: f64| {
        if v > 0.0 {
            1.0
        } else if v < 0.0 {
            -1.0
        } else {
            0.0
        }
    };
    Ok(gains
        .iter()
        .zip(delta_k)
        .map(|(g, k)| sgn(*g) * sgn(*k))
        .sum::<f64>()
        / gains.len() as f64)
}
