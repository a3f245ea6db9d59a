//! Seeded schedules: same seed, same schedule; different seeds, different ones.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigtwin_device::perturb::schedule::{
    ForcePulseScheduleConfig, force_pulse_schedule, position_schedule,
};

#[test]
fn force_pulse_schedule_is_deterministic_and_balanced() {
    let cfg = ForcePulseScheduleConfig::default();
    let a = force_pulse_schedule(&cfg, &mut ChaCha8Rng::seed_from_u64(7)).unwrap();
    let b = force_pulse_schedule(&cfg, &mut ChaCha8Rng::seed_from_u64(7)).unwrap();
    let c = force_pulse_schedule(&cfg, &mut ChaCha8Rng::seed_from_u64(8)).unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
    // 000_*: 8 angles × 10 repetitions = 80 perturbed, each with an unperturbed twin.
    assert_eq!(a.len(), 160);
    assert_eq!(a.iter().filter(|t| t.angle_deg.is_some()).count(), 80);
    for angle in &cfg.angles_deg {
        assert_eq!(a.iter().filter(|t| t.angle_deg == Some(*angle)).count(), 10);
    }
    assert!(a.iter().enumerate().all(|(i, t)| t.index as usize == i));
    // Shuffled: not the order it was built in (angle, twin, angle, twin, ...).
    let built: Vec<Option<f64>> = (0..10)
        .flat_map(|_| cfg.angles_deg.iter().flat_map(|a| [Some(*a), None]))
        .collect();
    assert_ne!(a.iter().map(|t| t.angle_deg).collect::<Vec<_>>(), built);
}

#[test]
fn bad_schedule_config_names_the_key() {
    let cfg = ForcePulseScheduleConfig {
        repetitions: 0,
        ..ForcePulseScheduleConfig::default()
    };
    let e = force_pulse_schedule(&cfg, &mut ChaCha8Rng::seed_from_u64(1)).unwrap_err();
    assert!(e.names("repetitions"), "{e}");
}

#[test]
fn position_schedule_draws_from_k_pi_over_4() {
    let a = position_schedule(50, &mut ChaCha8Rng::seed_from_u64(3));
    let b = position_schedule(50, &mut ChaCha8Rng::seed_from_u64(3));
    let c = position_schedule(50, &mut ChaCha8Rng::seed_from_u64(4));
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert_eq!(a.len(), 50);
    for p in &a {
        assert!((1..=8).contains(&p.k));
        // angle = k π/4 exactly as computed (1 ulp).
        assert!((p.angle_rad - f64::from(p.k) * core::f64::consts::FRAC_PI_4).abs() < 1e-15);
    }
    // 50 uniform draws over 8 directions: all 8 appear with probability > 99.8 %
    // (8 (7/8)^50 ≈ 1.1e-2 bounds the miss chance; seed 3 is fixed, so this is a
    // regression check on the draw, not a flaky one).
    let mut seen = [false; 8];
    for p in &a {
        seen[usize::from(p.k - 1)] = true;
    }
    assert!(seen.iter().all(|s| *s));
}
