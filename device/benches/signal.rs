//! Cost of the signal module on one Börner trial: 3.5 s at 4 kHz (14 000 samples),
//! the seed's Savitzky–Golay (order 5, window 253) for position and its first three
//! derivatives, the 5th-order 1 Hz Butterworth high-pass forward-backward, and a
//! Welch spectrum; plus the filter design itself.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin_device::signal::{EdgeMode, FilterKind, butter, savgol_filter, sosfiltfilt, welch};
use std::hint::black_box;

fn trial() -> Vec<f64> {
    (0..14_000)
        .map(|i| {
            let t = i as f64 / 4000.0;
            let tau = (t / 0.6).min(1.0);
            0.1 * (10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5))
                + 1e-4 * (2.0 * std::f64::consts::PI * 37.0 * t).sin()
        })
        .collect()
}

fn signal(c: &mut Criterion) {
    let x = trial();
    let dt = 1.0 / 4000.0;
    c.bench_function("savgol 253/5 deriv 0..=3, 14k samples (interp)", |b| {
        b.iter(|| {
            for d in 0..=3 {
                black_box(savgol_filter(black_box(&x), 253, 5, d, dt, EdgeMode::Interp).unwrap());
            }
        })
    });
    c.bench_function("savgol 253/5 deriv 0, 14k samples (mirror)", |b| {
        b.iter(|| black_box(savgol_filter(black_box(&x), 253, 5, 0, dt, EdgeMode::Mirror).unwrap()))
    });
    let sos = butter(5, 1.0, 4000.0, FilterKind::HighPass).unwrap();
    c.bench_function("butter 5 high-pass design", |b| {
        b.iter(|| black_box(butter(black_box(5), 1.0, 4000.0, FilterKind::HighPass).unwrap()))
    });
    c.bench_function("sosfiltfilt 5th-order, 14k samples", |b| {
        b.iter(|| black_box(sosfiltfilt(&sos, black_box(&x)).unwrap()))
    });
    c.bench_function("welch nperseg 4096, 14k samples", |b| {
        b.iter(|| black_box(welch(black_box(&x), 4000.0, 4096).unwrap()))
    });
}

criterion_group!(benches, signal);
criterion_main!(benches);
