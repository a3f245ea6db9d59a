//! Held-out predictions: on every trial the cart balance used, the motor command each
//! model predicts when fitted on the folds that hold the trial out (the baseline, then
//! every judged candidate by name), next to the command itself on the same rows.
//!
//! The balance is `u = model(signals) + residual`, so a model's prediction is
//! `u − residual`. These are the numbers the held-out gains are computed from; the viewer
//! draws them as they are and refits nothing.

use super::candidate::{Baseline, Candidate};
use super::diagnose::Analysis;
use super::error::DiscrepancyError;

/// One trial's held-out predictions.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// Trial id.
    pub id: u32,
    /// The fold that held it out.
    pub fold: usize,
    /// The trial table's rows evaluated (the balance's decimated rows).
    pub rows: Vec<usize>,
    /// The motor command on those rows per axis, N.
    pub command_n: [Vec<f64>; 2],
    /// Each model's predicted command on those rows per axis, N: `baseline` first, then
    /// the judged candidates in [`Analysis::fits`] order, by name.
    pub models: Vec<(&'static str, [Vec<f64>; 2])>,
}

impl Analysis {
    /// The held-out predictions of every trial the cart balance used, in
    /// [`Analysis::signals`] order (none without the cart balance).
    ///
    /// # Errors
    /// A signal-processing error while forming a residual.
    pub fn held_out(&self) -> Result<Vec<HeldOut>, DiscrepancyError> {
        let mut out = Vec::with_capacity(self.signals.len());
        for i in 0..self.signals.len() {
            out.extend(self.held_out_trial(i)?);
        }
        Ok(out)
    }

    /// The held-out predictions of the `i`-th trial of [`Analysis::signals`] (`None`
    /// without the cart balance, or past the last trial).
    ///
    /// # Errors
    /// A signal-processing error while forming a residual.
    pub fn held_out_trial(&self, i: usize) -> Result<Option<HeldOut>, DiscrepancyError> {
        let (Some(base), Some(folds)) = (&self.baseline, &self.folds) else {
            return Ok(None);
        };
        let (Some(sig), Some(&fold)) = (self.signals.get(i), folds.of_trial.get(i)) else {
            return Ok(None);
        };
        let Some(bf) = base.folds.get(fold) else {
            return Ok(None);
        };
        let command_n = [sig.at_rows(&sig.u[0]), sig.at_rows(&sig.u[1])];
        let predicted = |residual: [Vec<f64>; 2]| {
            [0, 1].map(|axis| {
                command_n[axis]
                    .iter()
                    .zip(&residual[axis])
                    .map(|(u, r)| u - r)
                    .collect::<Vec<f64>>()
            })
        };
        let mut models = vec![(
            "baseline",
            predicted(Baseline.residual(sig, 0, &bf.beta, self.latency_s)?),
        )];
        for cf in &self.fits {
            if let Some(f) = cf.fit.folds.get(fold) {
                let r = cf
                    .candidate
                    .residual(sig, f.setting, &f.beta, self.latency_s)?;
                models.push((cf.candidate.name(), predicted(r)));
            }
        }
        Ok(Some(HeldOut {
            id: sig.id,
            fold,
            rows: sig.rows.clone(),
            command_n,
            models,
        }))
    }
}
