//! `SequenceTracker`: serial-number arithmetic with wrap-around (RFC 1982, 32 bits),
//! duplicates, late datagrams and gaps — on hand-picked cases and against a model that
//! works on unwrapped 64-bit numbers.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeSet;

use proptest::prelude::*;
use rigtwin_wire::{Arrival, SequenceTracker};

fn run(seqs: &[u32]) -> Vec<Arrival> {
    let mut t = SequenceTracker::new();
    seqs.iter().map(|&s| t.classify(s)).collect()
}

#[test]
fn consecutive_numbers_wrap_from_max_to_zero() {
    let m = u32::MAX;
    assert_eq!(
        run(&[m - 1, m, 0, 1]),
        [Arrival::First, Arrival::Next, Arrival::Next, Arrival::Next]
    );
}

#[test]
fn a_gap_across_the_wrap_counts_the_skipped_numbers() {
    // MAX−1, then 2: MAX, 0 and 1 were skipped.
    assert_eq!(
        run(&[u32::MAX - 1, 2]),
        [Arrival::First, Arrival::Gap { missing: 3 }]
    );
}

#[test]
fn repeats_are_duplicates_and_late_ones_out_of_order() {
    assert_eq!(
        run(&[5, 5, 7, 6, 6, 7, 4, 8]),
        [
            Arrival::First,
            Arrival::Duplicate,          // 5 again
            Arrival::Gap { missing: 1 }, // 6 skipped
            Arrival::OutOfOrder,         // 6 arrives late, first time
            Arrival::Duplicate,          // 6 again
            Arrival::Duplicate,          // the newest, 7, again
            Arrival::OutOfOrder,         // 4: older than anything seen, never seen
            Arrival::Next,
        ]
    );
}

#[test]
fn half_the_number_space_away_is_older_never_newer() {
    // RFC 1982 leaves distance 2^31 undefined; treating it as older means a receiver
    // never jumps half the space forward on one datagram.
    assert_eq!(run(&[0, 1 << 31]), [Arrival::First, Arrival::OutOfOrder]);
    assert_eq!(
        run(&[0, (1 << 31) - 1]),
        [
            Arrival::First,
            Arrival::Gap {
                missing: (1 << 31) - 2
            }
        ]
    );
}

#[test]
fn beyond_the_window_a_repeat_is_only_known_as_late() {
    let w = SequenceTracker::WINDOW;
    let mut t = SequenceTracker::new();
    assert_eq!(t.classify(100), Arrival::First);
    assert_eq!(t.classify(100 + w), Arrival::Gap { missing: w - 1 });
    // 100 is now WINDOW behind: outside the window, so late rather than duplicate.
    assert_eq!(t.classify(100), Arrival::OutOfOrder);
    // 101 is WINDOW − 1 behind: inside, so its first arrival is late, its second a repeat.
    assert_eq!(t.classify(101), Arrival::OutOfOrder);
    assert_eq!(t.classify(101), Arrival::Duplicate);
    assert_eq!(t.newest(), Some(100 + w));
}

/// The tracker's rules restated on unwrapped numbers, where "newer" is plain `>`.
fn model(stream: &[u64]) -> Vec<Arrival> {
    let mut newest: Option<u64> = None;
    let mut seen = BTreeSet::new();
    let window = u64::from(SequenceTracker::WINDOW);
    stream
        .iter()
        .map(|&s| {
            let a = match newest {
                None => Arrival::First,
                Some(n) if s == n + 1 => Arrival::Next,
                Some(n) if s > n => Arrival::Gap {
                    missing: u32::try_from(s - n - 1).unwrap(),
                },
                Some(n) if n - s < window && seen.contains(&s) => Arrival::Duplicate,
                Some(_) => Arrival::OutOfOrder,
            };
            if newest.is_none_or(|n| s > n) {
                newest = Some(s);
            }
            seen.insert(s);
            a
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Streams that move forward with jitter (steps −80..+80, so repeats, late ones and
    /// gaps beyond the window all occur), started anywhere, including just below the
    /// wrap; the model sees the same stream unwrapped.
    #[test]
    fn matches_the_unwrapped_model(start in any::<u32>(), steps in prop::collection::vec(-80i64..80, 1..300)) {
        let mut x = i64::from(u32::MAX) * 4 + i64::from(start);
        let mut unwrapped = Vec::with_capacity(steps.len());
        for s in steps {
            x += s;
            unwrapped.push(u64::try_from(x).unwrap());
        }
        let wrapped: Vec<u32> = unwrapped.iter().map(|&u| u as u32).collect();
        prop_assert_eq!(run(&wrapped), model(&unwrapped));
    }
}
