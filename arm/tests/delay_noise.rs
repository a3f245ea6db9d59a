//! The delay line and the motor noise on their own.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rigtwin_arm::delay::DelayLine;
use rigtwin_arm::noise::{MotorNoise, NoiseParams};

/// A line read at lag N returns exactly the sample pushed N pushes earlier, and the
/// fill value before that; lags beyond the capacity clamp to it.
#[test]
fn delay_line_delays_by_exactly_n_samples() {
    for n in [0usize, 1, 7, 60, 240] {
        let mut d = DelayLine::new(n, -1i64);
        for i in 0..1_000i64 {
            d.push(i);
            let expected = if i >= n as i64 { i - n as i64 } else { -1 };
            assert_eq!(d.get(n), expected, "lag {n} at push {i}");
        }
        assert_eq!(d.get(n + 5), d.get(n));
        assert_eq!(d.max_lag(), n);
    }
}

/// The noise activation has zero mean and standard deviation cv · a. With τ_n = 50 ms
/// sampled at 1 kHz (φ = 0.980) 400 000 steps give ≈ 4 000 independent samples per
/// muscle: the standard error of the mean is 0.016 and of the std 1.1 %; tolerances
/// (in units of cv · a) are 0.08 and 5 %, about 4.5 standard errors. Zero activation
/// gives zero noise.
#[test]
fn noise_is_zero_mean_and_scales_with_activation() {
    let params = NoiseParams {
        activation_cv: 0.05,
        time_constant_ms: 50.0,
    };
    let mut noise = MotorNoise::new(&params, 1e-3, ChaCha8Rng::seed_from_u64(42));
    let a = [100.0, 200.0, 0.0, 50.0, 10.0, 400.0];
    let n = 400_000;
    let mut sum = [0.0; 6];
    let mut sq = [0.0; 6];
    for _ in 0..n {
        let x = noise.step(&a);
        for i in 0..6 {
            sum[i] += x[i];
            sq[i] += x[i] * x[i];
        }
    }
    for i in 0..6 {
        if a[i] == 0.0 {
            assert_eq!((sum[i], sq[i]), (0.0, 0.0));
            continue;
        }
        let scale = 0.05 * a[i];
        let mean = sum[i] / n as f64 / scale;
        let std = (sq[i] / n as f64 / (scale * scale) - mean * mean).sqrt();
        assert!(mean.abs() < 0.08, "muscle {i}: mean {mean}");
        assert!((std - 1.0).abs() < 0.05, "muscle {i}: std {std}");
    }
}

/// Same seed, same stream, bit for bit; another seed, another stream.
#[test]
fn noise_stream_is_the_seed_s() {
    let p = NoiseParams::default();
    let draw = |seed| {
        let mut n = MotorNoise::new(&p, 1e-3, ChaCha8Rng::seed_from_u64(seed));
        (0..1_000)
            .flat_map(|_| n.step(&[100.0; 6]))
            .map(f64::to_bits)
            .collect::<Vec<_>>()
    };
    assert_eq!(draw(9), draw(9));
    assert_ne!(draw(9), draw(10));
}
