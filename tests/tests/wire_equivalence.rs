//! The wire is transparent: trials whose every sensor frame and motor command crosses
//! the wire protocol (encoded, sent over an in-process lock-step channel, decoded) give
//! the very rows of the lock-step rehearsal, and a link that goes silent trips the
//! controller within the watchdog's ticks.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin::cosim::wired::WiredPlant;
use rigtwin::cosim::{self, CoSim, LockStep};
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{schedule, trial};
use rigtwin_device::{Mode, Rate, Tick};
use rigtwin_wire::{
    ChannelEnd, FaultInjector, FaultSpec, Faulty, PlantEnd, PlantLimits, RigLimits, WireRig,
    channel_pair,
};

/// The trial `plan` (seed 42) with its plant behind a fault-free in-process wire.
fn wired(
    protocol: &Protocol,
    subject: &rigtwin::protocol::VirtualSubject,
    plan: &rigtwin::rehearse::TrialPlan,
) -> CoSim<WiredPlant<ChannelEnd, ChannelEnd>> {
    let p = trial::parts(protocol, subject, 42, plan, true).unwrap();
    let (c, e) = channel_pair(8);
    let wired = WiredPlant::new(
        WireRig::new(c, RigLimits::default()).unwrap(),
        PlantEnd::new(e, PlantLimits::default()).unwrap(),
        p.plant,
    );
    CoSim::new(p.controller, p.driver, wired, p.recorder)
}

/// Six trials of the reach protocol (perturbed and unperturbed, seed 42, subject 1):
/// the wired rows equal the lock-step rows bit for bit (doubles cross the wire as their
/// little-endian bytes, and the plant applies the command of the same tick).
#[test]
fn a_fault_free_wire_gives_the_lock_step_rows() {
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let subject = protocol.subjects.draw(42, 1);
    for plan in schedule(&protocol, 42, 1).iter().take(6) {
        let lock = trial::simulate(&protocol, &subject, 42, plan, true).unwrap();
        let mut sim = wired(&protocol, &subject, plan);
        cosim::run(&mut sim, &mut LockStep, trial::trial_ticks(&protocol)).unwrap();
        let counters = sim.plant().rig().counters();
        let wired = sim.finish();
        assert_eq!(counters.rejected(), 0, "trial {}", plan.index + 1);
        assert_eq!(wired.rows.len(), lock.rows.len());
        assert!(
            wired.rows == lock.rows,
            "trial {}: rows differ",
            plan.index + 1
        );
        assert_eq!(wired.pulse_onset, lock.pulse_onset);
        assert_eq!(wired.extremes, lock.extremes);
    }
}

/// A link that stalls for 50 ms from 1 s on (no frame reaches the controller): the
/// controller's read fails as stale on the 4th tick without a new frame (1 ms at 4 kHz,
/// the wire's default) and the controller latches Fault there, with zero force.
#[test]
fn a_stalled_link_trips_the_controller_within_the_watchdog() {
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let subject = protocol.subjects.draw(42, 1);
    let plan = &schedule(&protocol, 42, 1)[0];
    let p = trial::parts(&protocol, &subject, 42, plan, true).unwrap();
    let (c, e) = channel_pair(64);
    let spec: FaultSpec = "stall=1s:50ms".parse().unwrap();
    let rate = protocol.controller.control_rate().unwrap();
    let faulty = Faulty::new(e, FaultInjector::new(spec, 7, rate));
    let wired = WiredPlant::new(
        WireRig::new(c, RigLimits::default()).unwrap(),
        PlantEnd::new(faulty, PlantLimits::default()).unwrap(),
        p.plant,
    );
    let mut sim = CoSim::new(p.controller, p.driver, wired, p.recorder);
    let mut fault_at = None;
    for n in 0..6000 {
        let r = sim.step(Tick(n)).unwrap();
        if r.mode == Mode::Fault {
            assert_eq!(r.command_n, [0.0, 0.0]);
            fault_at = Some(n);
            break;
        }
    }
    // The stall starts at 1 s, tick 4000 at 4 kHz; frames of ticks 4000.. never arrive,
    // so the newest frame is 3999's and the 4th tick after it, 4003, is stale.
    let stall_tick = u64::from(Rate::CONTROL.hz());
    assert_eq!(
        fault_at,
        Some(stall_tick + 3),
        "{:?}",
        sim.controller().events().last()
    );
}

/// The e-stop across the wire, in lock step: pressed at the plant at tick 6000 (1.5 s,
/// mid-reach, the motors pushing), the sensor frame of that tick carries it, the
/// controller trips on reading it and its fault command is taken up by the plant in the
/// same tick: the applied force is zero from tick 6000 on, within one tick of the press.
#[test]
fn an_estop_at_the_plant_zeroes_its_force_within_one_tick() {
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let subject = protocol.subjects.draw(42, 1);
    let plan = &schedule(&protocol, 42, 1)[0];
    let mut sim = wired(&protocol, &subject, plan);
    let press = 6000;
    let mut pushing_before = false;
    for n in 0..press + 40 {
        if n == press {
            sim.plant_mut().sim_mut().rig_mut().set_estop(true);
        }
        let r = sim.step(Tick(n)).unwrap();
        let applied = sim.plant().end().applied_force(Tick(n));
        if n == press - 1 {
            pushing_before = applied != [0.0, 0.0];
            assert_eq!(r.mode, Mode::Active);
        }
        if n >= press {
            assert_eq!(r.mode, Mode::Fault, "tick {n}");
            assert_eq!(
                applied,
                [0.0, 0.0],
                "tick {n}: the plant still applies force"
            );
        }
    }
    assert!(pushing_before, "the motors were pushing before the press");
    assert_eq!(
        sim.finish().extremes.trip,
        Some((press, "EStop".to_owned()))
    );
}
