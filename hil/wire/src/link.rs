//! Bookkeeping of one receiving end of a link: what arrived, what was accepted, and why
//! the rest was dropped.
//!
//! A receiver accepts a datagram only if it decodes, travels in the expected direction
//! and carries a sequence number newer than the newest one accepted so far. Sequence
//! numbers are compared with serial-number arithmetic (RFC 1982, 32 bits): `b` is newer
//! than `a` when `b − a (mod 2³²)` lies in `1 .. 2³¹`; the half-way distance 2³¹ counts as
//! older, so it is never accepted. A receiver therefore never goes back in time, and a
//! sender's wrap from `u32::MAX` to 0 is just the next datagram.
//!
//! Contract of [`LinkCounters`]: every datagram taken from the transport adds 1 to
//! `received` and to exactly one of `accepted` or the rejection counters (see
//! [`LinkCounters::rejected`]); `sequence_gaps` and `lost` describe the accepted stream and
//! are not rejections. A datagram skipped over by a gap and arriving later is counted in
//! `lost` and then again in `out_of_order` when it arrives (and is not used).

use core::fmt;

use rigtwin_device::Tick;

use crate::datagram::{self, Datagram, DecodeError};
use crate::error::WireError;
use crate::transport::Transport;

/// Counts of one receiving end, plus what it sent. All counts are datagrams.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LinkCounters {
    /// Datagrams taken from the transport.
    pub received: u64,
    /// Datagrams accepted (valid, right direction, newer than the newest).
    pub accepted: u64,
    /// Rejected: the first four bytes were not `RTWI` (garbage).
    pub bad_magic: u64,
    /// Rejected: shorter than the header or than the kind's length.
    pub truncated: u64,
    /// Rejected: longer than the kind's length.
    pub wrong_length: u64,
    /// Rejected: a protocol version other than 1.
    pub wrong_version: u64,
    /// Rejected: a kind other than sensor frame or motor command.
    pub unknown_kind: u64,
    /// Rejected: a valid datagram of the other direction (e.g. a command at the controller).
    pub wrong_direction: u64,
    /// Rejected: a non-finite motor force in a command.
    pub non_finite: u64,
    /// Rejected: a mode or e-stop byte outside its range.
    pub bad_field: u64,
    /// Rejected: older than the newest accepted (late or reordered).
    pub out_of_order: u64,
    /// Rejected: a sequence number already seen.
    pub duplicate: u64,
    /// Accepted datagrams that followed a gap in the sequence numbers.
    pub sequence_gaps: u64,
    /// Sequence numbers skipped over by those gaps.
    pub lost: u64,
    /// Datagrams this end handed to its transport.
    pub sent: u64,
    /// Datagrams this end could not hand over (socket buffer full, or no peer known yet).
    pub unsent: u64,
}

impl LinkCounters {
    /// The sum of the rejection counters; `received == accepted + rejected()` always.
    #[must_use]
    pub fn rejected(&self) -> u64 {
        self.bad_magic
            + self.truncated
            + self.wrong_length
            + self.wrong_version
            + self.unknown_kind
            + self.wrong_direction
            + self.non_finite
            + self.bad_field
            + self.out_of_order
            + self.duplicate
    }

    /// Counts a datagram that did not decode, in the one counter for its error.
    pub fn count_decode_error(&mut self, e: DecodeError) {
        let c = match e {
            DecodeError::BadMagic => &mut self.bad_magic,
            DecodeError::Truncated { .. } => &mut self.truncated,
            DecodeError::WrongLength { .. } => &mut self.wrong_length,
            DecodeError::UnsupportedVersion { .. } => &mut self.wrong_version,
            DecodeError::UnknownKind { .. } => &mut self.unknown_kind,
            DecodeError::NonFinite { .. } => &mut self.non_finite,
            DecodeError::BadMode { .. } | DecodeError::BadEstop { .. } => &mut self.bad_field,
        };
        *c += 1;
    }
}

impl fmt::Display for LinkCounters {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "sent {} (unsent {}), received {}, accepted {}, rejected {} \
             (bad magic {}, truncated {}, wrong length {}, wrong version {}, unknown kind {}, \
             wrong direction {}, non-finite {}, bad field {}, out of order {}, duplicate {}), \
             gaps {} (lost {})",
            self.sent,
            self.unsent,
            self.received,
            self.accepted,
            self.rejected(),
            self.bad_magic,
            self.truncated,
            self.wrong_length,
            self.wrong_version,
            self.unknown_kind,
            self.wrong_direction,
            self.non_finite,
            self.bad_field,
            self.out_of_order,
            self.duplicate,
            self.sequence_gaps,
            self.lost,
        )
    }
}

/// How an incoming sequence number relates to the ones seen before.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arrival {
    /// The first sequence number this tracker has seen.
    First,
    /// Exactly one after the newest.
    Next,
    /// Newer than the newest by more than one: `missing` numbers were skipped.
    Gap {
        /// Sequence numbers skipped (≥ 1).
        missing: u32,
    },
    /// Seen before (the newest, or an older one within the last [`SequenceTracker::WINDOW`]).
    Duplicate,
    /// Older than the newest and not seen before (late, or reordered).
    OutOfOrder,
}

impl Arrival {
    /// `true` for the arrivals a receiver accepts (first, next, after a gap).
    #[must_use]
    pub fn is_new(self) -> bool {
        matches!(self, Arrival::First | Arrival::Next | Arrival::Gap { .. })
    }
}

/// Classifies sequence numbers with wrap-around; remembers the newest and which of the
/// [`Self::WINDOW`] numbers before it were seen, so that a repeated older number is told
/// apart from a late one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SequenceTracker {
    newest: Option<u32>,
    /// Bit `i` set: `newest − i` has been seen (bit 0 is the newest itself).
    seen: u64,
}

impl SequenceTracker {
    /// How far back duplicates are told apart from late datagrams, in sequence numbers.
    pub const WINDOW: u32 = 64;

    /// A tracker that has seen nothing.
    #[must_use]
    pub fn new() -> SequenceTracker {
        SequenceTracker::default()
    }

    /// The newest sequence number seen, if any.
    #[must_use]
    pub fn newest(&self) -> Option<u32> {
        self.newest
    }

    /// Classifies `sequence` and records it.
    pub fn classify(&mut self, sequence: u32) -> Arrival {
        let Some(newest) = self.newest else {
            self.newest = Some(sequence);
            self.seen = 1;
            return Arrival::First;
        };
        let ahead = sequence.wrapping_sub(newest);
        if ahead == 0 {
            return Arrival::Duplicate;
        }
        if ahead < 1 << 31 {
            self.newest = Some(sequence);
            self.seen = if ahead >= Self::WINDOW {
                1
            } else {
                (self.seen << ahead) | 1
            };
            return if ahead == 1 {
                Arrival::Next
            } else {
                Arrival::Gap { missing: ahead - 1 }
            };
        }
        let behind = newest.wrapping_sub(sequence);
        if behind < Self::WINDOW {
            let bit = 1u64 << behind;
            if self.seen & bit != 0 {
                return Arrival::Duplicate;
            }
            self.seen |= bit;
        }
        Arrival::OutOfOrder
    }
}

/// Which datagram kind a receiving end expects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Expect {
    Sensor,
    Command,
}

/// The receiving half of an end: decode, check direction and sequence, count (the
/// sending half counts through [`send_counted`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct Inbox {
    pub(crate) tracker: SequenceTracker,
    pub(crate) counters: LinkCounters,
}

impl Inbox {
    /// Takes one received datagram; returns it with the number of sequence numbers it
    /// skipped if it is accepted, `None` (and one rejection counted) otherwise.
    pub(crate) fn admit(&mut self, bytes: &[u8], expect: Expect) -> Option<(Datagram, u32)> {
        let c = &mut self.counters;
        c.received += 1;
        let d = match datagram::decode(bytes) {
            Ok(d) => d,
            Err(e) => {
                c.count_decode_error(e);
                return None;
            }
        };
        let sequence = match (d, expect) {
            (Datagram::Sensor(s), Expect::Sensor) => s.sequence,
            (Datagram::Command(m), Expect::Command) => m.sequence,
            _ => {
                c.wrong_direction += 1;
                return None;
            }
        };
        let missing = match self.tracker.classify(sequence) {
            Arrival::Duplicate => {
                c.duplicate += 1;
                return None;
            }
            Arrival::OutOfOrder => {
                c.out_of_order += 1;
                return None;
            }
            Arrival::First | Arrival::Next => 0,
            Arrival::Gap { missing } => {
                c.sequence_gaps += 1;
                c.lost += u64::from(missing);
                missing
            }
        };
        c.accepted += 1;
        Some((d, missing))
    }
}

/// Sends one datagram of an end and counts it: `sent`, or `unsent` when the transport
/// could not take it (a full buffer, a peer not yet known), which loses the datagram
/// without an error; any other transport error is returned.
pub(crate) fn send_counted<T: Transport>(
    transport: &mut T,
    counters: &mut LinkCounters,
    now: Tick,
    bytes: &[u8],
) -> Result<(), WireError> {
    match transport.send(now, bytes) {
        Ok(()) => counters.sent += 1,
        Err(e) if e.is_unsent() => counters.unsent += 1,
        Err(e) => return Err(e.into()),
    }
    Ok(())
}

/// The watchdog limit both ends take: at least one tick.
pub(crate) fn check_stale_ticks(stale_ticks: u32) -> Result<(), WireError> {
    if stale_ticks == 0 {
        return Err(WireError::BadLimit {
            name: "stale_ticks",
            min: 1,
        });
    }
    Ok(())
}
