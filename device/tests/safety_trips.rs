//! The safety layer: each trip fires on the right tick, the command written at that
//! tick and every tick after it is zero until reset, and the event names tick and reason.
//! Every limit is tried on both axes and on both sides (the checks take magnitudes, and a
//! sign or index slip would show on one of the four). The watchdogs (stale force,
//! encoder stall, loop deadline, non-finite command) are in `safety_watchdogs.rs`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::io::ErrorKind;
use rigtwin_device::safety::{EVENT_CAPACITY, EventLog, IoStage, SafetyEvent, TripReason};
use rigtwin_device::testing::{MockRig, scripted};
use rigtwin_device::velocity::VelocityEstimator;
use rigtwin_device::{Controller, ControllerConfig, LifecycleError, Mode, Rate, Tick};

/// The push of [`run_case`] at tick `n`: (5, 3) N, with the last bits of the y reading
/// moving from tick to tick (1 µN), as a live sensor's do; the stale-force watchdog
/// (on by default) must see a working sensor.
fn live_force(n: u64) -> [f64; 2] {
    [5.0, 3.0 + 1e-6 * (n % 2) as f64]
}

/// The four (axis, sign) combinations every limit is tried on.
const SIDES: [(usize, i64); 4] = [(0, 1), (0, -1), (1, 1), (1, -1)];

/// Run an active controller from tick 1 with a 5 N push (so the command is non-zero),
/// let `inject` alter the rig before each tick, and check the trip at `trip_tick`.
/// The default encoder-stall watchdog stays on: on the mock's still carts the push
/// brings the x command to 50 N at tick 44 (measured) and the stall would trip 80
/// readings later, at tick 124, after every trip tested here (all by tick 60); a trip
/// before `trip_tick` fails the case.
fn run_case(
    config: ControllerConfig,
    start_counts: [i64; 2],
    mut inject: impl FnMut(&mut MockRig, u64),
    trip_tick: u64,
) -> (Controller, MockRig, SafetyEvent) {
    let mut rig = MockRig::default();
    rig.frame.encoder_counts = start_counts;
    rig.frame.force_raw_n = live_force(0);
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    for n in 1..trip_tick + 20 {
        rig.frame.force_raw_n = live_force(n);
        inject(&mut rig, n);
        let r = c.tick(&mut rig, Tick(n));
        let written = rig.last_write.map(|(_, cmd)| cmd.force_n);
        if n < trip_tick {
            assert_eq!(
                r.mode,
                Mode::Active,
                "tick {n}: tripped early: {:?}",
                c.events().last()
            );
            if n > 2 {
                assert!(
                    r.command_n != [0.0, 0.0],
                    "tick {n}: the push must give a non-zero command"
                );
            }
        } else {
            assert_eq!(r.mode, Mode::Fault, "tick {n}: not tripped");
            // Zero from the tripping tick's own write on, exactly; a failed write is
            // itself the trip, so zero starts with the write after it.
            if rig.fail_write.is_none() || n > trip_tick {
                assert_eq!(r.command_n, [0.0, 0.0], "tick {n}");
                assert_eq!(written, Some([0.0, 0.0]), "tick {n}: written");
            }
        }
        if n == trip_tick {
            assert!(r.trip.is_some());
        }
    }
    let event = c.events().last().unwrap();
    assert_eq!(event.tick, Tick(trip_tick));
    assert_eq!(
        c.events().len(),
        1,
        "one trip, one event: {:?}",
        c.events().iter().collect::<Vec<_>>()
    );
    (c, rig, event)
}

/// After a trip: reset → Inactive → activate works and commands resume.
fn recovers(mut c: Controller, mut rig: MockRig, from: u64) {
    rig.fail_read = None;
    rig.fail_write = None;
    rig.frame.estop = false;
    rig.frame.force_raw_n = [5.0, 3.0];
    c.reset().unwrap();
    assert_eq!(c.mode(), Mode::Inactive);
    assert_eq!(c.tick(&mut rig, Tick(from)).command_n, [0.0, 0.0]);
    c.activate().unwrap();
    for n in from + 1..from + 10 {
        // A live sensor: the reading moves a little every tick.
        rig.frame.force_raw_n[1] = 3.0 + 1e-6 * n as f64;
        assert_eq!(c.tick(&mut rig, Tick(n)).mode, Mode::Active);
    }
    assert!(c.report().command_n != [0.0, 0.0]);
}

#[test]
fn estop_zeroes_force_at_once_and_reset_waits_for_release() {
    let (mut c, mut rig, e) = run_case(
        ControllerConfig::default(),
        [0, 0],
        |r, n| r.frame.estop = n >= 50,
        50,
    );
    assert_eq!(e.reason, TripReason::EStop);
    assert_eq!(c.reset(), Err(LifecycleError::EStopPressed));
    rig.frame.estop = false;
    c.tick(&mut rig, Tick(200));
    recovers(c, rig, 201);
}

#[test]
fn nonfinite_force_trips_after_n_ticks_and_the_last_finite_force_is_held() {
    // Default N = 4: NaN from tick 50 trips at tick 53.
    let (c, rig, e) = run_case(
        ControllerConfig::default(),
        [0, 0],
        |r, n| {
            if n >= 50 {
                r.frame.force_raw_n = [f64::NAN, 3.0];
            }
        },
        53,
    );
    assert_eq!(e.reason, TripReason::NonFiniteForce { ticks: 4 });
    // The calibrated force stayed at the last finite reading (tick 49's), exactly.
    assert_eq!(c.report().force_n, live_force(49));
    recovers(c, rig, 300);
}

#[test]
fn velocity_limit_trips_on_the_tick_the_filtered_velocity_exceeds_it() {
    // From tick 50 a cart moves 400 counts (0.4 mm) per tick: 1.6 m/s raw, either way on
    // either axis. The filtered velocity after j samples is 1.6 (1 − (1 − α)^j); the
    // limit is 1 m/s, so the trip is the first j where that exceeds 1.
    let h = Rate::CONTROL.period_s();
    let alpha =
        VelocityEstimator::new(ControllerConfig::default().sensors.velocity_filter_hz, h).alpha();
    let j = (1..)
        .find(|j| 1.6 * (1.0 - (1.0 - alpha).powi(*j)) > 1.0)
        .unwrap() as u64;
    let trip = 49 + j;
    for (axis, sign) in SIDES {
        let (c, rig, e) = run_case(
            ControllerConfig::default(),
            [0, 0],
            |r, n| {
                if n >= 50 {
                    r.frame.encoder_counts[axis] = sign * 400 * (n as i64 - 49);
                }
            },
            trip,
        );
        assert!(
            matches!(e.reason, TripReason::VelocityLimit { axis: a, velocity_m_per_s: v }
                if a == axis && v * sign as f64 > 1.0),
            "axis {axis} sign {sign}: {:?}",
            e.reason
        );
        recovers(c, rig, 300);
    }
    eprintln!("velocity limit: tripped {j} ticks after the 1.6 m/s step (α = {alpha:.4})");
}

#[test]
fn encoder_jump_trips_on_the_jump() {
    // 2000 counts = 2 mm in one tick > the 1 mm limit, either way on either axis; the
    // step is reported in metres, signed (exact: 2000 × 1e-6).
    for (axis, sign) in SIDES {
        let (c, rig, e) = run_case(
            ControllerConfig::default(),
            [0, 0],
            |r, n| {
                if n >= 50 {
                    r.frame.encoder_counts[axis] = sign * 2_000;
                }
            },
            50,
        );
        let want = sign as f64 * 0.002;
        assert!(
            matches!(e.reason, TripReason::EncoderJump { axis: a, step_m } if a == axis && (step_m - want).abs() < 1e-15),
            "axis {axis} sign {sign}: {:?}",
            e.reason
        );
        recovers(c, rig, 300);
    }
}

#[test]
fn position_beyond_wall_plus_margin_trips() {
    // Start at ±0.169 m (inside 0.15 + 0.02), then 0.3 mm per tick outward from tick 50:
    // ±0.1702 m at tick 53 is the first beyond 0.17 m, on either side of either axis. The
    // velocity limit is raised so only the position check can fire.
    for (axis, sign) in SIDES {
        let mut config = ControllerConfig::default();
        config.safety.velocity_limit_m_per_s = 10.0;
        let mut start = [0, 0];
        start[axis] = sign * 169_000;
        let (c, mut rig, e) = run_case(
            config,
            start,
            |r, n| {
                if n >= 50 {
                    r.frame.encoder_counts[axis] = sign * (169_000 + 300 * (n as i64 - 49));
                }
            },
            53,
        );
        assert!(
            matches!(e.reason, TripReason::PositionLimit { axis: a, position_m }
                if a == axis && position_m * sign as f64 > 0.17),
            "axis {axis} sign {sign}: {:?}",
            e.reason
        );
        // Back inside the workspace before the reset.
        rig.frame.encoder_counts[axis] = 0;
        let mut c = c;
        c.tick(&mut rig, Tick(299));
        recovers(c, rig, 300);
    }
}

#[test]
fn io_errors_trip_on_the_failing_tick() {
    let (c, rig, e) = run_case(
        ControllerConfig::default(),
        [0, 0],
        |r, n| r.fail_read = (n >= 50).then_some(ErrorKind::Timeout),
        50,
    );
    assert_eq!(
        e.reason,
        TripReason::Io {
            stage: IoStage::Read,
            kind: ErrorKind::Timeout
        }
    );
    recovers(c, rig, 300);

    let (c, rig, e) = run_case(
        ControllerConfig::default(),
        [0, 0],
        |r, n| r.fail_write = (n == 50).then_some(ErrorKind::Disconnected),
        50,
    );
    assert_eq!(
        e.reason,
        TripReason::Io {
            stage: IoStage::Write,
            kind: ErrorKind::Disconnected
        }
    );
    recovers(c, rig, 300);
}

#[test]
fn a_missed_tick_while_active_trips() {
    // Default allowance 0: the first skipped tick trips, as a clock skip (one event: the
    // deadline watchdog, which would count the same late tick, comes second).
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = live_force(0);
    let mut c = Controller::new(ControllerConfig::default()).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    for n in 1..50 {
        rig.frame.force_raw_n = live_force(n);
        assert_eq!(c.tick(&mut rig, Tick(n)).mode, Mode::Active);
    }
    rig.frame.force_raw_n = live_force(51);
    let r = c.tick(&mut rig, Tick(51));
    assert_eq!(c.events().len(), 1);
    assert_eq!(r.mode, Mode::Fault);
    assert_eq!(r.command_n, [0.0, 0.0]);
    assert_eq!(
        c.events().last(),
        Some(SafetyEvent {
            tick: Tick(51),
            reason: TripReason::ClockSkip {
                expected: Tick(50),
                got: Tick(51)
            }
        })
    );
}

/// A real-time loop that misses deadlines skips ahead instead of bursting: with
/// `max_consecutive_misses = 4`, gaps of up to 4 skipped ticks keep the controller active
/// and commanding, the first gap of 5 trips it, at that tick, with the command zero.
#[test]
fn skipped_ticks_within_the_allowance_do_not_trip() {
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = [5.0, 0.0];
    let mut config = ControllerConfig::default();
    config.safety.max_consecutive_misses = 4;
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let mut n = 1;
    for gap in [0, 1, 4, 2, 4] {
        n += gap;
        let r = c.tick(&mut rig, Tick(n));
        assert_eq!(
            r.mode,
            Mode::Active,
            "gap of {gap} skipped ticks at tick {n}"
        );
        n += 1;
    }
    let r = c.tick(&mut rig, Tick(n + 5));
    assert_eq!(r.mode, Mode::Fault);
    assert_eq!(r.command_n, [0.0, 0.0]);
    assert_eq!(
        c.events().last(),
        Some(SafetyEvent {
            tick: Tick(n + 5),
            reason: TripReason::ClockSkip {
                expected: Tick(n),
                got: Tick(n + 5)
            }
        })
    );
}

#[test]
fn motor_force_is_clamped_to_the_limit() {
    // The reference runs away from carts held at 0 by the mock: the PD demand grows
    // past the 200 N limit, and the command must sit at exactly ±200 N, flagged, on both
    // axes and both sides. The mock's carts never move and its push is held bit for bit,
    // which the encoder-stall and stale-force watchdogs would (rightly) trip on within
    // 400 ticks: they are off ([`scripted`]); the clamp is under test.
    for push in [[15.0, -15.0], [-15.0, 15.0]] {
        let mut rig = MockRig::default();
        rig.frame.force_raw_n = push;
        let mut c = Controller::new(scripted(ControllerConfig::default())).unwrap();
        c.tick(&mut rig, Tick(0));
        c.activate().unwrap();
        let mut seen = false;
        for n in 1..400 {
            let r = c.tick(&mut rig, Tick(n));
            assert_eq!(r.mode, Mode::Active);
            assert!(r.command_n.iter().all(|f| f.abs() <= 200.0));
            if r.saturated == [true, true] {
                seen = true;
                assert_eq!(
                    r.command_n,
                    [200.0 * push[0].signum(), 200.0 * push[1].signum()]
                );
            }
        }
        assert!(seen, "{push:?}");
    }
}

#[test]
fn inactive_controller_trips_too_and_commands_zero() {
    // Safety is always on: an e-stop while inactive latches a fault as well.
    let mut rig = MockRig::default();
    let mut c = Controller::new(ControllerConfig::default()).unwrap();
    c.tick(&mut rig, Tick(0));
    rig.frame.estop = true;
    let r = c.tick(&mut rig, Tick(1));
    assert_eq!((r.mode, r.command_n), (Mode::Fault, [0.0, 0.0]));
    assert!(
        c.activate().is_err(),
        "a fault must be reset before activation"
    );
}

#[test]
fn event_log_keeps_the_latest_events_without_growing() {
    let mut log = EventLog::default();
    for t in 0..(EVENT_CAPACITY as u64 + 6) {
        log.push(SafetyEvent {
            tick: Tick(t),
            reason: TripReason::EStop,
        });
    }
    assert_eq!(log.len(), EVENT_CAPACITY);
    assert_eq!(log.total(), EVENT_CAPACITY as u64 + 6);
    assert_eq!(log.iter().next().map(|e| e.tick), Some(Tick(6)));
    assert_eq!(
        log.last().map(|e| e.tick),
        Some(Tick(EVENT_CAPACITY as u64 + 5))
    );
}
