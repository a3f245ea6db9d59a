//! Import speed: the requirement (README § Requirements) is "a 10-minute 4 kHz two-axis
//! log imports in under 10 s".
//!
//! One such log (2 400 000 samples: t, x, y, fx, fy, pert_fx, pert_fy, ref_x, ref_y,
//! cmd_x, cmd_y, marker; positions in mm with 6 decimals, forces in N with 4; a marker
//! rising every 4 s, so 150 trials; a force pulse in every third trial) is generated
//! deterministically, once, outside the timed loop, as a CSV file and as a MATLAB
//! level-5 `.mat` (uncompressed N×1 doubles, written by the minimal writer below; the
//! crate's own reader checks it) and as a MATLAB v7.3 `.mat` (deflate-compressed, by
//! hdf5-pure's MAT writer). Each iteration imports one of them into a fresh
//! output folder with `rigtwin_import::import`, through a map that uses every column,
//! the time column, the marker cut and perturbations read from the channels.
//!
//! Run: `cargo bench -p rigtwin-import --bench import`. Besides criterion's report, the
//! seconds of one untimed import of each file are printed.

#![allow(clippy::unwrap_used, clippy::expect_used)] // a panic in a bench is its failure message

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use criterion::{BatchSize, Criterion, SamplingMode, criterion_group, criterion_main};

const RATE_HZ: usize = 4000;
const SECONDS: usize = 600;
const N: usize = RATE_HZ * SECONDS;
/// A trial every 4 s.
const TRIAL: usize = 4 * RATE_HZ;

const COLUMNS: [&str; 12] = [
    "t", "x", "y", "fx", "fy", "pert_fx", "pert_fy", "ref_x", "ref_y", "cmd_x", "cmd_y", "marker",
];
/// Decimals each column is written with in the CSV.
const DECIMALS: [usize; 12] = [6, 6, 6, 4, 4, 4, 4, 6, 6, 4, 4, 0];

/// A small deterministic noise source (xorshift), in [-1, 1).
struct Noise(u64);

impl Noise {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// The log, column by column, with the values rounded as the CSV writes them, so that
/// both files hold the same numbers.
fn generate() -> Vec<Vec<f64>> {
    let mut cols = vec![Vec::with_capacity(N); COLUMNS.len()];
    let mut noise = Noise(0x2545_f491_4f6c_dd1d);
    let round = |v: f64, d: usize| {
        let p = 10f64.powi(d as i32);
        (v * p).round() / p
    };
    for i in 0..N {
        let t = i as f64 / RATE_HZ as f64;
        let k = i / TRIAL;
        let s = (i % TRIAL) as f64 / RATE_HZ as f64; // time in the trial, s
        // A reach of 100 mm toward a target on a circle, minimum-jerk over 1 s, held,
        // then back over 1 s.
        let angle = (k % 8) as f64 * std::f64::consts::FRAC_PI_4;
        let (gx, gy) = (100.0 * angle.cos(), 100.0 * angle.sin());
        let mj = |u: f64| {
            let u = u.clamp(0.0, 1.0);
            u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
        };
        let along = if s < 2.0 {
            mj(s - 0.5)
        } else {
            1.0 - mj(s - 2.5)
        };
        let pulse = k % 3 == 1 && (1.0..1.1).contains(&s);
        let (pfx, pfy) = if pulse {
            (-8.0 * angle.sin(), 8.0 * angle.cos())
        } else {
            (0.0, 0.0)
        };
        let x = gx * along + 0.05 * noise.next();
        let y = gy * along + 0.05 * noise.next();
        let values = [
            t,
            x,
            y,
            2.0 * (along - 0.5) + 0.3 * noise.next() + pfx * 0.2,
            -1.5 * (along - 0.5) + 0.3 * noise.next() + pfy * 0.2,
            pfx,
            pfy,
            gx * along,
            gy * along,
            4.0 * (gx * along - x) + 0.01 * noise.next(),
            4.0 * (gy * along - y) + 0.01 * noise.next(),
            if i % TRIAL < 40 { 1.0 } else { 0.0 },
        ];
        for (c, v) in values.into_iter().enumerate() {
            cols[c].push(round(v, DECIMALS[c]));
        }
    }
    cols
}

fn write_csv(path: &Path, cols: &[Vec<f64>]) {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    writeln!(out, "{}", COLUMNS.join(",")).unwrap();
    let mut line = String::new();
    for i in 0..N {
        line.clear();
        for (c, col) in cols.iter().enumerate() {
            if c > 0 {
                line.push(',');
            }
            let _ = write!(line, "{:.*}", DECIMALS[c], col[i]);
        }
        line.push('\n');
        out.write_all(line.as_bytes()).unwrap();
    }
    out.flush().unwrap();
}

/// A minimal MATLAB level-5 writer: the 128-byte header, then one uncompressed
/// miMATRIX per column, an N×1 double array.
fn write_mat(path: &Path, cols: &[Vec<f64>]) {
    const MI_INT8: u32 = 1;
    const MI_INT32: u32 = 5;
    const MI_UINT32: u32 = 6;
    const MI_DOUBLE: u32 = 9;
    const MI_MATRIX: u32 = 14;
    const MX_DOUBLE_CLASS: u32 = 6;
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut header =
        b"MATLAB 5.0 MAT-file, Platform: GLNXA64, written by the rigtwin-import bench".to_vec();
    header.resize(116, b' ');
    header.extend_from_slice(&[0; 8]); // no subsystem data
    header.extend_from_slice(&0x0100_u16.to_le_bytes());
    header.extend_from_slice(b"IM");
    out.write_all(&header).unwrap();
    let tag = |ty: u32, len: usize| {
        let mut t = ty.to_le_bytes().to_vec();
        t.extend_from_slice(&u32::try_from(len).unwrap().to_le_bytes());
        t
    };
    for (name, col) in COLUMNS.iter().zip(cols) {
        let mut body = Vec::new();
        body.extend(tag(MI_UINT32, 8));
        body.extend_from_slice(&MX_DOUBLE_CLASS.to_le_bytes());
        body.extend_from_slice(&0_u32.to_le_bytes());
        body.extend(tag(MI_INT32, 8));
        body.extend_from_slice(&u32::try_from(col.len()).unwrap().to_le_bytes());
        body.extend_from_slice(&1_u32.to_le_bytes());
        body.extend(tag(MI_INT8, name.len()));
        body.extend_from_slice(name.as_bytes());
        body.resize(body.len().div_ceil(8) * 8, 0);
        body.extend(tag(MI_DOUBLE, col.len() * 8));
        for v in col {
            body.extend_from_slice(&v.to_le_bytes());
        }
        out.write_all(&tag(MI_MATRIX, body.len())).unwrap();
        out.write_all(&body).unwrap();
    }
    out.flush().unwrap();
}

/// The same columns as a MATLAB v7.3 file (N×1 doubles, deflate-compressed and chunked
/// as MATLAB writes them), through hdf5-pure's MAT writer.
fn write_mat73(path: &Path, cols: &[Vec<f64>]) {
    use hdf5_pure::LibVer;
    use hdf5_pure::mat::{Compression, MatBuilder, Options};
    let mut options = Options::default();
    options.compression = Compression::Deflate {
        level: 3,
        shuffle: true,
    };
    // Compressed (chunked) datasets need the 1.10 chunk indices.
    options.libver = LibVer::V110;
    let mut mat = MatBuilder::new(options);
    for (name, col) in COLUMNS.iter().zip(cols) {
        mat.write_f64(name, &[col.len(), 1], col).unwrap();
    }
    mat.write(path).unwrap();
}

const MAP: &str = r#"
created = "2026-12-01T09:00:00Z"
[time]
var = "t"
[channels]
x_m = { var = "x", scale = 1e-3, unit = "mm" }
y_m = { var = "y", scale = 1e-3, unit = "mm" }
fx_n = { var = "fx", unit = "N" }
fy_n = { var = "fy", unit = "N" }
pert_fx_n = { var = "pert_fx", unit = "N" }
pert_fy_n = { var = "pert_fy", unit = "N" }
ref_x_m = { var = "ref_x", scale = 1e-3, unit = "mm" }
ref_y_m = { var = "ref_y", scale = 1e-3, unit = "mm" }
cmd_fx_n = { var = "cmd_x", unit = "N" }
cmd_fy_n = { var = "cmd_y", unit = "N" }
[device]
kind = "admittance"
mass_kg = [2.0, 2.0]
damping_n_s_per_m = [5.0, 5.0]
[subject]
id = "bench"
[trials]
cut = "marker"
marker = { var = "marker", above = 0.5 }
[perturbation]
from = "channel"
above_n = 0.5
"#;

/// Flushes the machine's dirty pages (the generated logs, a removed session), so that
/// an import is not timed writing back what the bench wrote before it. Best effort.
fn sync() {
    let _ = std::process::Command::new("sync").status();
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let cols = generate();
    let csv = dir.path().join("log.csv");
    let mat = dir.path().join("log.mat");
    let mat73 = dir.path().join("log73.mat");
    write_csv(&csv, &cols);
    write_mat(&mat, &cols);
    write_mat73(&mat73, &cols);
    drop(cols);
    let map = dir.path().join("map.toml");
    std::fs::write(&map, MAP).unwrap();
    let mb = |p: &Path| std::fs::metadata(p).unwrap().len() as f64 / 1e6;
    eprintln!(
        "log: {N} samples ({SECONDS} s at {RATE_HZ} Hz), CSV {:.0} MB, .mat level 5 {:.0} MB, \
         .mat v7.3 {:.0} MB",
        mb(&csv),
        mb(&mat),
        mb(&mat73)
    );

    sync();

    let mut run = 0_usize;
    let mut fresh = |dir: &Path| -> PathBuf {
        // The previous output is removed before the next (outside the timing), so that
        // the disk holds one session at a time, and the removal is flushed, so that
        // its writeback is not timed as the next import's.
        let old = dir.join(format!("out{run}"));
        let _ = std::fs::remove_dir_all(&old);
        sync();
        run += 1;
        dir.join(format!("out{run}"))
    };

    let mut group = c.benchmark_group("import 10 min 4 kHz two-axis");
    group
        .sample_size(10)
        // One import per sample: each takes seconds, so criterion's linear sampling
        // (1 + 2 + … + 10 iterations) would take minutes per case.
        .sampling_mode(SamplingMode::Flat)
        // About ten imports' worth: flat sampling then runs one import per sample.
        .measurement_time(Duration::from_secs(60))
        .warm_up_time(Duration::from_secs(1));
    for (name, file) in [("csv", &csv), ("mat level 5", &mat), ("mat v7.3", &mat73)] {
        // Reading alone (what `inspect` does: the whole log, parsed), then one import.
        let start = Instant::now();
        let inventory = rigtwin_import::inspect(file).unwrap();
        let read_s = start.elapsed().as_secs_f64();
        assert_eq!(inventory.entries.len(), COLUMNS.len());
        let out = fresh(dir.path());
        let start = Instant::now();
        let imported = rigtwin_import::import(std::slice::from_ref(file), &map, &out).unwrap();
        eprintln!(
            "{name}: reading took {read_s:.2} s; one import took {:.2} s ({} trials, {} \
             perturbed)",
            start.elapsed().as_secs_f64(),
            imported.samples.len(),
            imported.perturbed
        );
        assert_eq!(imported.samples.len(), 150);
        group.bench_function(name, |b| {
            b.iter_batched(
                || fresh(dir.path()),
                |out| rigtwin_import::import(std::slice::from_ref(file), &map, &out).unwrap(),
                BatchSize::PerIteration,
            );
        });
    }
    group.finish();
    let _ = std::fs::remove_dir_all(dir.path().join(format!("out{run}")));
}

criterion_group!(benches, bench);
criterion_main!(benches);
