//! A finished rehearsal in the viewer: every subject's written session (read back, so the
//! viewer shows exactly what the files hold), its safety events, the estimator's ellipses
//! next to the simulated arm's ground truth, all in one recording with the subjects back to
//! back on the timelines.

use sha2::{Digest as _, Sha256};

use super::columns::TrialSpan;
use super::impedance::{self, Impedance, Which};
use super::session::{Logged, log_session_at, recording_id};
use super::{EventLevel, Viewer, VizError};
use crate::protocol::ProtocolKind;
use crate::rehearse::{Rehearsal, SubjectResult, TICK_HZ, record::tick_time_s};
use crate::report::Report;
use crate::report::estimate::piovesan_on_session;
use crate::session::Session;

/// What [`log_rehearsal`] sent.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RehearsalLogged {
    /// Per subject, in order: what its session sent.
    pub sessions: Vec<Logged>,
    /// Börner session estimates drawn.
    pub borner: usize,
    /// Ground-truth ellipses drawn at perturbation onsets.
    pub onset_truths: usize,
    /// Piovesan window estimates drawn.
    pub windows: usize,
    /// Safety events logged (trips, saturation, soft walls).
    pub safety_events: usize,
}

/// The recording id of a rehearsal: protocol, seed and the first 16 hex digits of the
/// SHA-256 of the subjects' own recording ids (each a digest of its `session.toml`), so the
/// same protocol and seed give the same id.
pub fn rehearsal_recording_id(rehearsal: &Rehearsal) -> Result<String, VizError> {
    let mut hash = Sha256::new();
    for s in &rehearsal.subjects {
        let session = Session::open(&s.dir)?;
        let path = s.dir.join(crate::session::MANIFEST_FILE);
        let bytes = std::fs::read(&path).map_err(|source| VizError::Io { path, source })?;
        hash.update(session.manifest().subject.id.as_bytes());
        hash.update(Sha256::digest(&bytes));
    }
    let digest = hash.finalize();
    let hex: String = digest[..8].iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!(
        "{}-seed{}-{hex}",
        rehearsal.protocol.name, rehearsal.seed
    ))
}

/// Logs a rehearsal: each subject's session as written ([`log_session_at`]), its trials'
/// safety trips (error entries at the trip's tick), saturation and soft-wall contact
/// (warnings at the trial's start), and the impedance: for reaches the report's Börner
/// estimate of the subject with the arm's intrinsic impedance (mean over the onsets, as the
/// report compares them) beside it at the start of the session, and the arm's impedance at
/// each onset; for hold and calibration trials the windowed regression per window.
pub fn log_rehearsal(
    viewer: &mut Viewer,
    rehearsal: &Rehearsal,
    report: &Report,
) -> Result<RehearsalLogged, VizError> {
    let mut out = RehearsalLogged::default();
    let mut first_trial = 0u32;
    for subject in &rehearsal.subjects {
        let session = Session::read(&subject.dir)?;
        let logged = log_session_at(viewer, &session, first_trial)?;
        first_trial = first_trial.saturating_add(u32::try_from(logged.trials).unwrap_or(u32::MAX));
        let start = logged
            .spans
            .first()
            .map_or_else(|| viewer.stamp_at(0.0), |s| s.stamp(0.0));
        viewer.log_event(
            start,
            EventLevel::Info,
            // No folder in the text: the same protocol and seed give the same messages
            // wherever the sessions were written.
            &format!(
                "rehearsal {} seed {}: subject {} (session {})",
                rehearsal.protocol.name,
                rehearsal.seed,
                subject.subject.id,
                recording_id(&session)?
            ),
        )?;
        out.safety_events += log_safety(viewer, rehearsal, subject, &logged.spans)?;
        match rehearsal.protocol.kind {
            ProtocolKind::ReachPerturb => {
                let (truths, drawn) = log_onset_truths(viewer, rehearsal, subject, &logged.spans)?;
                out.onset_truths += drawn;
                let estimate = report
                    .estimates
                    .iter()
                    .find(|e| e.subject == subject.subject.id);
                match estimate {
                    Some(e) => match &e.estimate {
                        Some(est) => {
                            let truth = Impedance {
                                stiffness_n_per_m: e.truth_k_n_per_m,
                                damping_n_s_per_m: e.truth_d_ns_per_m,
                            };
                            let hand = impedance::mean_point(truths);
                            impedance::log_borner(viewer, start, hand, est, Some(&truth))?;
                            out.borner += 1;
                        }
                        None => viewer.log_event(
                            start,
                            EventLevel::Warn,
                            &format!(
                                "no Börner estimate for {}: {}",
                                subject.subject.id,
                                e.error.as_deref().unwrap_or("no perturbed trial")
                            ),
                        )?,
                    },
                    None => viewer.log_event(
                        start,
                        EventLevel::Warn,
                        &format!("no Börner estimate for {}", subject.subject.id),
                    )?,
                }
            }
            ProtocolKind::HoldSinusoid | ProtocolKind::CalibrationRig => {
                let m_hat_kg = (rehearsal.protocol.kind == ProtocolKind::CalibrationRig)
                    .then(|| rehearsal.protocol.calibration().mass_kg);
                match piovesan_on_session(&session, m_hat_kg) {
                    Ok(trials) => {
                        out.windows +=
                            impedance::log_piovesan(viewer, &session, &logged.spans, &trials)?;
                    }
                    Err(e) => viewer.log_event(
                        start,
                        EventLevel::Warn,
                        &format!("no windowed estimate for {}: {e}", subject.subject.id),
                    )?,
                }
            }
        }
        out.sessions.push(logged);
    }
    Ok(out)
}

fn table_time_s(rehearsal: &Rehearsal, tick: u64) -> f64 {
    let div = TICK_HZ / u64::from(rehearsal.protocol.recording.rate_hz.max(1));
    tick_time_s(tick, div)
}

fn log_safety(
    viewer: &mut Viewer,
    rehearsal: &Rehearsal,
    subject: &SubjectResult,
    spans: &[TrialSpan],
) -> Result<usize, VizError> {
    let mut n = 0;
    for (trial, span) in subject.trials.iter().zip(spans) {
        let e = &trial.extremes;
        let who = format!("{} trial {}", subject.subject.id, trial.id);
        if let Some((tick, why)) = &e.trip {
            let at = span.stamp(table_time_s(rehearsal, *tick));
            viewer.log_event(
                at,
                EventLevel::Error,
                &format!("{who}: safety trip at tick {tick}: {why}"),
            )?;
            n += 1;
        }
        if e.saturated_ticks > 0 {
            viewer.log_event(
                span.stamp(0.0),
                EventLevel::Warn,
                &format!(
                    "{who}: motor command saturated on {} ticks (peak |cmd| [{:.1}, {:.1}] N)",
                    e.saturated_ticks, e.peak_command_n[0], e.peak_command_n[1]
                ),
            )?;
            n += 1;
        }
        if e.wall_ticks > 0 {
            viewer.log_event(
                span.stamp(0.0),
                EventLevel::Warn,
                &format!(
                    "{who}: soft workspace wall acting on {} ticks (peak |x| [{:.3}, {:.3}] m)",
                    e.wall_ticks, e.peak_position_m[0], e.peak_position_m[1]
                ),
            )?;
            n += 1;
        }
    }
    Ok(n)
}

/// The arm's intrinsic impedance at each force-pulse onset, at the hand there; returns the
/// hand positions and the number drawn.
fn log_onset_truths(
    viewer: &mut Viewer,
    rehearsal: &Rehearsal,
    subject: &SubjectResult,
    spans: &[TrialSpan],
) -> Result<(Vec<[f64; 2]>, usize), VizError> {
    let mut hands = Vec::new();
    for (trial, span) in subject.trials.iter().zip(spans) {
        let Some(truth) = &trial.onset_truth else {
            continue;
        };
        let imp = Impedance {
            stiffness_n_per_m: truth.stiffness_n_per_m,
            damping_n_s_per_m: truth.damping_n_s_per_m,
        };
        let at = span.stamp(table_time_s(rehearsal, truth.tick));
        impedance::log_impedance(
            viewer,
            Which::TruthAtOnset,
            at,
            truth.hand_m,
            &imp,
            &format!("trial {}", trial.id),
        )?;
        hands.push(truth.hand_m);
    }
    let n = hands.len();
    Ok((hands, n))
}
