//! Round trips through MATLAB level-5 files written by an independent writer (scipy's
//! `savemat`, `format='5'`, compressed and not): known arrays in, a session out, read
//! back with `rigtwin_session::Session::read` and compared sample by sample.
//!
//! Tolerances: doubles and integer counts are exact (the importer computes
//! `raw * scale + offset` in f64 as the test does, and the session's CSV writes the
//! shortest text that reads back to the same f64); singles are compared with the f32
//! value widened to f64, which is exact too (within 2⁻²⁴ relative of the double they
//! were made from).

#![allow(clippy::unwrap_used, clippy::expect_used)] // a panic in a test is its failure message

mod common;

use std::path::Path;

use common::known::{N, check_samples, map_text, pos_mm, single, trig};
use common::{DEVICE, python, write};
use rigtwin_import::{Map, import, inspect};
use rigtwin_session::{Axes, Session};

fn write_mat(path: &Path, compress: bool) {
    let script = format!(
        r#"
import numpy as np, scipy.io
N = {N}
i = np.arange(N)
pos = (i % 97).astype(float) * 0.25 - 10.0 + (i // 97).astype(float) * 0.5
ref = (i % 50).astype(float) * 0.125
sig = np.stack([i * 0.5 + c * 1000.0 for c in range(3)], axis=1)   # N x 3
counts = (((i * 37) % 4001) - 2000).astype(np.int16)
single = (i * 0.001 + 0.1).astype(np.float32)
trig = (i >= 100) & (((i - 100) % 1000) < 50)
t = i / 1000.0
scipy.io.savemat(r"{path}", {{
    "t": t,
    "data": {{"pos": pos, "ref": ref, "note": "rig A"}},
    "log": {{"signals": {{"values": sig, "wide": sig.T.copy()}}, "label": "run 1"}},
    "counts": counts,
    "u": single,
    "trig": trig,
    "names": np.array(["a", "b"], dtype=object),
}}, do_compression={compress}, format="5", oned_as="row")
"#,
        path = path.display(),
        compress = if compress { "True" } else { "False" },
    );
    python(&script);
}

#[test]
fn structs_matrices_ints_and_singles_round_trip_compressed_and_not() {
    for compress in [true, false] {
        let dir = tempfile::tempdir().unwrap();
        let mat = dir.path().join("block1.mat");
        write_mat(&mat, compress);
        let map = write(dir.path(), "map.toml", &map_text(r#"cut = "whole""#, ""));
        // The pert channels are not mapped: zeros (no [perturbation]); forces are.
        let out = dir.path().join("session");
        let imported = import(std::slice::from_ref(&mat), &map, &out).unwrap();
        assert_eq!(imported.rate_hz, 1000.0);
        assert_eq!(imported.samples, vec![N]);
        let s = Session::read(&out).unwrap();
        assert_eq!(s.manifest.rate_hz, 1000.0);
        assert_eq!(s.manifest.subject.id, "S07");
        assert_eq!(s.manifest.created, "2026-12-01T09:00:00Z");
        assert_eq!(s.manifest.axes, Axes::Both);
        assert_eq!(s.trials.len(), 1);
        assert_eq!(s.trials[0].len(), N);
        check_samples(&s, &[0], |_, _, _| {});
        let text = imported.to_string();
        assert!(text.contains("1 trial at 1000 Hz"), "{text}");
        assert!(text.contains("x_m"), "{text}");
        assert!(text.contains("[mm]"), "{text}");
        assert!(text.contains("pert_fx_n = 0"), "{text}");
    }
}

#[test]
fn logical_marker_cuts_trials_from_a_mat_file() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("log.mat");
    write_mat(&mat, true);
    let map = write(
        dir.path(),
        "map.toml",
        &map_text(
            r#"cut = "marker"
marker = { var = "trig", above = 0.5 }"#,
            "",
        ),
    );
    let out = dir.path().join("s");
    let imported = import(&[mat], &map, &out).unwrap();
    let starts: Vec<usize> = (1..N).filter(|&i| trig(i) && !trig(i - 1)).collect();
    assert_eq!(starts, [100, 1100, 2100]);
    assert_eq!(imported.samples, vec![1000, 1000, N - 2100]);
    let s = Session::read(&out).unwrap();
    check_samples(&s, &starts, |_, _, _| {});
}

#[test]
fn inspect_lists_struct_fields_shapes_classes_and_the_time_rate() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("log.mat");
    write_mat(&mat, true);
    let inv = inspect(&mat).unwrap();
    let get = |n: &str| {
        inv.entries
            .iter()
            .find(|e| e.name == n)
            .unwrap_or_else(|| panic!("{n} missing from {inv}"))
    };
    assert_eq!(get("t").rate_hz, Some(1000.0));
    assert_eq!(get("t").shape, vec![1, N]);
    assert_eq!(get("data.pos").class, "double");
    assert_eq!(get("log.signals.values").shape, vec![N, 3]);
    assert_eq!(get("log.signals.wide").shape, vec![3, N]);
    assert_eq!(get("counts").class, "int16");
    assert_eq!(get("u").class, "single");
    assert_eq!(get("trig").class, "logical");
    assert_eq!(get("data.note").class, "char");
    assert!(!get("data.note").numeric);
    assert!(get("log").class.starts_with("struct"));
    assert_eq!(get("names").class, "cell");
    let text = inv.to_string();
    assert!(text.contains("MATLAB level 5"), "{text}");
    assert!(text.contains("log.signals.values"), "{text}");
    assert!(text.contains("3000×3"), "{text}");
    assert!(text.contains("uniform time: 1000 Hz"), "{text}");
}

#[test]
fn one_axis_rig_writes_the_absent_axis_as_zeros() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("stage.mat");
    write_mat(&mat, false);
    let map = write(
        dir.path(),
        "map.toml",
        &format!(
            r#"
axes = ["x"]
[time]
rate_hz = 1000.0
[channels]
x_m = {{ var = "data.pos", scale = 1e-3, unit = "mm" }}
ref_x_m = {{ var = "data.ref", scale = 1e-3, unit = "mm" }}
cmd_fx_n = {{ var = "u", scale = 12.5, unit = "V" }}
{DEVICE}
[trials]
cut = "whole"
"#
        ),
    );
    let out = dir.path().join("s");
    let imported = import(&[mat], &map, &out).unwrap();
    let s = Session::read(&out).unwrap();
    assert_eq!(s.manifest.axes, Axes::X);
    assert_eq!(s.manifest.subject.id, "stage");
    let t = &s.trials[0];
    assert!(t.y_m.iter().all(|&v| v == 0.0));
    assert!(t.fx_n.iter().all(|&v| v == 0.0));
    assert_eq!(t.ref_y_m.as_ref().unwrap().len(), N);
    assert!(t.ref_y_m.as_ref().unwrap().iter().all(|&v| v == 0.0));
    assert_eq!(t.cmd_fx_n.as_ref().unwrap()[7], f64::from(single(7)) * 12.5);
    let zeroed: Vec<&str> = imported.zeroed.iter().map(|z| z.column.as_str()).collect();
    assert_eq!(zeroed, ["y_m", "fx_n", "fy_n", "pert_fx_n", "pert_fy_n"]);
    let manifest = std::fs::read_to_string(out.join("session.toml")).unwrap();
    assert!(manifest.contains("axes = [\"x\"]"), "{manifest}");
    assert!(manifest.contains("source = \"rig\""), "{manifest}");
    assert!(manifest.contains("kind = \"position-servo\""), "{manifest}");
    let _ = Map::read(&dir.path().join("map.toml")).unwrap();
}

#[test]
fn simulink_structure_with_time_and_struct_arrays() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("sim.mat");
    python(&format!(
        r#"
import numpy as np, scipy.io
N = {N}
i = np.arange(N)
pos = (i % 97).astype(float) * 0.25 - 10.0 + (i // 97).astype(float) * 0.5
trials = np.zeros((1, 2), dtype=[("pos", "O"), ("id", "O")])
trials[0, 0] = (pos * 2.0, 1.0)
trials[0, 1] = (pos * 3.0, 2.0)
scipy.io.savemat(r"{}", {{
    "logsout": {{"time": (i / 2000.0).reshape(N, 1),
                 "signals": {{"values": pos.reshape(1, 1, N), "label": "x"}}}},
    "trials": trials,
}}, do_compression=True, format="5")
"#,
        mat.display()
    ));
    let inv = inspect(&mat).unwrap();
    let names: Vec<&str> = inv.entries.iter().map(|e| e.name.as_str()).collect();
    for n in [
        "logsout.time",
        "logsout.signals.values",
        "trials(1).pos",
        "trials(2).pos",
        "trials(2).id",
    ] {
        assert!(names.contains(&n), "{n} not in {names:?}");
    }
    let time = inv
        .entries
        .iter()
        .find(|e| e.name == "logsout.time")
        .unwrap();
    assert_eq!(time.rate_hz, Some(2000.0));
    let values = inv
        .entries
        .iter()
        .find(|e| e.name == "logsout.signals.values")
        .unwrap();
    assert_eq!(values.shape, vec![1, 1, N]);

    let map = write(
        dir.path(),
        "map.toml",
        &format!(
            r#"
axes = ["x"]
[time]
var = "logsout.time"
[channels]
x_m = {{ var = "logsout.signals.values", scale = 1e-3 }}
ref_x_m = {{ var = "trials(2).pos", scale = 1e-3 }}
{DEVICE}
[trials]
cut = "whole"
"#
        ),
    );
    let out = dir.path().join("s");
    import(&[mat], &map, &out).unwrap();
    let s = Session::read(&out).unwrap();
    assert_eq!(s.manifest.rate_hz, 2000.0);
    let t = &s.trials[0];
    for i in 0..N {
        assert_eq!(t.x_m[i], pos_mm(i) * 1e-3);
        assert_eq!(t.ref_x_m.as_ref().unwrap()[i], pos_mm(i) * 3.0 * 1e-3);
    }
}
