//! The two datagrams of wire protocol version 1, their fixed little-endian layout, and
//! their encoding and decoding.
//!
//! Every datagram starts with the same 20-byte header:
//!
//! | offset | size | type  | field      | meaning                                        |
//! |-------:|-----:|-------|------------|------------------------------------------------|
//! | 0      | 4    | bytes | `magic`    | `b"RTWI"`                                      |
//! | 4      | 2    | u16   | `version`  | [`VERSION`] (1)                                |
//! | 6      | 2    | u16   | `kind`     | 1 sensor frame, 2 motor command                |
//! | 8      | 4    | u32   | `sequence` | per sender, +1 per datagram, wrapping          |
//! | 12     | 8    | u64   | `tick`     | the sender's control tick when it sent this    |
//!
//! A sensor frame is [`SENSOR_LEN`] (64) bytes and a motor command [`COMMAND_LEN`] (48)
//! bytes; `hil/docs/wire.md` has both bodies byte by byte. Padding and the reserved flag
//! bits are sent as zero and ignored on receipt. Both bodies carry the 1-based `trial`
//! id the sender is running (0: none), so a plant that runs a protocol knows which
//! trial to set up and a controller knows when the plant has set it up.
//!
//! Contracts:
//! - [`decode`] never panics: any byte slice gives a datagram or a [`DecodeError`].
//! - A motor command with a non-finite force can neither be encoded nor decoded: a NaN
//!   command must never reach a motor.
//! - A sensor frame's force is passed through bit for bit, NaN included: a broken force
//!   sensor must reach the controller's safety layer as what it is.
//! - Encoding then decoding gives back the same value (forces bit for bit).

use rigtwin_device::{Mode, MotorCommand, SensorFrame, Tick};

/// The four magic bytes that open every datagram.
pub const MAGIC: [u8; 4] = *b"RTWI";
/// The protocol version this crate speaks.
pub const VERSION: u16 = 1;
/// Header size in bytes (magic, version, kind, sequence, tick).
pub const HEADER_LEN: usize = 20;
/// Size of a sensor frame datagram in bytes.
pub const SENSOR_LEN: usize = 64;
/// Size of a motor command datagram in bytes.
pub const COMMAND_LEN: usize = 48;
/// The `kind` field of a sensor frame.
pub const KIND_SENSOR: u16 = 1;
/// The `kind` field of a motor command.
pub const KIND_COMMAND: u16 = 2;
/// The tick value on the wire that means "no tick" (`echo_tick` before any command was
/// applied, `answers_tick` before any frame arrived).
pub const NO_TICK: u64 = u64::MAX;
/// Bit 0 of a sensor frame's `flags`: the plant's command watchdog has zeroed the force.
pub const FLAG_WATCHDOG_ZEROED: u8 = 1;

/// A sensor frame: the plant's sensors at one plant tick (plant → controller).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SensorDatagram {
    /// The plant's sequence number of this datagram.
    pub sequence: u32,
    /// The plant tick at which the sensors were sampled.
    pub tick: Tick,
    /// The trial the plant is running (the session's 1-based trial id), 0 when it runs
    /// none (a rig that knows no trials, or a plant between trials).
    pub trial: u16,
    /// Encoder counts and raw force (N), e-stop, in rig units.
    pub frame: SensorFrame,
    /// `true` when the plant's command watchdog has zeroed the motor force.
    pub watchdog_zeroed: bool,
    /// The controller tick of the newest command the plant has taken up, `None` before
    /// the first one.
    pub echo_tick: Option<Tick>,
}

/// A motor command: force per axis (N) and the controller's mode (controller → plant).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CommandDatagram {
    /// The controller's sequence number of this datagram.
    pub sequence: u32,
    /// The controller tick at which it was written.
    pub tick: Tick,
    /// The trial the controller is running (1-based trial id), 0 for a controller that
    /// runs none; a plant that runs a protocol sets up the trial named here.
    pub trial: u16,
    /// Force per axis, N, rig frame. Always finite.
    pub command: MotorCommand,
    /// The controller's lifecycle mode; the plant applies force only in `Active`.
    pub mode: Mode,
    /// The plant tick of the sensor frame this command answers, `None` before any.
    pub answers_tick: Option<Tick>,
}

/// One decoded datagram.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Datagram {
    /// Plant → controller.
    Sensor(SensorDatagram),
    /// Controller → plant.
    Command(CommandDatagram),
}

/// Why a byte slice is not a valid version-1 datagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DecodeError {
    /// The first four bytes are not `RTWI`.
    #[error("bad magic: not an RTWI datagram")]
    BadMagic,
    /// Shorter than the header, or than its kind's length.
    #[error("truncated datagram: {len} bytes, need {need}")]
    Truncated {
        /// Bytes received.
        len: usize,
        /// Bytes needed.
        need: usize,
    },
    /// Longer than its kind's fixed length.
    #[error("wrong length: {len} bytes, a kind-{kind} datagram is {expected}")]
    WrongLength {
        /// The datagram's kind.
        kind: u16,
        /// Bytes received.
        len: usize,
        /// The kind's fixed length.
        expected: usize,
    },
    /// A protocol version this crate does not speak.
    #[error("unsupported protocol version {got} (this end speaks {VERSION})")]
    UnsupportedVersion {
        /// The version field.
        got: u16,
    },
    /// A kind other than 1 (sensor) or 2 (command).
    #[error("unknown datagram kind {got}")]
    UnknownKind {
        /// The kind field.
        got: u16,
    },
    /// A motor command's force is NaN or infinite.
    #[error("non-finite value in {field}")]
    NonFinite {
        /// The field's name, e.g. `force_n[1]`.
        field: &'static str,
    },
    /// A mode byte other than 0–3.
    #[error("bad mode byte {got} (0 configured, 1 inactive, 2 active, 3 fault)")]
    BadMode {
        /// The mode byte.
        got: u8,
    },
    /// An e-stop byte other than 0 or 1.
    #[error("bad e-stop byte {got} (0 released, 1 pressed)")]
    BadEstop {
        /// The e-stop byte.
        got: u8,
    },
}

/// Why a value cannot be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum EncodeError {
    /// A motor command's force is NaN or infinite.
    #[error("refusing to encode a non-finite motor force in {field}")]
    NonFinite {
        /// The field's name, e.g. `force_n[0]`.
        field: &'static str,
    },
}

const FORCE_FIELDS: [&str; 2] = ["force_n[0]", "force_n[1]"];

fn tick_to_wire(t: Option<Tick>) -> u64 {
    t.map_or(NO_TICK, |t| t.0)
}

fn tick_from_wire(v: u64) -> Option<Tick> {
    (v != NO_TICK).then_some(Tick(v))
}

/// The mode's byte on the wire.
#[must_use]
pub fn mode_to_wire(mode: Mode) -> u8 {
    match mode {
        Mode::Configured => 0,
        Mode::Inactive => 1,
        Mode::Active => 2,
        Mode::Fault => 3,
    }
}

/// The mode a wire byte stands for; `None` outside 0–3.
#[must_use]
pub fn mode_from_wire(byte: u8) -> Option<Mode> {
    match byte {
        0 => Some(Mode::Configured),
        1 => Some(Mode::Inactive),
        2 => Some(Mode::Active),
        3 => Some(Mode::Fault),
        _ => None,
    }
}

/// A little-endian writer over a fixed buffer; offsets are the layout's, so a write past
/// the end would be a bug in this file, caught by the round-trip tests.
struct Writer<'a> {
    buf: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn put(&mut self, bytes: &[u8]) {
        if let Some(dst) = self.buf.get_mut(self.at..self.at + bytes.len()) {
            dst.copy_from_slice(bytes);
        }
        self.at += bytes.len();
    }

    fn header(&mut self, kind: u16, sequence: u32, tick: Tick) {
        self.put(&MAGIC);
        self.put(&VERSION.to_le_bytes());
        self.put(&kind.to_le_bytes());
        self.put(&sequence.to_le_bytes());
        self.put(&tick.0.to_le_bytes());
    }
}

/// A little-endian reader over a slice whose length has been checked against the layout.
struct Reader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(src) = self.buf.get(self.at..self.at + N) {
            out.copy_from_slice(src);
        }
        self.at += N;
        out
    }

    fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }

    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }

    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }

    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take())
    }

    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }

    fn skip(&mut self, n: usize) {
        self.at += n;
    }
}

impl SensorDatagram {
    /// The datagram's bytes, [`SENSOR_LEN`] long. Every value is encodable.
    #[must_use]
    pub fn encode(&self) -> [u8; SENSOR_LEN] {
        let mut buf = [0u8; SENSOR_LEN];
        let mut w = Writer {
            buf: &mut buf,
            at: 0,
        };
        w.header(KIND_SENSOR, self.sequence, self.tick);
        for c in self.frame.encoder_counts {
            w.put(&c.to_le_bytes());
        }
        for f in self.frame.force_raw_n {
            w.put(&f.to_le_bytes());
        }
        w.put(&[u8::from(self.frame.estop)]);
        let flags = if self.watchdog_zeroed {
            FLAG_WATCHDOG_ZEROED
        } else {
            0
        };
        w.put(&[flags]);
        w.put(&self.trial.to_le_bytes());
        w.put(&tick_to_wire(self.echo_tick).to_le_bytes());
        buf
    }
}

impl CommandDatagram {
    /// The datagram's bytes, [`COMMAND_LEN`] long; an error if a force is not finite.
    pub fn encode(&self) -> Result<[u8; COMMAND_LEN], EncodeError> {
        for (f, field) in self.command.force_n.iter().zip(FORCE_FIELDS) {
            if !f.is_finite() {
                return Err(EncodeError::NonFinite { field });
            }
        }
        let mut buf = [0u8; COMMAND_LEN];
        let mut w = Writer {
            buf: &mut buf,
            at: 0,
        };
        w.header(KIND_COMMAND, self.sequence, self.tick);
        for f in self.command.force_n {
            w.put(&f.to_le_bytes());
        }
        w.put(&[mode_to_wire(self.mode), 0]);
        w.put(&self.trial.to_le_bytes());
        w.put(&tick_to_wire(self.answers_tick).to_le_bytes());
        Ok(buf)
    }
}

/// Decodes one datagram. Checks, in this order: magic (if at least 4 bytes), header
/// length, version, kind, the kind's exact length, then field values. Never panics.
pub fn decode(bytes: &[u8]) -> Result<Datagram, DecodeError> {
    let len = bytes.len();
    if bytes.get(..4).is_some_and(|m| m != MAGIC) {
        return Err(DecodeError::BadMagic);
    }
    if len < HEADER_LEN {
        return Err(DecodeError::Truncated {
            len,
            need: HEADER_LEN,
        });
    }
    let mut r = Reader { buf: bytes, at: 4 };
    let version = u16::from_le_bytes(r.take());
    if version != VERSION {
        return Err(DecodeError::UnsupportedVersion { got: version });
    }
    let kind = u16::from_le_bytes(r.take());
    let expected = match kind {
        KIND_SENSOR => SENSOR_LEN,
        KIND_COMMAND => COMMAND_LEN,
        got => return Err(DecodeError::UnknownKind { got }),
    };
    if len < expected {
        return Err(DecodeError::Truncated {
            len,
            need: expected,
        });
    }
    if len > expected {
        return Err(DecodeError::WrongLength {
            kind,
            len,
            expected,
        });
    }
    let sequence = u32::from_le_bytes(r.take());
    let tick = Tick(r.u64());
    if kind == KIND_SENSOR {
        let encoder_counts = [r.i64(), r.i64()];
        let force_raw_n = [r.f64(), r.f64()];
        let estop = match r.u8() {
            0 => false,
            1 => true,
            got => return Err(DecodeError::BadEstop { got }),
        };
        let flags = r.u8();
        let trial = r.u16();
        let echo_tick = tick_from_wire(r.u64());
        Ok(Datagram::Sensor(SensorDatagram {
            sequence,
            tick,
            trial,
            frame: SensorFrame {
                encoder_counts,
                force_raw_n,
                estop,
            },
            watchdog_zeroed: flags & FLAG_WATCHDOG_ZEROED != 0,
            echo_tick,
        }))
    } else {
        let force_n = [r.f64(), r.f64()];
        for (f, field) in force_n.iter().zip(FORCE_FIELDS) {
            if !f.is_finite() {
                return Err(DecodeError::NonFinite { field });
            }
        }
        let byte = r.u8();
        let mode = mode_from_wire(byte).ok_or(DecodeError::BadMode { got: byte })?;
        r.skip(1);
        let trial = r.u16();
        let answers_tick = tick_from_wire(r.u64());
        Ok(Datagram::Command(CommandDatagram {
            sequence,
            tick,
            trial,
            command: MotorCommand { force_n },
            mode,
            answers_tick,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn command() -> CommandDatagram {
        CommandDatagram {
            sequence: 7,
            tick: Tick(1234),
            trial: 0x0102,
            command: MotorCommand {
                force_n: [1.5, -2.25],
            },
            mode: Mode::Active,
            answers_tick: Some(Tick(1233)),
        }
    }

    #[test]
    fn sizes_are_multiples_of_eight_and_fields_sit_where_the_spec_says() {
        // The layout tables in hil/docs/wire.md: trial at 54 and 38, echo_tick at 56,
        // answers_tick at 40.
        assert_eq!(SENSOR_LEN % 8, 0);
        assert_eq!(COMMAND_LEN % 8, 0);
        let s = SensorDatagram {
            sequence: 0x0403_0201,
            tick: Tick(9),
            trial: 0x0605,
            frame: SensorFrame {
                encoder_counts: [-1, 2],
                force_raw_n: [0.5, -0.5],
                estop: true,
            },
            watchdog_zeroed: true,
            echo_tick: Some(Tick(0x1122)),
        }
        .encode();
        assert_eq!(&s[0..4], b"RTWI");
        assert_eq!(&s[4..8], &[1, 0, 1, 0]);
        assert_eq!(&s[8..12], &[1, 2, 3, 4]);
        assert_eq!(&s[20..28], &(-1i64).to_le_bytes());
        assert_eq!(&s[44..52], &(-0.5f64).to_le_bytes());
        assert_eq!(s[52], 1);
        assert_eq!(s[53], FLAG_WATCHDOG_ZEROED);
        assert_eq!(&s[54..56], &[5, 6]);
        assert_eq!(&s[56..64], &0x1122u64.to_le_bytes());
        let c = command().encode().unwrap_or([0; COMMAND_LEN]);
        assert_eq!(&c[6..8], &[2, 0]);
        assert_eq!(&c[20..28], &1.5f64.to_le_bytes());
        assert_eq!(c[36], 2);
        assert_eq!(c[37], 0);
        assert_eq!(&c[38..40], &[2, 1]);
        assert_eq!(&c[40..48], &1233u64.to_le_bytes());
    }

    #[test]
    fn nan_command_is_refused_both_ways() {
        let mut c = command();
        c.command.force_n[1] = f64::NAN;
        assert_eq!(
            c.encode(),
            Err(EncodeError::NonFinite {
                field: "force_n[1]"
            })
        );
        // Forge one on the wire: a receiver must refuse it too.
        let mut bytes = command().encode().unwrap_or([0; COMMAND_LEN]);
        bytes[20..28].copy_from_slice(&f64::INFINITY.to_le_bytes());
        assert_eq!(
            decode(&bytes),
            Err(DecodeError::NonFinite {
                field: "force_n[0]"
            })
        );
    }

    #[test]
    fn none_ticks_use_the_sentinel() {
        let mut c = command();
        c.answers_tick = None;
        let bytes = c.encode().unwrap_or([0; COMMAND_LEN]);
        assert_eq!(&bytes[40..48], &[0xff; 8]);
        assert_eq!(decode(&bytes), Ok(Datagram::Command(c)));
    }

    #[test]
    fn each_header_fault_gets_its_own_error() {
        let good = command().encode().unwrap_or([0; COMMAND_LEN]);
        assert_eq!(
            decode(&good[..3]),
            Err(DecodeError::Truncated { len: 3, need: 20 })
        );
        assert_eq!(decode(b"XTWI"), Err(DecodeError::BadMagic));
        let mut v = good;
        v[4] = 2;
        assert_eq!(decode(&v), Err(DecodeError::UnsupportedVersion { got: 2 }));
        let mut k = good;
        k[6] = 9;
        assert_eq!(decode(&k), Err(DecodeError::UnknownKind { got: 9 }));
        assert_eq!(
            decode(&good[..47]),
            Err(DecodeError::Truncated { len: 47, need: 48 })
        );
        let mut long = [0u8; 49];
        long[..48].copy_from_slice(&good);
        assert_eq!(
            decode(&long),
            Err(DecodeError::WrongLength {
                kind: 2,
                len: 49,
                expected: 48
            })
        );
        let mut m = good;
        m[36] = 4;
        assert_eq!(decode(&m), Err(DecodeError::BadMode { got: 4 }));
        let mut s = SensorDatagram::default().encode();
        s[52] = 2;
        assert_eq!(decode(&s), Err(DecodeError::BadEstop { got: 2 }));
    }
}
