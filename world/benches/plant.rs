//! One plant step: arm torques + motor command + rapier step + sensors, against the
//! closed-form reduced model of the same plant (the ratio is the claim).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin_device::{MotorCommand, RigIo, Tick};
use rigtwin_world::{ReducedPlant, RigConfig, SimRig};

fn plant(c: &mut Criterion) {
    let cfg = RigConfig::default();
    let mut g = c.benchmark_group("plant_step");
    let mut rig = SimRig::with_seed(cfg.clone(), 1).unwrap();
    let mut k = 0u64;
    g.bench_function("rapier_full", |b| {
        b.iter(|| {
            // A small oscillating load keeps the plant moving without leaving the workspace.
            let s = ((k % 4000) as f64 * 1.5e-3).sin();
            rig.set_arm_torques([0.3 * s, -0.2 * s]).unwrap();
            let frame = rig.read(Tick(k)).unwrap();
            rig.write(
                Tick(k),
                MotorCommand {
                    force_n: [2.0 * s, 3.0 * s],
                },
            )
            .unwrap();
            rig.step().unwrap();
            k += 1;
            black_box(frame)
        })
    });
    // The same step without rapier's stabilisation pass and joint warm-start, to show
    // what the chosen settings cost (the crate docs give its accuracy).
    let mut cheap = cfg.clone();
    cheap.solver.stabilization_iterations = 0;
    cheap.solver.warmstart_joints = false;
    let mut rig2 = SimRig::with_seed(cheap, 1).unwrap();
    let mut k = 0u64;
    g.bench_function("rapier_full_no_stabilisation_no_warmstart", |b| {
        b.iter(|| {
            let s = ((k % 4000) as f64 * 1.5e-3).sin();
            rig2.set_arm_torques([0.3 * s, -0.2 * s]).unwrap();
            let frame = rig2.read(Tick(k)).unwrap();
            rig2.write(
                Tick(k),
                MotorCommand {
                    force_n: [2.0 * s, 3.0 * s],
                },
            )
            .unwrap();
            rig2.step().unwrap();
            k += 1;
            black_box(frame)
        })
    });
    let mut red = ReducedPlant::new(&cfg).unwrap();
    let mut k = 0u64;
    g.bench_function("reduced_closed_form", |b| {
        b.iter(|| {
            let s = ((k % 4000) as f64 * 1.5e-3).sin();
            red.step([2.0 * s, 3.0 * s], [0.3 * s, -0.2 * s]);
            k += 1;
            black_box(red.sensor_n())
        })
    });
    g.finish();
}

criterion_group!(benches, plant);
criterion_main!(benches);
