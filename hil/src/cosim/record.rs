//! Recording: block means of the 4 kHz ticks at the recording rate, and the session
//! table they become.
//!
//! Like the shared rig (`recordings/README.md`), each row is the mean of a block of
//! `4000 / rate_hz` consecutive ticks; `t_s` is the time of the block's centre with
//! the clock starting at the centre of the first block, so a tick `k` is at
//! `t = (k − (d − 1)/2) / 4000` s for blocks of `d` ticks. At 4 kHz (`d = 1`) the rows
//! are the ticks themselves. Values are rounded before writing to what the sensors
//! resolve (0.1 µm, 0.1 mN, 1 µm/s, 1 mN of command) so that files stay small and
//! their text is short; the simulator's ground-truth columns get the same rounding.

use rigtwin_arm::muscles::MUSCLES;
use rigtwin_device::TickReport;

use super::PlantSample;
use crate::session::{Column, Trial};

/// Number of channels in a [`Block`]: twelve x/y pairs, the six muscle activations and
/// the loop's timing (wake-up latency, held ticks).
pub const CHANNELS: usize = 26 + MUSCLES;

/// Channel indices into [`Block::v`].
pub mod ch {
    /// Encoder position x, y, m.
    pub const X: usize = 0;
    /// Calibrated hand force x, y, N.
    pub const F: usize = 2;
    /// Force-pulse perturbation x, y, N.
    pub const PERT: usize = 4;
    /// Drive velocity x, y, m/s.
    pub const V: usize = 6;
    /// Position reference x, y, m.
    pub const REF: usize = 8;
    /// Motor command x, y, N.
    pub const CMD: usize = 10;
    /// True handle position x, y, m.
    pub const TRUE_X: usize = 12;
    /// True handle velocity x, y, m/s.
    pub const TRUE_V: usize = 14;
    /// True force of the hand on the handle x, y, N.
    pub const HAND: usize = 16;
    /// True handle acceleration x, y, m/s².
    pub const ACC: usize = 18;
    /// Position-perturbation offset x, y, m.
    pub const PERT_POS: usize = 20;
    /// Virtual-spring anchor (imposed motion) x, y, m.
    pub const ANCHOR: usize = 22;
    /// The arm's six muscle activations, N, in the order of
    /// `rigtwin_arm::muscles::MUSCLE_NAMES` (zero without an arm). Kept in memory for the
    /// viewer; never written to the session table.
    pub const ACTIVATION: usize = 24;
    /// The wall clock's wake-up latency of the ticks the loop ran, µs (block mean; zero in
    /// lock step and for held ticks). Kept in memory for the viewer; never written.
    pub const WAKE_US: usize = 24 + super::MUSCLES;
    /// The share of the block's ticks that were held (missed deadlines: the controller
    /// did not run, the plant moved on under the held command). Never written.
    pub const HELD: usize = WAKE_US + 1;
}

/// One recorded row: the mean of each channel over its block of ticks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Block {
    /// Channel means, indexed by [`ch`].
    pub v: [f64; CHANNELS],
}

impl Block {
    /// The pair of a channel.
    #[must_use]
    pub fn pair(&self, c: usize) -> [f64; 2] {
        [self.v[c], self.v[c + 1]]
    }

    /// The six muscle activations, N.
    #[must_use]
    pub fn activations_n(&self) -> [f64; MUSCLES] {
        std::array::from_fn(|i| self.v[ch::ACTIVATION + i])
    }

    /// The loop's timing over the block: mean wake-up latency of the ticks run (µs) and
    /// the share of ticks held.
    #[must_use]
    pub fn timing(&self) -> [f64; 2] {
        [self.v[ch::WAKE_US], self.v[ch::HELD]]
    }
}

/// Accumulates ticks into blocks.
#[derive(Debug)]
pub struct Recorder {
    div: u64,
    count: u64,
    sum: [f64; CHANNELS],
    timing: [f64; 2],
    rows: Vec<Block>,
}

impl Recorder {
    /// Blocks of `div` ticks; `n_ticks` sizes the buffer.
    #[must_use]
    pub fn new(div: u64, n_ticks: u64) -> Recorder {
        Recorder {
            div: div.max(1),
            count: 0,
            sum: [0.0; CHANNELS],
            timing: [0.0; 2],
            rows: Vec::with_capacity((n_ticks / div.max(1)) as usize + 1),
        }
    }

    /// The loop's timing of the next tick [`Recorder::push`] adds: its wake-up latency,
    /// µs, and whether it was held. Zero unless set, as in lock step.
    pub fn set_tick_timing(&mut self, wake_us: f64, held: bool) {
        self.timing = [wake_us, f64::from(u8::from(held))];
    }

    /// Adds one tick: the controller's report and the plant's ground truth of the tick
    /// (zeros where the plant does not know it). Allocation-free: the rows were reserved
    /// by [`Recorder::new`].
    pub fn push(&mut self, r: &TickReport, truth: &PlantSample) {
        let pairs: [[f64; 2]; ch::ACTIVATION / 2] = [
            r.position_m,
            r.force_n,
            r.pert_force_n,
            r.velocity_m_per_s,
            r.ref_position_m,
            r.command_n,
            truth.position_m,
            truth.velocity_m_per_s,
            truth.hand_n,
            truth.acceleration_m_per_s2,
            r.pert_position_m,
            r.anchor_position_m,
        ];
        for (i, p) in pairs.iter().enumerate() {
            self.sum[2 * i] += p[0];
            self.sum[2 * i + 1] += p[1];
        }
        for (s, a) in self.sum[ch::ACTIVATION..]
            .iter_mut()
            .zip(&truth.activations_n)
        {
            *s += a;
        }
        self.sum[ch::WAKE_US] += self.timing[0];
        self.sum[ch::HELD] += self.timing[1];
        self.timing = [0.0; 2];
        self.count += 1;
        if self.count == self.div {
            let k = self.div as f64;
            self.rows.push(Block {
                v: self.sum.map(|s| s / k),
            });
            self.sum = [0.0; CHANNELS];
            self.count = 0;
        }
    }

    /// The complete blocks (a trailing partial block is dropped).
    #[must_use]
    pub fn finish(self) -> Vec<Block> {
        self.rows
    }
}

/// `v` rounded to a multiple of `quantum` (a negative power of ten), as the double
/// nearest to that decimal, so that its shortest text is the short decimal: `n / 10^k`
/// with `10^k` exact is one correctly rounded division, the same double that parsing
/// `"n e-k"` gives.
fn round_to(v: f64, quantum: f64) -> f64 {
    let inv = (1.0 / quantum).round();
    // Adding 0.0 turns a negative zero into zero.
    (v * inv).round() / inv + 0.0
}

/// Which columns a trial table gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Add `true_x_m, true_y_m, hand_fx_n, hand_fy_n`.
    pub truth: bool,
    /// Add `pert_x_m, pert_y_m` (position-perturbation offsets).
    pub position_perturbation: bool,
}

/// The session table of a trial's rows at `rate_hz`.
#[must_use]
pub fn to_trial(rows: &[Block], rate_hz: f64, layout: Layout) -> Trial {
    let col = |c: usize, q: f64| -> Vec<f64> { rows.iter().map(|b| round_to(b.v[c], q)).collect() };
    let mut extra = Vec::new();
    let mut named = |name: &str, c: usize, q: f64| {
        extra.push(Column {
            name: name.to_owned(),
            values: col(c, q),
        });
    };
    if layout.position_perturbation {
        named("pert_x_m", ch::PERT_POS, 1e-7);
        named("pert_y_m", ch::PERT_POS + 1, 1e-7);
    }
    if layout.truth {
        named("true_x_m", ch::TRUE_X, 1e-7);
        named("true_y_m", ch::TRUE_X + 1, 1e-7);
        named("hand_fx_n", ch::HAND, 1e-4);
        named("hand_fy_n", ch::HAND + 1, 1e-4);
    }
    Trial {
        t_s: (0..rows.len()).map(|i| i as f64 / rate_hz).collect(),
        x_m: col(ch::X, 1e-7),
        y_m: col(ch::X + 1, 1e-7),
        fx_n: col(ch::F, 1e-4),
        fy_n: col(ch::F + 1, 1e-4),
        pert_fx_n: col(ch::PERT, 1e-4),
        pert_fy_n: col(ch::PERT + 1, 1e-4),
        vx_m_per_s: Some(col(ch::V, 1e-6)),
        vy_m_per_s: Some(col(ch::V + 1, 1e-6)),
        ref_x_m: Some(col(ch::REF, 1e-7)),
        ref_y_m: Some(col(ch::REF + 1, 1e-7)),
        cmd_fx_n: Some(col(ch::CMD, 1e-3)),
        cmd_fy_n: Some(col(ch::CMD + 1, 1e-3)),
        extra,
    }
}

/// Time of tick `k` on the table clock of blocks of `div` ticks, s.
#[must_use]
pub fn tick_time_s(k: u64, div: u64) -> f64 {
    (k as f64 - (div.max(1) as f64 - 1.0) / 2.0) / f64::from(rigtwin_device::Rate::CONTROL.hz())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_gives_short_text() {
        assert_eq!(format!("{}", round_to(0.123_456_789, 1e-7)), "0.1234568");
        assert_eq!(format!("{}", round_to(-2.5e-9, 1e-7)), "0");
        assert_eq!(format!("{}", round_to(14.999_96, 1e-4)), "15");
    }

    /// Blocks of 4 ticks: each row's activations are the mean of its ticks', like every other
    /// channel (exact here: the sums of small integers are exact in f64), and a trailing
    /// partial block is dropped.
    #[test]
    fn activations_are_block_means() {
        let mut rec = Recorder::new(4, 10);
        for k in 0..10 {
            let truth = PlantSample {
                activations_n: std::array::from_fn(|m| (k * (m + 1)) as f64),
                ..PlantSample::default()
            };
            rec.push(&TickReport::default(), &truth);
        }
        let rows = rec.finish();
        assert_eq!(rows.len(), 2);
        for (b, row) in rows.iter().enumerate() {
            // Mean of k = 4b..4b+3 is 4b + 1.5; muscle m scales it by m + 1.
            let mean_k = 4.0 * b as f64 + 1.5;
            let want: [f64; MUSCLES] = std::array::from_fn(|m| mean_k * (m + 1) as f64);
            assert_eq!(row.activations_n(), want);
        }
    }

    #[test]
    fn block_centre_clock() {
        // Blocks of 4 ticks: tick 1.5 is the centre of the first block, t = 0.
        let hz = f64::from(rigtwin_device::Rate::CONTROL.hz());
        assert!((tick_time_s(1003, 4) - 1001.5 / hz).abs() < 1e-15);
        assert_eq!(tick_time_s(7, 1), 7.0 / hz);
    }
}
