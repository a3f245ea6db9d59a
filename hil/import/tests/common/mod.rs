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
            "python3 cannot import {modules} ({}): run `python3 -m pip install {pip}` (CI does, in .ci/run)",
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
