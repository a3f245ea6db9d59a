//! Properties of the datagram codec and of the receiving ends:
//! - encode → decode is the identity for both kinds (forces bit for bit, NaN included in
//!   sensor frames, where it must reach the controller's safety layer);
//! - decoding any bytes never panics, including valid datagrams with bits flipped,
//!   truncated or extended;
//! - every datagram fed through an end adds 1 to `received` and 1 to exactly one of
//!   `accepted` or a rejection counter.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use proptest::prelude::*;
use rigtwin_device::{Mode, MotorCommand, RigIo, SensorFrame, Tick};
use rigtwin_wire::{
    COMMAND_LEN, CommandDatagram, Datagram, LinkCounters, PlantEnd, PlantLimits, RigLimits,
    SENSOR_LEN, SensorDatagram, Transport, WireRig, channel_pair, decode,
};

/// Ticks as the wire carries them: `u64::MAX` is the "no tick" sentinel, so an optional
/// tick ranges over the rest.
fn opt_tick() -> impl Strategy<Value = Option<Tick>> {
    prop::option::of((0..u64::MAX).prop_map(Tick))
}

fn finite() -> impl Strategy<Value = f64> {
    any::<f64>().prop_filter("finite", |f| f.is_finite())
}

fn mode() -> impl Strategy<Value = Mode> {
    prop_oneof![
        Just(Mode::Configured),
        Just(Mode::Inactive),
        Just(Mode::Active),
        Just(Mode::Fault)
    ]
}

fn sensor() -> impl Strategy<Value = SensorDatagram> {
    (
        any::<u32>(),
        any::<u64>(),
        any::<[i64; 2]>(),
        any::<[f64; 2]>(),
        any::<bool>(),
        any::<bool>(),
        opt_tick(),
        any::<u16>(),
    )
        .prop_map(
            |(sequence, tick, counts, force, estop, wd, echo_tick, trial)| SensorDatagram {
                sequence,
                tick: Tick(tick),
                trial,
                frame: SensorFrame {
                    encoder_counts: counts,
                    force_raw_n: force,
                    estop,
                },
                watchdog_zeroed: wd,
                echo_tick,
            },
        )
}

fn command() -> impl Strategy<Value = CommandDatagram> {
    (
        any::<u32>(),
        any::<u64>(),
        [finite(), finite()],
        mode(),
        opt_tick(),
        any::<u16>(),
    )
        .prop_map(
            |(sequence, tick, force_n, mode, answers_tick, trial)| CommandDatagram {
                sequence,
                tick: Tick(tick),
                trial,
                command: MotorCommand { force_n },
                mode,
                answers_tick,
            },
        )
}

/// A valid datagram of either kind, then bit flips, a truncation and an extension.
fn mutated() -> impl Strategy<Value = Vec<u8>> {
    (
        prop_oneof![
            sensor().prop_map(|s| s.encode().to_vec()),
            command().prop_map(|c| c.encode().unwrap().to_vec()),
        ],
        prop::collection::vec((any::<usize>(), 0u8..8), 0..4),
        prop::option::of(any::<usize>()),
        prop::collection::vec(any::<u8>(), 0..3),
    )
        .prop_map(|(mut bytes, flips, cut, extra)| {
            let len = bytes.len();
            for (at, bit) in flips {
                bytes[at % len] ^= 1 << bit;
            }
            if let Some(cut) = cut {
                bytes.truncate(cut % (len + 1));
            }
            bytes.extend(extra);
            bytes
        })
}

fn outcomes(c: &LinkCounters) -> [u64; 11] {
    [
        c.accepted,
        c.bad_magic,
        c.truncated,
        c.wrong_length,
        c.wrong_version,
        c.unknown_kind,
        c.wrong_direction,
        c.non_finite,
        c.bad_field,
        c.out_of_order,
        c.duplicate,
    ]
}

/// `after − before` is one more datagram received, counted in exactly one outcome.
fn counted_once(before: &LinkCounters, after: &LinkCounters) -> Result<(), TestCaseError> {
    prop_assert_eq!(after.received, before.received + 1);
    let (b, a) = (outcomes(before), outcomes(after));
    let moved: Vec<u64> = a.iter().zip(b).map(|(a, b)| a - b).collect();
    prop_assert_eq!(moved.iter().sum::<u64>(), 1, "{:?}", moved);
    prop_assert_eq!(after.accepted + after.rejected(), after.received);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn sensor_frames_round_trip_bit_for_bit(s in sensor()) {
        let bytes = s.encode();
        prop_assert_eq!(bytes.len(), SENSOR_LEN);
        let Ok(Datagram::Sensor(back)) = decode(&bytes) else {
            return Err(TestCaseError::fail("a sensor frame did not decode as one"));
        };
        // Compare bytes, not f64s: NaN != NaN, but its bits must survive.
        prop_assert_eq!(back.encode(), bytes);
        if s.frame.force_raw_n.iter().all(|f| !f.is_nan()) {
            prop_assert_eq!(back, s);
        }
    }

    #[test]
    fn commands_round_trip(c in command()) {
        let bytes = c.encode().unwrap();
        prop_assert_eq!(bytes.len(), COMMAND_LEN);
        prop_assert_eq!(decode(&bytes), Ok(Datagram::Command(c)));
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        let _ = decode(&bytes);
    }

    #[test]
    fn mutated_datagrams_never_panic_and_are_counted_once_at_either_end(
        stream in prop::collection::vec(mutated(), 1..20)
    ) {
        // Each mutated datagram through both ends, one at a time, so each counter change
        // is attributable to one datagram. The ends keep their sequence state across
        // the stream, so duplicates and late datagrams occur too.
        let (rig_side, mut to_rig) = channel_pair(4);
        let (plant_side, mut to_plant) = channel_pair(4);
        let mut rig = WireRig::new(rig_side, RigLimits::default()).unwrap();
        let mut plant = PlantEnd::new(plant_side, PlantLimits::default()).unwrap();
        for (i, bytes) in stream.iter().enumerate() {
            let now = Tick(i as u64);
            to_rig.send(now, bytes).unwrap();
            let before = rig.counters();
            let _ = rig.read(now);
            counted_once(&before, &rig.counters())?;

            to_plant.send(now, bytes).unwrap();
            let before = plant.counters();
            plant.poll_command(now).unwrap();
            counted_once(&before, &plant.counters())?;
            // Whatever arrived, the plant never holds a non-finite force.
            prop_assert!(plant.applied_force(now).iter().all(|f| f.is_finite()));
        }
    }
}
