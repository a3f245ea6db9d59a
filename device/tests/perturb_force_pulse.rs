//! The force pulse of 000_* eq. 22–23: profile facts, the jerk of eq. 22 recovered from
//! the admittance's motion, direction, and both triggers.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::config::{Axis, ForcePulseConfig};
use rigtwin_device::perturb::Crossing;
use rigtwin_device::perturb::force_pulse::{
    ForcePulse, G_MAX, PulseTrigger, normalized_force, normalized_jerk,
};
use rigtwin_device::testing::{MockRig, scripted};
use rigtwin_device::{Controller, ControllerConfig, PerturbationStatus, Rate, Tick};

#[test]
fn profile_has_zero_force_and_jerk_at_both_ends_and_peak_amplitude() {
    let p = ForcePulse::new(&ForcePulseConfig::default(), Rate::CONTROL);
    // 150 ms at 4 kHz.
    assert_eq!(p.duration_ticks(), 600);
    let f = |k: u64| p.force_at(k, 0.0)[0];
    // Ends: the closed form is exactly zero at s = 0 and s = 3 up to sin(3π) rounding.
    assert!(
        f(0).abs() < 1e-12 && f(600).abs() < 1e-12,
        "{} {}",
        f(0),
        f(600)
    );
    // Jerk at the ends: eq. 22 starts as (π²/4) s², so the first difference over one
    // tick (s = 1/200) is ~1e-5 of the peak rate of change; bound it at 1e-4.
    let peak_rate = 15.0 / (0.05 * G_MAX); // A / (T_p g_max), N/s
    let h = Rate::CONTROL.period_s();
    assert!(((f(1) - f(0)) / h).abs() < 1e-4 * peak_rate);
    assert!(((f(600) - f(599)) / h).abs() < 1e-4 * peak_rate);
    // Peak at T_pert / 2 = tick 300 equals A_pert = 15 N (exact sample); no sample higher.
    let peak = (0..=600).map(f).fold(f64::MIN, f64::max);
    assert!(
        (f(300) - 15.0).abs() < 1e-12 && (peak - 15.0).abs() < 1e-12,
        "{peak}"
    );
    // Force never negative: the once-integrated eq. 22 is a single lobe.
    assert!((0..=600).all(|k| f(k) >= -1e-12));
}

#[test]
fn derivative_of_the_force_is_eq_22() {
    // Central difference of u_p against eq. 22 at every tick of the pulse. Error is
    // h²/6 · |u_p'''| ≤ (1/200)² π²/6 ≈ 4e-5 in units of eq. 22; bound 1e-4.
    let tp = 200.0;
    let mut worst = 0.0_f64;
    for k in 1..600 {
        let s = f64::from(k) / tp;
        let d =
            (normalized_force(s + 1.0 / tp) - normalized_force(s - 1.0 / tp)) / (2.0 / tp) * G_MAX;
        worst = worst.max((d - normalized_jerk(s)).abs());
    }
    assert!(worst < 1e-4, "{worst}");
}

#[test]
fn third_difference_of_a_pure_mass_driven_by_the_pulse_is_eq_22() {
    // Admittance without damping (D = 0): the reference is a pure mass, so its jerk is
    // u̇_pert / M, i.e. eq. 22 scaled by A / (M T_p g_max). The third difference of the
    // reported reference, sample by sample, must give eq. 22 within the central-
    // difference error (4e-5, see above) plus rounding (~1e-7); bound 1e-4.
    // The mock's force is zero bit for bit and its carts stay put: the stale-force and
    // encoder-stall watchdogs are off ([`scripted`]); the law is under test.
    let mut config = scripted(ControllerConfig::default());
    config.admittance.damping_n_s_per_m = [0.0, 0.0];
    let mass = config.admittance.mass_kg[0];
    let amp = config.force_pulse.amplitude_n;
    let angle = 30f64.to_radians();
    let mut rig = MockRig::default();
    let mut c = Controller::new(config).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    c.arm_force_pulse(angle, PulseTrigger::AtTick(Tick(100)))
        .unwrap();
    let mut x = Vec::new();
    let mut pert = Vec::new();
    for n in 1..=800u64 {
        let r = c.tick(&mut rig, Tick(n));
        x.push(r.ref_position_m);
        pert.push(r.pert_force_n);
        if n == 100 {
            assert_eq!(
                c.force_pulse_status(),
                PerturbationStatus::Running { onset: Tick(100) }
            );
        }
    }
    assert_eq!(
        c.force_pulse_status(),
        PerturbationStatus::Done { onset: Tick(100) }
    );
    let h = Rate::CONTROL.period_s();
    let tp = 0.05;
    let scale = amp / (mass * tp * G_MAX);
    let mut worst = 0.0_f64;
    // x[j] is the state at tick j+1; the input of tick n moves the state of tick n+1.
    // Δ³ over ticks n..n+3 equals (u(n+1) − u(n−1)) h² / 2M, centred on input tick n.
    for j in 0..x.len() - 3 {
        let n = j as f64 + 1.0 + 1.0; // input tick at the centre
        let s = (n - 100.0) * h / tp;
        for (axis, dir) in [(0, angle.cos()), (1, angle.sin())] {
            let d3 = x[j + 3][axis] - 3.0 * x[j + 2][axis] + 3.0 * x[j + 1][axis] - x[j][axis];
            let jerk = d3 / (h * h * h);
            let expect = scale * dir * normalized_jerk(s);
            worst = worst.max((jerk - expect).abs() / (scale * dir));
        }
    }
    eprintln!("force pulse: worst |Δ³x/h³ − eq.22| = {worst:.2e} of the eq. 22 scale");
    assert!(worst < 1e-4, "{worst}");
    // Direction: every non-zero sample points at 30° (to 1e-12 rad, rounding of atan2).
    for f in pert.iter().filter(|f| f[0].hypot(f[1]) > 1e-9) {
        assert!((f[1].atan2(f[0]) - angle).abs() < 1e-12);
    }
    // The peak magnitude is A_pert, 300 ticks after onset.
    let peak = pert[399][0].hypot(pert[399][1]);
    assert!((peak - amp).abs() < 1e-12, "{peak}");
}

#[test]
fn line_crossing_fires_on_the_tick_the_handle_crosses() {
    // The handle moves +10 µm per tick along y from −0.030 m; the pulse is armed for y
    // rising through −0.025 m (000_*: 0.1 m into a reach from −0.125 m). It crosses at
    // the tick where the count reaches −25 000: 500 steps after the start.
    let mut rig = MockRig::default();
    rig.frame.encoder_counts = [0, -30_000];
    // The scripted force is zero bit for bit: the stale-force watchdog is off.
    let mut c = Controller::new(scripted(ControllerConfig::default())).unwrap();
    c.tick(&mut rig, Tick(0));
    c.activate().unwrap();
    let trigger = PulseTrigger::LineCrossing {
        axis: Axis::Y,
        position_m: -0.025,
        direction: Crossing::Rising,
    };
    c.arm_force_pulse(120f64.to_radians(), trigger).unwrap();
    let mut onset = None;
    for n in 1..=700u64 {
        rig.frame.encoder_counts[1] = -30_000 + 10 * n as i64;
        let r = c.tick(&mut rig, Tick(n));
        if let PerturbationStatus::Running { onset: t } = r.force_pulse
            && onset.is_none()
        {
            onset = Some(t);
            // u_p(0) = 0: the onset tick carries no force yet.
            assert!(r.pert_force_n[0].abs() < 1e-12 && r.pert_force_n[1].abs() < 1e-12);
        }
    }
    assert_eq!(onset, Some(Tick(500)));
    assert!(c.force_pulse_status().is_running());
    assert!(
        c.arm_force_pulse(0.0, PulseTrigger::AtTick(Tick(0)))
            .is_err(),
        "re-arming while running must fail"
    );
    assert!(
        c.arm_force_pulse(f64::NAN, PulseTrigger::AtTick(Tick(0)))
            .is_err()
    );
}
