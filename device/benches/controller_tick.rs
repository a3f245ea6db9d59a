//! Cost of one controller tick (read → update → write against point-mass carts), for
//! both laws, with a force pulse and a position perturbation running. The 4 kHz loop
//! leaves 250 µs per tick; the ratio to that budget is the claim to read off.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin_device::perturb::force_pulse::PulseTrigger;
use rigtwin_device::perturb::position::PositionTrigger;
use rigtwin_device::testing::PointMassRig;
use rigtwin_device::{Controller, ControllerConfig, LawKind, Rate, Tick};

fn ticks(c: &mut Criterion) {
    for law in [LawKind::Admittance, LawKind::VirtualSpring] {
        let config = ControllerConfig {
            law,
            ..ControllerConfig::default()
        };
        let mut rig = PointMassRig::new(config.render.feedforward_mass_kg, Rate::CONTROL);
        rig.hand_stiffness_n_per_m = [300.0, 300.0];
        let mut ctl = Controller::new(config).unwrap();
        ctl.tick(&mut rig, Tick(0));
        ctl.activate().unwrap();
        let mut n = 1u64;
        c.bench_function(&format!("tick/{law:?}"), |b| {
            b.iter(|| {
                // Keep a pulse and a push running most of the time (600 and 1200 ticks).
                if n % 700 == 1 {
                    ctl.arm_force_pulse(0.5, PulseTrigger::AtTick(Tick(n)))
                        .unwrap();
                }
                if n % 1300 == 1 {
                    ctl.arm_position_perturbation(0.785, PositionTrigger::AtTick(Tick(n)))
                        .unwrap();
                }
                let r = ctl.tick(&mut rig, Tick(n));
                n += 1;
                black_box(r)
            });
        });
    }
}

criterion_group!(benches, ticks);
criterion_main!(benches);
