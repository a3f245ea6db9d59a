//! The two ends over the in-process channel pair, in lock step. Per tick `n` the plant
//! polls, applies, sends frame `n`; the controller reads it and writes command `n`,
//! which the plant takes up at `n + 1`. Everything here is exact: no tolerance is
//! needed because nothing is lost unless a test removes it.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::safety::{IoStage, TripReason};
use rigtwin_device::testing::PointMassRig;
use rigtwin_device::{
    Controller, ControllerConfig, ErrorKind, Mode, MotorCommand, Rate, RigIo, RigIoError,
    SensorFrame, Tick,
};
use rigtwin_wire::{
    ChannelEnd, PlantEnd, PlantLimits, RigLimits, SensorDatagram, Transport, WireError, WireRig,
    channel_pair,
};

fn frame_at(n: u64) -> SensorFrame {
    SensorFrame {
        encoder_counts: [n as i64, -(n as i64) * 3],
        force_raw_n: [n as f64 * 0.5, 1.0 / (n as f64 + 1.0)],
        estop: n % 97 == 13,
    }
}

fn command_at(n: u64) -> MotorCommand {
    MotorCommand {
        force_n: [n as f64 * 0.25 + 1.0, -(n as f64) - 2.0],
    }
}

fn ends(rig: RigLimits, plant: PlantLimits) -> (WireRig<ChannelEnd>, PlantEnd<ChannelEnd>) {
    let (a, b) = channel_pair(16);
    let mut r = WireRig::new(a, rig).unwrap();
    r.set_mode(Mode::Active);
    (r, PlantEnd::new(b, plant).unwrap())
}

#[test]
fn the_controller_sees_exactly_the_frames_sent_and_the_plant_applies_the_previous_command() {
    let (mut rig, mut plant) = ends(RigLimits::default(), PlantLimits::default());
    let ticks = 2000;
    for n in 0..ticks {
        let now = Tick(n);
        let fresh = plant.poll_command(now).unwrap();
        // Command n−1 arrives at n and is applied from n on (zero-order hold).
        let expected = if n == 0 {
            [0.0; 2]
        } else {
            command_at(n - 1).force_n
        };
        assert_eq!(plant.applied_force(now), expected, "tick {n}");
        if n > 0 {
            let c = fresh.unwrap();
            assert_eq!(c.tick, Tick(n - 1));
            assert_eq!(c.answers_tick, Some(Tick(n - 1)));
            assert_eq!(c.mode, Mode::Active);
        }
        plant.send_frame(now, frame_at(n)).unwrap();
        assert_eq!(rig.read(now).unwrap(), frame_at(n), "tick {n}");
        assert_eq!(rig.newest().map(|s| s.tick), Some(now));
        rig.write(now, command_at(n)).unwrap();
    }
    // One tick from write to the frame that echoes it.
    assert_eq!(rig.round_trip_ticks(), Some(1));
    let r = rig.counters();
    assert_eq!(
        (r.sent, r.received, r.accepted, r.rejected()),
        (ticks, ticks, ticks, 0)
    );
    assert_eq!((r.sequence_gaps, r.lost), (0, 0));
    let p = plant.counters();
    // The last command is still on the wire: the plant polled ticks − 1 of them.
    assert_eq!(
        (p.sent, p.received, p.accepted, p.rejected()),
        (ticks, ticks - 1, ticks - 1, 0)
    );
}

#[test]
fn the_command_watchdog_zeroes_force_at_exactly_stale_ticks_and_says_so() {
    for stale_ticks in [1u32, 4, 7] {
        let (mut rig, mut plant) = ends(RigLimits::default(), PlantLimits { stale_ticks });
        let last_write = 50u64;
        let mut zeroed_from = None;
        for n in 0..last_write + 20 {
            let now = Tick(n);
            plant.poll_command(now).unwrap();
            let f = plant.applied_force(now);
            let flag = plant.watchdog_zeroed(now);
            // The newest command (written at last_write) arrived at last_write + 1; the
            // watchdog fires on the stale_ticks-th poll after that without a new one.
            if n > last_write + 1 {
                let polls_without = n - (last_write + 1);
                let fired = polls_without >= u64::from(stale_ticks);
                assert_eq!(flag, fired, "stale_ticks {stale_ticks}, tick {n}");
                let want = if fired {
                    [0.0; 2]
                } else {
                    command_at(last_write).force_n
                };
                assert_eq!(f, want, "stale_ticks {stale_ticks}, tick {n}");
                if fired && zeroed_from.is_none() {
                    zeroed_from = Some(n);
                }
            } else {
                assert!(!flag, "tick {n}");
            }
            plant.send_frame(now, frame_at(n)).unwrap();
            let _ = rig.read(now).unwrap();
            // The flag travels in the frame of the same tick.
            assert_eq!(rig.newest().map(|s| s.watchdog_zeroed), Some(flag));
            if n <= last_write {
                rig.write(now, command_at(n)).unwrap();
            }
        }
        assert_eq!(
            zeroed_from,
            Some(last_write + 1 + u64::from(stale_ticks)),
            "stale_ticks {stale_ticks}"
        );
        // A fresh command is applied again: the plant's watchdog does not latch.
        let now = Tick(last_write + 20);
        rig.write(now, command_at(7)).unwrap();
        plant.poll_command(now.next()).unwrap();
        assert_eq!(plant.applied_force(now.next()), command_at(7).force_n);
        assert!(!plant.watchdog_zeroed(now.next()));
    }
}

#[test]
fn the_rig_times_out_at_exactly_stale_ticks_missing_frames() {
    for stale_ticks in [1u32, 4, 7] {
        let limits = RigLimits {
            stale_ticks,
            max_gap: 3,
        };
        let (mut rig, mut plant) = ends(limits, PlantLimits::default());
        let last_frame = 30u64;
        for n in 0..last_frame + 12 {
            let now = Tick(n);
            plant.poll_command(now).unwrap();
            if n <= last_frame {
                plant.send_frame(now, frame_at(n)).unwrap();
            }
            let missing = n.saturating_sub(last_frame);
            match rig.read(now) {
                Ok(f) => {
                    assert!(missing < u64::from(stale_ticks), "tick {n}");
                    // Reads before the timeout hold the newest frame.
                    assert_eq!(f, frame_at(n.min(last_frame)));
                }
                Err(e) => {
                    assert!(missing >= u64::from(stale_ticks), "tick {n}: {e}");
                    assert_eq!(e.kind(), ErrorKind::Timeout);
                    assert_eq!(
                        e,
                        WireError::Stale {
                            ticks: missing,
                            limit: stale_ticks
                        }
                    );
                }
            }
            rig.write(now, MotorCommand::ZERO).unwrap();
        }
    }
}

#[test]
fn before_the_first_frame_the_rig_is_disconnected_and_the_plant_applies_nothing() {
    let (mut rig, mut plant) = ends(RigLimits::default(), PlantLimits::default());
    let e = rig.read(Tick(0)).unwrap_err();
    assert_eq!(e, WireError::NoFrameYet);
    assert_eq!(e.kind(), ErrorKind::Disconnected);
    // No command yet: zero force, and the watchdog flag stays off (nothing went stale).
    assert_eq!(plant.poll_command(Tick(100)).unwrap(), None);
    assert_eq!(plant.applied_force(Tick(100)), [0.0; 2]);
    assert!(!plant.watchdog_zeroed(Tick(100)));
}

#[test]
fn only_an_active_command_moves_the_motors() {
    let (mut rig, mut plant) = ends(RigLimits::default(), PlantLimits::default());
    for (n, mode) in [Mode::Configured, Mode::Inactive, Mode::Fault, Mode::Active]
        .into_iter()
        .enumerate()
    {
        let now = Tick(n as u64);
        rig.set_mode(mode);
        rig.write(now, command_at(5)).unwrap();
        let c = plant.poll_command(now).unwrap().unwrap();
        assert_eq!(c.mode, mode);
        let want = if mode == Mode::Active {
            command_at(5).force_n
        } else {
            [0.0; 2]
        };
        assert_eq!(plant.applied_force(now), want, "{mode:?}");
    }
}

#[test]
fn a_non_finite_command_is_refused_and_never_sent() {
    let (mut rig, mut plant) = ends(RigLimits::default(), PlantLimits::default());
    rig.write(Tick(0), command_at(1)).unwrap();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let e = rig
            .write(
                Tick(1),
                MotorCommand {
                    force_n: [0.0, bad],
                },
            )
            .unwrap_err();
        assert!(matches!(e, WireError::Encode(_)), "{e}");
        assert_eq!(e.kind(), ErrorKind::Other);
    }
    assert_eq!(rig.counters().sent, 1);
    plant.poll_command(Tick(1)).unwrap();
    assert_eq!(plant.counters().received, 1);
    assert_eq!(plant.applied_force(Tick(1)), command_at(1).force_n);
}

/// A raw sender of hand-made sensor frames, to make gaps the plant end never makes.
fn raw_frame(raw: &mut ChannelEnd, sequence: u32, tick: u64) {
    let d = SensorDatagram {
        sequence,
        tick: Tick(tick),
        frame: frame_at(tick),
        ..SensorDatagram::default()
    };
    raw.send(Tick(tick), &d.encode()).unwrap();
}

#[test]
fn a_gap_longer_than_max_gap_is_an_error_of_kind_other() {
    let (a, mut raw) = channel_pair(16);
    let mut rig = WireRig::new(a, RigLimits::default()).unwrap();
    raw_frame(&mut raw, 0, 0);
    raw_frame(&mut raw, 1, 1);
    assert_eq!(rig.read(Tick(1)).unwrap(), frame_at(1));
    // 2, 3, 4 lost: a gap of 3 = max_gap is tolerated.
    raw_frame(&mut raw, 5, 2);
    assert_eq!(rig.read(Tick(2)).unwrap(), frame_at(2));
    // 6..=9 lost: 4 > max_gap.
    raw_frame(&mut raw, 10, 3);
    let e = rig.read(Tick(3)).unwrap_err();
    assert_eq!(
        e,
        WireError::GapTooLarge {
            missing: 4,
            limit: 3
        }
    );
    assert_eq!(e.kind(), ErrorKind::Other);
    // The frame after the gap was kept, and the next read is fine again.
    raw_frame(&mut raw, 11, 4);
    assert_eq!(rig.read(Tick(4)).unwrap(), frame_at(4));
    let c = rig.counters();
    assert_eq!((c.accepted, c.sequence_gaps, c.lost), (5, 2, 7));
}

#[test]
fn late_and_repeated_frames_are_dropped_and_the_newest_is_kept() {
    let (a, mut raw) = channel_pair(16);
    let mut rig = WireRig::new(a, RigLimits::default()).unwrap();
    // Arrival order within one read: 0, 2, 1 (late), 2 (repeat), 3.
    for (seq, tick) in [(0, 0), (2, 2), (1, 1), (2, 2), (3, 3)] {
        raw_frame(&mut raw, seq, tick);
    }
    assert_eq!(rig.read(Tick(0)).unwrap(), frame_at(3));
    let c = rig.counters();
    assert_eq!(
        (c.received, c.accepted, c.out_of_order, c.duplicate, c.lost),
        (5, 3, 1, 1, 1)
    );
}

#[test]
fn a_command_at_the_controller_is_the_wrong_direction() {
    let (a, b) = channel_pair(4);
    let mut rig = WireRig::new(a, RigLimits::default()).unwrap();
    let mut other = WireRig::new(b, RigLimits::default()).unwrap();
    other.write(Tick(0), command_at(0)).unwrap();
    assert_eq!(rig.read(Tick(0)).unwrap_err(), WireError::NoFrameYet);
    assert_eq!(rig.counters().wrong_direction, 1);
}

/// The rig's own controller drives a point-mass plant through the wire; when the plant
/// falls silent, the controller trips on the read timeout at exactly `stale_ticks`.
#[test]
fn the_device_controller_runs_over_the_wire_and_trips_on_a_silent_plant() {
    let config = ControllerConfig::default();
    let mut carts = PointMassRig::new(config.render.feedforward_mass_kg, Rate::CONTROL);
    carts.hand_force_n = [1.0, -0.5];
    carts.hand_stiffness_n_per_m = [200.0, 200.0];
    let mut ctl = Controller::new(config).unwrap();
    let (mut rig, mut plant) = ends(RigLimits::default(), PlantLimits::default());
    let silent_from = 4000u64;
    let mut trip = None;
    for n in 0..silent_from + 10 {
        let now = Tick(n);
        plant.poll_command(now).unwrap();
        let force_n = plant.applied_force(now);
        carts.write(now, MotorCommand { force_n }).unwrap();
        if n < silent_from {
            plant.send_frame(now, carts.read(now).unwrap()).unwrap();
        }
        rig.set_mode(ctl.mode());
        let report = ctl.tick(&mut rig, now);
        if n == 0 {
            ctl.activate().unwrap();
        }
        if let Some(t) = report.trip {
            trip.get_or_insert((n, t));
        }
    }
    // Active and untripped until the silence; the 4th read without a frame trips it.
    let stale = u64::from(RigLimits::default().stale_ticks);
    assert_eq!(
        trip,
        Some((
            silent_from - 1 + stale,
            TripReason::Io {
                stage: IoStage::Read,
                kind: ErrorKind::Timeout
            }
        ))
    );
    assert_eq!(ctl.mode(), Mode::Fault);
    // The carts moved under the hand force while active (admittance rendered something).
    assert!(carts.position_m[0].abs() > 1e-4, "{:?}", carts.position_m);
    let c = rig.counters();
    assert_eq!((c.accepted, c.rejected()), (silent_from, 0));
}
