//! The controller's tick across the wire allocates nothing: `CoSim::step` over a
//! `RemotePlant` (the controller's `WireRig`, what `rigtwin controller` runs at 4 kHz) —
//! the driver, the controller's read → update → write, the datagrams and the recorder —
//! is counted by a global allocator over a whole perturbed reach of 14 000 ticks, with
//! the pulse firing. The plant's side is a point-mass rig behind a `PlantEnd` on the
//! other end of an in-process channel, stepped on the test's thread outside the count.
//! Everything the loop needs (the recorder's rows, the onset list, the wire's buffers)
//! is allocated before the first tick; only a trip formats its reason, once.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin::cosim::CoSim;
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{TrialTask, schedule, trial};
use rigtwin::remote::controller::RemotePlant;
use rigtwin_device::testing::PointMassRig;
use rigtwin_device::testing::alloc::{Counting, allocations};
use rigtwin_device::{Mode, MotorCommand, Rate, RigIo, Tick};
use rigtwin_wire::{PlantEnd, PlantLimits, RigLimits, WireRig, channel_pair};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn the_controllers_tick_across_the_wire_allocates_nothing() {
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let subject = protocol.subjects.draw(42, 1);
    let plan = schedule(&protocol, 42, 1)
        .into_iter()
        .find(|p| {
            matches!(
                p.task,
                TrialTask::Reach {
                    angle_deg: Some(_),
                    ..
                }
            )
        })
        .unwrap();
    let id = u16::try_from(plan.index + 1).unwrap();
    let parts = trial::controller_parts(&protocol, &subject, 42, &plan, true).unwrap();
    let (c, p) = channel_pair(8);
    let mut rig = WireRig::new(c, RigLimits::default()).unwrap();
    rig.begin_trial(id);
    let mut end = PlantEnd::new(p, PlantLimits::default()).unwrap();
    end.set_trial(id);
    // A hand that pushes toward the goal: the handle crosses the trigger line and the
    // pulse fires.
    let mut carts = PointMassRig::new([2.0, 2.0], Rate::CONTROL);
    carts.position_m = protocol.reach().start_m;
    carts.hand_force_n = [0.0, 4.0];
    let mut cosim = CoSim::new(
        parts.controller,
        parts.driver,
        RemotePlant::new(&mut rig),
        parts.recorder,
    );
    let mut in_loop = 0;
    let mut active = 0;
    for n in 0..trial::trial_ticks(&protocol) {
        let now = Tick(n);
        let frame = carts.read(now).unwrap();
        end.send_frame(now, frame).unwrap();
        let before = allocations();
        let report = cosim.step(now).unwrap();
        in_loop += allocations() - before;
        if report.mode == Mode::Active {
            active += 1;
        }
        end.poll_command(now).unwrap();
        carts
            .write(
                now,
                MotorCommand {
                    force_n: end.applied_force(now),
                },
            )
            .unwrap();
    }
    let sim = cosim.finish();
    assert!(sim.extremes.trip.is_none(), "{:?}", sim.extremes.trip);
    assert!(sim.pulse_onset.is_some(), "the pulse fired");
    assert!(active > 13_000, "{active} active ticks");
    assert_eq!(in_loop, 0, "allocations in 14 000 ticks across the wire");
}
