//! The session re-simulated: the reach-perturb protocol with the session's own device,
//! handle, shoulder and targets, and one trial of it replayed with a given subject.

use rigtwin_diagnose::DiscrepancyError;
use serde::Serialize;

use super::errors::onset_row;
use crate::protocol::{Protocol, VirtualSubject, whole_ticks};
use crate::rehearse::record::{Layout, tick_time_s, to_trial};
use crate::rehearse::trial::simulate;
use crate::rehearse::{TICK_HZ, TrialPlan, TrialTask};
use crate::session::{Session, Trial, TrialEntry};

/// Reach timing of a replay: when the planned movement starts and how long it lasts, s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timing {
    /// Still time before the planned movement, s.
    pub start_s: f64,
    /// Planned movement duration, s.
    pub duration_s: f64,
}

/// The reach-perturb protocol with the session's device, handle and shoulder; the arm is
/// the nominal one with the segment masses of the subject's body mass where the manifest
/// gives it (segment lengths come in through the subject's factors).
pub(crate) fn session_protocol(session: &Session) -> Result<Protocol, DiscrepancyError> {
    let m = &session.manifest;
    let err = |reason: String| DiscrepancyError::Replay { trial: 0, reason };
    let rate = m.rate_hz;
    let div = TICK_HZ as f64 / rate;
    if !(rate > 0.0 && (div - div.round()).abs() < 1e-9) {
        return Err(err(format!(
            "rate {rate} Hz does not divide the 4 kHz control clock"
        )));
    }
    if let Some(e) = m.trials.iter().find(|e| e.kind.as_str() != "reach") {
        return Err(DiscrepancyError::Replay {
            trial: e.id,
            reason: format!(
                "kind `{}`: compare replays reach trials only",
                e.kind.as_str()
            ),
        });
    }
    let mut protocol = Protocol::builtin("reach-perturb").map_err(|e| err(e.to_string()))?;
    protocol.recording.rate_hz = rate.round() as u32;
    protocol.recording.truth_columns = false;
    protocol.controller.admittance.mass_kg = m.device.mass_kg;
    protocol.controller.admittance.damping_n_s_per_m = m.device.damping_n_s_per_m;
    if let Some(h) = m.device.handle_mass_kg {
        protocol.plant.handle_mass_kg = h;
    }
    protocol.subjects.first_is_nominal = true;
    protocol.subjects.shoulder_m = m.subject.shoulder_m;
    if let Some(kg) = m.subject.body_mass_kg {
        protocol.subjects.arm = protocol
            .subjects
            .arm
            .clone()
            .with_body_mass(kg)
            .map_err(|e| err(format!("subject.body_mass_kg: {e}")))?;
    }
    Ok(protocol)
}

/// The factors of the session's segment lengths over the nominal arm's
/// (1 when the manifest does not give them).
pub(crate) fn length_factors(session: &Session, protocol: &Protocol) -> [f64; 2] {
    let s = &session.manifest.subject;
    let arm = &protocol.subjects.arm;
    [
        s.upper_arm_m.map_or(1.0, |l| l / arm.upper.length_m),
        s.forearm_m.map_or(1.0, |l| l / arm.fore.length_m),
    ]
}

/// The protocol without motor and sensor noise (the encoder quantum stays: it is
/// deterministic). A noiseless simulated sensor may repeat its reading bit for bit (the
/// handle at rest), which the controller's stale-force watchdog would take for a frozen
/// sensor: it is switched off here, as for any simulation without sensor noise.
pub(crate) fn noise_free(protocol: &Protocol) -> Protocol {
    let mut p = protocol.clone();
    p.subjects.arm.noise.activation_cv = 0.0;
    p.plant.force_noise_rms_n = 0.0;
    p.controller.safety.stale_force_ticks = 0;
    p
}

/// One trial replayed: its table and the simulated pulse onset on the table clock.
pub(crate) struct Replayed {
    pub(crate) table: Trial,
    pub(crate) onset_s: Option<f64>,
}

/// Replays trial `index` of `session` (entry and measured table) with `subject`, the
/// reach planned at `timing`, as long as the measured table.
pub(crate) fn replay_trial(
    protocol: &Protocol,
    subject: &VirtualSubject,
    timing: Timing,
    index: usize,
    entry: &TrialEntry,
    measured: &Trial,
) -> Result<Replayed, DiscrepancyError> {
    let rate = f64::from(protocol.recording.rate_hz);
    let mut p = protocol.clone();
    if let Some(r) = p.reach.as_mut() {
        if let (Some(s), Some(g)) = (entry.start_m, entry.goal_m) {
            if g != r.goal_m {
                // A reach to another goal (a centre-out session's): its pulse fires at
                // the protocol's fraction of its own way, on the axis it travels along
                // more, as the rehearsal fired it.
                *r = r.toward_goal(g);
            }
            r.start_m = s;
            r.goal_m = g;
        }
        let total = whole_ticks(measured.len() as f64 / rate);
        r.still_before_s = whole_ticks(timing.start_s.max(0.0));
        r.movement_s = whole_ticks(timing.duration_s.max(1.0 / TICK_HZ as f64));
        // A reach out and back spends its time at the goal and its way back before the
        // still phase after it.
        r.still_after_s = (total - r.still_before_s - r.movement_s - r.back_s()).max(0.0);
    }
    let plan = TrialPlan {
        index: u32::try_from(index).unwrap_or(u32::MAX),
        task: TrialTask::Reach {
            angle_deg: entry.perturbation.as_ref().map(|q| q.angle_deg),
            target: None,
        },
    };
    let seed = p.seed;
    let sim = simulate(&p, subject, seed, &plan, true).map_err(|e| DiscrepancyError::Replay {
        trial: entry.id,
        reason: e.to_string(),
    })?;
    let div = TICK_HZ / u64::from(p.recording.rate_hz).max(1);
    Ok(Replayed {
        table: to_trial(
            &sim.rows,
            rate,
            Layout {
                truth: false,
                position_perturbation: false,
            },
        ),
        onset_s: sim.pulse_onset.map(|k| tick_time_s(k, div)),
    })
}

/// The (measured, simulated) onset rows of a trial, when both pulses fired.
pub(crate) fn onsets(
    entry: &TrialEntry,
    replay: &Replayed,
    rate_hz: f64,
) -> Option<(usize, usize)> {
    let m = entry.perturbation.as_ref()?.onset_s;
    let s = replay.onset_s?;
    Some((onset_row(m, rate_hz), onset_row(s, rate_hz)))
}
