//! Measured against simulated in one plot: the overlays of `rigtwin compare --rerun` and
//! `rigtwin diagnose --rerun`.
//!
//! - [`log_replay_overlay`]: every trial's measured channels under `measured/plots/…` and
//!   its simulated replay's under `simulated/plots/…`, both stamped on the same trial span,
//!   so the position, force, velocity and command plots of the layout show the two curves
//!   of each channel on top of each other.
//! - [`log_diagnosis_overlay`]: for every trial the diagnosis used, held out in its
//!   cross-validation fold, the motor command the cart force balance predicts with the
//!   baseline and with each candidate effect (fitted without that trial) next to the
//!   command on the same rows, under `predicted/plots/command/{x,y}/<model>`: the
//!   diagnosis's own held-out predictions (`rigtwin_diagnose::HeldOut`), drawn as they are.
//!
//! Entity paths are in [`super::paths`].

use super::columns::{Stamp, TrialSpan};
use super::{EventLevel, Viewer, VizError, paths};
use crate::session::{Session, Trial};
use rigtwin_diagnose::{Analysis, DiscrepancyError};

/// Colours of the measured x and y channels.
const MEASURED_RGB: [[u8; 3]; 2] = [[200, 50, 30], [30, 80, 200]];
/// Colours of the simulated x and y channels (lighter, so the measured curve stays on top).
const SIMULATED_RGB: [[u8; 3]; 2] = [[250, 150, 120], [120, 170, 250]];
/// Colours of the predicted commands: the command itself, the baseline, then candidates.
const MODEL_RGB: [[u8; 3]; 6] = [
    [40, 40, 40],
    [30, 90, 200],
    [210, 60, 40],
    [40, 160, 80],
    [170, 60, 170],
    [220, 150, 30],
];

/// What an overlay sent.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Overlaid {
    /// Trials overlaid.
    pub trials: usize,
    /// Samples of the first kind (measured; for a diagnosis, evaluated rows), all trials.
    pub measured_samples: usize,
    /// Samples of the second kind (simulated; for a diagnosis, predicted rows of every
    /// model), all trials.
    pub simulated_samples: usize,
}

/// What can go wrong while building a diagnosis overlay.
#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    /// Sending to the viewer failed.
    #[error(transparent)]
    Viz(#[from] VizError),
    /// A model's prediction could not be computed.
    #[error("predicting the motor command: {0}")]
    Discrepancy(#[from] DiscrepancyError),
}

/// The axis of a column: its line in the paired series entity (0 = x, 1 = y).
fn axis_of(column: &str) -> usize {
    paths::series(column).map_or(0, |(_, line)| line)
}

/// Logs every channel of `trial` under `prefix` on `span`; returns the samples.
fn log_prefixed(
    viewer: &mut Viewer,
    prefix: &str,
    rgb: &[[u8; 3]; 2],
    span: &TrialSpan,
    trial: &Trial,
) -> Result<usize, VizError> {
    let columns = super::session::columns_of(trial);
    columns.check()?;
    for (name, values) in columns.named() {
        if let Some(path) = paths::overlay_series(prefix, name) {
            let legend = format!("{name} {prefix}");
            viewer.log_series(
                &path,
                &legend,
                rgb[axis_of(name)],
                span,
                columns.t_s,
                values,
            )?;
        }
    }
    Ok(trial.len())
}

/// Logs each trial of `session` under `measured/` and `simulated[i]`, its replay, under
/// `simulated/`, trial by trial on the same span (trials end to end in manifest order, each
/// as long as the longer of the two tables), with an event naming the trial at its start.
///
/// `simulated` pairs with the session's trials in order (as [`crate::compare::compare`]
/// keeps them); trials without a replay are not logged.
pub fn log_replay_overlay(
    viewer: &mut Viewer,
    session: &Session,
    simulated: &[Trial],
) -> Result<Overlaid, VizError> {
    let rate_hz = session.manifest.rate_hz;
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(VizError::NotPositive {
            what: "session rate_hz",
            value: rate_hz,
        });
    }
    let mut out = Overlaid::default();
    for (index, ((entry, measured), sim)) in session.iter().zip(simulated).enumerate() {
        let span = TrialSpan {
            trial_index: u32::try_from(index).unwrap_or(u32::MAX),
            offset_s: viewer.next_trial_offset_s(),
            duration_s: measured.len().max(sim.len()) as f64 / rate_hz,
        };
        viewer.log_event(
            span.stamp(0.0),
            EventLevel::Info,
            &format!(
                "trial {} ({}): measured {} samples, simulated {}",
                entry.id,
                entry.kind.as_str(),
                measured.len(),
                sim.len()
            ),
        )?;
        out.measured_samples +=
            log_prefixed(viewer, paths::MEASURED, &MEASURED_RGB, &span, measured)?;
        out.simulated_samples +=
            log_prefixed(viewer, paths::SIMULATED, &SIMULATED_RGB, &span, sim)?;
        out.trials += 1;
        viewer.skip_to_offset_s(span.offset_s + span.duration_s);
    }
    Ok(out)
}

/// Logs, after the session itself (see [`super::log_session`], logged first on the same
/// viewer, so the trials' spans are known), the motor command the cart force balance
/// predicts on every trial the diagnosis used, with each model fitted on the folds that hold
/// the trial out: `baseline` (the nominal balance) and every judged candidate by name, next
/// to `measured` (the command on the same evaluated rows).
///
/// Returns the evaluated rows in `measured_samples` and the predicted rows of all models
/// in `simulated_samples`.
pub fn log_diagnosis_overlay(
    viewer: &mut Viewer,
    session: &Session,
    analysis: &Analysis,
) -> Result<Overlaid, OverlayError> {
    let mut out = Overlaid::default();
    let rate_hz = session.manifest.rate_hz;
    // The spans `log_session` gave each trial: end to end, n / rate each.
    let mut spans = Vec::with_capacity(session.trials.len());
    let mut offset_s = 0.0;
    for (index, (entry, trial)) in session.iter().enumerate() {
        let span = TrialSpan {
            trial_index: u32::try_from(index).unwrap_or(u32::MAX),
            offset_s,
            duration_s: trial.len() as f64 / rate_hz,
        };
        offset_s += span.duration_s;
        spans.push((entry.id, span, trial));
    }
    for held in analysis.held_out()? {
        let Some((_, span, trial)) = spans.iter().find(|(id, _, _)| *id == held.id) else {
            continue;
        };
        let t_s: Vec<f64> = held
            .rows
            .iter()
            .map(|&r| trial.t_s.get(r).copied().unwrap_or(r as f64 / rate_hz))
            .collect();
        let (u, models) = (&held.command_n, &held.models);
        for axis in 0..2 {
            viewer.log_series(
                &paths::predicted_command(axis, paths::MEASURED),
                &format!("{} measured", ["x", "y"][axis]),
                MODEL_RGB[0],
                span,
                &t_s,
                &u[axis],
            )?;
            out.measured_samples += t_s.len();
            for (k, (model, predicted)) in models.iter().enumerate() {
                let predicted = &predicted[axis];
                if predicted.len() != t_s.len() {
                    continue;
                }
                viewer.log_series(
                    &paths::predicted_command(axis, model),
                    &format!("{} {model}", ["x", "y"][axis]),
                    MODEL_RGB[(k + 1).min(MODEL_RGB.len() - 1)],
                    span,
                    &t_s,
                    predicted,
                )?;
                out.simulated_samples += predicted.len();
            }
        }
        let at: Stamp = span.stamp(t_s.first().copied().unwrap_or(0.0));
        viewer.log_event(
            at,
            EventLevel::Info,
            &format!(
                "trial {}: force balance predicted with the models fitted without fold {}",
                held.id, held.fold
            ),
        )?;
        out.trials += 1;
    }
    Ok(out)
}
