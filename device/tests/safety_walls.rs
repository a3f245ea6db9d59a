//! Soft workspace walls: a stiff virtual spring-damper on the law's state beyond
//! ±wall_m, which pushes back and never pulls.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::testing::MockRig;
use rigtwin_device::{Controller, ControllerConfig, LawKind, Mode, Tick};

fn settle(law: LawKind, push_n: f64) -> (f64, f64, f64) {
    let mut config = ControllerConfig {
        law,
        ..ControllerConfig::default()
    };
    // A still anchor for the spring law, so only the wall and the push act.
    config.imposed_motion.amplitude_m = 0.0;
    // Make the virtual spring soft enough that a push reaches the wall.
    config.virtual_spring.stiffness_n_per_m = [10.0, 10.0];
    config.virtual_spring.damping_n_s_per_m = [50.0, 50.0];
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = [push_n, 0.0];
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let mut r = c.report().to_owned();
    for n in 1..=40_000u64 {
        r = c.tick(&mut rig, Tick(n));
        assert_eq!(r.mode, Mode::Active);
    }
    (
        r.ref_position_m[0],
        r.ref_velocity_m_per_s[0],
        r.wall_force_n[0],
    )
}

#[test]
fn a_steady_push_rests_on_the_wall_at_its_spring_deflection() {
    // Admittance, 15 N outward: equilibrium where the wall spring balances the push,
    // x = 0.15 + 15 / 20 000 = 0.15075 m. After 10 s (the wall mode is 63 rad/s,
    // damped by 415 N s/m) the residual is far below 1 µm; bound 1e-6 m.
    let (x, v, f) = settle(LawKind::Admittance, 15.0);
    assert!((x - 0.15075).abs() < 1e-6, "{x}");
    assert!(v.abs() < 1e-6 && (f + 15.0).abs() < 1e-3, "{v} {f}");
    // The other side, the virtual spring: 20 N on a 10 N/m spring would go to 2 m;
    // the wall stops it where 20 = 10 x + 20 000 (x − 0.15) → x = 0.150924...
    let (x, _, _) = settle(LawKind::VirtualSpring, -20.0);
    let expect = -(20.0 + 20_000.0 * 0.15) / (10.0 + 20_000.0);
    assert!((x - expect).abs() < 1e-6, "{x} vs {expect}");
}

#[test]
fn the_wall_never_pulls() {
    // Beyond the wall and moving inward fast, spring + damper would give an outward
    // force; the wall must give zero instead (no sticking).
    let config = ControllerConfig::default();
    let mut rig = MockRig::default();
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    // Drive the reference past the wall with a strong push, then pull back hard.
    rig.frame.force_raw_n = [60.0, 0.0];
    let mut n = 1;
    while c.report().ref_position_m[0] < 0.1505 {
        c.tick(&mut rig, Tick(n));
        n += 1;
        assert!(n < 40_000);
    }
    rig.frame.force_raw_n = [-200.0, 0.0];
    for _ in 0..400 {
        let r = c.tick(&mut rig, Tick(n));
        n += 1;
        assert!(
            r.wall_force_n[0] <= 0.0,
            "outward wall force {:?}",
            r.wall_force_n
        );
    }
}
