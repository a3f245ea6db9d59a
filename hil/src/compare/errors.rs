//! How far a replay is from the measurement, per channel and phase: RMSE and NRMSE over
//! the whole reach (row by row) and over the perturbation response (from each table's own
//! pulse onset, as the change from the value there, both tables smoothed alike).

use rigtwin_diagnose::{CHANNELS, channels_of};
use rigtwin_session::Trial;
use serde::Serialize;

/// Length of the perturbation-response window, s (the 150 ms pulse).
pub const RESPONSE_WINDOW_S: f64 = 0.150;

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
