//! [`RigIo`] implementations for tests: a scripted mock whose sensor frame the test
//! sets, and a point-mass rig that closes the loop with exact double-integrator carts.
//! Public so other rooms' tests can drive the controller without the simulator.
//! [`alloc`] is the counting allocator of the tests that prove a tick allocates nothing.
//!
//! The point-mass rig's force sensor is live: its reading carries a ±1 mN square wave
//! (the last bits of a real ADC always move), so the stale-force watchdog sees a working
//! sensor. The mock reads back exactly what the test set: a frame held for 40 ticks is
//! a frozen sensor, and carts that never move under a growing command are a dead
//! encoder. Tests of the control law on the mock say so with [`scripted`].

pub mod alloc;

use crate::config::ControllerConfig;
use crate::io::{ErrorKind, MotorCommand, RigIo, RigIoError, SensorFrame};
use crate::time::{Rate, Tick};

/// `config` with the two watchdogs that a scripted [`MockRig`] cannot satisfy switched
/// off: the stale-force watchdog (the mock repeats its frame bit for bit) and the
/// encoder-stall watchdog (its carts stay where the test put them, whatever the
/// command). For tests of the control law, not of the safety layer.
#[must_use]
pub fn scripted(mut config: ControllerConfig) -> ControllerConfig {
    config.safety.stale_force_ticks = 0;
    config.safety.encoder_stall_ticks = 0;
    config
}

/// The mock's error: just a kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("mock rig error: {0:?}")]
pub struct MockError(pub ErrorKind);

impl RigIoError for MockError {
    fn kind(&self) -> ErrorKind {
        self.0
    }
}

/// A scripted rig: `read` returns `frame`, `write` records the command.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MockRig {
    /// Returned by every `read` (set it between ticks).
    pub frame: SensorFrame,
    /// The last write.
    pub last_write: Option<(Tick, MotorCommand)>,
    /// Number of writes.
    pub writes: u64,
    /// When set, `read` fails with this kind.
    pub fail_read: Option<ErrorKind>,
    /// When set, `write` fails with this kind (the command is still recorded).
    pub fail_write: Option<ErrorKind>,
}

impl RigIo for MockRig {
    type Error = MockError;

    fn read(&mut self, _now: Tick) -> Result<SensorFrame, MockError> {
        match self.fail_read {
            Some(k) => Err(MockError(k)),
            None => Ok(self.frame),
        }
    }

    fn write(&mut self, now: Tick, command: MotorCommand) -> Result<(), MockError> {
        self.last_write = Some((now, command));
        self.writes += 1;
        match self.fail_write {
            Some(k) => Err(MockError(k)),
            None => Ok(()),
        }
    }
}

/// Two independent carts as point masses, integrated exactly for the held motor plus
/// hand force over each tick, with a hand modelled as a constant force plus a
/// spring-damper to an anchor. Encoders quantise the position; the force sensor reads
/// the hand force (identity calibration) plus `force_dither_n` with the sign
/// alternating from one read to the next.
#[derive(Debug, Clone, PartialEq)]
pub struct PointMassRig {
    /// Moving mass per axis, kg.
    pub mass_kg: [f64; 2],
    /// Cart position, m.
    pub position_m: [f64; 2],
    /// Cart velocity, m/s.
    pub velocity_m_per_s: [f64; 2],
    /// Constant hand force on the handle, N.
    pub hand_force_n: [f64; 2],
    /// Hand stiffness to `hand_anchor_m`, N/m.
    pub hand_stiffness_n_per_m: [f64; 2],
    /// Hand damping, N s/m.
    pub hand_damping_n_s_per_m: [f64; 2],
    /// Where the hand spring is at rest, m.
    pub hand_anchor_m: [f64; 2],
    /// Encoder quantum, m per count.
    pub m_per_count: [f64; 2],
    /// The e-stop input.
    pub estop: bool,
    /// The last command written.
    pub command: MotorCommand,
    /// Amplitude of the square wave on the force reading, N (default 1 mN, about one
    /// LSB of a strain-gauge ADC): a live sensor's last bits move every reading. At the
    /// 2 kHz Nyquist rate and zero mean it moves the default 5 kg admittance by
    /// ~1e-11 m. 0 makes the sensor noiseless (and frozen to the stale-force watchdog
    /// whenever the hand force is constant).
    pub force_dither_n: f64,
    reads: u64,
    period_s: f64,
}

impl PointMassRig {
    /// Carts of `mass_kg` at rest at the origin, no hand, 1 µm encoders.
    #[must_use]
    pub fn new(mass_kg: [f64; 2], rate: Rate) -> Self {
        PointMassRig {
            mass_kg,
            position_m: [0.0; 2],
            velocity_m_per_s: [0.0; 2],
            hand_force_n: [0.0; 2],
            hand_stiffness_n_per_m: [0.0; 2],
            hand_damping_n_s_per_m: [0.0; 2],
            hand_anchor_m: [0.0; 2],
            m_per_count: [1e-6; 2],
            estop: false,
            command: MotorCommand::ZERO,
            force_dither_n: 1e-3,
            reads: 0,
            period_s: rate.period_s(),
        }
    }

    /// The force the hand exerts on the handle now, N.
    #[must_use]
    pub fn hand_n(&self) -> [f64; 2] {
        let f = |i: usize| {
            self.hand_force_n[i]
                - self.hand_stiffness_n_per_m[i] * (self.position_m[i] - self.hand_anchor_m[i])
                - self.hand_damping_n_s_per_m[i] * self.velocity_m_per_s[i]
        };
        [f(0), f(1)]
    }
}

impl RigIo for PointMassRig {
    type Error = core::convert::Infallible;

    fn read(&mut self, _now: Tick) -> Result<SensorFrame, Self::Error> {
        let counts = |i: usize| (self.position_m[i] / self.m_per_count[i]).round() as i64;
        let dither = if self.reads.is_multiple_of(2) {
            self.force_dither_n
        } else {
            -self.force_dither_n
        };
        self.reads += 1;
        let hand = self.hand_n();
        Ok(SensorFrame {
            encoder_counts: [counts(0), counts(1)],
            force_raw_n: [hand[0] + dither, hand[1] + dither],
            estop: self.estop,
        })
    }

    fn write(&mut self, _now: Tick, command: MotorCommand) -> Result<(), Self::Error> {
        self.command = command;
        let hand = self.hand_n();
        let h = self.period_s;
        for (i, hand_i) in hand.iter().enumerate() {
            let a = (command.force_n[i] + hand_i) / self.mass_kg[i];
            self.position_m[i] += self.velocity_m_per_s[i] * h + 0.5 * a * h * h;
            self.velocity_m_per_s[i] += a * h;
        }
        Ok(())
    }
}
