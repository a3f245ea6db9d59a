//! The admittance law (000_* eq. 20) inside the controller, against its closed form.
#![allow(clippy::unwrap_used, clippy::expect_used)]
// Loops over the two axes index several per-axis arrays at once.
#![allow(clippy::needless_range_loop)]

use rigtwin_device::calib::ForceCalibration;
use rigtwin_device::testing::{MockRig, PointMassRig, scripted};
use rigtwin_device::{Controller, ControllerConfig, Mode, Rate, Tick};

/// The default config with the soft walls moved out of the way: these tests push the
/// reference metres away, and a wall force would (rightly) break the closed form. On the
/// mock the force is held bit for bit and the carts never follow the reference, which
/// the stale-force and encoder-stall watchdogs would (rightly) call a frozen sensor and a
/// dead encoder: they are off here ([`scripted`]); `safety_trips.rs` tests them.
fn unwalled() -> ControllerConfig {
    let mut c = scripted(ControllerConfig::default());
    c.safety.wall_m = 100.0;
    c
}

/// Prime (Configured → Inactive) at tick 0 and activate; the next tick is 1.
fn started(config: ControllerConfig, rig: &mut MockRig) -> Controller {
    let mut c = Controller::new(config).unwrap();
    c.tick(rig, Tick(0));
    assert_eq!(c.mode(), Mode::Inactive);
    c.activate().unwrap();
    c
}

#[test]
fn constant_force_matches_the_closed_form_at_every_tick() {
    let config = unwalled();
    let (m, d) = (
        config.admittance.mass_kg,
        config.admittance.damping_n_s_per_m,
    );
    let force = [6.0, -9.0];
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = force;
    let mut c = started(config, &mut rig);
    let h = Rate::CONTROL.period_s();
    let mut worst = 0.0_f64;
    let mut last = None;
    for n in 1..=16_000u64 {
        let r = c.tick(&mut rig, Tick(n));
        // The reference reported at tick n is the state at t_n: n − 1 periods of held
        // force since the first active tick (tick 1, at rest).
        let t = (n - 1) as f64 * h;
        if n == 1 {
            continue;
        }
        for i in 0..2 {
            let (f, mi, di) = (force[i], m[i], d[i]);
            let tau = mi / di;
            let v = f / di * (1.0 - (-t / tau).exp());
            let x = f / di * (t - tau * (1.0 - (-t / tau).exp()));
            worst = worst.max(((r.ref_velocity_m_per_s[i] - v) / v).abs());
            worst = worst.max(((r.ref_position_m[i] - x) / x).abs());
        }
        last = Some(r);
    }
    // Exact discretization: only rounding separates the two, a few ulps per step over
    // 16 000 steps, so 1e-9 relative is a generous bound (the brief's figure).
    assert!(worst < 1e-9, "worst relative error {worst:e}");
    eprintln!("admittance closed form: worst relative error {worst:.2e} over 16000 ticks");
    // After 4 s = 12 time constants (τ = M/D = 1/3 s) the velocity is F/D within e^-12.
    let r = last.unwrap();
    for i in 0..2 {
        let vinf = force[i] / d[i];
        assert!((r.ref_velocity_m_per_s[i] - vinf).abs() < 1e-5 * vinf.abs());
    }
}

#[test]
fn time_constant_is_mass_over_damping() {
    // At t = τ = M/D the velocity has covered 1 − 1/e of its way to F/D. τ = 1/3 s is
    // 1333.3 ticks after the first active tick; ticks 1334 and 1335 bracket it.
    let config = unwalled();
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = [15.0, 0.0];
    let mut c = started(config, &mut rig);
    let mut v = Vec::new();
    for n in 1..=1335u64 {
        v.push(c.tick(&mut rig, Tick(n)).ref_velocity_m_per_s[0]);
    }
    let target = 1.0 - (-1.0f64).exp(); // F/D = 1 m/s
    assert!(
        v[1333] < target && target < v[1334],
        "{} {} {}",
        v[1333],
        target,
        v[1334]
    );
}

#[test]
fn calibration_rotates_the_raw_reading_into_the_rig_frame() {
    // A sensor mounted at 90° with a 1 N bias on its x channel: raw (1, -5) is 5 N
    // along rig +x. Tolerance 1e-12 N: one rotation.
    let mut config = ControllerConfig::default();
    config.sensors.force_calibration =
        ForceCalibration::rotation(core::f64::consts::FRAC_PI_2, [1.0, 0.0]);
    let mut rig = MockRig::default();
    rig.frame.force_raw_n = [1.0, -5.0];
    let mut c = started(config, &mut rig);
    c.tick(&mut rig, Tick(1));
    let r = c.tick(&mut rig, Tick(2));
    assert!(
        (r.force_n[0] - 5.0).abs() < 1e-12 && r.force_n[1].abs() < 1e-12,
        "{:?}",
        r.force_n
    );
    assert!(r.ref_velocity_m_per_s[0] > 0.0 && r.ref_velocity_m_per_s[1].abs() < 1e-15);
}

#[test]
fn carts_track_the_admittance_reference_in_closed_loop() {
    // Point-mass carts of the default feed-forward masses, a hand pushing 10 N along x
    // and -5 N along y. The PD (50 Hz, critically damped) must keep the carts on the
    // reference (both at the tick's time): steady error is F/K_p = 10 / 3.9e5 = 26 µm
    // on x plus the 1 µm encoder quantum; allow 0.1 mm.
    let config = unwalled();
    let mut rig = PointMassRig::new(config.render.feedforward_mass_kg, Rate::CONTROL);
    rig.hand_force_n = [10.0, -5.0];
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let mut worst = [0.0_f64; 2];
    for n in 1..=8000u64 {
        let r = c.tick(&mut rig, Tick(n));
        assert_eq!(r.mode, Mode::Active, "tripped: {:?}", c.events().last());
        if n > 400 {
            for i in 0..2 {
                worst[i] = worst[i].max((r.ref_position_m[i] - r.position_m[i]).abs());
            }
        }
    }
    eprintln!(
        "closed-loop tracking error after 0.1 s: x {:.1} µm, y {:.1} µm",
        worst[0] * 1e6,
        worst[1] * 1e6
    );
    assert!(worst[0] < 1e-4 && worst[1] < 1e-4, "{worst:?}");
    // The carts move at the admittance's F/D: 10/15 m/s, within 1 % after 2 s (6 τ).
    assert!(
        (rig.velocity_m_per_s[0] - 10.0 / 15.0).abs() < 0.01 * 10.0 / 15.0,
        "{:?}",
        rig.velocity_m_per_s
    );
}
