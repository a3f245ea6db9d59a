//! The integer control clock. Time on the rig is a count of 4 kHz ticks; durations are
//! whole ticks and float time is derived, never accumulated.

use serde::{Deserialize, Serialize};

/// One tick of the control clock: the `n`-th period since the clock started.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize,
)]
pub struct Tick(pub u64);

impl Tick {
    /// Time of this tick in seconds at the given clock rate.
    #[must_use]
    pub fn seconds(self, rate: Rate) -> f64 {
        self.0 as f64 / rate.hz() as f64
    }

    /// The next tick.
    #[must_use]
    pub fn next(self) -> Tick {
        Tick(self.0 + 1)
    }
}

/// A clock rate in whole hertz (the control clock is 4000 Hz on the Börner rig).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Rate(u32);

impl Rate {
    /// The rig's control clock, 4 kHz (000_* section 5.1).
    pub const CONTROL: Rate = Rate(4000);

    /// A rate in hertz; `None` for zero.
    #[must_use]
    pub const fn new(hz: u32) -> Option<Rate> {
        if hz == 0 { None } else { Some(Rate(hz)) }
    }

    /// The rate in hertz.
    #[must_use]
    pub const fn hz(self) -> u32 {
        self.0
    }

    /// The period in seconds.
    #[must_use]
    pub fn period_s(self) -> f64 {
        1.0 / f64::from(self.0)
    }

    /// Number of ticks of `self` per tick of `slower`, if `slower` divides `self` exactly.
    #[must_use]
    pub const fn divisor_of(self, slower: Rate) -> Option<u32> {
        if slower.0 <= self.0 && self.0.is_multiple_of(slower.0) {
            Some(self.0 / slower.0)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_seconds_is_exact_for_whole_periods() {
        // One second of ticks is exactly one second: integer time must not drift.
        let hz = u64::from(Rate::CONTROL.hz());
        assert_eq!(Tick(hz).seconds(Rate::CONTROL), 1.0);
        assert_eq!(Tick(1000 * hz).seconds(Rate::CONTROL), 1000.0);
    }

    #[test]
    fn divisors_are_integer_only() {
        let motor = Rate::new(2000).unwrap_or(Rate::CONTROL);
        assert_eq!(Rate::CONTROL.divisor_of(motor), Some(2));
        assert_eq!(
            Rate::CONTROL.divisor_of(Rate::new(3000).unwrap_or(Rate::CONTROL)),
            None
        );
        assert!(Rate::new(0).is_none());
    }
}
