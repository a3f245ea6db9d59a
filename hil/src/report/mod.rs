//! The rehearsal report: what a lab wants to know before a human sits down.
//!
//! Session length; per trial peak hand force, speed and perturbation deviation;
//! safety margins and trips; whether the workspace suffices; the estimator's result on
//! the perturbed trials against the simulated arm's ground truth; and the seeds'
//! published figures side by side. Built from a [`Rehearsal`], printed as aligned
//! tables and written as `report.md` and `report.json` in the rehearsal folder.

pub mod estimate;
mod render;

use serde::Serialize;

use crate::protocol::ProtocolKind;
use crate::rehearse::{Rehearsal, TrialTask, TwinTruth};
pub use estimate::{
    BornerResult, PiovesanTrial, SessionEstimateError, borner, borner_on_session,
    piovesan_on_session,
};
pub use render::{markdown, summary_text, timing_text};

/// Mean and sample standard deviation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct MeanStd {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for fewer than two values).
    pub std: f64,
    /// Number of values.
    pub n: usize,
}

impl MeanStd {
    /// Of a list of values.
    #[must_use]
    pub fn of(v: &[f64]) -> MeanStd {
        let n = v.len();
        if n == 0 {
            return MeanStd::default();
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        MeanStd { mean, std, n }
    }
}

/// Figures published in 000_* (Börner et al.).
pub mod seed000 {
    /// Max deviation within the estimation window along x1, mm: mean, std (section 4.2).
    pub const DEV_X_MM: (f64, f64) = (6.1, 1.8);
    /// Along x2, mm.
    pub const DEV_Y_MM: (f64, f64) = (5.9, 1.7);
    /// NRMSE bounds of the estimated Δx, Δẋ, Δẍ, Δu_ext (section 4.3, Fig. 4).
    pub const NRMSE_BOUNDS: [f64; 4] = [0.05, 0.05, 0.075, 0.15];
    /// Table 1, D mean, N s/m.
    pub const D_MEAN: [[f64; 2]; 2] = [[10.98, -7.94], [-8.54, 6.75]];
    /// Table 1, D std.
    pub const D_STD: [[f64; 2]; 2] = [[4.85, 3.26], [4.16, 4.27]];
    /// Table 1, K mean, N/m.
    pub const K_MEAN: [[f64; 2]; 2] = [[110.52, -106.05], [-106.04, 313.75]];
    /// Table 1, K std.
    pub const K_STD: [[f64; 2]; 2] = [[48.54, 62.91], [62.91, 77.46]];
}

/// Figures published in 001_* (Piovesan et al.), Appendix B.
pub mod seed001 {
    /// Calibrated rig stiffness, N/m.
    pub const K_RIG: [f64; 2] = [615.0, 507.0];
    /// Estimates within this relative drift.
    pub const K_TOLERANCE: f64 = 0.027;
    /// Canonical correlation of the rig.
    pub const R2: f64 = 0.96;
}

/// One row of the per-trial table.
#[derive(Debug, Clone, Serialize)]
pub struct TrialRow {
    /// Subject code.
    pub subject: String,
    /// Trial id.
    pub id: u32,
    /// `reach`, `reach 30°`, `hold +x/y`, `calibration`.
    pub task: String,
    /// Peak |hand force|, N.
    pub peak_force_n: f64,
    /// Peak handle speed, m/s.
    pub peak_speed_m_per_s: f64,
    /// Max |Δx| within the estimation window per axis, mm (perturbed trials).
    pub deviation_mm: Option<[f64; 2]>,
    /// First safety trip.
    pub trip: Option<String>,
    /// SHA-256 of the table.
    pub sha256: String,
}

/// Safety margins over the whole rehearsal.
#[derive(Debug, Clone, Serialize)]
pub struct Safety {
    /// Motor force limit per axis, N.
    pub force_limit_n: [f64; 2],
    /// Peak |command| per axis, N.
    pub peak_command_n: [f64; 2],
    /// Velocity trip level, m/s.
    pub velocity_limit_m_per_s: f64,
    /// Peak speed, m/s.
    pub peak_speed_m_per_s: f64,
    /// Peak |hand force|, N.
    pub peak_force_n: f64,
    /// Ticks with a saturated command.
    pub saturated_ticks: u64,
    /// Trips: (subject, trial, tick, reason).
    pub trips: Vec<(String, u32, u64, String)>,
}

/// Whether the workspace suffices.
#[derive(Debug, Clone, Serialize)]
pub struct Workspace {
    /// Soft walls, ±m.
    pub wall_m: f64,
    /// Peak |position| per axis, m.
    pub peak_position_m: [f64; 2],
    /// Smallest distance to a wall, m.
    pub margin_m: f64,
    /// Ticks with a wall force acting.
    pub wall_ticks: u64,
    /// No wall touched and no trip.
    pub suffices: bool,
}

/// NRMSE of the estimated variational dynamics against the twin truth.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct Nrmse {
    /// `Δx`: mean and max over trials.
    pub position: (f64, f64),
    /// `Δẋ`.
    pub velocity: (f64, f64),
    /// `Δẍ`.
    pub acceleration: (f64, f64),
    /// `Δu_ext`.
    pub force: (f64, f64),
}

/// Estimation for one subject against its ground truth.
#[derive(Debug, Clone, Serialize)]
pub struct SubjectEstimate {
    /// Subject code.
    pub subject: String,
    /// The estimate (None if it failed).
    pub estimate: Option<BornerResult>,
    /// Why it failed.
    pub error: Option<String>,
    /// Mean intrinsic endpoint damping at the onsets, N s/m.
    pub truth_d_ns_per_m: [[f64; 2]; 2],
    /// Mean intrinsic endpoint stiffness at the onsets, N/m.
    pub truth_k_n_per_m: [[f64; 2]; 2],
    /// NRMSE against the twin truth.
    pub nrmse: Option<Nrmse>,
}

/// Estimation summary per parameter across subjects.
#[derive(Debug, Clone, Serialize)]
pub struct ParamRow {
    /// `D11` ... `K22`.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Estimates across subjects.
    pub estimate: MeanStd,
    /// Mean jackknife standard error.
    pub std_err: f64,
    /// Ground truth across subjects.
    pub truth: MeanStd,
    /// Estimate − truth across subjects.
    pub bias: MeanStd,
    /// Table 1 of 000_*: mean, std.
    pub table1: (f64, f64),
}

/// A position-perturbation summary (hold kinds).
#[derive(Debug, Clone, Serialize)]
pub struct HoldSummary {
    /// Position perturbations applied.
    pub pushes: usize,
    /// Max |x − anchor| within the window per axis, mm.
    pub deviation_x_mm: MeanStd,
    /// Along y.
    pub deviation_y_mm: MeanStd,
}

/// The Piovesan windowed regression over the hold trials (001_*).
#[derive(Debug, Clone, Serialize, Default)]
pub struct PiovesanSummary {
    /// Window estimates pooled (all trials and subjects).
    pub windows: usize,
    /// `K` per element over windows, N/m.
    pub k_n_per_m: [[MeanStd; 2]; 2],
    /// `B` per element over windows, N s/m.
    pub b_ns_per_m: [[MeanStd; 2]; 2],
    /// Canonical correlation r² over windows.
    pub r2: MeanStd,
    /// The inertia subtracted, kg.
    pub m_hat_kg: [[f64; 2]; 2],
    /// Calibration rig: the known stiffness diagonal, N/m.
    pub k_true_n_per_m: Option<[f64; 2]>,
    /// Calibration rig: relative error of the mean diagonal `K` per axis.
    pub k_rel_error: Option<[f64; 2]>,
    /// Calibration rig: largest relative deviation of a window's diagonal per axis.
    pub k_max_rel_drift: Option<[f64; 2]>,
    /// Trials the estimator refused, with why.
    pub errors: Vec<String>,
}

/// The whole report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Protocol name.
    pub protocol: String,
    /// Protocol kind.
    pub kind: String,
    /// Session seed.
    pub seed: u64,
    /// Subjects.
    pub subjects: usize,
    /// Trials per subject.
    pub trials_per_subject: usize,
    /// Perturbed trials per subject.
    pub perturbed_per_subject: usize,
    /// Length of one session (trial time only, no breaks), s.
    pub session_length_s: f64,
    /// Simulated time including unperturbed twins, s.
    pub simulated_s: f64,
    /// Wall-clock time, s.
    pub wall_s: f64,
    /// Worker threads.
    pub jobs: usize,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    /// Per trial.
    pub trials: Vec<TrialRow>,
    /// Safety.
    pub safety: Safety,
    /// Workspace.
    pub workspace: Workspace,
    /// Max deviations along x and y, mm (reach): mean (std) over perturbed trials.
    pub deviation_mm: Option<[MeanStd; 2]>,
    /// Pooled NRMSE over all subjects (reach).
    pub nrmse: Option<Nrmse>,
    /// Per subject.
    pub estimates: Vec<SubjectEstimate>,
    /// Per parameter.
    pub parameters: Vec<ParamRow>,
    /// Hold kinds.
    pub hold: Option<HoldSummary>,
    /// Hold kinds: the Piovesan windowed regression.
    pub piovesan: Option<PiovesanSummary>,
    /// Real-time pacing: how each subject's loop kept its clock (empty in lock step).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub timing: Vec<SubjectTiming>,
}

/// The real-time timing of one subject's session.
#[derive(Debug, Clone, Serialize)]
pub struct SubjectTiming {
    /// Subject id.
    pub subject: String,
    /// The loop's clock over the session.
    pub timing: crate::session::Timing,
}

fn nrmse_of(est: &[[f64; 2]], truth: &[[f64; 2]]) -> f64 {
    let n = est.len().min(truth.len());
    if n == 0 {
        return f64::NAN;
    }
    let mut se = 0.0;
    let mut peak: f64 = 0.0;
    for i in 0..n {
        let e = [est[i][0] - truth[i][0], est[i][1] - truth[i][1]];
        se += e[0] * e[0] + e[1] * e[1];
        peak = peak.max(truth[i][0].hypot(truth[i][1]));
    }
    let rms = (se / n as f64).sqrt();
    if peak > 0.0 { rms / peak } else { f64::NAN }
}

fn nrmse_summary(pairs: &[(&rigtwin_device::estimate::VariationalDynamics, &TwinTruth)]) -> Nrmse {
    let stat = |f: &dyn Fn(&rigtwin_device::estimate::VariationalDynamics, &TwinTruth) -> f64| {
        let v: Vec<f64> = pairs
            .iter()
            .map(|(e, t)| f(e, t))
            .filter(|x| x.is_finite())
            .collect();
        let m = MeanStd::of(&v);
        (m.mean, v.iter().copied().fold(0.0, f64::max))
    };
    Nrmse {
        position: stat(&|e, t| nrmse_of(&e.dx_m, &t.dx_m)),
        velocity: stat(&|e, t| nrmse_of(&e.dv_m_per_s, &t.dv_m_per_s)),
        acceleration: stat(&|e, t| nrmse_of(&e.da_m_per_s2, &t.da_m_per_s2)),
        force: stat(&|e, t| nrmse_of(&e.du_ext_n, &t.du_ext_n)),
    }
}

fn task_label(t: &TrialTask) -> String {
    match t {
        TrialTask::Reach {
            angle_deg: None, ..
        } => "reach".to_owned(),
        TrialTask::Reach {
            angle_deg: Some(a), ..
        } => format!("reach {a:.0}°"),
        TrialTask::Hold { condition } => {
            let axis = match condition.axis {
                rigtwin_device::config::Axis::X => "x",
                rigtwin_device::config::Axis::Y => "y",
            };
            format!("hold {:.0}°/{axis}", condition.force_deg)
        }
        TrialTask::Calibration => "calibration".to_owned(),
    }
}

fn mean_mat(ms: &[[[f64; 2]; 2]]) -> [[f64; 2]; 2] {
    let n = ms.len().max(1) as f64;
    let mut out = [[0.0; 2]; 2];
    for m in ms {
        for r in 0..2 {
            for c in 0..2 {
                out[r][c] += m[r][c] / n;
            }
        }
    }
    out
}

/// Builds the report of a rehearsal (runs the estimators).
#[must_use]
pub fn build(r: &Rehearsal) -> Report {
    let p = &r.protocol;
    let c = &p.controller;
    let mut trials = Vec::new();
    let mut safety = Safety {
        force_limit_n: c.safety.force_limit_n,
        peak_command_n: [0.0; 2],
        velocity_limit_m_per_s: c.safety.velocity_limit_m_per_s,
        peak_speed_m_per_s: 0.0,
        peak_force_n: 0.0,
        saturated_ticks: 0,
        trips: Vec::new(),
    };
    let mut workspace = Workspace {
        wall_m: c.safety.wall_m,
        peak_position_m: [0.0; 2],
        margin_m: c.safety.wall_m,
        wall_ticks: 0,
        suffices: true,
    };
    let mut dev = [Vec::new(), Vec::new()];
    let mut estimates = Vec::new();
    let mut all_pairs_owned = Vec::new();
    let mut push_dev = [Vec::new(), Vec::new()];
    let rate = f64::from(p.recording.rate_hz);
    for s in &r.subjects {
        for t in &s.trials {
            let e = &t.extremes;
            trials.push(TrialRow {
                subject: s.subject.id.clone(),
                id: t.id,
                task: task_label(&t.task),
                peak_force_n: e.peak_force_n,
                peak_speed_m_per_s: e.peak_speed_m_per_s,
                deviation_mm: t.deviation_m.map(|d| [d[0] * 1e3, d[1] * 1e3]),
                trip: e.trip.as_ref().map(|(k, why)| format!("tick {k}: {why}")),
                sha256: t.sha256.clone(),
            });
            for i in 0..2 {
                safety.peak_command_n[i] = safety.peak_command_n[i].max(e.peak_command_n[i]);
                workspace.peak_position_m[i] =
                    workspace.peak_position_m[i].max(e.peak_position_m[i]);
            }
            safety.peak_speed_m_per_s = safety.peak_speed_m_per_s.max(e.peak_speed_m_per_s);
            safety.peak_force_n = safety.peak_force_n.max(e.peak_force_n);
            safety.saturated_ticks += e.saturated_ticks;
            workspace.wall_ticks += e.wall_ticks;
            if let Some((k, why)) = &e.trip {
                safety
                    .trips
                    .push((s.subject.id.clone(), t.id, *k, why.clone()));
            }
            if let Some(d) = t.deviation_m {
                dev[0].push(d[0] * 1e3);
                dev[1].push(d[1] * 1e3);
            }
            for push in &t.pushes {
                push_dev[0].push(push.deviation_m[0] * 1e3);
                push_dev[1].push(push.deviation_m[1] * 1e3);
            }
        }
        if p.kind == ProtocolKind::ReachPerturb {
            let perturbed: Vec<_> = s
                .trials
                .iter()
                .filter_map(|t| match (&t.table, t.onset_s, &t.onset_truth) {
                    (Some(tab), Some(o), Some(g)) => {
                        Some((t, tab, estimate::onset_index(o, rate), g))
                    }
                    _ => None,
                })
                .collect();
            let truth_m = mean_mat(&perturbed.iter().map(|x| x.3.mass_kg).collect::<Vec<_>>());
            let truth_d = mean_mat(
                &perturbed
                    .iter()
                    .map(|x| x.3.damping_n_s_per_m)
                    .collect::<Vec<_>>(),
            );
            let truth_k = mean_mat(
                &perturbed
                    .iter()
                    .map(|x| x.3.stiffness_n_per_m)
                    .collect::<Vec<_>>(),
            );
            let inputs: Vec<(&crate::session::Trial, usize)> =
                perturbed.iter().map(|x| (x.1, x.2)).collect();
            let adm = rigtwin_device::estimate::Admittance {
                m_adm_kg: [
                    [c.admittance.mass_kg[0], 0.0],
                    [0.0, c.admittance.mass_kg[1]],
                ],
                d_adm_ns_per_m: [
                    [c.admittance.damping_n_s_per_m[0], 0.0],
                    [0.0, c.admittance.damping_n_s_per_m[1]],
                ],
                m_handle_kg: [[p.plant.handle_mass_kg, 0.0], [0.0, p.plant.handle_mass_kg]],
            };
            let result = borner(&inputs, rate, &adm, &truth_m, &p.estimate);
            let (estimate, error, nrmse) = match result {
                Ok(b) => {
                    let pairs: Vec<_> = b
                        .raw
                        .as_ref()
                        .map(|raw| {
                            raw.variational
                                .iter()
                                .zip(perturbed.iter())
                                .filter_map(|(v, x)| {
                                    x.0.twin.as_ref().map(|t| (v.clone(), t.clone()))
                                })
                                .collect::<Vec<_>>()
                        })
                        .unwrap_or_default();
                    let refs: Vec<_> = pairs.iter().map(|(v, t)| (v, t)).collect();
                    let n = (!refs.is_empty()).then(|| nrmse_summary(&refs));
                    all_pairs_owned.extend(pairs);
                    (Some(b), None, n)
                }
                Err(e) => (None, Some(e.to_string()), None),
            };
            estimates.push(SubjectEstimate {
                subject: s.subject.id.clone(),
                estimate,
                error,
                truth_d_ns_per_m: truth_d,
                truth_k_n_per_m: truth_k,
                nrmse,
            });
        }
    }
    workspace.margin_m =
        workspace.wall_m - workspace.peak_position_m[0].max(workspace.peak_position_m[1]);
    workspace.suffices = workspace.wall_ticks == 0 && safety.trips.is_empty();
    let pooled: Vec<_> = all_pairs_owned.iter().map(|(v, t)| (v, t)).collect();
    let nrmse = (!pooled.is_empty()).then(|| nrmse_summary(&pooled));
    let parameters = parameter_rows(&estimates);
    let per_subject = r.subjects.first().map_or(0, |s| s.trials.len());
    let perturbed_per_subject = r.subjects.first().map_or(0, |s| {
        s.trials
            .iter()
            .filter(|t| t.onset_s.is_some() || !t.pushes.is_empty())
            .count()
    });
    let session_length_s = r
        .subjects
        .first()
        .map_or(0.0, |s| s.trials.iter().map(|t| t.duration_s).sum());
    let hold = (p.kind != ProtocolKind::ReachPerturb).then(|| HoldSummary {
        pushes: push_dev[0].len(),
        deviation_x_mm: MeanStd::of(&push_dev[0]),
        deviation_y_mm: MeanStd::of(&push_dev[1]),
    });
    let piovesan = (p.kind != ProtocolKind::ReachPerturb).then(|| piovesan_summary(r));
    Report {
        protocol: p.name.clone(),
        kind: p.kind.as_str().to_owned(),
        seed: r.seed,
        subjects: r.subjects.len(),
        trials_per_subject: per_subject,
        perturbed_per_subject,
        session_length_s,
        simulated_s: r.simulated_s,
        wall_s: r.wall_s,
        jobs: r.jobs,
        real_time_factor: if r.wall_s > 0.0 {
            r.simulated_s / r.wall_s
        } else {
            0.0
        },
        trials,
        safety,
        workspace,
        deviation_mm: (!dev[0].is_empty()).then(|| [MeanStd::of(&dev[0]), MeanStd::of(&dev[1])]),
        nrmse,
        estimates,
        parameters,
        hold,
        piovesan,
        timing: r
            .subjects
            .iter()
            .filter_map(|s| {
                s.timing.map(|timing| SubjectTiming {
                    subject: s.subject.id.clone(),
                    timing,
                })
            })
            .collect(),
    }
}

/// Runs the windowed regression of 001_* on every hold trial. The force regressed is
/// the one the handle exerts on the hand (minus the recorded hand force), and the
/// inertia subtracted is the handle's plus the test mass (calibration rig) or the
/// arm's endpoint inertia at the hold posture.
fn piovesan_summary(r: &Rehearsal) -> PiovesanSummary {
    use rigtwin_device::estimate::{
        ImposedMotionTrial, PiovesanConfig, PositionPerturbation, windowed_impedance,
    };
    let p = &r.protocol;
    let rate = f64::from(p.recording.rate_hz);
    let m = &p.controller.imposed_motion;
    let n_cycles = m.cycles as usize;
    let period_s = 1.0 / m.frequency_hz;
    // The full-amplitude part starts after the ramp; the controller starts at tick 1.
    let full_start_s = crate::rehearse::record::tick_time_s(
        1,
        crate::rehearse::TICK_HZ / u64::from(p.recording.rate_hz),
    ) + m.ramp_s;
    let config = PiovesanConfig {
        window_cycles: PiovesanConfig::default().window_cycles.min(n_cycles.max(1)),
        ..PiovesanConfig::default()
    };
    let h = p.plant.handle_mass_kg;
    let calibration = p.kind == ProtocolKind::CalibrationRig;
    let mut out = PiovesanSummary::default();
    let mut ks: [[Vec<f64>; 2]; 2] = Default::default();
    let mut bs: [[Vec<f64>; 2]; 2] = Default::default();
    let mut r2 = Vec::new();
    for s in &r.subjects {
        let m_hat = if calibration {
            let k = p.calibration();
            [[k.mass_kg + h, 0.0], [0.0, k.mass_kg + h]]
        } else {
            let hold = p.hold();
            match estimate::endpoint_inertia(&s.subject.arm, s.subject.shoulder_m, hold.hand_m) {
                Ok(mi) => [[mi[0][0] + h, mi[0][1]], [mi[1][0], mi[1][1] + h]],
                Err(e) => {
                    out.errors.push(format!("{}: {e}", s.subject.id));
                    continue;
                }
            }
        };
        out.m_hat_kg = m_hat;
        for t in &s.trials {
            let Some(table) = &t.table else { continue };
            let pushes: Vec<PositionPerturbation> = t
                .pushes
                .iter()
                .map(|push| PositionPerturbation {
                    onset_index: estimate::onset_index(push.onset_s, rate),
                    cycle: (((push.onset_s - full_start_s) / period_s + 1e-6)
                        .floor()
                        .max(0.0) as usize)
                        .min(n_cycles.saturating_sub(1)),
                })
                .collect();
            let fx: Vec<f64> = table.fx_n.iter().map(|v| -v).collect();
            let fy: Vec<f64> = table.fy_n.iter().map(|v| -v).collect();
            let trial = ImposedMotionTrial {
                x_m: [&table.x_m, &table.y_m],
                force_n: [&fx, &fy],
                perturbations: &pushes,
                n_cycles,
            };
            match windowed_impedance(&trial, rate, &m_hat, &config) {
                Ok(windows) => {
                    for w in windows {
                        for i in 0..2 {
                            for j in 0..2 {
                                ks[i][j].push(w.k_n_per_m[i][j]);
                                bs[i][j].push(w.b_ns_per_m[i][j]);
                            }
                        }
                        r2.push(w.canonical_r2);
                        out.windows += 1;
                    }
                }
                Err(e) => out
                    .errors
                    .push(format!("{} trial {}: {e}", s.subject.id, t.id)),
            }
        }
    }
    for i in 0..2 {
        for j in 0..2 {
            out.k_n_per_m[i][j] = MeanStd::of(&ks[i][j]);
            out.b_ns_per_m[i][j] = MeanStd::of(&bs[i][j]);
        }
    }
    out.r2 = MeanStd::of(&r2);
    if calibration && out.windows > 0 {
        let k = p.calibration().stiffness_n_per_m;
        out.k_true_n_per_m = Some(k);
        out.k_rel_error = Some([0, 1].map(|a| out.k_n_per_m[a][a].mean / k[a] - 1.0));
        out.k_max_rel_drift = Some([0, 1].map(|a| {
            ks[a][a]
                .iter()
                .map(|v| (v / k[a] - 1.0).abs())
                .fold(0.0, f64::max)
        }));
    }
    out
}

fn parameter_rows(estimates: &[SubjectEstimate]) -> Vec<ParamRow> {
    let mut rows = Vec::new();
    for (name, unit, r, c, is_k) in [
        ("D11", "N s/m", 0, 0, false),
        ("D12", "N s/m", 0, 1, false),
        ("D21", "N s/m", 1, 0, false),
        ("D22", "N s/m", 1, 1, false),
        ("K11", "N/m", 0, 0, true),
        ("K12", "N/m", 0, 1, true),
        ("K22", "N/m", 1, 1, true),
    ] {
        let mut est = Vec::new();
        let mut se = Vec::new();
        let mut truth = Vec::new();
        let mut bias = Vec::new();
        for s in estimates {
            let Some(b) = &s.estimate else { continue };
            let (e, err, t) = if is_k {
                (
                    b.k_n_per_m[r][c],
                    b.k_std_err_n_per_m[r][c],
                    s.truth_k_n_per_m[r][c],
                )
            } else {
                (
                    b.d_ns_per_m[r][c],
                    b.d_std_err_ns_per_m[r][c],
                    s.truth_d_ns_per_m[r][c],
                )
            };
            est.push(e);
            se.push(err);
            truth.push(t);
            bias.push(e - t);
        }
        if est.is_empty() {
            continue;
        }
        let table1 = if is_k {
            (seed000::K_MEAN[r][c], seed000::K_STD[r][c])
        } else {
            (seed000::D_MEAN[r][c], seed000::D_STD[r][c])
        };
        rows.push(ParamRow {
            name: name.to_owned(),
            unit: unit.to_owned(),
            estimate: MeanStd::of(&est),
            std_err: MeanStd::of(&se).mean,
            truth: MeanStd::of(&truth),
            bias: MeanStd::of(&bias),
            table1,
        });
    }
    rows
}

/// Writes `report.md` and `report.json` into the rehearsal folder.
///
/// # Errors
/// I/O errors, naming the file.
pub fn write(report: &Report, dir: &std::path::Path) -> Result<(), std::io::Error> {
    let md = dir.join("report.md");
    std::fs::write(&md, markdown(report))
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", md.display())))?;
    let json = dir.join("report.json");
    let text = serde_json::to_string_pretty(report).map_err(std::io::Error::other)?;
    std::fs::write(&json, text + "\n")
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", json.display())))
}
