//! [`ReplayRig`]: a recorded trial played back through the rig's hardware boundary.
//!
//! It is the second implementation of [`RigIo`] beside the simulator: the controller
//! reads encoder counts and the raw force reading of a measured trial, tick by tick,
//! and its motor commands are recorded instead of driving anything. The file's rate
//! (1 kHz for the shared sessions) is mapped onto the control clock (4 kHz) by
//! sample-and-hold or by linear interpolation between rows.

use rigtwin_device::{ErrorKind, MotorCommand, Rate, RigIo, RigIoError, SensorFrame, Tick};

use crate::Trial;

/// How samples between two file rows are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    /// Each tick sees the last row at or before it (what a logger that holds does).
    SampleAndHold,
    /// Each tick sees the straight line between the rows around it.
    Linear,
}

/// Why a replay cannot go on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReplayError {
    /// The tick is past the trial's last sample.
    #[error(
        "tick {tick} is past the end of the replayed trial ({samples} samples at {rate_hz} Hz)"
    )]
    EndOfData {
        /// The tick that was asked for.
        tick: u64,
        /// Samples in the trial.
        samples: usize,
        /// The trial's rate, Hz.
        rate_hz: f64,
    },
    /// The replay cannot be set up: an empty trial or a bad rate or quantum.
    #[error("cannot replay: {0}")]
    Setup(String),
}

impl RigIoError for ReplayError {
    fn kind(&self) -> ErrorKind {
        match self {
            ReplayError::EndOfData { .. } => ErrorKind::EndOfData,
            ReplayError::Setup(_) => ErrorKind::Other,
        }
    }
}

/// Plays one recorded trial through [`RigIo`] and records the commands written.
///
/// Encoder counts are the recorded position divided by the encoder quantum, rounded to
/// the nearest count. The raw force reading is the recorded hand force `(fx_n, fy_n)`:
/// the replay assumes an identity sensor calibration (sensor frame = rig frame, no
/// offset), so a controller replaying it must be configured with that calibration.
#[derive(Debug, Clone)]
pub struct ReplayRig {
    x_m: Vec<f64>,
    y_m: Vec<f64>,
    fx_n: Vec<f64>,
    fy_n: Vec<f64>,
    rate_hz: f64,
    clock: Rate,
    quantum_m: f64,
    mode: Interpolation,
    commands: Vec<(Tick, MotorCommand)>,
}

impl ReplayRig {
    /// The encoder quantum of the Börner rig, m.
    pub const QUANTUM_M: f64 = 1e-6;

    /// A replay of `trial`, recorded at `rate_hz`, on the control clock `clock`, with
    /// encoders of quantum `quantum_m` (m per count).
    ///
    /// # Errors
    /// [`ReplayError::Setup`] for an empty trial or a non-positive rate or quantum.
    pub fn new(
        trial: &Trial,
        rate_hz: f64,
        clock: Rate,
        quantum_m: f64,
        mode: Interpolation,
    ) -> Result<ReplayRig, ReplayError> {
        if trial.is_empty() {
            return Err(ReplayError::Setup("the trial has no sample".into()));
        }
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(ReplayError::Setup(format!(
                "rate {rate_hz} Hz must be finite and > 0"
            )));
        }
        if !(quantum_m.is_finite() && quantum_m > 0.0) {
            return Err(ReplayError::Setup(format!(
                "encoder quantum {quantum_m} m must be finite and > 0"
            )));
        }
        let ticks = (trial.len() as f64 * f64::from(clock.hz()) / rate_hz).ceil() as usize;
        Ok(ReplayRig {
            x_m: trial.x_m.clone(),
            y_m: trial.y_m.clone(),
            fx_n: trial.fx_n.clone(),
            fy_n: trial.fy_n.clone(),
            rate_hz,
            clock,
            quantum_m,
            mode,
            commands: Vec::with_capacity(ticks + 1),
        })
    }

    /// A replay on the 4 kHz control clock with 1 µm encoders.
    ///
    /// # Errors
    /// As [`ReplayRig::new`].
    pub fn at_control_rate(
        trial: &Trial,
        rate_hz: f64,
        mode: Interpolation,
    ) -> Result<ReplayRig, ReplayError> {
        ReplayRig::new(trial, rate_hz, Rate::CONTROL, Self::QUANTUM_M, mode)
    }

    /// The commands written so far, with the tick of each write.
    #[must_use]
    pub fn commands(&self) -> &[(Tick, MotorCommand)] {
        &self.commands
    }

    /// The commands written, giving up the replay.
    #[must_use]
    pub fn into_commands(self) -> Vec<(Tick, MotorCommand)> {
        self.commands
    }

    /// The last tick that has data: ticks `0..=last_tick()` read successfully.
    #[must_use]
    pub fn last_tick(&self) -> Tick {
        let clock = f64::from(self.clock.hz());
        let last_row = (self.x_m.len() - 1) as f64;
        // Largest n with n * rate / clock <= last_row, guarded against rounding.
        let mut n = (last_row * clock / self.rate_hz).floor() as u64;
        while self
            .position(n + 1)
            .is_some_and(|(i, _)| (i as f64) <= last_row)
            && n < u64::MAX - 1
        {
            n += 1;
        }
        while n > 0 && self.position(n).is_none() {
            n -= 1;
        }
        Tick(n)
    }

    /// The row and the fraction toward the next row at tick `n`, if within the data.
    fn position(&self, n: u64) -> Option<(usize, f64)> {
        // Row index in file samples; the epsilon keeps exact multiples (a 4 kHz tick on
        // a 1 kHz row) from flooring one row short.
        let exact = n as f64 * self.rate_hz / f64::from(self.clock.hz());
        let row = (exact + 1e-9).floor();
        let frac = (exact - row).max(0.0);
        let i = row as usize;
        let last = self.x_m.len() - 1;
        match self.mode {
            _ if i > last => None,
            Interpolation::Linear if i == last && frac > 1e-9 => None,
            _ => Some((i, frac)),
        }
    }

    fn value(&self, column: &[f64], i: usize, frac: f64) -> f64 {
        match (self.mode, column.get(i + 1)) {
            (Interpolation::Linear, Some(next)) => column[i] + frac * (next - column[i]),
            _ => column[i],
        }
    }
}

impl RigIo for ReplayRig {
    type Error = ReplayError;

    fn read(&mut self, now: Tick) -> Result<SensorFrame, ReplayError> {
        let Some((i, frac)) = self.position(now.0) else {
            return Err(ReplayError::EndOfData {
                tick: now.0,
                samples: self.x_m.len(),
                rate_hz: self.rate_hz,
            });
        };
        let counts = |m: f64| (m / self.quantum_m).round() as i64;
        Ok(SensorFrame {
            encoder_counts: [
                counts(self.value(&self.x_m, i, frac)),
                counts(self.value(&self.y_m, i, frac)),
            ],
            force_raw_n: [
                self.value(&self.fx_n, i, frac),
                self.value(&self.fy_n, i, frac),
            ],
            estop: false,
        })
    }

    fn write(&mut self, now: Tick, command: MotorCommand) -> Result<(), ReplayError> {
        self.commands.push((now, command));
        Ok(())
    }
}
