//! Speed of `diagnose` on a 32-trial session (the shared sessions' size), on 1 and 2
//! rayon threads in the same run so that the speed-up is a ratio measured together.
//! The session is rehearsed once from the shipped `reach-perturb` protocol at 1 kHz.
//! The requirement (README § Requirements, diagnosis speed): under 60 s on 2 cores.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::atomic::AtomicBool;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options};
use rigtwin::session::Session;
use rigtwin_diagnose::{DiagnoseOptions, diagnose};

fn bench(c: &mut Criterion) {
    let tmp = tempfile::tempdir().unwrap();
    let mut protocol = Protocol::builtin("reach-perturb").unwrap();
    protocol.recording.rate_hz = 1000;
    protocol.recording.truth_columns = false;
    let opts = Options {
        subjects: 1,
        seed: 1,
        out_dir: tmp.path().join("out"),
        jobs: 2,
        max_trials: Some(32),
    };
    let r = rehearse::rehearse(&protocol, &opts, &|_| {}, &AtomicBool::new(false)).unwrap();
    let session = Session::read(&r.subjects[0].dir).unwrap();
    let mut group = c.benchmark_group("diagnose 32 trials at 1 kHz");
    group.sample_size(10);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        group.bench_function(format!("{threads} threads"), |b| {
            b.iter(|| pool.install(|| diagnose(&session, &DiagnoseOptions::default()).unwrap()));
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
