//! `compare`: replay every trial of a session in simulation with the session's own
//! inputs (device admittance, handle mass, subject shoulder and segment lengths,
//! start and goal, perturbation angle; the pulse fires on the protocol's trigger, as on
//! the rig) and measure how far the simulation is from the measurement:
//!
//! 1. **Subject fit** ([`fit_subject`]): subjects differ, so the baseline subject's
//!    muscle stiffness, co-contraction and feedback gain factors and the timing of the
//!    reach are first fitted to the session (noise-free replays of a subset of trials).
//! 2. **Replay**: every trial with the fitted subject and the model's own seeded noise
//!    (motor noise of the arm, force-sensor noise of the plant, stream of the protocol's
//!    seed): the frequency content and the estimator should see a subject as noisy as the
//!    model says a subject is.
//! 3. **Per channel and phase**: RMSE and NRMSE over the whole reach (row by row) and over
//!    the 150 ms perturbation response (from each table's own onset, as the change from
//!    the value there); per frequency band ([`band_errors`]); the Börner estimate of
//!    D and K on the measured and on the simulated trials (the code path of
//!    `rigtwin estimate`).
//!
//! With an extended model ([`ExtendedModel`]), the subject is still fitted with the
//! baseline model, then kept: the model's plant and human-side effects are added to that
//! subject's replay, so baseline and model runs differ by the model alone.

use rayon::prelude::*;
use serde::Serialize;

use super::bands::{BandError, band_errors};
use super::error::DiscrepancyError;
use super::model::ExtendedModel;
use super::subject_fit::{FitOptions, SubjectFit, fit_subject};
use crate::protocol::{EstimateConfig, Protocol, VirtualSubject, whole_ticks};
use crate::rehearse::record::{Layout, tick_time_s, to_trial};
use crate::rehearse::trial::simulate;
use crate::rehearse::{TICK_HZ, TrialPlan, TrialTask};
use crate::report::estimate::{BornerResult, borner_on_session};
use crate::session::{Session, Trial, TrialEntry};

/// Length of the perturbation-response window, s (the 150 ms pulse).
pub const RESPONSE_WINDOW_S: f64 = 0.150;

/// Channel names compared, in order (units in the names).
pub const CHANNELS: [&str; 6] = ["x_m", "y_m", "fx_n", "fy_n", "cmd_fx_n", "cmd_fy_n"];

/// Discrepancy of one channel over one phase, pooled over trials.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelError {
    /// Column name (unit in the name).
    pub channel: String,
    /// `reach` (whole trial, row by row) or `response` (150 ms from each table's own
    /// pulse onset, as the change from the value at the onset).
    pub phase: String,
    /// Root-mean-square of simulated − measured, in the channel's unit.
    pub rmse: f64,
    /// RMSE over the RMS of the measured channel about its mean in that phase.
    pub nrmse: f64,
    /// Samples pooled.
    pub samples: usize,
}

/// The Börner estimate (000_*) of the measured and of the simulated trials.
#[derive(Debug, Clone, Serialize)]
pub struct ImpedanceComparison {
    /// On the measured session, exactly as `rigtwin estimate` computes it.
    pub measured: BornerResult,
    /// On the simulated replay, the simulated pulse onsets in place of the measured ones.
    pub simulated: BornerResult,
    /// `D̂` simulated − measured, N s/m.
    pub d_diff_ns_per_m: [[f64; 2]; 2],
    /// `K̂` simulated − measured, N/m.
    pub k_diff_n_per_m: [[f64; 2]; 2],
}

/// The outcome of [`compare`].
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// Session directory.
    pub session: String,
    /// Trials replayed.
    pub trials: usize,
    /// Whether an extended model's effects were simulated.
    pub with_model: bool,
    /// The baseline subject fitted to the session (kept for a model run).
    pub subject: SubjectFit,
    /// Per channel and phase, replay with the fitted subject.
    pub channels: Vec<ChannelError>,
    /// Per channel and frequency band, replay with the fitted subject.
    pub frequency: Vec<BandError>,
    /// D and K from measured vs simulated data; `None` without force-pulse trials (the
    /// reason is in `notes`).
    pub impedance: Option<ImpedanceComparison>,
    /// How the numbers were made, and what could not be done.
    pub notes: Vec<String>,
    /// The simulated replay of every trial, in session order, when
    /// [`CompareOptions::keep_simulated`] asks for it (empty otherwise; not in the JSON).
    #[serde(skip)]
    pub simulated: Vec<Trial>,
}

/// How [`compare`] runs.
#[derive(Debug, Clone, Default)]
pub struct CompareOptions {
    /// The subject fit.
    pub fit: FitOptions,
    /// Keep the simulated tables in [`Comparison::simulated`] (for the viewer overlay).
    pub keep_simulated: bool,
}

#[derive(Default, Clone, Copy)]
pub(crate) struct Acc {
    se: f64,
    sum: f64,
    sum2: f64,
    pub(crate) n: usize,
}

impl Acc {
    pub(crate) fn push(&mut self, meas: f64, sim: f64) {
        self.se += (sim - meas) * (sim - meas);
        self.sum += meas;
        self.sum2 += meas * meas;
        self.n += 1;
    }
    pub(crate) fn add(&mut self, o: &Acc) {
        self.se += o.se;
        self.sum += o.sum;
        self.sum2 += o.sum2;
        self.n += o.n;
    }
    pub(crate) fn result(&self, channel: &str, phase: &str) -> ChannelError {
        let n = self.n.max(1) as f64;
        let var = (self.sum2 / n - (self.sum / n).powi(2)).max(0.0);
        let rmse = (self.se / n).sqrt();
        ChannelError {
            channel: channel.into(),
            phase: phase.into(),
            rmse,
            nrmse: if var > 0.0 {
                rmse / var.sqrt()
            } else {
                f64::NAN
            },
            samples: self.n,
        }
    }
}

/// Reach timing of a replay: when the planned movement starts and how long it lasts, s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timing {
    /// Still time before the planned movement, s.
    pub start_s: f64,
    /// Planned movement duration, s.
    pub duration_s: f64,
}

/// The reach-perturb protocol with the session's device, handle and shoulder; the arm is
/// the nominal one (segment lengths come in through the subject's factors).
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
            r.start_m = s;
            r.goal_m = g;
        }
        let total = whole_ticks(measured.len() as f64 / rate);
        r.still_before_s = whole_ticks(timing.start_s.max(0.0));
        r.movement_s = whole_ticks(timing.duration_s.max(1.0 / TICK_HZ as f64));
        r.still_after_s = (total - r.still_before_s - r.movement_s).max(0.0);
    }
    let plan = TrialPlan {
        index: u32::try_from(index).unwrap_or(u32::MAX),
        task: TrialTask::Reach {
            angle_deg: entry.perturbation.as_ref().map(|q| q.angle_deg),
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

/// The compared channels of a table, in [`CHANNELS`] order; a missing optional column is
/// empty.
pub(crate) fn channels_of(t: &Trial) -> [&[f64]; 6] {
    [
        &t.x_m,
        &t.y_m,
        &t.fx_n,
        &t.fy_n,
        t.cmd_fx_n.as_deref().unwrap_or(&[]),
        t.cmd_fy_n.as_deref().unwrap_or(&[]),
    ]
}

/// Centred moving mean applied to both tables over the response, s: the sensor's white
/// noise (0.05 N RMS at 4 kHz) would otherwise dominate the force response, and the
/// response's own content lies below 30 Hz (the estimator's Savitzky–Golay cut-off);
/// an 11-row mean at 1 kHz passes 30 Hz at −1.6 dB.
pub const RESPONSE_SMOOTHING_S: f64 = 0.010;

/// Mean of `x[k − h ..= k + h]` (clipped to the table).
fn smooth(x: &[f64], k: usize, h: usize) -> f64 {
    let lo = k.saturating_sub(h);
    let hi = (k + h + 1).min(x.len());
    x[lo..hi].iter().sum::<f64>() / (hi - lo).max(1) as f64
}

/// The first row of the response window of a trial whose pulse fired at `onset_s`.
pub(crate) fn onset_row(onset_s: f64, rate_hz: f64) -> usize {
    (onset_s * rate_hz).round().max(0.0) as usize
}

/// Accumulates one trial's errors into `reach` and `resp` (per [`CHANNELS`]). The
/// whole-reach phase compares the tables row by row. The response phase compares the
/// 150 ms after each table's own pulse onset (`onsets`: measured, simulated rows), as the
/// change from the value at that onset, both smoothed by a centred
/// [`RESPONSE_SMOOTHING_S`] mean: both pulses fire on the same line crossing, so
/// this is the response itself, not a difference of reach timing.
pub(crate) fn accumulate(
    measured: &Trial,
    simulated: &Trial,
    onsets: Option<(usize, usize)>,
    rate_hz: f64,
    reach: &mut [Acc; 6],
    resp: &mut [Acc; 6],
) {
    let (mc, sc) = (channels_of(measured), channels_of(simulated));
    let len = (RESPONSE_WINDOW_S * rate_hz).round() as usize;
    let h = (RESPONSE_SMOOTHING_S * rate_hz / 2.0).round() as usize;
    for c in 0..6 {
        let n = mc[c].len().min(sc[c].len());
        for k in 0..n {
            reach[c].push(mc[c][k], sc[c][k]);
        }
        if let Some((a, b)) = onsets
            && a + len + h <= mc[c].len()
            && b + len + h <= sc[c].len()
        {
            let (m0, s0) = (smooth(mc[c], a, h), smooth(sc[c], b, h));
            for k in 0..len {
                resp[c].push(smooth(mc[c], a + k, h) - m0, smooth(sc[c], b + k, h) - s0);
            }
        }
    }
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

/// The per-channel errors of accumulated phases (channels without samples left out).
pub(crate) fn channel_errors(reach: &[Acc; 6], resp: &[Acc; 6]) -> Vec<ChannelError> {
    let mut out: Vec<ChannelError> = (0..6)
        .filter(|c| reach[*c].n > 0)
        .map(|c| reach[c].result(CHANNELS[c], "reach"))
        .collect();
    out.extend(
        (0..6)
            .filter(|c| resp[*c].n > 0)
            .map(|c| resp[c].result(CHANNELS[c], "response")),
    );
    out
}

fn diff(a: &[[f64; 2]; 2], b: &[[f64; 2]; 2]) -> [[f64; 2]; 2] {
    [0, 1].map(|r| [0, 1].map(|c| a[r][c] - b[r][c]))
}

/// Replays `session` (see the module docs) with the subject fitted to it and, if given,
/// the extended model's plant and human-side effects added.
///
/// # Errors
/// [`DiscrepancyError::Replay`] when the session cannot be replayed (rate not a divisor
/// of 4 kHz, a trial that is not a reach, a reach that never covers 95 % of its
/// travel) or the simulation fails.
pub fn compare(
    session: &Session,
    model: Option<&ExtendedModel>,
    options: &CompareOptions,
) -> Result<Comparison, DiscrepancyError> {
    let rate = session.manifest.rate_hz;
    let baseline = session_protocol(session)?;
    let fit = fit_subject(session, &baseline, &options.fit)?;
    let mut protocol = baseline;
    if let Some(m) = model {
        m.apply_to(&mut protocol);
    }
    let subject = protocol.subjects.with_factors(1, fit.factors());
    let timing = fit.timing;
    let replays: Vec<Replayed> = session
        .iter()
        .enumerate()
        .collect::<Vec<_>>()
        .par_iter()
        .map(|(i, (entry, meas))| replay_trial(&protocol, &subject, timing, *i, entry, meas))
        .collect::<Result<_, _>>()?;
    let mut reach = [Acc::default(); 6];
    let mut resp = [Acc::default(); 6];
    for ((entry, meas), sim) in session.iter().zip(&replays) {
        accumulate(
            meas,
            &sim.table,
            onsets(entry, sim, rate),
            rate,
            &mut reach,
            &mut resp,
        );
    }
    let pairs: Vec<(&Trial, &Trial)> = session
        .trials
        .iter()
        .zip(replays.iter().map(|r| &r.table))
        .collect();
    let frequency = band_errors(&pairs, rate);
    let mut notes = vec![
        format!(
            "subject: fitted to the baseline model on {} trials by noise-free replays ({} evaluations){}",
            fit.fit_trials.len(),
            fit.evaluations,
            if model.is_some() {
                "; kept as fitted for the model run, so baseline and model differ by the model alone"
            } else {
                ""
            }
        ),
        format!(
            "replay: every trial with the fitted subject and the model's seeded noise (arm motor noise cv {}, force-sensor noise {} N RMS, protocol seed {}): spectra and estimates see the noise the model says a subject and a sensor have",
            protocol.subjects.arm.noise.activation_cv,
            protocol.plant.force_noise_rms_n,
            protocol.seed
        ),
        "response phase: 150 ms from each table's own pulse onset (the simulated pulse fires on the protocol's line trigger, as on the rig), as the change from the value at the onset"
            .into(),
    ];
    let impedance = match impedance(session, &replays) {
        Ok(i) => Some(i),
        Err(reason) => {
            notes.push(format!("estimator D and K not compared: {reason}"));
            None
        }
    };
    Ok(Comparison {
        session: session.dir.display().to_string(),
        trials: replays.len(),
        with_model: model.is_some(),
        subject: fit,
        channels: channel_errors(&reach, &resp),
        frequency,
        impedance,
        notes,
        simulated: if options.keep_simulated {
            replays.into_iter().map(|r| r.table).collect()
        } else {
            Vec::new()
        },
    })
}

/// The Börner estimate on the measured session and on the replay, which is handed to
/// the same function as a session in memory whose perturbation onsets are the
/// simulated ones (a trial whose simulated pulse did not fire is left out).
fn impedance(session: &Session, replays: &[Replayed]) -> Result<ImpedanceComparison, String> {
    let config = EstimateConfig::default();
    let measured = borner_on_session(session, &config).map_err(|e| format!("measured: {e}"))?;
    let mut manifest = session.manifest.clone();
    for (entry, r) in manifest.trials.iter_mut().zip(replays) {
        match (entry.perturbation.as_mut(), r.onset_s) {
            (Some(p), Some(t)) => p.onset_s = t,
            (Some(_), None) => entry.perturbation = None,
            _ => {}
        }
    }
    let replay = Session {
        dir: session.dir.join("(replay)"),
        manifest,
        trials: replays.iter().map(|r| r.table.clone()).collect(),
    };
    let simulated = borner_on_session(&replay, &config).map_err(|e| format!("simulated: {e}"))?;
    Ok(ImpedanceComparison {
        d_diff_ns_per_m: diff(&simulated.d_ns_per_m, &measured.d_ns_per_m),
        k_diff_n_per_m: diff(&simulated.k_n_per_m, &measured.k_n_per_m),
        measured,
        simulated,
    })
}
