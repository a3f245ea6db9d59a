//! Bad inputs: each error is the right variant and its message names the file, the
//! line or variable, and the map key. Corrupt `.mat` files are errors, never panics.

#![allow(clippy::unwrap_used, clippy::expect_used)] // a panic in a test is its failure message

mod common;

use std::path::{Path, PathBuf};

use common::{DEVICE, python, write};
use rigtwin_import::{ImportError, Map, import, inspect};

/// 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    1 + text
        .lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("{needle:?} not in the map"))
}

fn name(p: &Path) -> String {
    p.file_name().unwrap().to_string_lossy().into_owned()
}

/// Asserts that `msg` names the map file at `line` and the key.
fn names_map(msg: &str, map: &Path, line: usize, key: &str) {
    assert!(
        msg.contains(&format!("{}:{line}", map.display())),
        "{msg:?} does not name {}:{line}",
        map.display()
    );
    assert!(
        msg.contains(&format!("`{key}`")),
        "{msg:?} does not name key `{key}`"
    );
}

/// A `.mat` file written by scipy from a Python dict literal (numpy as np).
fn mat(dir: &Path, file: &str, vars: &str) -> PathBuf {
    let p = dir.join(file);
    python(&format!(
        "import numpy as np, scipy.io\nN = 1000\ni = np.arange(N)\nscipy.io.savemat(r\"{}\", {vars}, do_compression=False, format='5')",
        p.display()
    ));
    p
}

fn simple_map(time: &str, channels: &str, trials: &str) -> String {
    format!("[time]\n{time}\n\n[channels]\n{channels}\n{DEVICE}\naxes_placeholder = 0\n[trials]\n{trials}\n")
        .replace("axes_placeholder = 0\n", "")
}

struct Case {
    dir: tempfile::TempDir,
    map: PathBuf,
    text: String,
}

impl Case {
    fn new(map_text: &str) -> Case {
        let dir = tempfile::tempdir().unwrap();
        let map = write(dir.path(), "map.toml", map_text);
        Case {
            dir,
            map,
            text: map_text.to_string(),
        }
    }
    fn run(&self, files: &[PathBuf]) -> ImportError {
        import(files, &self.map, &self.dir.path().join("out")).unwrap_err()
    }
    fn line(&self, needle: &str) -> usize {
        line_of(&self.text, needle)
    }
}

const X_ONLY: &str = "x_m = { var = \"pos\", scale = 1e-3 }";

#[test]
fn a_missing_variable_is_named_with_the_names_the_file_has() {
    let text = "axes = [\"x\"]\n".to_string()
        + &simple_map(
            "rate_hz = 1000.0",
            "x_m = { var = \"data.poss\" }",
            "cut = \"whole\"",
        );
    let c = Case::new(&text);
    let f = mat(
        c.dir.path(),
        "log.mat",
        "{'data': {'pos': i * 1.0, 'ref': i * 2.0}}",
    );
    let e = c.run(std::slice::from_ref(&f));
    assert!(matches!(e, ImportError::MissingVariable { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.contains(&name(&f)) && msg.contains("data.poss"),
        "{msg}"
    );
    assert!(msg.contains("data.pos, data.ref"), "{msg}");
    names_map(&msg, &c.map, c.line("data.poss"), "channels.x_m");
}

#[test]
fn a_matrix_without_column_and_a_column_out_of_range_are_wrong_shapes() {
    for (channel, expect) in [
        ("x_m = { var = \"wide\" }", "say which with `column = 1..3`"),
        (
            "x_m = { var = \"wide\", column = 4 }",
            "`column = 4` is not in 1..3",
        ),
        ("x_m = { var = \"cube\", column = 1 }", "more than two"),
        ("x_m = { var = \"label\" }", "char array"),
    ] {
        let text = "axes = [\"x\"]\n".to_string()
            + &simple_map("rate_hz = 1000.0", channel, "cut = \"whole\"");
        let c = Case::new(&text);
        let f = mat(
            c.dir.path(),
            "log.mat",
            "{'wide': np.stack([i, i, i]) * 1.0, 'cube': np.zeros((3, 4, 5)), 'label': 'abc'}",
        );
        let e = c.run(std::slice::from_ref(&f));
        assert!(matches!(e, ImportError::WrongShape { .. }), "{e:?}");
        let msg = e.to_string();
        assert!(msg.contains(expect), "{msg}");
        assert!(msg.contains(&name(&f)), "{msg}");
        names_map(&msg, &c.map, c.line("x_m ="), "channels.x_m");
        if channel.contains("wide") {
            assert!(msg.contains("3×1000"), "{msg}");
        }
    }
}

#[test]
fn channels_of_different_lengths_are_an_error_naming_both() {
    let text = "axes = [\"x\"]\n".to_string()
        + &simple_map(
            "rate_hz = 1000.0",
            "x_m = { var = \"pos\" }\nref_x_m = { var = \"ref\" }",
            "cut = \"whole\"",
        );
    let c = Case::new(&text);
    let f = mat(
        c.dir.path(),
        "log.mat",
        "{'pos': i * 1.0, 'ref': i[:-1] * 1.0}",
    );
    let e = c.run(&[f]);
    assert!(
        matches!(
            e,
            ImportError::LengthMismatch {
                len: 999,
                other_len: 1000,
                ..
            }
        ),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains("`ref` has 999") && msg.contains("`pos` (channels.x_m) has 1000"),
        "{msg}"
    );
    names_map(&msg, &c.map, c.line("ref_x_m"), "channels.ref_x_m");
}

#[test]
fn nan_and_inf_samples_are_named_by_variable_sample_and_line() {
    let text =
        "axes = [\"x\"]\n".to_string() + &simple_map("rate_hz = 1000.0", X_ONLY, "cut = \"whole\"");
    let c = Case::new(&text);
    let f = mat(
        c.dir.path(),
        "log.mat",
        "{'pos': np.where(i == 17, np.nan, i * 1.0)}",
    );
    let e = c.run(&[f]);
    assert!(
        matches!(
            e,
            ImportError::NonFinite {
                sample: rigtwin_import::SampleAt {
                    sample: 18,
                    line: None
                },
                ..
            }
        ),
        "{e:?}"
    );
    names_map(&e.to_string(), &c.map, c.line("x_m"), "channels.x_m");

    // In a text log: the line, counted with comments and CRLF.
    let csv = write(
        c.dir.path(),
        "log.csv",
        "# c\r\npos\r\n1\r\n2\r\ninf\r\n4\r\n",
    );
    let e = c.run(&[csv]);
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            ImportError::NonFinite {
                sample: rigtwin_import::SampleAt {
                    sample: 3,
                    line: Some(5)
                },
                ..
            }
        ),
        "{e:?}"
    );
    assert!(msg.contains("log.csv") && msg.contains("line 5"), "{msg}");
}

#[test]
fn text_faults_name_their_line() {
    let text =
        "axes = [\"x\"]\n".to_string() + &simple_map("rate_hz = 1000.0", X_ONLY, "cut = \"whole\"");
    let c = Case::new(&text);
    // A field that is not a number, in a used column.
    let csv = write(
        c.dir.path(),
        "a.csv",
        "pos,note\r\n1,ok\r\n# c\r\n2x,ok\r\n",
    );
    let e = c.run(&[csv]);
    assert!(matches!(e, ImportError::BadNumber { line: 4, .. }), "{e:?}");
    names_map(&e.to_string(), &c.map, c.line("x_m"), "channels.x_m");
    // Text in a column the map does not use is fine.
    let ok = write(c.dir.path(), "b.csv", "pos,note\n1,ok\n2,fine\n");
    import(&[ok], &c.map, &c.dir.path().join("ok")).unwrap();
    // A row with a missing field.
    let ragged = write(c.dir.path(), "c.csv", "pos,note\r\n1,a\r\n\r\n2\r\n");
    let e = c.run(&[ragged]);
    assert!(matches!(e, ImportError::Csv { line: 4, .. }), "{e:?}");
    assert!(e.to_string().contains("c.csv:4"), "{e}");
}

#[test]
fn non_uniform_time_names_the_sample() {
    let text =
        "axes = [\"x\"]\n".to_string() + &simple_map("var = \"t\"", X_ONLY, "cut = \"whole\"");
    let c = Case::new(&text);
    let f = mat(
        c.dir.path(),
        "log.mat",
        "{'t': np.where(i >= 500, i + 1, i) / 1000.0, 'pos': i * 1.0}",
    );
    let e = c.run(&[f]);
    let ImportError::NonUniformTime { sample, .. } = &e else {
        panic!("{e:?}")
    };
    // The fitted clock is off by up to half a period on both sides of the gap; the
    // first sample off it is named.
    assert!(sample.sample <= 501, "{e}");
    names_map(&e.to_string(), &c.map, c.line("var = \"t\""), "time.var");

    // A missing row in a CSV, with its line.
    let mut csv = String::from("t,pos\n");
    for i in (0..100).filter(|&i| i != 60) {
        csv.push_str(&format!("{:.3},{i}\n", f64::from(i) / 1000.0));
    }
    let f = write(c.dir.path(), "gap.csv", &csv);
    let e = c.run(&[f]);
    assert!(matches!(e, ImportError::NonUniformTime { .. }), "{e:?}");
    assert!(e.to_string().contains("line"), "{e}");
}

#[test]
fn a_marker_that_never_rises_and_onsets_past_the_end() {
    let text = "axes = [\"x\"]\n".to_string()
        + &simple_map(
            "rate_hz = 100.0",
            X_ONLY,
            "cut = \"marker\"\nmarker = { var = \"trig\", above = 0.5 }",
        );
    let c = Case::new(&text);
    let csv = write(c.dir.path(), "m.csv", "pos,trig\n1,0\n2,0.4\n3,0\n");
    let e = c.run(&[csv]);
    assert!(matches!(e, ImportError::MarkerNeverRises { .. }), "{e:?}");
    names_map(&e.to_string(), &c.map, c.line("marker ="), "trials.marker");

    let text = "axes = [\"x\"]\n".to_string()
        + &simple_map(
            "rate_hz = 100.0",
            X_ONLY,
            "cut = \"onsets\"\nonsets_s = [0.0, 0.02, 5.0]",
        );
    let c = Case::new(&text);
    let csv = write(c.dir.path(), "o.csv", "pos\n1\n2\n3\n4\n5\n");
    let e = c.run(&[csv]);
    assert!(
        matches!(e, ImportError::TrialOutsideLog { trial: 3, .. }),
        "{e:?}"
    );
    names_map(
        &e.to_string(),
        &c.map,
        c.line("onsets_s"),
        "trials.onsets_s",
    );
}

#[test]
fn required_channels_missing_are_errors_unless_their_axis_or_sensor_is_absent() {
    // Two axes, no y_m: an error naming channels.y_m.
    let text = simple_map("rate_hz = 100.0", X_ONLY, "cut = \"whole\"");
    let c = Case::new(&text);
    let csv = write(c.dir.path(), "a.csv", "pos\n1\n2\n");
    let e = c.run(&[csv]);
    assert!(
        matches!(&e, ImportError::MissingChannel { column, .. } if column == "y_m"),
        "{e:?}"
    );
    names_map(&e.to_string(), &c.map, c.line("[channels]"), "channels.y_m");

    // A force sensor (the default) and no fx_n.
    let text = "axes = [\"x\"]\n".to_string()
        + &simple_map("rate_hz = 100.0", X_ONLY, "cut = \"whole\"")
            .replace("force_sensor = false\n", "");
    let c = Case::new(&text);
    let csv = write(c.dir.path(), "a.csv", "pos\n1\n2\n");
    let e = c.run(&[csv]);
    assert!(
        matches!(&e, ImportError::MissingChannel { column, .. } if column == "fx_n"),
        "{e:?}"
    );
    assert!(e.to_string().contains("force_sensor = false"), "{e}");

    // Perturbations from the channel need it mapped.
    let text = "axes = [\"x\"]\n".to_string()
        + &simple_map("rate_hz = 100.0", X_ONLY, "cut = \"whole\"")
        + "[perturbation]\nfrom = \"channel\"\n";
    let c = Case::new(&text);
    let csv = write(c.dir.path(), "a.csv", "pos\n1\n2\n");
    let e = c.run(&[csv]);
    assert!(
        matches!(&e, ImportError::MissingChannel { column, .. } if column == "pert_fx_n"),
        "{e:?}"
    );
}

#[test]
fn bad_map_values_name_the_map_line_and_key() {
    let base =
        "axes = [\"x\"]\n".to_string() + &simple_map("rate_hz = 1000.0", X_ONLY, "cut = \"whole\"");
    // (edit, needle on the faulty line, key, expected variant)
    let cases: [(&str, &str, &str, &str, &str); 12] = [
        (
            "scale = 1e-3",
            "scal = 1e-3",
            "scal",
            "channels.x_m.scal",
            "unknown",
        ),
        (
            "force_sensor = false",
            "force_sensr = false",
            "force_sensr",
            "device.force_sensr",
            "unknown",
        ),
        (
            "axes = [\"x\"]",
            "axis = [\"x\"]",
            "axis",
            "axis",
            "unknown",
        ),
        (
            "mass_kg = [2.0, 2.0]",
            "mass_kg = [2.0, -1.0]",
            "mass_kg",
            "device.mass_kg",
            "value",
        ),
        (
            "mass_kg = [2.0, 2.0]",
            "mass_kg = [2.0]",
            "mass_kg",
            "device.mass_kg",
            "value",
        ),
        (
            "cut = \"whole\"",
            "cut = \"hole\"",
            "cut =",
            "trials.cut",
            "value",
        ),
        ("x_m = {", "xx_m = {", "xx_m", "channels.xx_m", "unknown"),
        (
            "rate_hz = 1000.0",
            "rate_hz = -5.0",
            "rate_hz",
            "time.rate_hz",
            "value",
        ),
        (
            "rate_hz = 1000.0",
            "rate_hz = \"fast\"",
            "rate_hz",
            "time.rate_hz",
            "syntax",
        ),
        ("axes = [\"x\"]", "axes = [\"z\"]", "axes", "axes", "value"),
        (
            "cut = \"whole\"",
            "cut = \"whole\"\nmarker = { var = \"m\" }",
            "marker",
            "trials.marker",
            "value",
        ),
        (
            "scale = 1e-3",
            "scale = 1e-3, column = 0",
            "column = 0",
            "channels.x_m",
            "value",
        ),
    ];
    for (from, to, needle, key, kind) in cases {
        let text = base.replacen(from, to, 1);
        assert_ne!(text, base, "{from}");
        let c = Case::new(&text);
        let e = Map::read(&c.map).unwrap_err();
        let ok = match kind {
            "unknown" => matches!(e, ImportError::MapUnknownKey { .. }),
            "value" => matches!(e, ImportError::MapValue { .. }),
            _ => matches!(e, ImportError::MapSyntax { .. }),
        };
        assert!(ok, "{to}: {e:?}");
        names_map(&e.to_string(), &c.map, c.line(needle), key);
        // import reports the same, before reading any log.
        assert!(matches!(
            c.run(&[c.dir.path().join("absent.csv")]),
            ImportError::MapUnknownKey { .. }
                | ImportError::MapValue { .. }
                | ImportError::MapSyntax { .. }
        ));
    }
    // A missing required key names its table.
    let text = base.replace("mass_kg = [2.0, 2.0]\n", "");
    let c = Case::new(&text);
    let e = Map::read(&c.map).unwrap_err();
    assert!(matches!(e, ImportError::MapMissingKey { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(msg.contains("`device.mass_kg`"), "{msg}");
    names_map(&msg, &c.map, c.line("[device]"), "device.mass_kg");
    // So does a missing table.
    let text = base.replace("[trials]\ncut = \"whole\"\n", "");
    let c = Case::new(&text);
    let e = Map::read(&c.map).unwrap_err();
    assert!(matches!(e, ImportError::MapMissingKey { .. }), "{e:?}");
    names_map(&e.to_string(), &c.map, 1, "trials");
}

#[test]
fn output_must_be_new_or_empty() {
    let text =
        "axes = [\"x\"]\n".to_string() + &simple_map("rate_hz = 100.0", X_ONLY, "cut = \"whole\"");
    let c = Case::new(&text);
    let csv = write(c.dir.path(), "a.csv", "pos\n1\n2\n");
    let out = c.dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    import(std::slice::from_ref(&csv), &c.map, &out).unwrap();
    let e = import(&[csv], &c.map, &out).unwrap_err();
    assert!(matches!(e, ImportError::OutputNotEmpty { .. }), "{e:?}");
    assert!(e.to_string().contains("out"), "{e}");
}

#[test]
fn a_v73_file_whose_hdf5_part_is_garbage_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Nov 30 10:00:00 2026 HDF5 schema 1.00 .".to_vec();
    bytes.resize(512, b' ');
    bytes.extend_from_slice(b"\x89HDF\r\n\x1a\n");
    bytes.extend((0..1536_u32).map(|k| (k.wrapping_mul(2_654_435_761) >> 24) as u8));
    let f = dir.path().join("big.mat");
    std::fs::write(&f, &bytes).unwrap();
    let e = inspect(&f).unwrap_err();
    assert!(
        matches!(&e, ImportError::MatV73Corrupt { what, .. } if what == "HDF5 file"),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(msg.contains("big.mat") && msg.contains("v7.3"), "{msg}");
    // The HDF5 signature alone (at byte 512) is enough to read it as v7.3.
    bytes[..10].copy_from_slice(b"MATLAB 5.0");
    std::fs::write(&f, &bytes).unwrap();
    assert!(matches!(
        inspect(&f),
        Err(ImportError::MatV73Corrupt { .. })
    ));
    // MATLAB's header with nothing behind it.
    std::fs::write(&f, &bytes[..200]).unwrap();
    let mut short = bytes[..200].to_vec();
    short[..10].copy_from_slice(b"MATLAB 7.3");
    std::fs::write(&f, &short).unwrap();
    assert!(matches!(
        inspect(&f),
        Err(ImportError::MatV73Corrupt { .. })
    ));
}

#[test]
fn truncated_and_bit_flipped_mat_files_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    for compress in ["True", "False"] {
        let p = dir.path().join(format!("log{compress}.mat"));
        python(&format!(
            "import numpy as np, scipy.io\ni = np.arange(300)\nscipy.io.savemat(r\"{}\", {{'t': i / 100.0, 's': {{'a': i * 1.0, 'b': {{'c': i.astype(np.int16)}}}}, 'm': np.stack([i, i]).astype(np.float32)}}, do_compression={compress}, format='5')",
            p.display()
        ));
        let good = std::fs::read(&p).unwrap();
        assert!(inspect(&p).is_ok());
        // Truncated anywhere past the header: an error (or, cut between elements, fewer
        // variables), never a panic.
        let cut = dir.path().join("cut.mat");
        for len in (0..good.len())
            .step_by(7)
            .chain([good.len() / 2, good.len() - 1])
        {
            std::fs::write(&cut, &good[..len]).unwrap();
            let r = inspect(&cut);
            if len < 128 {
                assert!(
                    matches!(r, Err(ImportError::MatCorrupt { .. })),
                    "{len}: {r:?}"
                );
            }
        }
        std::fs::write(&cut, &good[..good.len() / 2]).unwrap();
        let e = inspect(&cut).unwrap_err();
        assert!(matches!(e, ImportError::MatCorrupt { .. }), "{e:?}");
        assert!(e.to_string().contains("cut.mat"), "{e}");
        // Every other byte flipped in turn, one at a time.
        let flip = dir.path().join("flip.mat");
        let mut errors = 0;
        for k in (128..good.len()).step_by(2) {
            let mut bad = good.clone();
            bad[k] ^= 0xff;
            std::fs::write(&flip, &bad).unwrap();
            errors += usize::from(inspect(&flip).is_err());
        }
        assert!(errors > 0);
        // A flipped byte in the first element's tag is an error.
        let mut bad = good.clone();
        bad[131] ^= 0x40;
        std::fs::write(&flip, &bad).unwrap();
        assert!(matches!(
            inspect(&flip),
            Err(ImportError::MatCorrupt { .. })
        ));
    }
}
