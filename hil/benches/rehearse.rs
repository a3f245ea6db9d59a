//! Speed of the lock-step co-simulation on the default reach-perturb protocol.
//!
//! A representative slice: the first 4 trials of the default schedule for subject 1
//! (seed 1), which hold one perturbed trial and its unperturbed twin, all recorded
//! through the crash-safe writer; then the same slice on 1 and 2 worker threads in
//! the same run, so the speed-up is a ratio measured together. Throughput is given in
//! control ticks: divide the reported ticks/s by 4000 for the real-time factor
//! (simulated seconds per wall-clock second).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::atomic::AtomicBool;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options, TrialTask};

fn bench(c: &mut Criterion) {
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let trials = 4;
    let plans = rehearse::schedule(&protocol, 1, 1);
    let perturbed = plans
        .iter()
        .take(trials)
        .filter(|p| {
            matches!(
                p.task,
                TrialTask::Reach {
                    angle_deg: Some(_),
                    ..
                }
            )
        })
        .count();
    let ticks_per_trial = rehearse::trial::trial_ticks(&protocol);
    let ticks = ticks_per_trial * (trials + perturbed) as u64;
    let mut group = c.benchmark_group("rehearse reach-perturb slice");
    group.sample_size(10);
    group.throughput(Throughput::Elements(ticks));
    for jobs in [1, 2] {
        group.bench_function(format!("{trials} trials, {jobs} job(s)"), |b| {
            b.iter(|| {
                let tmp = tempfile::tempdir().unwrap();
                let opts = Options {
                    subjects: 1,
                    seed: 1,
                    out_dir: tmp.path().join("r"),
                    jobs,
                    max_trials: Some(trials),
                };
                rehearse::rehearse(&protocol, &opts, &|_| {}, &AtomicBool::new(false)).unwrap()
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
