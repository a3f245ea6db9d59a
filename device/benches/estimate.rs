//! Speed of the estimators on a full session: 24 perturbed trials (3 x the 8 seed
//! angles) of 3.5 s at 4 kHz for the Börner estimator (target < 50 ms), and one
//! 25-cycle imposed-motion trial at 250 Hz for the Piovesan windows.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::needless_range_loop)]

#[path = "../tests/estimate_support.rs"]
mod support;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin_device::estimate::{
    Admittance, BornerConfig, ImposedMotionTrial, PerturbedTrial, PiovesanConfig,
    PositionPerturbation, VariationalMode, estimate_involuntary_impedance, windowed_impedance,
};
use std::hint::black_box;
use support::*;

fn borner(c: &mut Criterion) {
    let m = add(&add(&M_ADM, &M_HANDLE), &M_ARM);
    let d = add(&D_ADM, &D_TABLE1);
    let sims: Vec<SimTrial> = (0..3)
        .flat_map(|_| ANGLES_DEG.iter())
        .map(|phi| {
            simulate_pulse(
                &m,
                &d,
                &K_TABLE1,
                *phi,
                15.0,
                0.15,
                4000.0,
                3.5,
                1.5,
                1,
                [0.0, 0.4],
            )
        })
        .collect();
    let trials: Vec<PerturbedTrial<'_>> = sims
        .iter()
        .map(|s| PerturbedTrial {
            x_m: [&s.x_m[0], &s.x_m[1]],
            u_pert_n: [&s.u_n[0], &s.u_n[1]],
            onset_index: s.onset_index,
        })
        .collect();
    let adm = Admittance {
        m_adm_kg: M_ADM,
        d_adm_ns_per_m: D_ADM,
        m_handle_kg: M_HANDLE,
    };
    let seed = BornerConfig::default();
    let consistent = BornerConfig {
        mode: VariationalMode::Consistent,
        ..seed
    };
    let mut g = c.benchmark_group("borner_24_trials_3.5s_4kHz");
    g.sample_size(10);
    g.bench_function("seed_mode", |b| {
        b.iter(|| {
            estimate_involuntary_impedance(black_box(&trials), 4000.0, &adm, &M_ARM, &seed).unwrap()
        })
    });
    g.bench_function("consistent_mode", |b| {
        b.iter(|| {
            estimate_involuntary_impedance(black_box(&trials), 4000.0, &adm, &M_ARM, &consistent)
                .unwrap()
        })
    });
    g.finish();
}

fn piovesan(c: &mut Criterion) {
    let mk = [[1.87, 0.0], [0.0, 1.87]];
    let trial = imposed_motion(
        &mk,
        &[[6.0, 1.5], [1.5, 5.0]],
        &[[615.0, 40.0], [40.0, 507.0]],
        250.0,
        25,
        1,
        0.0,
        7,
    );
    let perts: Vec<PositionPerturbation> = trial
        .perturbations
        .iter()
        .map(|(o, c)| PositionPerturbation {
            onset_index: *o,
            cycle: *c,
        })
        .collect();
    let view = ImposedMotionTrial {
        x_m: [&trial.x_m[0], &trial.x_m[1]],
        force_n: [&trial.force_n[0], &trial.force_n[1]],
        perturbations: &perts,
        n_cycles: trial.n_cycles,
    };
    c.bench_function("piovesan_25_cycles_250Hz_16_windows", |b| {
        b.iter(|| {
            windowed_impedance(black_box(&view), 250.0, &mk, &PiovesanConfig::default()).unwrap()
        })
    });
}

criterion_group!(benches, borner, piovesan);
criterion_main!(benches);
