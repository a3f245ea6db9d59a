//! What streaming to rerun costs: a 32-trial 1 kHz session (the shared `example-friction`
//! recording) read and logged to an in-memory `.rrd`, against the same session only read.
//! The ratio of the two is the claim; both run in the same process, back to back.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin::session::Session;
use rigtwin::viz::{Viewer, log_session};

const SESSION: &str = "/work/shared/recordings/example-friction";

/// Reads the session and logs it to memory; the size of the `.rrd` (0 on any error, which
/// the assertion in `bench` turns into a failed run).
fn read_and_log(dir: &Path) -> usize {
    let Ok(session) = Session::read(dir) else {
        return 0;
    };
    let Ok(mut viewer) = Viewer::in_memory("rigtwin", "bench") else {
        return 0;
    };
    if log_session(&mut viewer, &session).is_err() {
        return 0;
    }
    viewer
        .finish()
        .ok()
        .flatten()
        .map_or(0, |bytes| bytes.len())
}

fn bench(c: &mut Criterion) {
    let dir = Path::new(SESSION);
    match Session::read(dir) {
        Ok(session) => assert_eq!(session.trials.len(), 32, "the benchmark session changed"),
        Err(err) => panic!("cannot read {SESSION}: {err}"),
    }
    assert!(read_and_log(dir) > 0, "logging {SESSION} failed");
    let mut group = c.benchmark_group("example-friction 32 trials 1 kHz");
    group.sample_size(10);
    group.bench_function("read", |b| b.iter(|| black_box(Session::read(dir)).is_ok()));
    group.bench_function("read + log to memory rrd", |b| {
        b.iter(|| black_box(read_and_log(dir)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
