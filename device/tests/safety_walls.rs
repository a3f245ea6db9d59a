//! Soft workspace walls: a stiff virtual spring-damper on the law's state beyond
//! ±wall_m, which pushes back and never pulls.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::config::SafetyConfig;
use rigtwin_device::safety::SafetyMonitor;
use rigtwin_device::testing::{MockRig, scripted};
use rigtwin_device::{Controller, ControllerConfig, LawKind, Mode, Tick};

/// Pushes `push_n` along `axis` for 10 s and returns that axis's reference position,
/// velocity and wall force at the end.
fn settle(law: LawKind, axis: usize, push_n: f64) -> (f64, f64, f64) {
    // The mock holds the push bit for bit and its carts stay at the origin while the
    // reference goes to the wall: the stale-force and encoder-stall watchdogs are off
    // ([`scripted`]); the wall's force on the law is under test.
    let mut config = scripted(ControllerConfig {
        law,
        ..ControllerConfig::default()
    });
    // A still anchor for the spring law, so only the wall and the push act.
    config.imposed_motion.amplitude_m = 0.0;
    // Make the virtual spring soft enough that a push reaches the wall.
    config.virtual_spring.stiffness_n_per_m = [10.0, 10.0];
    config.virtual_spring.damping_n_s_per_m = [50.0, 50.0];
    let mut rig = MockRig::default();
    rig.frame.force_raw_n[axis] = push_n;
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let mut r = c.report().to_owned();
    for n in 1..=40_000u64 {
        r = c.tick(&mut rig, Tick(n));
        assert_eq!(r.mode, Mode::Active);
    }
    // The other axis was not pushed: it stayed at the origin, untouched by its walls.
    assert_eq!(
        (r.ref_position_m[1 - axis], r.wall_force_n[1 - axis]),
        (0.0, 0.0)
    );
    (
        r.ref_position_m[axis],
        r.ref_velocity_m_per_s[axis],
        r.wall_force_n[axis],
    )
}

#[test]
fn a_steady_push_rests_on_the_wall_at_its_spring_deflection() {
    for axis in [0, 1] {
        for sign in [1.0, -1.0] {
            // Admittance, 15 N outward: equilibrium where the wall spring balances the
            // push, |x| = 0.15 + 15 / 20 000 = 0.15075 m. After 10 s (the wall mode is
            // 63 rad/s, damped by 415 N s/m) the residual is far below 1 µm; bound 1e-6 m.
            let (x, v, f) = settle(LawKind::Admittance, axis, 15.0 * sign);
            assert!((x - 0.15075 * sign).abs() < 1e-6, "axis {axis}: {x}");
            assert!(
                v.abs() < 1e-6 && (f + 15.0 * sign).abs() < 1e-3,
                "axis {axis}: {v} {f}"
            );
            // The virtual spring: 20 N on a 10 N/m spring would go to 2 m; the wall stops
            // it where 20 = 10 |x| + 20 000 (|x| − 0.15) → |x| = 0.150924...
            let (x, _, _) = settle(LawKind::VirtualSpring, axis, 20.0 * sign);
            let expect = sign * (20.0 + 20_000.0 * 0.15) / (10.0 + 20_000.0);
            assert!((x - expect).abs() < 1e-6, "axis {axis}: {x} vs {expect}");
        }
    }
}

#[test]
fn the_wall_pushes_back_on_every_side_and_never_pulls() {
    // The wall force on a state 1 cm beyond each of the four walls: at rest the spring's
    // 20 000 N/m × 0.01 m = 200 N inward, on that axis alone; moving inward at 1 m/s
    // the damper's 400 N s/m would add 400 N outward, net 200 N outward, which a wall
    // never gives: 0. Moving outward at 1 m/s: 600 N inward. Exact arithmetic on
    // binary-exact inputs except 0.16, hence the 1e-9 N bound.
    let m = SafetyMonitor::new(&SafetyConfig::default());
    for axis in [0, 1] {
        for sign in [1.0, -1.0] {
            let mut x = [0.0; 2];
            let mut v = [0.0; 2];
            x[axis] = 0.16 * sign;
            let f = m.wall_force(x, v);
            assert!(
                (f[axis] + 200.0 * sign).abs() < 1e-9,
                "{axis} {sign}: {f:?}"
            );
            assert_eq!(f[1 - axis], 0.0);
            v[axis] = -sign;
            assert_eq!(m.wall_force(x, v)[axis], 0.0, "{axis} {sign}: pulled");
            v[axis] = sign;
            let f = m.wall_force(x, v)[axis];
            assert!((f + 600.0 * sign).abs() < 1e-9, "{axis} {sign}: {f}");
            // Inside the walls, nothing.
            x[axis] = 0.149 * sign;
            assert_eq!(m.wall_force(x, v), [0.0, 0.0]);
        }
    }
}

#[test]
fn the_wall_never_pulls() {
    // Beyond the wall and moving inward fast, spring + damper would give an outward
    // force; the wall must give zero instead (no sticking).
    // Scripted pushes on carts that stay put (see `settle`).
    let config = scripted(ControllerConfig::default());
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
