//! The real-time path does not allocate: a counting global allocator sees zero
//! allocations over 10 000 active ticks with both perturbations firing, in both laws,
//! nor while each watchdog counts up to its trip and the trip is logged.
//! The count is per thread (a `const` thread-local, which itself never allocates), so
//! the test harness's own threads, which may allocate at any moment, cannot be mistaken
//! for the controller.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::config::Axis;
use rigtwin_device::perturb::Crossing;
use rigtwin_device::perturb::force_pulse::PulseTrigger;
use rigtwin_device::perturb::position::PositionTrigger;
use rigtwin_device::safety::TripReason;
use rigtwin_device::testing::alloc::{Counting, allocations};
use rigtwin_device::testing::{MockRig, PointMassRig};
use rigtwin_device::{Controller, ControllerConfig, LawKind, Mode, Rate, Tick};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs 10 000 active ticks, re-arming both perturbations whenever they are idle, and
/// returns the allocations counted during the loop and the number of pulses and pushes.
fn count(law: LawKind) -> (u64, u32, u32, u32) {
    let config = ControllerConfig {
        law,
        ..ControllerConfig::default()
    };
    let mut rig = PointMassRig::new(config.render.feedforward_mass_kg, Rate::CONTROL);
    rig.hand_force_n = [2.0, -1.0];
    rig.hand_stiffness_n_per_m = [300.0, 300.0];
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let (mut pulses, mut pushes, mut both) = (0, 0, 0);
    let before = allocations();
    for n in 1..=10_000u64 {
        if !c.force_pulse_status().is_running() && n % 1000 == 1 {
            let trigger = if n % 2000 == 1 {
                PulseTrigger::AtTick(Tick(n + 10))
            } else {
                PulseTrigger::LineCrossing {
                    axis: Axis::X,
                    position_m: -1.0,
                    direction: Crossing::Either,
                }
            };
            c.arm_force_pulse(0.5 + n as f64 * 1e-4, trigger).unwrap();
            pulses += 1;
        }
        if !c.position_perturbation_status().is_running() && n % 1500 == 1 {
            c.arm_position_perturbation(0.785, PositionTrigger::AtTick(Tick(n + 5)))
                .unwrap();
            pushes += 1;
        }
        let r = c.tick(&mut rig, Tick(n));
        assert_eq!(r.mode, Mode::Active);
        if r.pert_force_n != [0.0, 0.0] && r.pert_position_m != [0.0, 0.0] {
            both += 1;
        }
    }
    let after = allocations();
    (after - before, pulses, pushes, both)
}

#[test]
fn ten_thousand_active_ticks_allocate_nothing() {
    for law in [LawKind::Admittance, LawKind::VirtualSpring] {
        let (allocs, pulses, pushes, both) = count(law);
        eprintln!(
            "{law:?}: {allocs} allocations over 10 000 ticks ({pulses} pulses, {pushes} pushes armed; {both} ticks with both running)"
        );
        // Exactly zero: any allocation inside tick would be a real-time hazard.
        assert_eq!(allocs, 0, "{law:?}");
        // Both perturbations really ran, and overlapped for a while.
        assert!(pulses >= 5 && pushes >= 5 && both > 100, "{both}");
    }
}

/// One watchdog case: a controller built and activated outside the count, a scripted
/// rig, and what the rig does before each tick.
struct Case {
    controller: Controller,
    rig: MockRig,
    ticks: Vec<u64>,
    script: fn(&mut MockRig, u64),
}

fn case(config: ControllerConfig, ticks: Vec<u64>, script: fn(&mut MockRig, u64)) -> Case {
    let mut rig = MockRig::default();
    let mut controller = Controller::new(config).unwrap();
    controller.tick(&mut rig, Tick(0));
    controller.activate().unwrap();
    Case {
        controller,
        rig,
        ticks,
        script,
    }
}

/// A live 5 N push along x (its last bits move with period 3).
fn live(rig: &mut MockRig, n: u64) {
    rig.frame.force_raw_n = [5.0 + 1e-6 * (n % 3) as f64, 0.0];
}

#[test]
fn each_watchdog_counts_to_its_trip_without_allocating() {
    let mut late = ControllerConfig::default();
    late.safety.max_consecutive_misses = 4;
    let mut cases = [
        // A frozen reading: 40 identical readings.
        case(ControllerConfig::default(), (1..200).collect(), |r, _| {
            r.frame.force_raw_n = [0.5, 0.3];
        }),
        // A dead encoder under the runaway command: 80 still readings at >= 50 N.
        case(ControllerConfig::default(), (1..400).collect(), live),
        // A loop late at every 15th tick: 5 late ticks in 64.
        case(late, (1..400).filter(|n| n % 15 != 14).collect(), live),
        // A force word of f64::MAX: the command overflows.
        case(ControllerConfig::default(), (1..100).collect(), |r, n| {
            r.frame.force_raw_n = [f64::from_bits(f64::MAX.to_bits() - n % 2), 0.0];
        }),
    ];
    let before = allocations();
    let mut trips = [None; 4];
    for (case, trip) in cases.iter_mut().zip(&mut trips) {
        for &n in &case.ticks {
            (case.script)(&mut case.rig, n);
            if let Some(t) = case.controller.tick(&mut case.rig, Tick(n)).trip {
                *trip = Some(t);
                break;
            }
        }
    }
    let allocs = allocations() - before;
    // Every watchdog really counted to its trip, each the one meant.
    assert!(
        matches!(trips[0], Some(TripReason::StaleForce { .. })),
        "{trips:?}"
    );
    assert!(
        matches!(trips[1], Some(TripReason::EncoderStall { .. })),
        "{trips:?}"
    );
    assert!(
        matches!(trips[2], Some(TripReason::DeadlineOverrun { .. })),
        "{trips:?}"
    );
    assert!(
        matches!(trips[3], Some(TripReason::NonFiniteCommand { .. })),
        "{trips:?}"
    );
    // Exactly zero, as for the active loop above.
    assert_eq!(allocs, 0);
}
