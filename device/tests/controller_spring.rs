//! The virtual spring (001_* eq. 4) and the imposed motion inside the controller.
#![allow(clippy::unwrap_used, clippy::expect_used)]
// Loops over the two axes index several per-axis arrays at once.
#![allow(clippy::needless_range_loop)]

use rigtwin_device::testing::{MockRig, PointMassRig, scripted};
use rigtwin_device::{Controller, ControllerConfig, LawKind, Mode, Rate, Tick};

/// The virtual-spring law on the mock, whose force is held bit for bit and whose carts
/// never move: the stale-force and encoder-stall watchdogs are off ([`scripted`]), as
/// the law, not the safety layer, is under test.
fn spring_config(mass: f64, k: f64, b: f64) -> ControllerConfig {
    let mut c = scripted(ControllerConfig {
        law: LawKind::VirtualSpring,
        ..ControllerConfig::default()
    });
    c.virtual_spring.mass_kg = [mass; 2];
    c.virtual_spring.stiffness_n_per_m = [k; 2];
    c.virtual_spring.damping_n_s_per_m = [b; 2];
    // A still anchor: the step response is the pure second-order system.
    c.imposed_motion.amplitude_m = 0.0;
    c
}

/// Step response of `M ẍ + B ẋ + K x = F` from rest, any damping.
fn analytic(mass: f64, k: f64, b: f64, f: f64, t: f64) -> f64 {
    let wn = (k / mass).sqrt();
    let zeta = b / (2.0 * (k * mass).sqrt());
    let xs = f / k;
    if (zeta - 1.0).abs() < 1e-12 {
        xs * (1.0 - (1.0 + wn * t) * (-wn * t).exp())
    } else if zeta < 1.0 {
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        xs * (1.0 - (-zeta * wn * t).exp() * ((wd * t).cos() + zeta * wn / wd * (wd * t).sin()))
    } else {
        let r = wn * (zeta * zeta - 1.0).sqrt();
        let (s1, s2) = (-zeta * wn + r, -zeta * wn - r);
        xs * (1.0 + (s2 * (s1 * t).exp() - s1 * (s2 * t).exp()) / (s1 - s2))
    }
}

fn run_step(mass: f64, k: f64, b: f64) -> f64 {
    let force = [20.0, -12.0];
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = force;
    let mut c = Controller::new(spring_config(mass, k, b)).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let h = Rate::CONTROL.period_s();
    let mut worst = 0.0_f64;
    // One second of ticks.
    for n in 1..=u64::from(Rate::CONTROL.hz()) {
        let r = c.tick(&mut rig, Tick(n));
        for i in 0..2 {
            let x = analytic(mass, k, b, force[i], (n - 1) as f64 * h);
            worst = worst.max((r.ref_position_m[i] - x).abs() / (force[i] / k).abs());
        }
    }
    worst
}

#[test]
fn step_response_matches_the_analytic_second_order_solution() {
    // The matrix-exponential step is exact for a held force: errors are rounding only.
    // Measured against the static deflection F/K, 1e-9 is far above a few ulps × 4000.
    let critical = 2.0 * (10_000.0f64 * 5.0).sqrt();
    for (m, k, b) in [
        (5.0, 10_000.0, critical),
        (5.0, 10_000.0, 100.0),
        (2.0, 500.0, 200.0),
    ] {
        let worst = run_step(m, k, b);
        eprintln!("virtual spring M={m} K={k} B={b}: worst error {worst:.2e} of F/K");
        assert!(worst < 1e-9, "M={m} K={k} B={b}: {worst:e}");
    }
}

#[test]
fn handle_follows_the_imposed_sinusoid_and_yields_to_a_push() {
    // 001_* defaults: ±0.10 m at 0.125 Hz on y behind a 10 kN/m, 447 N s/m spring.
    // Point-mass carts; the hand pushes 10 N along x. Over the first 12 s (ramp plus a
    // full cycle) the y handle must stay within 0.2 mm of the anchor (the spring-mass
    // lag is M ω²/K · A = 0.03 mm, PD tracking adds less), and x must settle to the
    // deflection F/K = 1 mm within 1 % (the x PD's steady error F/K_p adds 0.026 mm).
    let config = ControllerConfig {
        law: LawKind::VirtualSpring,
        ..ControllerConfig::default()
    };
    let mut rig = PointMassRig::new(config.render.feedforward_mass_kg, Rate::CONTROL);
    rig.hand_force_n = [10.0, 0.0];
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let mut worst_y = 0.0_f64;
    let mut peak_y = 0.0_f64;
    for n in 1..=48_000u64 {
        let r = c.tick(&mut rig, Tick(n));
        assert_eq!(r.mode, Mode::Active, "tripped: {:?}", c.events().last());
        worst_y = worst_y.max((rig.position_m[1] - r.anchor_position_m[1]).abs());
        peak_y = peak_y.max(rig.position_m[1].abs());
    }
    eprintln!(
        "imposed motion: worst |y - anchor| {:.3} mm, peak |y| {:.4} m, x {:.4} mm",
        worst_y * 1e3,
        peak_y,
        rig.position_m[0] * 1e3
    );
    assert!(worst_y < 2e-4, "{worst_y}");
    // The envelope reaches 1 after 4 s, so the peak is the full 0.10 m within 0.3 mm.
    assert!((peak_y - 0.10).abs() < 3e-4, "{peak_y}");
    assert!(
        (rig.position_m[0] - 1e-3).abs() < 1e-5 + 2.6e-5,
        "{}",
        rig.position_m[0]
    );
}
