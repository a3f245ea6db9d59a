//! The watchdogs that look for a part of the loop gone quiet, on by default: a frozen
//! force reading (stale force), a motor pushing while its encoder does not move
//! (encoder stall), a loop that is late too often (deadline overrun); and the last line
//! before the motor, a NaN or infinite command. Each trips on the tick its contract
//! says, and does not trip where the contract says the rig is working.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::config::SafetyConfig;
use rigtwin_device::safety::{SafetyMonitor, TripReason};
use rigtwin_device::testing::{MockRig, PointMassRig};
use rigtwin_device::{Controller, ControllerConfig, LawKind, Mode, Rate, Tick};

/// The four (axis, sign) combinations each watchdog that has an axis is tried on.
const SIDES: [(usize, f64); 4] = [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)];

/// A live sensor reading `push`: its last bits (1 µN steps) move from tick to tick, on
/// every tick and on every other one alike (a period of 3).
fn live(push: [f64; 2], n: u64) -> [f64; 2] {
    let d = 1e-6 * (n % 3) as f64;
    [push[0] + d, push[1] + d]
}

/// A controller primed at tick 0 on `rig` and activated; the next tick is 1.
fn active(config: ControllerConfig, rig: &mut MockRig) -> Controller {
    let mut c = Controller::new(config).unwrap();
    c.tick(rig, Tick(0));
    c.activate().unwrap();
    c
}

// ---------------------------------------------------------------------------------
// Stale force
// ---------------------------------------------------------------------------------

#[test]
fn a_frozen_force_reading_trips_at_its_40th_identical_reading_by_default() {
    // A live 0.5 N push (small, so the mock's still carts never see 50 N commanded and
    // only this watchdog can fire) until tick 50, then the reading freezes. Tick 50's
    // reading is the first of the run, so the 40th identical one, the trip, is tick 89:
    // 10 ms at 4 kHz, the default.
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = live([0.5, 0.3], 0);
    let mut c = active(ControllerConfig::default(), &mut rig);
    let mut trip = None;
    for n in 1..200u64 {
        rig.frame.force_raw_n = live([0.5, 0.3], n.min(50));
        let r = c.tick(&mut rig, Tick(n));
        if let Some(t) = r.trip {
            trip.get_or_insert((n, t, r.command_n));
        }
    }
    assert_eq!(
        trip,
        Some((89, TripReason::StaleForce { ticks: 40 }, [0.0, 0.0]))
    );
    assert_eq!(c.events().len(), 1);
}

#[test]
fn a_noiseless_simulated_sensor_runs_with_stale_force_ticks_0() {
    // Point-mass carts and a hand pushing a constant 4 N along y with the sensor's dither
    // off: a noiseless simulator at its purest, reading (0, 4) N bit for bit at every
    // tick from tick 0. By default that is a frozen sensor: the 40th identical reading,
    // tick 39, trips. With the explicit opt-out, 8000 active ticks (2 s) run and the
    // carts move under the push (the law is rendered, not stopped).
    let run = |stale_force_ticks: u32| {
        let mut config = ControllerConfig::default();
        config.safety.stale_force_ticks = stale_force_ticks;
        let mut rig = PointMassRig::new(config.render.feedforward_mass_kg, Rate::CONTROL);
        rig.force_dither_n = 0.0;
        rig.hand_force_n = [0.0, 4.0];
        let mut c = Controller::new(config).unwrap();
        c.tick(&mut rig, Tick(0));
        c.activate().unwrap();
        for n in 1..=8000u64 {
            c.tick(&mut rig, Tick(n));
        }
        (c.events().iter().next(), rig.position_m[1])
    };
    let (event, _) = run(ControllerConfig::default().safety.stale_force_ticks);
    let event = event.unwrap();
    assert_eq!(
        (event.tick, event.reason),
        (Tick(39), TripReason::StaleForce { ticks: 40 })
    );
    let (event, y) = run(0);
    assert_eq!(event, None);
    // 4 N on the 5 kg, 15 N s/m admittance: 4/15 m/s after τ = 1/3 s, so y is well past
    // 0.3 m after 2 s; 0.1 m says "moved" with room to spare.
    assert!(y > 0.1, "{y}");
}

// ---------------------------------------------------------------------------------
// Encoder stall
// ---------------------------------------------------------------------------------

/// A trip as the tests see it: the tick, the reason and the command written then.
type Trip = (u64, TripReason, [f64; 2]);

/// Runs a push of 20 N · `sign` along `axis` on the mock, whose encoders never move (a
/// cut cable), and returns the first tick whose written command reached 50 N on that
/// axis and the first trip (tick, reason, command written then).
fn dead_encoder(
    axis: usize,
    sign: f64,
    mut counts: impl FnMut(u64) -> i64,
    ticks: u64,
) -> (Option<u64>, Option<Trip>) {
    let mut push = [0.0; 2];
    push[axis] = 20.0 * sign;
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = live(push, 0);
    let mut c = active(ControllerConfig::default(), &mut rig);
    let (mut reached, mut trip) = (None, None);
    for n in 1..ticks {
        rig.frame.force_raw_n = live(push, n);
        rig.frame.encoder_counts[axis] = counts(n);
        let r = c.tick(&mut rig, Tick(n));
        if r.command_n[axis].abs() >= 50.0 && reached.is_none() {
            reached = Some(n);
        }
        if let Some(t) = r.trip {
            trip.get_or_insert((n, t, r.command_n));
        }
        // The other axis is pushed by the 1 µN dither alone: its command stays far below
        // the 50 N threshold (< 1 N), so the stall is the pushed axis's.
        assert!(r.command_n[1 - axis].abs() < 1.0, "{:?}", r.command_n);
    }
    (reached, trip)
}

#[test]
fn a_dead_encoder_under_a_growing_command_trips_encoder_stall_after_20_ms() {
    // A 20 N push runs the admittance reference away from carts the mock holds at one
    // count; the position loop's command grows through 50 N (written at tick w) to the
    // 200 N limit. The readings at w+1 … w+80 are under ≥ 50 N with no count of motion:
    // the 80th, tick w + 80 (20 ms), trips, on either axis, either way, and the velocity
    // and position limits, which read the same dead encoder, never fire.
    for (axis, sign) in SIDES {
        let (reached, trip) = dead_encoder(axis, sign, |_| 0, 400);
        let w = reached.unwrap();
        let (n, reason, written) = trip.unwrap();
        assert_eq!(n, w + 80, "axis {axis} sign {sign}: {reason:?}");
        assert!(
            matches!(reason, TripReason::EncoderStall { axis: a, command_n, ticks: 80 }
                if a == axis && command_n * sign >= 50.0),
            "axis {axis} sign {sign}: {reason:?}"
        );
        assert_eq!(written, [0.0, 0.0]);
        eprintln!("encoder stall, axis {axis} sign {sign}: 50 N at tick {w}, trip at {n}");
    }
}

#[test]
fn one_count_of_motion_within_the_stall_time_resets_it() {
    // The same runaway command, but the encoder moves by one count (1 µm) every 80 ticks:
    // no 80 readings in a row are still, so 4000 ticks (1 s) at the 200 N limit do not
    // trip. One count every 81 ticks leaves 80 still readings: that trips. The encoder
    // speed (1 µm per 20 ms) is far below the velocity limit.
    let one_second = u64::from(Rate::CONTROL.hz());
    for (axis, sign) in SIDES {
        let step = |every: u64| move |n: u64| (sign as i64) * (n / every) as i64;
        let (_, trip) = dead_encoder(axis, sign, step(80), one_second);
        assert_eq!(trip, None, "axis {axis} sign {sign}");
        let (_, trip) = dead_encoder(axis, sign, step(81), one_second);
        assert!(
            matches!(trip, Some((_, TripReason::EncoderStall { axis: a, ticks: 80, .. }, _)) if a == axis),
            "axis {axis} sign {sign}: {trip:?}"
        );
    }
}

#[test]
fn a_still_encoder_under_a_steady_command_trips_only_at_50_n() {
    // The virtual spring with a still anchor (10 kN/m) on the mock, whose carts never
    // move: a push F puts the reference at F/K and the position loop then commands a
    // steady K_p F/K on carts that stay at 0 (K_p = 3.95e5 N/m on x). A 1.0 N push gives
    // 39.5 N: under the threshold, 4 s without a trip, the encoder perfectly still. A
    // 1.5 N push gives 59 N: the 80th still reading after the command reached 50 N trips.
    let run = |push: f64| {
        let mut config = ControllerConfig {
            law: LawKind::VirtualSpring,
            ..ControllerConfig::default()
        };
        config.imposed_motion.amplitude_m = 0.0;
        let mut rig = MockRig::default();
        let mut c = active(config, &mut rig);
        let (mut reached, mut last) = (None, [0.0; 2]);
        for n in 1..=16_000u64 {
            rig.frame.force_raw_n = live([push, 0.0], n);
            let r = c.tick(&mut rig, Tick(n));
            if let Some(t) = r.trip {
                return (Some((n, t)), reached, last);
            }
            if r.command_n[0].abs() >= 50.0 && reached.is_none() {
                reached = Some(n);
            }
            last = r.command_n;
        }
        (None, reached, last)
    };
    let (trip, _, last) = run(1.0);
    assert_eq!(trip, None);
    let kp = ControllerConfig::default().render.kp_n_per_m[0];
    // Steady: K_p · F/K, to 0.1 N (the 1 µN dither through the spring is far less).
    assert!((last[0] - kp * 1.0 / 10_000.0).abs() < 0.1, "{last:?}");
    let (trip, reached, _) = run(1.5);
    let w = reached.unwrap();
    assert!(
        matches!(trip, Some((n, TripReason::EncoderStall { axis: 0, ticks: 80, .. })) if n == w + 80),
        "{trip:?}, 50 N at {w}"
    );
}

/// A hand pushing `force_n` along x, with a 10 Hz wobble of `wobble_n`, into the virtual
/// spring with a still anchor (10 kN/m, 447 N s/m) on point-mass carts, with the stall
/// watchdog at `stall_ticks`. Returns the first trip over 4 s and the number of
/// distinct x counts in the last 2 s.
fn hold(force_n: f64, wobble_n: f64, stall_ticks: u32) -> (Option<TripReason>, usize) {
    let mut config = ControllerConfig {
        law: LawKind::VirtualSpring,
        ..ControllerConfig::default()
    };
    config.imposed_motion.amplitude_m = 0.0;
    config.safety.encoder_stall_ticks = stall_ticks;
    let mut rig = PointMassRig::new(config.render.feedforward_mass_kg, Rate::CONTROL);
    let h = Rate::CONTROL.period_s();
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let mut counts = std::collections::BTreeSet::new();
    for n in 1..=16_000u64 {
        let wobble = wobble_n * (2.0 * std::f64::consts::PI * 10.0 * n as f64 * h).sin();
        rig.hand_force_n = [force_n + wobble, 0.0];
        let r = c.tick(&mut rig, Tick(n));
        if let Some(t) = r.trip {
            return (Some(t), counts.len());
        }
        if n > 8000 {
            counts.insert((r.position_m[0] * 1e6).round() as i64);
        }
    }
    (None, counts.len())
}

#[test]
fn a_hand_holding_the_handle_trips_only_if_it_holds_it_within_a_count_for_20_ms() {
    // Holding against the virtual spring as the hold protocol does: 10 N, steady or with
    // a 10 Hz wobble, is under the 50 N threshold and never trips.
    for w in [0.0, 0.1] {
        assert_eq!(hold(10.0, w, 80).0, None, "10 N, wobble {w} N");
    }
    // At 55 N the motor pushes back with 55 N: over the threshold, so the count must
    // move within 20 ms. A steady push does move it here (the position loop's own limit
    // cycle on the 1 µm quantum); a wobble of 0.2 N (an assumption: a hand's isometric
    // force is not steadier at 55 N) moves the handle ±8 µm about F/K = 5.5 mm, and a
    // sinusoid of amplitude A stays within one count q of a turning point for
    // 2 sqrt(2 q / (A ω²)) = 16 ms < 20 ms: no trip in 4 s.
    for w in [0.0, 0.2] {
        let (trip, counts) = hold(55.0, w, 80);
        assert_eq!(trip, None, "55 N, wobble {w} N");
        assert!(counts >= 3, "55 N, wobble {w} N: {counts} counts");
    }
    // The contract's edge: a wobble of 0.1 N moves it ±4.5 µm (10 counts measured), and
    // the dwell at a turning point, 21 ms, is a stall by the contract: it trips, with
    // the motor's 55 N on the record. A set-up that holds that still under that force
    // on purpose sets encoder_stall_ticks = 0.
    let (trip, counts) = hold(55.0, 0.1, 80);
    assert!(
        matches!(trip, Some(TripReason::EncoderStall { axis: 0, command_n, ticks: 80 }) if (command_n + 55.0).abs() < 1.0),
        "{trip:?}"
    );
    assert!(
        counts >= 8,
        "{counts}: it was moving, by 10 counts, between dwells"
    );
    assert_eq!(hold(55.0, 0.1, 0).0, None);
}

// ---------------------------------------------------------------------------------
// Loop deadline
// ---------------------------------------------------------------------------------

/// An active controller on a still mock (live force, no push: the command stays near
/// zero) with `max_consecutive_misses` = `allowance`, run on the ticks `ticks` yields;
/// returns the first trip.
fn paced(
    mut config: ControllerConfig,
    allowance: u32,
    ticks: impl Iterator<Item = u64>,
) -> Option<(u64, TripReason)> {
    config.safety.max_consecutive_misses = allowance;
    let mut rig = MockRig::default();
    let mut c = active(config, &mut rig);
    for n in ticks {
        rig.frame.force_raw_n = live([0.0, 0.0], n);
        if let Some(t) = c.tick(&mut rig, Tick(n)).trip {
            return Some((n, t));
        }
    }
    None
}

#[test]
fn late_ticks_more_often_than_the_budget_trip_a_deadline_overrun() {
    // The shipped real-time allowance (4 skipped ticks in a row) and the default budget
    // (4 late ticks in any 64). The loop skips the tick before every multiple of P: one
    // late tick per P. At P = 16 a 64-tick window holds 4 of them: 10 000 ticks run. At
    // P = 15 the window ending at tick 75 holds the late ticks 15, 30, 45, 60 and 75:
    // five, the trip, at 75. No single gap exceeds the clock-skip allowance.
    let every = |p: u64| (1..10_000u64).filter(move |n| n % p != p - 1);
    assert_eq!(paced(ControllerConfig::default(), 4, every(16)), None);
    assert_eq!(
        paced(ControllerConfig::default(), 4, every(15)),
        Some((
            75,
            TripReason::DeadlineOverrun {
                overruns: 5,
                window_ticks: 64
            }
        ))
    );
    // Off (window 0), the same late loop runs.
    let mut off = ControllerConfig::default();
    off.safety.deadline_window_ticks = 0;
    assert_eq!(paced(off, 4, every(15)), None);
}

#[test]
fn an_odd_tick_loop_never_updates_the_motor_and_trips_at_its_fifth_late_tick() {
    // With one skipped tick allowed, a loop that runs ticks 1..=10 and then only odd
    // ticks never misses more than one deadline in a row, so no clock skip; but the
    // motor command is recomputed on even ticks (4 kHz / 2 kHz), so from tick 10 on the
    // motor holds tick 10's command while the law moves on. The late ticks are 13, 15,
    // 17, 19, 21: the fifth, tick 21, trips, 11 ticks (2.75 ms) after the last motor
    // update. Without the watchdog the loop runs on, open loop, for 2000 ticks.
    let run = |window: u32| {
        let mut config = ControllerConfig::default();
        config.safety.max_consecutive_misses = 1;
        config.safety.deadline_window_ticks = window;
        let mut rig = MockRig::default();
        // A 5 N push, so the command changes at every motor update.
        let mut c = active(config, &mut rig);
        let ticks = (1..=10u64).chain((11..4000).step_by(2));
        let (mut held, mut trip, mut ran) = (None, None, 0);
        for n in ticks {
            rig.frame.force_raw_n = live([5.0, 0.0], n);
            let r = c.tick(&mut rig, Tick(n));
            ran += 1;
            if n == 10 {
                assert!(r.motor_update);
                held = Some(r.command_n);
            }
            if let Some(t) = r.trip {
                trip = Some((n, t, r.command_n));
                break;
            }
            if n > 10 {
                assert!(!r.motor_update, "tick {n}");
                assert_eq!(Some(r.command_n), held, "tick {n}: the held command");
            }
        }
        (trip, ran, held)
    };
    let (trip, _, held) = run(64);
    assert!(held.unwrap()[0] > 1.0, "{held:?}: a command worth holding");
    assert_eq!(
        trip,
        Some((
            21,
            TripReason::DeadlineOverrun {
                overruns: 5,
                window_ticks: 64
            },
            [0.0, 0.0]
        ))
    );
    let (trip, ran, _) = run(0);
    assert_eq!((trip, ran), (None, 10 + 1995));
}

#[test]
fn gaps_while_inactive_do_not_count_against_the_active_loop() {
    // Inactive, the controller commands zero, so its gaps are harmless: every other tick
    // skipped for 400 ticks, then activation and 1000 consecutive ticks. With the
    // default allowance (0) and budget nothing trips: neither the clock skip nor the
    // deadline watchdog judged the inactive gaps.
    let mut rig = MockRig::default();
    let mut c = Controller::new(ControllerConfig::default()).unwrap();
    for n in (0..400u64).step_by(2) {
        rig.frame.force_raw_n = live([0.0, 0.0], n / 2);
        assert_eq!(c.tick(&mut rig, Tick(n)).mode, Mode::Inactive);
    }
    c.activate().unwrap();
    for n in 399..1400u64 {
        rig.frame.force_raw_n = live([0.0, 0.0], n);
        assert_eq!(c.tick(&mut rig, Tick(n)).trip, None, "tick {n}");
    }
}

// ---------------------------------------------------------------------------------
// Non-finite commands
// ---------------------------------------------------------------------------------

#[test]
fn clamp_never_sends_a_nonfinite_command_nor_turns_it_into_the_limit() {
    // Different limits per axis (200, 150 N) so an index slip shows. A NaN or infinite
    // axis becomes exactly 0, flagged; a finite one beyond ±limit becomes ±limit,
    // flagged; inside, it passes unchanged.
    let config = SafetyConfig {
        force_limit_n: [200.0, 150.0],
        ..SafetyConfig::default()
    };
    let m = SafetyMonitor::new(&config);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(m.clamp([bad, 10.0]), ([0.0, 10.0], [true, false]), "{bad}");
        assert_eq!(
            m.clamp([-10.0, bad]),
            ([-10.0, 0.0], [false, true]),
            "{bad}"
        );
        assert_eq!(
            SafetyMonitor::nonfinite_command([1.0, bad]),
            Some(TripReason::NonFiniteCommand { axis: 1 })
        );
        assert_eq!(
            SafetyMonitor::nonfinite_command([bad, bad]),
            Some(TripReason::NonFiniteCommand { axis: 0 })
        );
    }
    assert_eq!(SafetyMonitor::nonfinite_command([f64::MAX, -0.0]), None);
    assert_eq!(m.clamp([1e9, -1e9]), ([200.0, -150.0], [true, true]));
    assert_eq!(m.clamp([-1e9, 1e9]), ([-200.0, 150.0], [true, true]));
    assert_eq!(m.clamp([199.0, -149.0]), ([199.0, -149.0], [false, false]));
}

#[test]
fn a_law_driven_to_overflow_trips_nonfinite_command_and_writes_zero() {
    // A force word of ±f64::MAX (finite: a corrupted reading the finite check lets
    // through) drives the admittance's acceleration to ~3.6e307 m/s²; within a few
    // ticks the renderer's m ẍ + K_p e + K_d ė overflows to ±inf or NaN. The old clamp
    // would have sent an infinite command as the ±200 N limit; now the tick trips and
    // writes zero. Every command written before is finite and within the limit. The
    // reading's last bit moves (a live sensor), so only this check can fire first.
    for (axis, sign) in SIDES {
        let word = |n: u64| {
            let m = f64::from_bits(f64::MAX.to_bits() - n % 2);
            let mut f = [0.0, 0.0];
            f[axis] = sign * m;
            live(f, n)
        };
        let mut rig = MockRig::default();
        rig.frame.force_raw_n = word(0);
        let mut c = active(ControllerConfig::default(), &mut rig);
        let mut trip = None;
        for n in 1..100u64 {
            rig.frame.force_raw_n = word(n);
            let r = c.tick(&mut rig, Tick(n));
            let written = rig.last_write.unwrap().1.force_n;
            assert!(
                written.iter().all(|f| f.is_finite() && f.abs() <= 200.0),
                "tick {n}: {written:?}"
            );
            if let Some(t) = r.trip {
                trip = Some((n, t, written));
                break;
            }
        }
        let (n, reason, written) = trip.unwrap();
        assert_eq!(
            reason,
            TripReason::NonFiniteCommand { axis },
            "axis {axis} sign {sign}"
        );
        assert_eq!(written, [0.0, 0.0]);
        assert_eq!(c.mode(), Mode::Fault);
        eprintln!("non-finite command, axis {axis} sign {sign}: tripped at tick {n}");
    }
}
