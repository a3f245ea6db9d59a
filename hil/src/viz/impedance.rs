//! Impedance ellipses from the seed estimators, drawn at the hand position, with the
//! simulated arm's ground truth beside the estimate when it is known.
//!
//! The estimates are the ones `rigtwin estimate` and the rehearsal report compute (this
//! module calls [`crate::report`], it does not estimate anything itself):
//!
//! - Börner et al. (000_*), force-pulse reaches: one `K̂`, `D̂` per session (one trial
//!   perturbs along one direction and cannot separate the seven parameters), drawn at the
//!   mean hand position at the onsets, at the start of the session; a rehearsal adds the
//!   arm's intrinsic impedance at each onset, at that onset.
//! - Piovesan et al. (001_*), hold trials with position perturbations: one `K̂`, `B̂` per
//!   10-cycle window, at the window's last perturbation, at the hand position there.
//!
//! Entities: `ellipses/{stiffness,damping}/{estimate,truth,truth_at_onset}/{outline,axes}`
//! and the matrices, `f64`, as time series `plots/impedance/{stiffness,damping}/...`.

use super::columns::TrialSpan;
use super::{EllipseAxes, EventLevel, Stamp, Viewer, VizError};
use crate::protocol::EstimateConfig;
use crate::report::estimate::{
    BornerResult, PiovesanTrial, SessionEstimateError, borner_on_session, onset_index,
    piovesan_on_session, push_onsets,
};
use crate::session::{PerturbationKind, Session};

/// Drawing scale of a stiffness ellipse: metres per N/m (300 N/m is 45 mm).
pub const STIFFNESS_SCALE_M_PER_N_PER_M: f64 = 1.5e-4;

/// Drawing scale of a damping ellipse: metres per N s/m (10 N s/m is 30 mm).
pub const DAMPING_SCALE_M_PER_N_S_PER_M: f64 = 3e-3;

const ESTIMATE_RGB: [u8; 3] = [170, 60, 170];
const TRUTH_RGB: [u8; 3] = [40, 160, 90];
const ONSET_TRUTH_RGB: [u8; 3] = [120, 200, 140];

/// A stiffness and a damping, row-major 2x2, rig frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impedance {
    /// `K`, N/m.
    pub stiffness_n_per_m: [[f64; 2]; 2],
    /// `D` (or `B`), N s/m.
    pub damping_n_s_per_m: [[f64; 2]; 2],
}

/// Which ellipse of a pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    /// The estimator's output.
    Estimate,
    /// The simulated arm's intrinsic impedance matching the estimate (mean over the onsets
    /// the estimate used).
    Truth,
    /// The simulated arm's intrinsic impedance at one perturbation onset.
    TruthAtOnset,
}

impl Which {
    /// The name under `ellipses/stiffness/` and `ellipses/damping/`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Estimate => "estimate",
            Self::Truth => "truth",
            Self::TruthAtOnset => "truth_at_onset",
        }
    }

    fn rgb(self) -> [u8; 3] {
        match self {
            Self::Estimate => ESTIMATE_RGB,
            Self::Truth => TRUTH_RGB,
            Self::TruthAtOnset => ONSET_TRUTH_RGB,
        }
    }

    /// The time-series entities of the stiffness and damping matrices.
    pub fn matrix_paths(self) -> [&'static str; 2] {
        match self {
            Self::Estimate => [
                "plots/impedance/stiffness/estimate",
                "plots/impedance/damping/estimate",
            ],
            Self::Truth => [
                "plots/impedance/stiffness/truth",
                "plots/impedance/damping/truth",
            ],
            Self::TruthAtOnset => [
                "plots/impedance/stiffness/truth_at_onset",
                "plots/impedance/damping/truth_at_onset",
            ],
        }
    }
}

/// The ellipse names (for [`super::paths::ellipse_outline`] and
/// [`super::paths::ellipse_axes`]) of the stiffness and damping of `which`.
pub fn ellipse_names(which: Which) -> [String; 2] {
    [
        format!("stiffness/{}", which.name()),
        format!("damping/{}", which.name()),
    ]
}

/// Draws the stiffness and damping ellipses of `imp` at `hand_m` and logs both matrices as
/// time series; `note` goes into the labels. Returns the axes drawn (stiffness, damping).
pub fn log_impedance(
    viewer: &mut Viewer,
    which: Which,
    at: Stamp,
    hand_m: [f64; 2],
    imp: &Impedance,
    note: &str,
) -> Result<[EllipseAxes; 2], VizError> {
    let [k_name, d_name] = ellipse_names(which);
    let [k_path, d_path] = which.matrix_paths();
    let sep = if note.is_empty() { "" } else { " " };
    let k = viewer.log_ellipse_rgb(
        &k_name,
        Some(at),
        hand_m,
        imp.stiffness_n_per_m,
        STIFFNESS_SCALE_M_PER_N_PER_M,
        &format!("K {}{sep}{note} (N/m)", which.name()),
        which.rgb(),
    )?;
    let d = viewer.log_ellipse_rgb(
        &d_name,
        Some(at),
        hand_m,
        imp.damping_n_s_per_m,
        DAMPING_SCALE_M_PER_N_S_PER_M,
        &format!("D {}{sep}{note} (N s/m)", which.name()),
        which.rgb(),
    )?;
    viewer.log_matrix(
        k_path,
        at,
        ["K11", "K12", "K21", "K22"],
        imp.stiffness_n_per_m,
    )?;
    viewer.log_matrix(
        d_path,
        at,
        ["D11", "D12", "D21", "D22"],
        imp.damping_n_s_per_m,
    )?;
    Ok([k, d])
}

fn fmt_mat(m: &[[f64; 2]; 2]) -> String {
    format!(
        "[[{:.1}, {:.1}], [{:.1}, {:.1}]]",
        m[0][0], m[0][1], m[1][0], m[1][1]
    )
}

/// The hand position at the onset of every force-pulse trial of a session (the trials and
/// rows [`borner_on_session`] uses), with the trial's position in the session.
pub fn pulse_onsets(session: &Session) -> Vec<(usize, [f64; 2])> {
    let rate = session.manifest.rate_hz;
    session
        .iter()
        .enumerate()
        .filter_map(|(i, (entry, table))| {
            let p = entry.perturbation.as_ref()?;
            if p.kind != PerturbationKind::ForcePulse {
                return None;
            }
            let i0 = onset_index(p.onset_s, rate);
            Some((i, [*table.x_m.get(i0)?, *table.y_m.get(i0)?]))
        })
        .collect()
}

/// The mean of some points (the origin for none).
pub fn mean_point(points: impl IntoIterator<Item = [f64; 2]>) -> [f64; 2] {
    let (mut sum, mut n) = ([0.0; 2], 0.0);
    for p in points {
        sum[0] += p[0];
        sum[1] += p[1];
        n += 1.0;
    }
    if n > 0.0 {
        [sum[0] / n, sum[1] / n]
    } else {
        [0.0; 2]
    }
}

/// Logs a session's Börner estimate at `at` (the start of the session), drawn at `hand_m`,
/// with the ground truth beside it when given, and an event with the values.
pub fn log_borner(
    viewer: &mut Viewer,
    at: Stamp,
    hand_m: [f64; 2],
    est: &BornerResult,
    truth: Option<&Impedance>,
) -> Result<(), VizError> {
    let imp = Impedance {
        stiffness_n_per_m: est.k_n_per_m,
        damping_n_s_per_m: est.d_ns_per_m,
    };
    let note = format!("Börner, {} trials", est.trials);
    log_impedance(viewer, Which::Estimate, at, hand_m, &imp, &note)?;
    let mut text = format!(
        "Börner estimate over {} force-pulse trials at hand [{:.3}, {:.3}] m: K {} N/m, D {} N s/m",
        est.trials,
        hand_m[0],
        hand_m[1],
        fmt_mat(&est.k_n_per_m),
        fmt_mat(&est.d_ns_per_m)
    );
    if let Some(t) = truth {
        log_impedance(
            viewer,
            Which::Truth,
            at,
            hand_m,
            t,
            "intrinsic, mean at onsets",
        )?;
        text.push_str(&format!(
            "; simulated arm (intrinsic, mean at the onsets): K {} N/m, D {} N s/m",
            fmt_mat(&t.stiffness_n_per_m),
            fmt_mat(&t.damping_n_s_per_m)
        ));
    }
    viewer.log_event(at, EventLevel::Info, &text)
}

/// Logs one window estimate per window of every hold trial of a session (the output of
/// [`piovesan_on_session`]); `spans` are the trials' places on the timelines
/// ([`super::Logged::spans`]). Returns the number of windows drawn.
pub fn log_piovesan(
    viewer: &mut Viewer,
    session: &Session,
    spans: &[TrialSpan],
    trials: &[Result<PiovesanTrial, String>],
) -> Result<usize, VizError> {
    let mut drawn = 0;
    for trial in trials {
        let t = match trial {
            Ok(t) => t,
            Err(why) => {
                let at = spans
                    .first()
                    .map_or_else(|| viewer.stamp_at(0.0), |s| s.stamp(0.0));
                viewer.log_event(at, EventLevel::Warn, &format!("windowed regression: {why}"))?;
                continue;
            }
        };
        let Some(index) = session.manifest.trials.iter().position(|e| e.id == t.id) else {
            continue;
        };
        let (Some(span), Some(table)) = (spans.get(index), session.trials.get(index)) else {
            continue;
        };
        let n_cycles = t.onsets.len().div_ceil(2);
        let window_cycles = (n_cycles + 1)
            .saturating_sub(t.window_estimates.len())
            .max(1);
        for (j, w) in t.window_estimates.iter().enumerate() {
            // The window's estimate exists once its last perturbation has happened.
            let last = (2 * (j + window_cycles)).saturating_sub(1);
            let Some(&row) = t.onsets.get(last.min(t.onsets.len().saturating_sub(1))) else {
                continue;
            };
            let (Some(&x), Some(&y), Some(&time)) =
                (table.x_m.get(row), table.y_m.get(row), table.t_s.get(row))
            else {
                continue;
            };
            let imp = Impedance {
                stiffness_n_per_m: w.k_n_per_m,
                damping_n_s_per_m: w.b_ns_per_m,
            };
            let note = format!(
                "trial {} cycles {}-{}, r² {:.2}",
                t.id,
                w.first_cycle + 1,
                w.first_cycle + window_cycles,
                w.canonical_r2
            );
            log_impedance(
                viewer,
                Which::Estimate,
                span.stamp(time),
                [x, y],
                &imp,
                &note,
            )?;
            drawn += 1;
        }
    }
    Ok(drawn)
}

/// What [`log_session_estimates`] drew.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EstimatesLogged {
    /// Börner session estimates (0 or 1).
    pub borner: usize,
    /// Piovesan window estimates.
    pub windows: usize,
}

/// The estimator `rigtwin estimate` would run on this session, drawn: the Börner estimate
/// when the session has force pulses, the windowed regression when its trials carry
/// position perturbations. No ground truth (a measured session has none). A session with
/// nothing to estimate, or an estimator that refuses it, gives a warning event, not an error:
/// the samples are still worth looking at.
pub fn log_session_estimates(
    viewer: &mut Viewer,
    session: &Session,
    spans: &[TrialSpan],
    config: &EstimateConfig,
    m_hat_kg: Option<f64>,
) -> Result<EstimatesLogged, VizError> {
    let start = spans
        .first()
        .map_or_else(|| viewer.stamp_at(0.0), |s| s.stamp(0.0));
    let onsets = pulse_onsets(session);
    let mut out = EstimatesLogged::default();
    let warn = |viewer: &mut Viewer, e: &SessionEstimateError| {
        viewer.log_event(
            start,
            EventLevel::Warn,
            &format!("no impedance estimate: {e}"),
        )
    };
    if onsets.is_empty() && session.trials.iter().any(|t| !push_onsets(t).is_empty()) {
        match piovesan_on_session(session, m_hat_kg) {
            Ok(trials) => out.windows = log_piovesan(viewer, session, spans, &trials)?,
            Err(e) => warn(viewer, &e)?,
        }
        return Ok(out);
    }
    match borner_on_session(session, config) {
        Ok(est) => {
            let hand = mean_point(onsets.iter().map(|(_, h)| *h));
            log_borner(viewer, start, hand, &est, None)?;
            out.borner = 1;
        }
        Err(e) => warn(viewer, &e)?,
    }
    Ok(out)
}
