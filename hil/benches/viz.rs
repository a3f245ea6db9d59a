//! What streaming to rerun costs.
//!
//! 1. `rigtwin rehearse --rerun save=`: the first 8 trials of the default reach-perturb
//!    protocol (seed 1, 2 worker threads, as the command line runs them) rehearsed and
//!    reported, against the same plus the whole rehearsal written to an `.rrd` file (every
//!    sample, the muscle activations, the ellipses, the events), logged as the command line
//!    does: each trial as it is written, overlapped with the simulation. The requirement (README § Requirements) is a slowdown of at most 20 %;
//!    both run in the same process, interleaved, and the ratio of their medians is printed.
//! 2. A 32-trial 1 kHz session (the shared `example-friction` recording) read and logged to
//!    an in-memory `.rrd`, against the same session only read.

use std::hint::black_box;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options, RehearsalObserver};
use rigtwin::report;
use rigtwin::session::Session;
use rigtwin::viz::{RehearsalLogger, Target, Viewer, log_session, rehearsal_recording_id};

/// Trials of the reach-perturb schedule per rehearsal.
const TRIALS: usize = 8;

/// Interleaved pairs of runs (without, with `--rerun save=`) for the printed ratio.
const PAIRS: usize = 7;

/// What `rigtwin rehearse` does: rehearse, build and write the report; with `rrd`, also
/// stream the rehearsal to that file, each trial as it is written (overlapped with the
/// simulation), the ellipses after the report. Returns the number of trials (0 on any error,
/// which the assertion in `bench` turns into a failed run).
fn rehearse_once(protocol: &Protocol, rrd: bool) -> usize {
    let Ok(tmp) = tempfile::tempdir() else {
        return 0;
    };
    let out = tmp.path().join("r");
    let opts = Options {
        subjects: 1,
        seed: 1,
        out_dir: out.clone(),
        jobs: 2,
        max_trials: Some(TRIALS),
    };
    let mut viewer = None;
    if rrd {
        let target = Target::Save(tmp.path().join("r.rrd"));
        let Ok(id) = rehearsal_recording_id(protocol, &opts) else {
            return 0;
        };
        let Ok(v) = Viewer::new(&target, "rigtwin", &id) else {
            return 0;
        };
        viewer = Some(v);
    }
    let mut logger = viewer
        .as_mut()
        .map(|v| RehearsalLogger::new(v, protocol, opts.seed));
    let observer: &mut dyn RehearsalObserver = match logger.as_mut() {
        Some(l) => l,
        None => &mut (),
    };
    let Ok(rehearsal) =
        rehearse::rehearse_observed(protocol, &opts, &|_| {}, &AtomicBool::new(false), observer)
    else {
        return 0;
    };
    let rep = report::build(&rehearsal);
    if report::write(&rep, &out).is_err() {
        return 0;
    }
    if let Some(logger) = logger
        && logger.finish(&rehearsal, &rep).is_err()
    {
        return 0;
    }
    if let Some(viewer) = viewer
        && viewer.finish().is_err()
    {
        return 0;
    }
    rehearsal.subjects.iter().map(|s| s.trials.len()).sum()
}

fn median_s(protocol: &Protocol, rrd: bool, runs: usize) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            black_box(rehearse_once(protocol, rrd));
            start.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn bench_rehearse(c: &mut Criterion) {
    let protocol = match Protocol::builtin("reach-perturb") {
        Ok(p) => p,
        Err(err) => panic!("the shipped reach-perturb protocol: {err}"),
    };
    assert_eq!(
        rehearse_once(&protocol, true),
        TRIALS,
        "rehearse --rerun failed"
    );
    let mut group = c.benchmark_group(format!("rehearse reach-perturb {TRIALS} trials"));
    group.sample_size(10);
    group.bench_function("rehearse + report", |b| {
        b.iter(|| black_box(rehearse_once(&protocol, false)))
    });
    group.bench_function("rehearse + report + --rerun save=", |b| {
        b.iter(|| black_box(rehearse_once(&protocol, true)))
    });
    group.finish();
    // The ratio from interleaved runs, so that load from elsewhere hits both alike.
    let (mut plain, mut saved) = (Vec::new(), Vec::new());
    for _ in 0..PAIRS {
        plain.push(median_s(&protocol, false, 1));
        saved.push(median_s(&protocol, true, 1));
    }
    plain.sort_by(f64::total_cmp);
    saved.sort_by(f64::total_cmp);
    let (p, s) = (plain[PAIRS / 2], saved[PAIRS / 2]);
    println!(
        "rehearse --rerun save= overhead: median {s:.3} s vs {p:.3} s without, ratio {:.3} (bound 1.20)",
        s / p
    );
}

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

criterion_group!(benches, bench_rehearse, bench);
criterion_main!(benches);
