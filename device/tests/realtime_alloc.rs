//! The real-time path does not allocate: a counting global allocator sees zero
//! allocations over 10 000 active ticks with both perturbations firing, in both laws.
//! The count is per thread (a `const` thread-local, which itself never allocates), so
//! the test harness's own threads, which may allocate at any moment, cannot be mistaken
//! for the controller.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::config::Axis;
use rigtwin_device::perturb::Crossing;
use rigtwin_device::perturb::force_pulse::PulseTrigger;
use rigtwin_device::perturb::position::PositionTrigger;
use rigtwin_device::testing::PointMassRig;
use rigtwin_device::testing::alloc::{Counting, allocations};
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
