//! Lifecycle: Configured → Inactive (reads, zero force) → Active → Fault (latched).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::testing::MockRig;
use rigtwin_device::{Controller, ControllerConfig, LawKind, LifecycleError, Mode, Tick};

#[test]
fn lifecycle_transitions_and_zero_force_outside_active() {
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = [10.0, 0.0];
    rig.frame.encoder_counts = [1234, -5678];
    let mut c = Controller::new(ControllerConfig::default()).unwrap();
    assert_eq!(c.mode(), Mode::Configured);
    assert!(matches!(
        c.activate(),
        Err(LifecycleError::WrongMode {
            mode: Mode::Configured,
            ..
        })
    ));
    assert!(matches!(c.reset(), Err(LifecycleError::WrongMode { .. })));

    // Inactive reads the sensors (1 µm counts → m, exact in binary to 1e-18 m) and
    // commands exactly zero despite the 10 N push.
    let r = c.step(&mut rig);
    assert_eq!(
        (r.tick, r.mode, r.command_n),
        (Tick(0), Mode::Inactive, [0.0, 0.0])
    );
    assert!(
        (r.position_m[0] - 1.234e-3).abs() < 1e-18 && (r.position_m[1] + 5.678e-3).abs() < 1e-18
    );
    assert_eq!(r.force_n, [10.0, 0.0]);
    for _ in 0..10 {
        assert_eq!(c.step(&mut rig).command_n, [0.0, 0.0]);
    }

    c.activate().unwrap();
    assert!(
        c.set_law(LawKind::VirtualSpring).is_err(),
        "no law switch while active"
    );
    let mut last = c.step(&mut rig);
    for _ in 0..10 {
        last = c.step(&mut rig);
    }
    // The clock of step() continues from the last tick: 11 inactive + 11 active ticks.
    assert_eq!(last.tick, Tick(21));
    assert_eq!(last.mode, Mode::Active);
    assert!(last.command_n[0] != 0.0);
    // The reference starts at the handle's position at activation.
    assert!((last.ref_position_m[1] + 5.678e-3).abs() < 1e-9);

    c.deactivate().unwrap();
    assert_eq!(c.step(&mut rig).command_n, [0.0, 0.0]);
    assert!(c.set_law(LawKind::VirtualSpring).is_ok());
    assert_eq!(c.law(), LawKind::VirtualSpring);
    c.activate().unwrap();
    assert_eq!(c.step(&mut rig).law, LawKind::VirtualSpring);
}
