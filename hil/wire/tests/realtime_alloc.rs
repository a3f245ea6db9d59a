//! The per-tick calls of both ends — `WireRig::read`/`write`, `PlantEnd::poll_command`/
//! `applied_force`/`send_frame` — do not allocate: a counting global allocator sees
//! zero allocations over 10 000 lock-step ticks over the in-process channel, plain and
//! with every fault injected in both directions (so the error paths, the injector's
//! queue and the sequence bookkeeping all run). The count is per thread (a `const`
//! thread-local, which itself never allocates), so the test harness's other threads
//! cannot be mistaken for the link.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::testing::alloc::{Counting, allocations};
use rigtwin_device::{Mode, MotorCommand, Rate, RigIo, SensorFrame, Tick};
use rigtwin_wire::{
    FaultInjector, FaultSpec, Faulty, PlantEnd, PlantLimits, RigLimits, Transport, WireRig,
    channel_pair,
};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs 10 000 lock-step ticks and returns the allocations counted in the loop, the
/// frames the controller accepted and the reads that failed.
fn count<A: Transport, B: Transport>(
    rig: &mut WireRig<A>,
    plant: &mut PlantEnd<B>,
) -> (u64, u64, u64) {
    rig.set_mode(Mode::Active);
    let mut failed_reads = 0u64;
    let mut applied_sum = 0.0;
    let before = allocations();
    for n in 0..10_000u64 {
        let now = Tick(n);
        let _ = plant.poll_command(now).unwrap();
        applied_sum += plant.applied_force(now)[0];
        let frame = SensorFrame {
            encoder_counts: [n as i64, 0],
            force_raw_n: [1.0, 0.5],
            estop: false,
        };
        plant.send_frame(now, frame).unwrap();
        if rig.read(now).is_err() {
            failed_reads += 1;
        }
        rig.write(
            now,
            MotorCommand {
                force_n: [1.0, 0.0],
            },
        )
        .unwrap();
    }
    let after = allocations();
    assert!(applied_sum > 9000.0, "{applied_sum}");
    (after - before, rig.counters().accepted, failed_reads)
}

#[test]
fn ten_thousand_ticks_over_the_channel_allocate_nothing() {
    let (a, b) = channel_pair(64);
    let mut rig = WireRig::new(a, RigLimits::default()).unwrap();
    let mut plant = PlantEnd::new(b, PlantLimits::default()).unwrap();
    let (allocs, accepted, failed) = count(&mut rig, &mut plant);
    eprintln!("plain: {allocs} allocations, {accepted} frames, {failed} failed reads");
    // Exactly zero: any allocation in a per-tick call would be a real-time hazard.
    assert_eq!(allocs, 0);
    assert_eq!((accepted, failed), (10_000, 0));
}

#[test]
fn ten_thousand_faulty_ticks_allocate_nothing() {
    let spec: FaultSpec = "drop=0.02,delay_ticks=2,duplicate=0.02,reorder=0.02,stall=1s:5ms"
        .parse()
        .unwrap();
    let (a, b) = channel_pair(64);
    let inj = |seed| FaultInjector::new(spec, seed, Rate::CONTROL);
    let mut rig = WireRig::new(Faulty::new(a, inj(1)), RigLimits::default()).unwrap();
    let mut plant = PlantEnd::new(Faulty::new(b, inj(2)), PlantLimits::default()).unwrap();
    let (allocs, accepted, failed) = count(&mut rig, &mut plant);
    eprintln!("faulty: {allocs} allocations, {accepted} frames, {failed} failed reads");
    assert_eq!(allocs, 0);
    // The faults really happened: the 5 ms stall alone makes 20 reads fail, and the
    // rig saw late, repeated and missing frames.
    let c = rig.counters();
    assert!(failed >= 20, "{failed}");
    assert!(c.duplicate > 0 && c.out_of_order > 0 && c.lost > 0, "{c}");
}
