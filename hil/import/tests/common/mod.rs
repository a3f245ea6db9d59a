//! Helpers shared by the import tests: independent `.mat` writers (Python's scipy for
//! level 5, h5py for v7.3), map files and logs in a temporary directory.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `script` with python3, which must have scipy and numpy: the tests' `.mat` files
/// come from an independent writer. Without them the test fails, never skips.
pub fn python(script: &str) {
    probe("scipy.io, numpy", "scipy numpy");
    run(script);
}

/// Runs `script` with python3, which must have h5py and numpy: the tests' MATLAB v7.3
/// files come from an independent HDF5 writer (the HDF5 C library under h5py). Without
/// them the test fails, never skips.
pub fn python_h5py(script: &str) {
    probe("h5py, numpy", "h5py numpy");
    run(script);
}

/// Fails (never skips) when python3 cannot import `modules`, saying what to install.
fn probe(modules: &str, pip: &str) {
    let probe = Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .output();
    match probe {
        Ok(o) if o.status.success() => {}
        Ok(o) => panic!(
            "python3 cannot import {modules} ({}): run `python3 -m pip install {pip}` (the README's test command does)",
            String::from_utf8_lossy(&o.stderr).trim()
        ),
        Err(e) => {
            panic!("python3 is not available ({e}): install it and `python3 -m pip install {pip}`")
        }
    }
}

fn run(script: &str) {
    let out = Command::new("python3")
        .args(["-c", script])
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "python3 failed:\n{}\n{script}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

/// A map's `[device]` for a rig without force sensor.
pub const DEVICE: &str = r#"
[device]
kind = "position-servo"
mass_kg = [2.0, 2.0]
damping_n_s_per_m = [0.0, 0.0]
force_sensor = false
"#;

/// All files under `dir` with their bytes, sorted by path.
pub fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("read_dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).expect("read");
                out.push((p.strip_prefix(dir).expect("prefix").to_path_buf(), bytes));
            }
        }
    }
    out.sort();
    out
}

/// The known arrays of the `.mat` round trips, computed the same way here and in the
/// Python writers (exact binary arithmetic, so both sides hold the same doubles).
pub mod known {
    use super::DEVICE;
    use rigtwin_session::Session;

    pub const N: usize = 3000;

    pub fn pos_mm(i: usize) -> f64 {
        (i % 97) as f64 * 0.25 - 10.0 + (i / 97) as f64 * 0.5
    }
    pub fn ref_mm(i: usize) -> f64 {
        (i % 50) as f64 * 0.125
    }
    pub fn sig(i: usize, col: usize) -> f64 {
        (i as f64) * 0.5 + (col as f64) * 1000.0
    }
    pub fn counts(i: usize) -> i16 {
        ((i * 37) % 4001) as i16 - 2000
    }
    pub fn single(i: usize) -> f32 {
        ((i as f64) * 0.001 + 0.1) as f32
    }
    pub fn trig(i: usize) -> bool {
        // Rises at 100, 1100, 2100; each pulse lasts 50 samples.
        i >= 100 && (i - 100) % 1000 < 50
    }

    /// The map of the known arrays' files, with `cut` for `[trials]` and `extra` lines
    /// for `[channels]`.
    pub fn map_text(cut: &str, extra: &str) -> String {
        format!(
            r#"
created = "2026-12-01T09:00:00Z"
[time]
var = "t"

[channels]
x_m = {{ var = "data.pos", scale = 1e-3, unit = "mm" }}
ref_x_m = {{ var = "data.ref", scale = 1e-3, unit = "mm" }}
y_m = {{ var = "log.signals.values", column = 2, scale = 1e-6 }}
ref_y_m = {{ var = "log.signals.wide", column = 3, scale = 1e-6 }}
fx_n = {{ var = "counts", scale = 0.01, unit = "count" }}
fy_n = {{ var = "u", scale = 2.0, offset = 0.5, unit = "V" }}
{extra}

{DEVICE}

[subject]
id = "S07"

[trials]
{cut}
kind = "reach"
"#
        )
    }

    /// Every sample of `s` against the known arrays, trial `k` starting at sample
    /// `starts[k]`; `more(trial, i, j)` checks further columns.
    pub fn check_samples(
        s: &Session,
        starts: &[usize],
        more: impl Fn(&rigtwin_session::Trial, usize, usize),
    ) {
        assert_eq!(s.trials.len(), starts.len());
        for (k, (entry, trial)) in s.iter().enumerate() {
            assert_eq!(entry.id as usize, k + 1);
            let a = starts[k];
            for (j, &x) in trial.x_m.iter().enumerate() {
                let i = a + j;
                assert_eq!(x, pos_mm(i) * 1e-3, "x_m trial {} row {j}", k + 1);
                assert_eq!(trial.ref_x_m.as_ref().unwrap()[j], ref_mm(i) * 1e-3);
                assert_eq!(trial.y_m[j], sig(i, 1) * 1e-6, "y_m row {j}");
                assert_eq!(trial.ref_y_m.as_ref().unwrap()[j], sig(i, 2) * 1e-6);
                assert_eq!(trial.fx_n[j], f64::from(counts(i)) * 0.01);
                assert_eq!(trial.fy_n[j], f64::from(single(i)) * 2.0 + 0.5);
                assert_eq!(trial.pert_fx_n[j], 0.0);
                assert_eq!(trial.t_s[j], j as f64 / 1000.0);
                more(trial, i, j);
            }
        }
    }
}
