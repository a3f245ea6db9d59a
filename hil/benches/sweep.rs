//! A run inside a sweep against a standalone rehearsal of the same session, in the same
//! run (README § Requirements: within 10 %), and a shard of four runs on one and two
//! worker threads (throughput with cores, as a ratio measured together).
//!
//! The session: the seed protocol's first 10 reaches with 8 pulses (1 per angle), the
//! sweep's run 0 (its drawn subject and seed). "Standalone" is what `rigtwin rehearse`
//! does for it: rehearse, then build the report (D and K against the truth).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::atomic::AtomicBool;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin::rehearse::{self, Options};
use rigtwin::sweep::{self, Run, SweepFile};

/// The sweep tests' small sweep (`tests/slurm/small-sweep.toml`) with one amplitude and
/// four subjects, seed 1.
fn sweep_text() -> String {
    include_str!("../tests/slurm/small-sweep.toml")
        .replace(
            "\"controller.force_pulse.amplitude_n\" = [10.0, 15.0]",
            "\"controller.force_pulse.amplitude_n\" = [15.0]",
        )
        .replace("subjects = 2", "subjects = 4")
        .replace("seed = 5", "seed = 1")
}

fn bench(c: &mut Criterion) {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("bench.toml");
    std::fs::write(&path, sweep_text()).unwrap();
    let s = SweepFile::load(&path).unwrap();
    let run = Run::at(&s, 0);
    let protocol = sweep::run::protocol_of(&s, &run);
    let mut group = c.benchmark_group("sweep run vs standalone rehearsal");
    group.sample_size(10);
    group.bench_function("standalone rehearse + report", |b| {
        b.iter(|| {
            let dir = tempfile::tempdir().unwrap();
            let opts = Options {
                subjects: 1,
                seed: run.session_seed(&s),
                out_dir: dir.path().join("r"),
                jobs: 1,
                max_trials: s.max_trials,
            };
            let r = rehearse::rehearse(&protocol, &opts, &|_| {}, &AtomicBool::new(false)).unwrap();
            rigtwin::report::build(&r)
        });
    });
    group.bench_function("sweep run_one", |b| {
        b.iter(|| {
            let dir = tempfile::tempdir().unwrap();
            sweep::run::run_one(&s, &run, dir.path(), None).unwrap()
        });
    });
    group.finish();
    let mut group = c.benchmark_group("sweep shard of 4 runs");
    group.sample_size(10);
    for jobs in [1, 2] {
        group.bench_function(format!("{jobs} worker(s)"), |b| {
            b.iter(|| {
                let dir = tempfile::tempdir().unwrap();
                sweep::run_runs(&s, &[0, 1, 2, 3], dir.path(), None, jobs, &|_, _| {}).unwrap()
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
