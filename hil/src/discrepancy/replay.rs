//! `compare`: replay every trial of a session in simulation with the session's own
//! inputs (device admittance, handle mass, subject shoulder and segment lengths,
//! start and goal, perturbation angle; the pulse fires on the protocol's trigger, as on
//! the rig) and measure, per channel and per phase, how far the simulation is from the
//! measurement.
//!
//! The simulated subject is the nominal virtual subject with the session's geometry:
//! the baseline subject parameters (impedance scale, co-contraction, feedback gain,
//! reach timing) are **not fitted** yet, so human-side discrepancies are reported but
//! not attributed.

use rigtwin_world::PlantEffects;
use serde::Serialize;

use super::error::DiscrepancyError;
use crate::protocol::Protocol;
use crate::rehearse::record::{Layout, to_trial};
use crate::rehearse::trial::simulate;
use crate::rehearse::{TrialPlan, TrialTask};
use crate::session::{Session, Trial};

/// Length of the perturbation-response window, s (the 150 ms pulse).
pub const RESPONSE_WINDOW_S: f64 = 0.150;

/// Discrepancy of one channel over one phase, pooled over trials.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelError {
    /// Column name (unit in the name).
    pub channel: String,
    /// `reach` (whole trial) or `response` (150 ms from each pulse onset).
    pub phase: String,
    /// Root-mean-square of simulated − measured, in the channel's unit.
    pub rmse: f64,
    /// RMSE over the RMS of the measured channel about its mean in that phase.
    pub nrmse: f64,
    /// Samples pooled.
    pub samples: usize,
}

/// The outcome of [`compare`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Session directory.
    pub session: String,
    /// Trials replayed.
    pub trials: usize,
    /// Whether an extended model's effects were simulated.
    pub with_model: bool,
    /// Per channel and phase.
    pub channels: Vec<ChannelError>,
    /// What was and was not done.
    pub notes: Vec<String>,
}

#[derive(Default, Clone, Copy)]
struct Acc {
    se: f64,
    sum: f64,
    sum2: f64,
    n: usize,
}

impl Acc {
    fn push(&mut self, meas: f64, sim: f64) {
        self.se += (sim - meas) * (sim - meas);
        self.sum += meas;
        self.sum2 += meas * meas;
        self.n += 1;
    }
    fn result(&self, channel: &str, phase: &str) -> ChannelError {
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

/// Replays `session` (see the module docs), with `effects` added to the plant if given.
///
/// # Errors
/// [`DiscrepancyError::Replay`] when the session cannot be replayed (rate not a divisor
/// of 4 kHz, a trial that is not a reach) or the simulation fails.
pub fn compare(
    session: &Session,
    effects: Option<&PlantEffects>,
) -> Result<Comparison, DiscrepancyError> {
    let m = &session.manifest;
    let err = |trial: u32, reason: String| DiscrepancyError::Replay { trial, reason };
    let rate = m.rate_hz;
    let div = 4000.0 / rate;
    if !(rate > 0.0 && (div - div.round()).abs() < 1e-9) {
        return Err(err(
            0,
            format!("rate {rate} Hz does not divide the 4 kHz control clock"),
        ));
    }
    let mut protocol = Protocol::builtin("reach-perturb").map_err(|e| err(0, e.to_string()))?;
    protocol.recording.rate_hz = rate.round() as u32;
    protocol.recording.truth_columns = false;
    protocol.controller.admittance.mass_kg = m.device.mass_kg;
    protocol.controller.admittance.damping_n_s_per_m = m.device.damping_n_s_per_m;
    if let Some(h) = m.device.handle_mass_kg {
        protocol.plant.handle_mass_kg = h;
    }
    if let Some(e) = effects {
        protocol.plant.effects = e.clone();
    }
    protocol.subjects.first_is_nominal = true;
    protocol.subjects.shoulder_m = m.subject.shoulder_m;
    if let Some(l) = m.subject.upper_arm_m {
        protocol.subjects.arm.upper.length_m = l;
    }
    if let Some(l) = m.subject.forearm_m {
        protocol.subjects.arm.fore.length_m = l;
    }
    let seed = protocol.seed;
    let subject = protocol.subjects.draw(seed, 1);
    let names = ["x_m", "y_m", "fx_n", "fy_n", "cmd_fx_n", "cmd_fy_n"];
    let mut reach = [Acc::default(); 6];
    let mut resp = [Acc::default(); 6];
    let mut replayed = 0;
    for (i, (entry, meas)) in session.iter().enumerate() {
        let mut p = protocol.clone();
        if let (Some(r), Some(s), Some(g)) = (p.reach.as_mut(), entry.start_m, entry.goal_m) {
            r.start_m = s;
            r.goal_m = g;
        }
        let plan = TrialPlan {
            index: u32::try_from(i).unwrap_or(u32::MAX),
            task: TrialTask::Reach {
                angle_deg: entry.perturbation.as_ref().map(|q| q.angle_deg),
            },
        };
        let sim =
            simulate(&p, &subject, seed, &plan, true).map_err(|e| err(entry.id, e.to_string()))?;
        let st = to_trial(
            &sim.rows,
            rate,
            Layout {
                truth: false,
                position_perturbation: false,
            },
        );
        // The motor command shows plant-side effects that the stiff position loop keeps
        // out of the positions; it is compared when the session has it.
        let chans = |t: &Trial| {
            [
                t.x_m.clone(),
                t.y_m.clone(),
                t.fx_n.clone(),
                t.fy_n.clone(),
                t.cmd_fx_n.clone().unwrap_or_default(),
                t.cmd_fy_n.clone().unwrap_or_default(),
            ]
        };
        let (mc, sc) = (chans(meas), chans(&st));
        let n = meas.len().min(st.len());
        let window = entry.perturbation.as_ref().map(|q| {
            let a = (q.onset_s * rate).round() as usize;
            (a, a + (RESPONSE_WINDOW_S * rate).round() as usize)
        });
        for c in 0..6 {
            let n = n.min(mc[c].len()).min(sc[c].len());
            for k in 0..n {
                reach[c].push(mc[c][k], sc[c][k]);
                if let Some((a, b)) = window
                    && (a..b).contains(&k)
                {
                    resp[c].push(mc[c][k], sc[c][k]);
                }
            }
        }
        replayed += 1;
    }
    let mut channels: Vec<ChannelError> = (0..6)
        .filter(|c| reach[*c].n > 0)
        .map(|c| reach[c].result(names[c], "reach"))
        .collect();
    channels.extend(
        (0..6)
            .filter(|c| resp[*c].n > 0)
            .map(|c| resp[c].result(names[c], "response")),
    );
    Ok(Comparison {
        session: session.dir.display().to_string(),
        trials: replayed,
        with_model: effects.is_some(),
        channels,
        notes: vec![
            "subject: the nominal virtual subject with the session's shoulder and segment lengths; impedance scale, \
             co-contraction, feedback gain and reach timing are not fitted yet"
                .into(),
            "response window: 150 ms from the measured onset; the simulated pulse fires on the protocol's own trigger"
                .into(),
            "not done yet: frequency content, estimator D and K measured vs simulated".into(),
        ],
    })
}
