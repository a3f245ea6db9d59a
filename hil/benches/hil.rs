//! Hardware in the loop, measured.
//!
//! 1. The cost of the wire per tick: one reach trial's 14 000 ticks stepped in lock step
//!    with the in-process `SimPlant`, and with the same plant behind the wire
//!    (`WiredPlant`: every frame and command encoded, sent over an in-process channel,
//!    decoded), in the same run; the ratio is the wire's share of a tick.
//! 2. The wall clock at 4 kHz: 10⁵ ticks of an empty loop body on `WallClock`, quiet and
//!    with a CPU hog spinning on another thread, printed as HDR percentiles of the
//!    wake-up latency and the missed deadlines per 10⁵ (not criterion: what matters is
//!    the distribution, not a mean). Skip it with `RIGTWIN_BENCH_CLOCK=0`; it takes 50 s.
//!
//! `cargo bench --profile release -p rigtwin --bench hil`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group};
use rigtwin::cosim::wired::WiredPlant;
use rigtwin::cosim::{self, Clock, CoSim, LockStep, WallClock};
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{schedule, trial};
use rigtwin_device::{Rate, Tick};
use rigtwin_wire::{PlantEnd, PlantLimits, RigLimits, WireRig, channel_pair};

fn wire_cost(c: &mut Criterion) {
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let subject = protocol.subjects.draw(42, 1);
    let plan = schedule(&protocol, 42, 1)[0].clone();
    let n = trial::trial_ticks(&protocol);
    let mut group = c.benchmark_group("co-simulation step, one reach");
    group.sample_size(10);
    group.throughput(Throughput::Elements(n));
    group.bench_function("in-process SimPlant", |b| {
        b.iter(|| {
            let mut sim = trial::build(&protocol, &subject, 42, &plan, true).unwrap();
            cosim::run(&mut sim, &mut LockStep, n).unwrap();
            sim.finish()
        });
    });
    group.bench_function("SimPlant behind the wire (channel)", |b| {
        b.iter(|| {
            let p = trial::parts(&protocol, &subject, 42, &plan, true).unwrap();
            let (ce, pe) = channel_pair(8);
            let wired = WiredPlant::new(
                WireRig::new(ce, RigLimits::default()).unwrap(),
                PlantEnd::new(pe, PlantLimits::default()).unwrap(),
                p.plant,
            );
            let mut sim = CoSim::new(p.controller, p.driver, wired, p.recorder);
            cosim::run(&mut sim, &mut LockStep, n).unwrap();
            sim.finish()
        });
    });
    group.finish();
}

/// 10⁵ ticks on the wall clock; prints one row of percentiles.
fn clock_run(label: &str) {
    let mut clock = WallClock::new(Rate::CONTROL, Duration::ZERO).unwrap();
    let n = 100_000;
    let mut k = 0;
    while k < n {
        k = clock.wait(Tick(k), Tick(n - 1)).0 + 1;
    }
    let t = clock.summary();
    println!(
        "{label:<28} ticks {:>6}  missed {:>5} ({:>6.1} per 1e5, longest run {:>3})  wake p50 {:>6.1} p99 {:>6.1} p99.9 {:>6.1} max {:>8.1} µs",
        t.ticks,
        t.missed_deadlines,
        t.misses_per_1e5(),
        t.max_consecutive_misses,
        t.wake_latency.p50_us,
        t.wake_latency.p99_us,
        t.wake_latency.p999_us,
        t.wake_latency.max_us
    );
}

fn clock_distribution() {
    if std::env::var("RIGTWIN_BENCH_CLOCK").is_ok_and(|v| v == "0") {
        return;
    }
    println!("\nWallClock at 4 kHz, 1e5 deadlines, empty loop body:");
    clock_run("quiet");
    let stop = Arc::new(AtomicBool::new(false));
    let hog = {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            let mut x = 0_u64;
            while !stop.load(Ordering::Relaxed) {
                x = std::hint::black_box(x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1));
            }
            x
        })
    };
    clock_run("one CPU hog beside it");
    stop.store(true, Ordering::Relaxed);
    let _ = hog.join();
}

criterion_group!(benches, wire_cost);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    clock_distribution();
}
