//! `compare`: replay every trial of a session in simulation with the session's own
//! inputs (device admittance, handle mass, subject shoulder and segment lengths,
//! start and goal, perturbation angle; the pulse fires on the protocol's trigger, as on
//! the rig) and measure how far the simulation is from the measurement:
//!
//! 1. **Subject fit** ([`fit_subject`](crate::compare::fit_subject)): subjects differ, so the baseline subject's
//!    muscle stiffness, co-contraction and feedback gain factors and the timing of the
//!    reach are first fitted to the session (noise-free replays of a subset of trials).
//! 2. **Replay**: every trial with the fitted subject and the model's own seeded noise
//!    (motor noise of the arm, force-sensor noise of the plant, stream of the protocol's
//!    seed): the frequency content and the estimator should see a subject as noisy as the
//!    model says a subject is.
//! 3. **Per channel and phase**: RMSE and NRMSE over the whole reach (row by row) and over
//!    the 150 ms perturbation response (from each table's own onset, as the change from
//!    the value there); per frequency band ([`band_errors`](rigtwin_diagnose::band_errors)); the Börner estimate of
//!    D and K on the measured and on the simulated trials (the code path of
//!    `rigtwin estimate`).
//!
//! With an extended model ([`ExtendedModel`](rigtwin_diagnose::ExtendedModel)), the subject is still fitted with the
//! baseline model, then kept: the model's plant and human-side effects are added to that
//! subject's replay, so baseline and model runs differ by the model alone.

mod errors;
mod resim;
mod subject_fit;

pub use errors::{ChannelError, RESPONSE_SMOOTHING_S, RESPONSE_WINDOW_S};
pub use resim::Timing;
pub use subject_fit::{
    FitOptions, FitResidual, SubjectFit, fit_subject, fit_trials, travel_times_s,
};

use rayon::prelude::*;
use rigtwin_diagnose::{BandError, DiscrepancyError, ExtendedModel, band_errors};
use serde::Serialize;

use crate::protocol::EstimateConfig;
use crate::report::estimate::{BornerResult, borner_on_session};
use crate::session::{Session, Trial};
use errors::{Acc, accumulate, channel_errors};
use resim::{Replayed, onsets, replay_trial, session_protocol};

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
        m.apply_to(
            &mut protocol.plant.effects,
            &mut protocol.subjects.arm.stretch_reflex,
        );
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
