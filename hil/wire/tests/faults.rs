//! Fault specs (parse, print, refuse) and the seeded injector (reproducible, rates within
//! binomial tolerance, exact delays, swaps and stall windows), alone and in lock step
//! between the two ends.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use proptest::prelude::*;
use rigtwin_device::{Mode, MotorCommand, Rate, RigIo, SensorFrame, Tick};
use rigtwin_wire::faults::{Nanos, Stall};
use rigtwin_wire::{
    FaultInjector, FaultSpec, FaultSpecError, Faulty, PlantEnd, PlantLimits, RigLimits, WireRig,
    channel_pair,
};

fn spec(s: &str) -> FaultSpec {
    s.parse().unwrap()
}

#[test]
fn the_example_string_parses_to_its_values() {
    let s = spec("drop=0.01,delay_ticks=2,duplicate=0.001,reorder=0.001,stall=1.5s:50ms");
    assert_eq!(
        s,
        FaultSpec {
            drop: 0.01,
            delay_ticks: 2,
            duplicate: 0.001,
            reorder: 0.001,
            stall: Some(Stall {
                start: Nanos(1_500_000_000),
                length: Nanos(50_000_000)
            }),
        }
    );
    assert_eq!(
        s.to_string(),
        "drop=0.01,delay_ticks=2,duplicate=0.001,reorder=0.001,stall=1.5s:50ms"
    );
    // Every key is optional, spaces around pairs are allowed, order is free.
    assert_eq!(spec(" reorder=0.5 , drop=1 ").drop, 1.0);
    assert_eq!(spec(""), FaultSpec::default());
    assert_eq!(spec("none"), FaultSpec::default());
    assert_eq!(FaultSpec::default().to_string(), "none");
    // 1.5 s at 4 kHz is tick 6000; 50 ms is 200 ticks.
    let inj = FaultInjector::new(s, 0, Rate::CONTROL);
    assert_eq!(inj.stall_ticks(), Some((Tick(6000), Tick(6200))));
}

#[test]
fn bad_specs_name_the_key_and_the_value() {
    let cases: [(&str, &str, &str); 11] = [
        ("drop=1.5", "drop", "1.5"),
        ("drop=-0.1", "drop", "-0.1"),
        ("drop=NaN", "drop", "NaN"),
        ("duplicate=lots", "duplicate", "lots"),
        ("reorder=", "reorder", ""),
        ("delay_ticks=-1", "delay_ticks", "-1"),
        ("delay_ticks=2.5", "delay_ticks", "2.5"),
        ("stall=1s", "stall", "1s"),
        ("stall=1s:0ms", "stall", "1s:0ms"),
        ("stall=1:50ms", "stall", "1:50ms"),
        ("stall=1s:50 parsecs", "stall", "1s:50 parsecs"),
    ];
    for (input, key, value) in cases {
        let e = input.parse::<FaultSpec>().unwrap_err();
        let FaultSpecError::BadValue {
            key: k, value: v, ..
        } = &e
        else {
            panic!("{input}: {e:?}");
        };
        assert_eq!((k.as_str(), v.as_str()), (key, value), "{input}");
        let msg = e.to_string();
        assert!(msg.contains(key) && msg.contains(value), "{msg}");
    }
    assert_eq!(
        "jitter=0.1".parse::<FaultSpec>(),
        Err(FaultSpecError::UnknownKey {
            key: "jitter".into()
        })
    );
    assert_eq!(
        "drop".parse::<FaultSpec>(),
        Err(FaultSpecError::MissingValue { key: "drop".into() })
    );
    assert_eq!(
        "drop=0.1,drop=0.2".parse::<FaultSpec>(),
        Err(FaultSpecError::Repeated { key: "drop".into() })
    );
}

fn probability() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0f64]
}

fn any_spec() -> impl Strategy<Value = FaultSpec> {
    (
        probability(),
        any::<u32>(),
        probability(),
        probability(),
        prop::option::of((any::<u32>(), 1..u32::MAX)),
    )
        .prop_map(|(drop, delay_ticks, duplicate, reorder, stall)| FaultSpec {
            drop,
            delay_ticks,
            duplicate,
            reorder,
            // Nanosecond counts of every size, so all four units get printed.
            stall: stall.map(|(a, b)| Stall {
                start: Nanos(u64::from(a) * 1000 + u64::from(a % 7)),
                length: Nanos(u64::from(b)),
            }),
        })
}

proptest! {
    #[test]
    fn display_then_parse_gives_back_the_spec(s in any_spec()) {
        prop_assert_eq!(s.to_string().parse::<FaultSpec>(), Ok(s));
    }

    #[test]
    fn parsing_any_text_never_panics(text in "[a-z_=.,:0-9 -]{0,40}") {
        let _ = text.parse::<FaultSpec>();
    }
}

/// Offers one 8-byte datagram (its index) per tick for `n` ticks and returns what left,
/// as (tick, index), with the injector's counters.
fn run(s: FaultSpec, seed: u64, n: u64) -> (Vec<(u64, u64)>, FaultInjector) {
    let mut inj = FaultInjector::new(s, seed, Rate::CONTROL);
    let mut out = Vec::new();
    for t in 0..n {
        inj.offer(Tick(t), &t.to_le_bytes());
        while let Some(b) = inj.next_due(Tick(t)) {
            out.push((t, u64::from_le_bytes(b.try_into().unwrap())));
        }
    }
    (out, inj)
}

const ALL: &str = "drop=0.05,delay_ticks=3,duplicate=0.05,reorder=0.05,stall=0.5s:10ms";

#[test]
fn the_same_seed_gives_the_same_stream_and_another_seed_another() {
    let (a, _) = run(spec(ALL), 42, 10_000);
    let (b, _) = run(spec(ALL), 42, 10_000);
    let (c, _) = run(spec(ALL), 43, 10_000);
    assert_eq!(a, b);
    assert_ne!(a, c);
    // Not vacuous: every fault happened.
    let (_, inj) = run(spec(ALL), 42, 10_000);
    let k = inj.counters();
    assert!(
        k.dropped > 0 && k.duplicated > 0 && k.reordered > 0 && k.stalled > 0,
        "{k:?}"
    );
    assert_eq!(k.overflowed, 0);
}

#[test]
fn drop_and_duplicate_rates_are_within_five_sigma_of_binomial() {
    // 100 000 Bernoulli(p) draws: the count is binomial, sigma = sqrt(n p (1 − p)); a
    // correct injector leaves the 5-sigma band with probability < 1e-6 per seed.
    let n = 100_000u64;
    for (key, p) in [("drop", 0.01), ("drop", 0.3), ("duplicate", 0.01)] {
        for seed in [1u64, 2, 3] {
            let (out, inj) = run(spec(&format!("{key}={p}")), seed, n);
            let k = inj.counters();
            let count = if key == "drop" {
                k.dropped
            } else {
                k.duplicated
            };
            let mean = n as f64 * p;
            let sigma = (n as f64 * p * (1.0 - p)).sqrt();
            assert!(
                (count as f64 - mean).abs() <= 5.0 * sigma,
                "{key}={p} seed {seed}: {count} vs {mean} ± 5 × {sigma:.1}"
            );
            // Conservation: what left is what was offered, minus drops, plus copies.
            assert_eq!(out.len() as u64, n - k.dropped + k.duplicated);
            assert_eq!(k.released, out.len() as u64);
        }
    }
}

#[test]
fn a_delay_is_exactly_delay_ticks() {
    let (out, _) = run(spec("delay_ticks=5"), 0, 100);
    assert_eq!(out.len(), 95);
    assert!(out.iter().all(|&(t, i)| t == i + 5), "{out:?}");
}

#[test]
fn reorder_swaps_each_datagram_with_the_next() {
    // With probability 1 every datagram that is not released as a swap partner is held:
    // 1, 0, 3, 2, ... each pair leaving when its second member is offered.
    let (out, inj) = run(spec("reorder=1"), 0, 10);
    assert_eq!(
        out,
        [
            (1, 1),
            (1, 0),
            (3, 3),
            (3, 2),
            (5, 5),
            (5, 4),
            (7, 7),
            (7, 6),
            (9, 9),
            (9, 8)
        ]
    );
    assert_eq!(inj.counters().reordered, 5);
}

#[test]
fn a_stall_silences_exactly_its_window_including_queued_datagrams() {
    // 1 ms from 1 ms at 4 kHz: ticks 4..8. With a 2-tick delay, datagrams 2 and 3 come
    // due in the window and 4..=7 are offered in it; those six never leave.
    let (out, inj) = run(spec("delay_ticks=2,stall=1ms:1ms"), 0, 20);
    let indices: Vec<u64> = out.iter().map(|&(_, i)| i).collect();
    assert_eq!(indices, [0, 1, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17]);
    assert_eq!(inj.counters().stalled, 6);
}

#[test]
fn a_full_queue_loses_datagrams_and_counts_them() {
    // The ring holds 3 × (delay + 2) = 9 datagrams; many offers in one tick overflow it.
    let mut inj = FaultInjector::new(spec("delay_ticks=1"), 0, Rate::CONTROL);
    for i in 0..20u64 {
        inj.offer(Tick(0), &i.to_le_bytes());
    }
    assert_eq!(inj.counters().overflowed, 11);
    let mut left = 0;
    while inj.next_due(Tick(1)).is_some() {
        left += 1;
    }
    assert_eq!(left, 9);
}

/// Both directions faulty, in lock step for 20 000 ticks: the ends' counters must agree
/// with what the injectors did, exactly.
#[test]
fn the_ends_count_what_the_injector_did() {
    let s = spec("drop=0.02,delay_ticks=1,duplicate=0.02,reorder=0.02");
    let (a, b) = channel_pair(32);
    let mut rig = WireRig::new(
        Faulty::new(a, FaultInjector::new(s, 7, Rate::CONTROL)),
        RigLimits::default(),
    )
    .unwrap();
    let mut plant = PlantEnd::new(
        Faulty::new(b, FaultInjector::new(s, 8, Rate::CONTROL)),
        PlantLimits::default(),
    )
    .unwrap();
    rig.set_mode(Mode::Active);
    let mut read_errors = 0;
    for n in 0..20_000u64 {
        let now = Tick(n);
        plant.poll_command(now).unwrap();
        let f = plant.applied_force(now);
        assert!(f == [0.0; 2] || f == [1.0, 2.0]);
        plant.send_frame(now, SensorFrame::default()).unwrap();
        if rig.read(now).is_err() {
            read_errors += 1;
        }
        rig.write(
            now,
            MotorCommand {
                force_n: [1.0, 2.0],
            },
        )
        .unwrap();
    }
    for (c, inj, newest, pending) in [
        (
            rig.counters(),
            plant.transport().injector().counters(),
            rig.newest().unwrap().sequence,
            rig.transport().inner().pending(),
        ),
        (
            plant.counters(),
            rig.transport().injector().counters(),
            plant.latest_command().unwrap().sequence,
            plant.transport().inner().pending(),
        ),
    ] {
        // Everything released arrived or is still in the channel (which never filled),
        // and each arrival was counted once.
        assert_eq!(c.received + pending as u64, inj.released);
        assert_eq!(c.accepted + c.rejected(), c.received);
        // Each extra copy arrives right after its original: a duplicate.
        assert_eq!(c.duplicate, inj.duplicated);
        // Each held datagram arrives after a newer one: late. The last may still be held.
        assert!(
            c.out_of_order == inj.reordered || c.out_of_order + 1 == inj.reordered,
            "{c} / {inj:?}"
        );
        // Every sequence number up to the newest was either accepted or skipped.
        assert_eq!(c.accepted + c.lost, u64::from(newest) + 1);
        assert_eq!(c.bad_magic + c.truncated + c.non_finite, 0);
    }
    // Drops of 2 % rarely reach 4 in a row; the controller saw some stale reads at most.
    assert!(read_errors < 20, "{read_errors}");
}
