//! A rehearsal in the viewer, logged while it runs: a [`RehearsalLogger`] observes the
//! rehearsal ([`crate::rehearse::rehearse_observed`]) and logs each trial from memory as soon
//! as it is written, in trial order, on the writing thread while the workers simulate the
//! next ones: the table exactly as written to the session (the same per-trial logging as a
//! session read from disk), the simulated arm's muscle activations (which the session files
//! do not hold), the trial's safety events and the arm's impedance at the force-pulse onset.
//! After the report, [`RehearsalLogger::finish`] adds what needs the whole session: the
//! estimator's ellipses next to the simulated arm's ground truth. The subjects are back to
//! back on the timelines, in one recording.

use sha2::{Digest as _, Sha256};

use super::columns::{Stamp, TrialSpan};
use super::impedance::{self, Impedance, Which};
use super::session::{
    Logged, log_session_end, log_session_start, log_session_trial, session_recording_id,
};
use super::{EventLevel, Viewer, VizError};
use crate::protocol::{Protocol, ProtocolKind, VirtualSubject};
use crate::rehearse::{
    Options, Rehearsal, RehearsalObserver, TICK_HZ, TrialResult, WrittenTrial, record::tick_time_s,
};
use crate::report::Report;
use crate::report::estimate::piovesan_on_session;
use crate::session::{Manifest, Session};

/// What a [`RehearsalLogger`] sent.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RehearsalLogged {
    /// Per subject, in order: what its session sent.
    pub sessions: Vec<Logged>,
    /// Samples with the arm's muscle activations, all subjects.
    pub activation_samples: usize,
    /// Samples with the real-time loop's timing, all subjects (real-time rehearsals).
    pub timing_samples: usize,
    /// Börner session estimates drawn.
    pub borner: usize,
    /// Ground-truth ellipses drawn at perturbation onsets.
    pub onset_truths: usize,
    /// Piovesan window estimates drawn.
    pub windows: usize,
    /// Safety events logged (trips, saturation, soft walls).
    pub safety_events: usize,
}

/// The recording id of a rehearsal, known before it runs: protocol name, seed and the first
/// 16 hex digits of the SHA-256 of the protocol as run (its JSON form, so a `--model` applied
/// to it counts), the number of subjects and the trial limit. The same protocol and seed
/// give the same id wherever the sessions are written.
pub fn rehearsal_recording_id(protocol: &Protocol, options: &Options) -> Result<String, VizError> {
    let json = serde_json::to_vec(protocol).map_err(VizError::ProtocolId)?;
    let mut hash = Sha256::new();
    hash.update(&json);
    hash.update(options.subjects.to_le_bytes());
    hash.update(
        options
            .max_trials
            .map_or(u64::MAX, |m| m as u64)
            .to_le_bytes(),
    );
    let digest = hash.finalize();
    let hex: String = digest[..8].iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("{}-seed{}-{hex}", protocol.name, options.seed))
}

/// One subject's session as logged, kept for the ellipses at the end.
#[derive(Debug)]
struct SubjectLog {
    id: String,
    dir: std::path::PathBuf,
    logged: Logged,
    /// Hand positions at the force-pulse onsets, m.
    onset_hands_m: Vec<[f64; 2]>,
}

impl SubjectLog {
    /// The stamp of the session's start.
    fn start(&self, viewer: &Viewer) -> Stamp {
        self.logged
            .spans
            .first()
            .map_or_else(|| viewer.stamp_at(0.0), |s| s.stamp(0.0))
    }
}

/// Logs a rehearsal as it runs: pass it to [`crate::rehearse::rehearse_observed`], then call
/// [`Self::finish`] with the report.
///
/// For each subject it logs the rig, then per trial (in trial order, whatever worker finished
/// first, so the same protocol and seed give the same messages): the session's trial as
/// written (series, overlays, arm), the arm's six muscle activations at every sample, the
/// safety trip (an error entry at its tick), saturation and soft-wall contact (warnings at
/// the trial's start) and, for a perturbed reach, the arm's intrinsic impedance at the
/// onset; at the session's end its summary. A viewer error does not stop the rehearsal (the
/// sessions are the record): logging stops and [`Self::finish`] returns the error.
#[derive(Debug)]
pub struct RehearsalLogger<'v> {
    viewer: &'v mut Viewer,
    protocol_name: String,
    kind: ProtocolKind,
    seed: u64,
    /// Rate of the trial tables, Hz.
    rate_hz: u32,
    /// The session being written: its manifest (without trials) and what was logged.
    current: Option<(Manifest, SubjectLog)>,
    subjects: Vec<SubjectLog>,
    next_trial: u32,
    out: RehearsalLogged,
    error: Option<VizError>,
}

impl<'v> RehearsalLogger<'v> {
    /// A logger of a rehearsal of `protocol` with session seed `seed` into `viewer`.
    pub fn new(viewer: &'v mut Viewer, protocol: &Protocol, seed: u64) -> Self {
        Self {
            viewer,
            protocol_name: protocol.name.clone(),
            kind: protocol.kind,
            seed,
            rate_hz: protocol.recording.rate_hz,
            current: None,
            subjects: Vec::new(),
            next_trial: 0,
            out: RehearsalLogged::default(),
            error: None,
        }
    }

    /// Runs `log` unless an earlier call failed; keeps the first error.
    fn guarded(&mut self, log: impl FnOnce(&mut Self) -> Result<(), VizError>) {
        if self.error.is_none()
            && let Err(err) = log(self)
        {
            self.error = Some(err);
        }
    }

    fn table_time_s(&self, tick: u64) -> f64 {
        let div = TICK_HZ / u64::from(self.rate_hz.max(1));
        tick_time_s(tick, div)
    }

    fn log_trial(&mut self, trial: &WrittenTrial<'_>) -> Result<(), VizError> {
        let Some((manifest, subject)) = self.current.as_mut() else {
            return Err(VizError::Order(format!(
                "trial {} of {} arrived outside a session",
                trial.entry.id, trial.subject.id
            )));
        };
        let trial_index = self.next_trial;
        self.next_trial = self.next_trial.saturating_add(1);
        let span = log_session_trial(
            self.viewer,
            manifest,
            trial_index,
            trial.entry,
            trial.table,
            &mut subject.logged,
        )?;
        if let Some(activations) = trial.activations_n {
            self.viewer
                .log_activations(&span, &trial.table.t_s, activations)?;
            self.out.activation_samples += activations.len();
        }
        if let Some(timing) = trial.timing {
            self.viewer.log_timing(&span, &trial.table.t_s, timing)?;
            self.out.timing_samples += timing.len();
        }
        let id = subject.id.clone();
        self.out.safety_events += self.log_safety(&id, trial.result, &span)?;
        if let Some(truth) = &trial.result.onset_truth {
            let imp = Impedance {
                stiffness_n_per_m: truth.stiffness_n_per_m,
                damping_n_s_per_m: truth.damping_n_s_per_m,
            };
            let at = span.stamp(self.table_time_s(truth.tick));
            impedance::log_impedance(
                self.viewer,
                Which::TruthAtOnset,
                at,
                truth.hand_m,
                &imp,
                &format!("trial {}", trial.result.id),
            )?;
            self.out.onset_truths += 1;
            if let Some((_, s)) = self.current.as_mut() {
                s.onset_hands_m.push(truth.hand_m);
            }
        }
        Ok(())
    }

    fn log_safety(
        &mut self,
        subject: &str,
        trial: &TrialResult,
        span: &TrialSpan,
    ) -> Result<usize, VizError> {
        let mut n = 0;
        let e = &trial.extremes;
        let who = format!("{subject} trial {}", trial.id);
        if let Some((tick, why)) = &e.trip {
            let at = span.stamp(self.table_time_s(*tick));
            self.viewer.log_event(
                at,
                EventLevel::Error,
                &format!("{who}: safety trip at tick {tick}: {why}"),
            )?;
            n += 1;
        }
        if e.saturated_ticks > 0 {
            self.viewer.log_event(
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
            self.viewer.log_event(
                span.stamp(0.0),
                EventLevel::Warn,
                &format!(
                    "{who}: soft workspace wall acting on {} ticks (peak |x| [{:.3}, {:.3}] m)",
                    e.wall_ticks, e.peak_position_m[0], e.peak_position_m[1]
                ),
            )?;
            n += 1;
        }
        Ok(n)
    }

    fn end_session(&mut self, dir: &std::path::Path, manifest: &Manifest) -> Result<(), VizError> {
        let Some((_, subject)) = self.current.take() else {
            return Err(VizError::Order(format!(
                "the session in {} ended without starting",
                dir.display()
            )));
        };
        log_session_end(self.viewer, manifest, &subject.logged)?;
        let start = subject.start(self.viewer);
        // No folder in the text: the same protocol and seed give the same messages wherever
        // the sessions were written.
        let text = format!(
            "rehearsal {} seed {}: subject {} (session {})",
            self.protocol_name,
            self.seed,
            subject.id,
            session_recording_id(dir, &manifest.subject.id)?
        );
        self.viewer.log_event(start, EventLevel::Info, &text)?;
        self.subjects.push(SubjectLog {
            dir: dir.to_path_buf(),
            ..subject
        });
        Ok(())
    }

    /// Ends the logging once the report is built: for reaches the report's Börner estimate
    /// of each subject with the arm's intrinsic impedance (mean over the onsets, as the
    /// report compares them) beside it, at the mean onset hand position and the start of the
    /// session; for hold and calibration trials the windowed regression per window (computed
    /// from the session read back, as `rigtwin estimate` does). Returns what was sent, or
    /// the first error met while logging.
    pub fn finish(
        mut self,
        rehearsal: &Rehearsal,
        report: &Report,
    ) -> Result<RehearsalLogged, VizError> {
        if let Some(err) = self.error.take() {
            return Err(err);
        }
        if self.current.is_some() {
            return Err(VizError::Order(
                "the rehearsal ended in the middle of a session".to_owned(),
            ));
        }
        let subjects = std::mem::take(&mut self.subjects);
        for subject in &subjects {
            let start = subject.start(self.viewer);
            match self.kind {
                ProtocolKind::ReachPerturb => self.log_borner(subject, start, report)?,
                ProtocolKind::HoldSinusoid | ProtocolKind::CalibrationRig => {
                    self.log_windows(subject, start, rehearsal)?;
                }
            }
        }
        self.out.sessions = subjects.into_iter().map(|s| s.logged).collect();
        Ok(self.out)
    }

    fn log_borner(
        &mut self,
        subject: &SubjectLog,
        start: Stamp,
        report: &Report,
    ) -> Result<(), VizError> {
        let estimate = report.estimates.iter().find(|e| e.subject == subject.id);
        match estimate {
            Some(e) => match &e.estimate {
                Some(est) => {
                    let truth = Impedance {
                        stiffness_n_per_m: e.truth_k_n_per_m,
                        damping_n_s_per_m: e.truth_d_ns_per_m,
                    };
                    let hand = impedance::mean_point(subject.onset_hands_m.iter().copied());
                    impedance::log_borner(self.viewer, start, hand, est, Some(&truth))?;
                    self.out.borner += 1;
                    Ok(())
                }
                None => self.viewer.log_event(
                    start,
                    EventLevel::Warn,
                    &format!(
                        "no Börner estimate for {}: {}",
                        subject.id,
                        e.error.as_deref().unwrap_or("no perturbed trial")
                    ),
                ),
            },
            None => self.viewer.log_event(
                start,
                EventLevel::Warn,
                &format!("no Börner estimate for {}", subject.id),
            ),
        }
    }

    fn log_windows(
        &mut self,
        subject: &SubjectLog,
        start: Stamp,
        rehearsal: &Rehearsal,
    ) -> Result<(), VizError> {
        let session = Session::read(&subject.dir)?;
        let m_hat_kg = (rehearsal.protocol.kind == ProtocolKind::CalibrationRig)
            .then(|| rehearsal.protocol.calibration().mass_kg);
        match piovesan_on_session(&session, m_hat_kg) {
            Ok(trials) => {
                self.out.windows +=
                    impedance::log_piovesan(self.viewer, &session, &subject.logged.spans, &trials)?;
                Ok(())
            }
            Err(e) => self.viewer.log_event(
                start,
                EventLevel::Warn,
                &format!("no windowed estimate for {}: {e}", subject.id),
            ),
        }
    }
}

impl RehearsalObserver for RehearsalLogger<'_> {
    fn session_started(&mut self, subject: &VirtualSubject, manifest: &Manifest) {
        self.guarded(|me| {
            log_session_start(me.viewer, manifest)?;
            me.current = Some((
                manifest.clone(),
                SubjectLog {
                    id: subject.id.clone(),
                    dir: std::path::PathBuf::new(),
                    logged: Logged::default(),
                    onset_hands_m: Vec::new(),
                },
            ));
            Ok(())
        });
    }

    fn trial_written(&mut self, trial: &WrittenTrial<'_>) {
        self.guarded(|me| me.log_trial(trial));
    }

    fn session_finished(
        &mut self,
        _subject: &VirtualSubject,
        dir: &std::path::Path,
        manifest: &Manifest,
    ) {
        self.guarded(|me| me.end_session(dir, manifest));
    }
}
