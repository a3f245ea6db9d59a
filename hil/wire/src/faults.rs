//! Seeded fault injection on the sending side of a link: what a lossy, late, jittery
//! network or a stalling sender does to the datagram stream, reproducibly.
//!
//! A [`FaultSpec`] is written as comma-separated `key=value` pairs, every key optional,
//! each at most once:
//!
//! ```text
//! drop=0.01,delay_ticks=2,duplicate=0.001,reorder=0.001,stall=1.5s:50ms
//! ```
//!
//! | key           | value                  | effect on each outgoing datagram                       |
//! |---------------|------------------------|--------------------------------------------------------|
//! | `drop`        | probability in [0, 1]  | lost                                                   |
//! | `duplicate`   | probability in [0, 1]  | sent twice                                             |
//! | `reorder`     | probability in [0, 1]  | held back and sent right after the next one            |
//! | `delay_ticks` | whole ticks ≥ 0        | every datagram leaves this many ticks late             |
//! | `stall`       | `START:LENGTH`         | nothing leaves in `[START, START + LENGTH)` of the run  |
//!
//! Durations are a decimal number and a unit `s`, `ms`, `us` or `ns` (`1.5s`, `50ms`),
//! held exactly as integer nanoseconds and converted to ticks, rounded to the nearest,
//! when the injector is built. `none` or the empty string is the spec without faults.
//!
//! The [`FaultInjector`] draws three uniforms per offered datagram from a `ChaCha8Rng`
//! seeded with a `u64` (drop, duplicate, reorder, in that order), whatever the outcome,
//! so the same seed and the same offered stream give the same output stream, and one
//! probability does not shift the draws of another. Order of decisions for a datagram
//! offered at tick `n`: a stall window swallows it; else it is dropped with `drop`; else
//! queued (twice with `duplicate`) to leave at `n + delay_ticks`, or, with `reorder`,
//! held (and not duplicated) until the next datagram has been queued. Queued datagrams due inside a stall are
//! swallowed when they come due. The queue is a ring of fixed-size slots allocated when
//! the injector is built; nothing is allocated per datagram. A datagram that finds the
//! ring full is lost and counted as `overflowed`.

use core::fmt;
use core::str::FromStr;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigtwin_device::{Rate, Tick};

/// The largest datagram the injector (and the transports) carry, bytes; a receive buffer
/// of this size also tells an oversized datagram from a valid one.
pub const MAX_DATAGRAM: usize = 256;

const NS_PER_S: u64 = 1_000_000_000;

/// A duration held exactly, in nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct Nanos(pub u64);

impl Nanos {
    /// The duration in whole ticks at `rate`, rounded to the nearest (halves up).
    #[must_use]
    pub fn to_ticks(self, rate: Rate) -> u64 {
        let t = (u128::from(self.0) * u128::from(rate.hz()) + u128::from(NS_PER_S / 2))
            / u128::from(NS_PER_S);
        u64::try_from(t).unwrap_or(u64::MAX)
    }
}

impl fmt::Display for Nanos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ns = self.0;
        if ns >= NS_PER_S {
            let frac = ns % NS_PER_S;
            if frac == 0 {
                write!(f, "{}s", ns / NS_PER_S)
            } else {
                let digits = format!("{frac:09}");
                write!(f, "{}.{}s", ns / NS_PER_S, digits.trim_end_matches('0'))
            }
        } else if ns.is_multiple_of(1_000_000) {
            write!(f, "{}ms", ns / 1_000_000)
        } else if ns.is_multiple_of(1_000) {
            write!(f, "{}us", ns / 1_000)
        } else {
            write!(f, "{ns}ns")
        }
    }
}

impl FromStr for Nanos {
    type Err = ();

    /// `<digits>[.<digits>]<unit>`, unit one of `s`, `ms`, `us`, `ns`; exact, or an error
    /// if it needs a fraction of a nanosecond or overflows.
    fn from_str(s: &str) -> Result<Nanos, ()> {
        let (number, scale_digits) = if let Some(n) = s.strip_suffix("ms") {
            (n, 6)
        } else if let Some(n) = s.strip_suffix("us") {
            (n, 3)
        } else if let Some(n) = s.strip_suffix("ns") {
            (n, 0)
        } else if let Some(n) = s.strip_suffix('s') {
            (n, 9)
        } else {
            return Err(());
        };
        let (whole, frac) = number.split_once('.').unwrap_or((number, ""));
        let all_digits = |p: &str| p.bytes().all(|b| b.is_ascii_digit());
        if whole.is_empty() || !all_digits(whole) || !all_digits(frac) {
            return Err(());
        }
        if number.contains('.') && frac.is_empty() {
            return Err(());
        }
        let frac = frac.trim_end_matches('0');
        if frac.len() > scale_digits {
            return Err(());
        }
        let scale = 10u64.pow(scale_digits as u32);
        let whole: u64 = whole.parse().map_err(|_| ())?;
        let frac_value: u64 = if frac.is_empty() {
            0
        } else {
            let f: u64 = frac.parse().map_err(|_| ())?;
            f * 10u64.pow((scale_digits - frac.len()) as u32)
        };
        whole
            .checked_mul(scale)
            .and_then(|w| w.checked_add(frac_value))
            .map(Nanos)
            .ok_or(())
    }
}

/// A sender that goes silent: at `start` into the run, for `length`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stall {
    /// When the silence starts, from tick 0.
    pub start: Nanos,
    /// How long it lasts (> 0).
    pub length: Nanos,
}

/// What faults to inject on a link's sending side. The default injects none.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FaultSpec {
    /// Probability that a datagram is lost, in [0, 1].
    pub drop: f64,
    /// Fixed extra latency of every datagram, ticks.
    pub delay_ticks: u32,
    /// Probability that a datagram is sent twice, in [0, 1].
    pub duplicate: f64,
    /// Probability that a datagram swaps places with the next one, in [0, 1].
    pub reorder: f64,
    /// A window in which nothing leaves.
    pub stall: Option<Stall>,
}

/// Why a fault spec string was refused; every variant names the key and the value.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FaultSpecError {
    /// A key that is not one of `drop`, `delay_ticks`, `duplicate`, `reorder`, `stall`.
    #[error("unknown fault key `{key}` (known: drop, delay_ticks, duplicate, reorder, stall)")]
    UnknownKey {
        /// The key as written.
        key: String,
    },
    /// A pair without `=value`.
    #[error("fault key `{key}` has no value (write `{key}=...`)")]
    MissingValue {
        /// The key as written.
        key: String,
    },
    /// The same key twice.
    #[error("fault key `{key}` is given twice")]
    Repeated {
        /// The key.
        key: String,
    },
    /// A value that does not parse or lies outside its range.
    #[error("fault key `{key}`: bad value `{value}`: {expected}")]
    BadValue {
        /// The key.
        key: String,
        /// The value as written.
        value: String,
        /// What the key accepts.
        expected: &'static str,
    },
}

fn bad(key: &str, value: &str, expected: &'static str) -> FaultSpecError {
    FaultSpecError::BadValue {
        key: key.to_owned(),
        value: value.to_owned(),
        expected,
    }
}

fn probability(key: &str, value: &str) -> Result<f64, FaultSpecError> {
    const EXPECTED: &str = "a probability between 0 and 1";
    match value.parse::<f64>() {
        Ok(p) if (0.0..=1.0).contains(&p) => Ok(p),
        _ => Err(bad(key, value, EXPECTED)),
    }
}

impl FromStr for FaultSpec {
    type Err = FaultSpecError;

    fn from_str(s: &str) -> Result<FaultSpec, FaultSpecError> {
        let mut spec = FaultSpec::default();
        let s = s.trim();
        if s.is_empty() || s == "none" {
            return Ok(spec);
        }
        let mut given = [false; 5];
        for pair in s.split(',') {
            let pair = pair.trim();
            let (key, value) = pair
                .split_once('=')
                .map(|(k, v)| (k.trim(), v.trim()))
                .ok_or_else(|| FaultSpecError::MissingValue {
                    key: pair.to_owned(),
                })?;
            let slot = match key {
                "drop" => 0,
                "delay_ticks" => 1,
                "duplicate" => 2,
                "reorder" => 3,
                "stall" => 4,
                _ => {
                    return Err(FaultSpecError::UnknownKey {
                        key: key.to_owned(),
                    });
                }
            };
            if given[slot] {
                return Err(FaultSpecError::Repeated {
                    key: key.to_owned(),
                });
            }
            given[slot] = true;
            match slot {
                0 => spec.drop = probability(key, value)?,
                1 => {
                    spec.delay_ticks = value
                        .parse()
                        .map_err(|_| bad(key, value, "a whole number of ticks"))?;
                }
                2 => spec.duplicate = probability(key, value)?,
                3 => spec.reorder = probability(key, value)?,
                _ => {
                    const EXPECTED: &str = "START:LENGTH, durations like 1.5s or 50ms, LENGTH > 0";
                    let (start, length) = value
                        .split_once(':')
                        .ok_or_else(|| bad(key, value, EXPECTED))?;
                    let start: Nanos = start.parse().map_err(|()| bad(key, value, EXPECTED))?;
                    let length: Nanos = length.parse().map_err(|()| bad(key, value, EXPECTED))?;
                    if length.0 == 0 {
                        return Err(bad(key, value, EXPECTED));
                    }
                    spec.stall = Some(Stall { start, length });
                }
            }
        }
        Ok(spec)
    }
}

impl fmt::Display for FaultSpec {
    /// The keys that differ from no fault, in a fixed order; `none` if there are none.
    /// Parsing the output gives back the same spec.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut sep = "";
        let mut item = |f: &mut fmt::Formatter<'_>, args: fmt::Arguments<'_>| {
            let r = write!(f, "{sep}{args}");
            sep = ",";
            r
        };
        if self.drop != 0.0 {
            item(f, format_args!("drop={}", self.drop))?;
        }
        if self.delay_ticks != 0 {
            item(f, format_args!("delay_ticks={}", self.delay_ticks))?;
        }
        if self.duplicate != 0.0 {
            item(f, format_args!("duplicate={}", self.duplicate))?;
        }
        if self.reorder != 0.0 {
            item(f, format_args!("reorder={}", self.reorder))?;
        }
        if let Some(s) = self.stall {
            item(f, format_args!("stall={}:{}", s.start, s.length))?;
        }
        if sep.is_empty() {
            write!(f, "none")?;
        }
        Ok(())
    }
}

/// What the injector did to the datagrams offered to it. Counts are datagrams.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FaultCounters {
    /// Offered by the sender.
    pub offered: u64,
    /// Lost to `drop`.
    pub dropped: u64,
    /// Swallowed by the stall window (on offer or when due).
    pub stalled: u64,
    /// Extra copies made by `duplicate`.
    pub duplicated: u64,
    /// Held back by `reorder`.
    pub reordered: u64,
    /// Lost because the queue was full.
    pub overflowed: u64,
    /// Released to the transport.
    pub released: u64,
}

#[derive(Debug, Clone, Copy)]
struct Slot {
    due: u64,
    len: usize,
    bytes: [u8; MAX_DATAGRAM],
}

const EMPTY: Slot = Slot {
    due: 0,
    len: 0,
    bytes: [0; MAX_DATAGRAM],
};

/// Decides, per outgoing datagram, what leaves and when (module docs). Reproducible from
/// its seed; allocation-free after [`FaultInjector::new`].
#[derive(Debug, Clone)]
pub struct FaultInjector {
    spec: FaultSpec,
    rng: ChaCha8Rng,
    stall_ticks: Option<(u64, u64)>,
    ring: Vec<Slot>,
    head: usize,
    len: usize,
    held: Option<Slot>,
    counters: FaultCounters,
}

impl FaultInjector {
    /// Slots the ring holds per tick of delay; one send per tick, each possibly
    /// duplicated, plus a released reordered one, fits in 3.
    const SLOTS_PER_TICK: usize = 3;

    /// An injector for `spec`, seeded with `seed`, converting the stall window to ticks
    /// of `rate`. Its queue holds `3 × (delay_ticks + 2)` datagrams: enough for one send
    /// per tick with duplicates and a reordered one in flight.
    #[must_use]
    pub fn new(spec: FaultSpec, seed: u64, rate: Rate) -> FaultInjector {
        let capacity = Self::SLOTS_PER_TICK * (spec.delay_ticks as usize + 2);
        FaultInjector {
            spec,
            rng: ChaCha8Rng::seed_from_u64(seed),
            stall_ticks: spec.stall.map(|s| {
                let start = s.start.to_ticks(rate);
                (start, start.saturating_add(s.length.to_ticks(rate)))
            }),
            ring: vec![EMPTY; capacity],
            head: 0,
            len: 0,
            held: None,
            counters: FaultCounters::default(),
        }
    }

    /// The spec this injector follows.
    #[must_use]
    pub fn spec(&self) -> &FaultSpec {
        &self.spec
    }

    /// What it has done so far.
    #[must_use]
    pub fn counters(&self) -> FaultCounters {
        self.counters
    }

    /// The stall window in ticks, `[start, end)`, if any.
    #[must_use]
    pub fn stall_ticks(&self) -> Option<(Tick, Tick)> {
        self.stall_ticks.map(|(a, b)| (Tick(a), Tick(b)))
    }

    fn stalled(&self, now: u64) -> bool {
        self.stall_ticks.is_some_and(|(a, b)| (a..b).contains(&now))
    }

    fn enqueue(&mut self, slot: Slot) {
        if self.len == self.ring.len() {
            self.counters.overflowed += 1;
            return;
        }
        let i = (self.head + self.len) % self.ring.len();
        if let Some(s) = self.ring.get_mut(i) {
            *s = slot;
            self.len += 1;
        }
    }

    /// Offers the datagram `bytes` sent at tick `now`. Datagrams longer than
    /// [`MAX_DATAGRAM`] are cut to that length (the wire's are 64 bytes at most).
    pub fn offer(&mut self, now: Tick, bytes: &[u8]) {
        self.counters.offered += 1;
        let u_drop: f64 = self.rng.random();
        let u_dup: f64 = self.rng.random();
        let u_reorder: f64 = self.rng.random();
        if self.stalled(now.0) {
            self.counters.stalled += 1;
            return;
        }
        if u_drop < self.spec.drop {
            self.counters.dropped += 1;
            return;
        }
        let len = bytes.len().min(MAX_DATAGRAM);
        let mut slot = Slot {
            due: now.0.saturating_add(u64::from(self.spec.delay_ticks)),
            len,
            bytes: [0; MAX_DATAGRAM],
        };
        slot.bytes[..len].copy_from_slice(&bytes[..len]);
        let held = self.held.take();
        if u_reorder < self.spec.reorder && held.is_none() {
            self.counters.reordered += 1;
            self.held = Some(slot);
        } else {
            self.enqueue(slot);
            if u_dup < self.spec.duplicate {
                self.counters.duplicated += 1;
                self.enqueue(slot);
            }
        }
        if let Some(h) = held {
            self.enqueue(h);
        }
    }

    /// The next datagram due at or before `now`, in queue order, or `None`. Call until
    /// `None` after each [`Self::offer`]. A datagram held back by `reorder` waits for the
    /// next offer.
    pub fn next_due(&mut self, now: Tick) -> Option<&[u8]> {
        loop {
            let front = *self.ring.get(self.head)?;
            if self.len == 0 || front.due > now.0 {
                return None;
            }
            self.head = (self.head + 1) % self.ring.len();
            self.len -= 1;
            if self.stalled(now.0) {
                self.counters.stalled += 1;
                continue;
            }
            self.counters.released += 1;
            let slot = self
                .ring
                .get((self.head + self.ring.len() - 1) % self.ring.len())?;
            return slot.bytes.get(..slot.len);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse_exactly_and_print_back() {
        let cases = [
            ("1.5s", 1_500_000_000),
            ("50ms", 50_000_000),
            ("0.25ms", 250_000),
            ("7us", 7_000),
            ("3ns", 3),
            ("2s", 2_000_000_000),
        ];
        for (s, ns) in cases {
            assert_eq!(s.parse::<Nanos>(), Ok(Nanos(ns)), "{s}");
            let back: Result<Nanos, ()> = Nanos(ns).to_string().parse();
            assert_eq!(back, Ok(Nanos(ns)), "{s}");
        }
        for s in [
            "",
            "s",
            "1",
            "1.s",
            ".5s",
            "1.5",
            "0.1ns",
            "-1s",
            "1e3ms",
            "99999999999s",
        ] {
            assert_eq!(s.parse::<Nanos>(), Err(()), "{s:?}");
        }
        // 50 ms at 4 kHz is 200 ticks; 0.1 ms is 0.4 tick, rounded to 0; 0.125 ms to 1.
        assert_eq!(Nanos(50_000_000).to_ticks(Rate::CONTROL), 200);
        assert_eq!(Nanos(100_000).to_ticks(Rate::CONTROL), 0);
        assert_eq!(Nanos(125_000).to_ticks(Rate::CONTROL), 1);
    }
}
