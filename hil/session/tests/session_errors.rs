//! Every way a session can break the format gives its own error variant, naming the
//! file, the line and the field. Each case corrupts a copy of `example-none`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::fs;
use std::path::{Path, PathBuf};

use rigtwin_session::{Session, SessionError};

fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/recordings")
        .join(name)
}

/// A writable copy of `example-none`.
fn copy() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let src = shared("example-none");
    fs::create_dir(dir.path().join("trials")).unwrap();
    fs::copy(src.join("session.toml"), dir.path().join("session.toml")).unwrap();
    for e in fs::read_dir(src.join("trials")).unwrap() {
        let e = e.unwrap();
        fs::copy(e.path(), dir.path().join("trials").join(e.file_name())).unwrap();
    }
    dir
}

fn edit(path: &Path, f: impl FnOnce(String) -> String) {
    let text = fs::read_to_string(path).unwrap();
    fs::write(path, f(text)).unwrap();
}

/// Replaces 1-based line `n`.
fn replace_line(text: &str, n: usize, with: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    lines[n - 1] = with;
    lines.join("\n") + "\n"
}

/// A copy whose manifest has no digests, so that edited trial files reach the parser.
fn copy_without_sha() -> tempfile::TempDir {
    let dir = copy();
    edit(&dir.path().join("session.toml"), |t| {
        t.lines()
            .filter(|l| !l.starts_with("sha256"))
            .map(|l| format!("{l}\n"))
            .collect()
    });
    dir
}

fn manifest(dir: &tempfile::TempDir) -> PathBuf {
    dir.path().join("session.toml")
}

fn trial1(dir: &tempfile::TempDir) -> PathBuf {
    dir.path().join("trials/0001.csv")
}

/// The error names its file and line in its message, as a person reads it.
fn read_err(dir: &tempfile::TempDir) -> SessionError {
    let e = Session::read(dir.path()).expect_err("the corrupted session must not read");
    let text = e.to_string();
    assert!(text.contains(&e.file().display().to_string()), "{text}");
    if let Some(line) = e.line() {
        assert!(
            text.contains(&format!(":{line}")) || text.contains(&format!("line {line}")),
            "{text}"
        );
    }
    e
}

#[test]
fn unclosed_table_header_is_a_toml_error_at_its_line() {
    let d = copy();
    edit(&manifest(&d), |t| t.replace("[device]", "[device"));
    match read_err(&d) {
        SessionError::Toml { file, line, .. } => assert_eq!((file, line), (manifest(&d), 7)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn wrong_format_and_version_are_named() {
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replace("\"rig-session\"", "\"rig-sessions\"")
    });
    match read_err(&d) {
        SessionError::WrongFormat {
            file,
            line,
            field,
            found,
        } => {
            assert_eq!(
                (file, line, field.as_str(), found.as_str()),
                (manifest(&d), 1, "format", "rig-sessions")
            );
        }
        e => panic!("{e:?}"),
    }
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replace("format_version = 1", "format_version = 2")
    });
    match read_err(&d) {
        SessionError::UnsupportedVersion { line, found, .. } => assert_eq!((line, found), (2, 2)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn missing_keys_are_named_with_their_table() {
    let d = copy();
    edit(&manifest(&d), |t| replace_line(&t, 4, ""));
    match read_err(&d) {
        SessionError::MissingKey { field, .. } => assert_eq!(field, "rate_hz"),
        e => panic!("{e:?}"),
    }
    // The first trial's `kind` (line 25): the error points at its [[trial]] (line 21).
    let d = copy();
    edit(&manifest(&d), |t| replace_line(&t, 25, ""));
    match read_err(&d) {
        SessionError::MissingKey { line, field, .. } => {
            assert_eq!((line, field.as_str()), (21, "trial.kind"))
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn unknown_key_in_a_strict_table_is_an_error_but_subject_keeps_extras() {
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replace("[device]\n", "[device]\nhandle_mass = 0.3\n")
    });
    match read_err(&d) {
        SessionError::UnknownKey { line, field, .. } => {
            assert_eq!((line, field.as_str()), (8, "device.handle_mass"))
        }
        e => panic!("{e:?}"),
    }
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replace("[subject]\n", "[subject]\nhandedness = \"right\"\n")
    });
    let s = Session::read(d.path()).unwrap();
    assert_eq!(
        s.manifest
            .subject
            .extra
            .get("handedness")
            .and_then(|v| v.as_str()),
        Some("right")
    );
}

#[test]
fn bad_manifest_values_are_named() {
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replacen("onset_s = 1.588375", "onset_s = nan", 1)
    });
    match read_err(&d) {
        SessionError::InvalidValue { line, field, .. } => {
            assert_eq!((line, field.as_str()), (31, "trial.perturbation.onset_s"));
        }
        e => panic!("{e:?}"),
    }
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replace("mass_kg = [5.0, 5.0]", "mass_kg = [5.0, 5.0, 5.0]")
    });
    match read_err(&d) {
        SessionError::InvalidValue { line, field, .. } => {
            assert_eq!((line, field.as_str()), (9, "device.mass_kg"))
        }
        e => panic!("{e:?}"),
    }
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replace("rate_hz = 1000.0", "rate_hz = -1000.0")
    });
    match read_err(&d) {
        SessionError::InvalidValue { line, field, .. } => {
            assert_eq!((line, field.as_str()), (4, "rate_hz"))
        }
        e => panic!("{e:?}"),
    }
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replace("file = \"trials/0001.csv\"", "file = \"../0001.csv\"")
    });
    match read_err(&d) {
        SessionError::InvalidValue { line, field, .. } => {
            assert_eq!((line, field.as_str()), (23, "trial.file"))
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn duplicate_trial_id_names_both_lines() {
    let d = copy();
    // The second [[trial]]'s id (line 37) becomes 1.
    edit(&manifest(&d), |t| t.replacen("id = 2\n", "id = 1\n", 1));
    match read_err(&d) {
        SessionError::DuplicateTrialId {
            line,
            first_line,
            id,
            field,
            ..
        } => {
            assert_eq!(
                (line, first_line, id, field.as_str()),
                (37, 22, 1, "trial.id")
            );
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn missing_trial_file_is_named_at_its_manifest_line() {
    let d = copy();
    fs::remove_file(d.path().join("trials/0003.csv")).unwrap();
    match read_err(&d) {
        SessionError::TrialFileMissing {
            file,
            line,
            missing,
            ..
        } => {
            assert_eq!(file, manifest(&d));
            assert_eq!(missing, d.path().join("trials/0003.csv"));
            let text = fs::read_to_string(manifest(&d)).unwrap();
            assert_eq!(
                text.lines().nth(line - 1),
                Some("file = \"trials/0003.csv\"")
            );
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn changed_trial_file_fails_its_digest() {
    let d = copy();
    edit(&d.path().join("trials/0002.csv"), |t| {
        t.replacen("-0.125", "-0.126", 1)
    });
    match read_err(&d) {
        SessionError::ShaMismatch {
            file,
            manifest: m,
            line,
            expected,
            actual,
        } => {
            assert_eq!(file, d.path().join("trials/0002.csv"));
            assert_eq!(m, manifest(&d));
            let text = fs::read_to_string(manifest(&d)).unwrap();
            assert_eq!(
                text.lines().nth(line - 1),
                Some(format!("sha256 = \"{expected}\"").as_str())
            );
            assert_ne!(expected, actual);
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn truncated_trial_file_has_a_short_last_row() {
    let d = copy_without_sha();
    edit(&trial1(&d), |t| {
        let keep: Vec<&str> = t.lines().take(101).collect();
        let last = keep[100].split(',').take(5).collect::<Vec<_>>().join(",");
        keep[..100].join("\n") + "\n" + &last
    });
    match read_err(&d) {
        SessionError::FieldCount {
            file,
            line,
            expected,
            found,
        } => {
            assert_eq!((file, line, expected, found), (trial1(&d), 101, 13, 5));
        }
        e => panic!("{e:?}"),
    }
}

/// Sets field `column` (0-based) of 1-based line `n` of a trial file.
fn set_field(path: &Path, n: usize, column: usize, value: &str) {
    edit(path, |t| {
        let line = t.lines().nth(n - 1).unwrap();
        let mut fields: Vec<&str> = line.split(',').collect();
        fields[column] = value;
        let joined = fields.join(",");
        replace_line(&t, n, &joined)
    });
}

#[test]
fn nan_inf_empty_and_text_fields_are_named_by_line_and_column() {
    for (text, want) in [
        ("NaN", "NonFinite"),
        ("inf", "NonFinite"),
        ("-infinity", "NonFinite"),
        ("", "EmptyField"),
        ("0.1.2", "BadNumber"),
    ] {
        let d = copy_without_sha();
        set_field(&trial1(&d), 50, 4, text);
        let e = read_err(&d);
        let (file, line, column) = match &e {
            SessionError::NonFinite {
                file, line, column, ..
            } if want == "NonFinite" => (file, line, column),
            SessionError::EmptyField { file, line, column } if want == "EmptyField" => {
                (file, line, column)
            }
            SessionError::BadNumber {
                file, line, column, ..
            } if want == "BadNumber" => (file, line, column),
            e => panic!("{text:?}: {e:?}"),
        };
        assert_eq!(
            (file, *line, column.as_str()),
            (&trial1(&d), 50, "fy_n"),
            "{text:?}"
        );
    }
}

#[test]
fn missing_sample_is_non_uniform_time() {
    let d = copy_without_sha();
    edit(&trial1(&d), |t| {
        let lines: Vec<&str> = t.lines().collect();
        [&lines[..199], &lines[200..]].concat().join("\n") + "\n"
    });
    match read_err(&d) {
        SessionError::NonUniformTime {
            file,
            line,
            column,
            expected_s,
            found_s,
        } => {
            assert_eq!((file, line, column.as_str()), (trial1(&d), 200, "t_s"));
            assert_eq!((expected_s, found_s), (0.198, 0.199));
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn repeated_time_is_non_monotonic_and_late_start_is_non_uniform() {
    let d = copy_without_sha();
    set_field(&trial1(&d), 301, 0, "0.298");
    match read_err(&d) {
        SessionError::NonMonotonicTime {
            line,
            previous_s,
            found_s,
            ..
        } => {
            assert_eq!((line, previous_s, found_s), (301, 0.298, 0.298));
        }
        e => panic!("{e:?}"),
    }
    let d = copy_without_sha();
    set_field(&trial1(&d), 2, 0, "-0.001");
    match read_err(&d) {
        SessionError::NonUniformTime {
            line, expected_s, ..
        } => assert_eq!((line, expected_s), (2, 0.0)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn missing_or_duplicate_column_is_named() {
    let d = copy_without_sha();
    set_field(&trial1(&d), 1, 6, "pert_fy");
    match read_err(&d) {
        SessionError::MissingColumn { file, line, column } => {
            assert_eq!((file, line, column.as_str()), (trial1(&d), 1, "pert_fy_n"));
        }
        e => panic!("{e:?}"),
    }
    let d = copy_without_sha();
    set_field(&trial1(&d), 1, 12, "x_m");
    match read_err(&d) {
        SessionError::BadColumnName { line, column, .. } => {
            assert_eq!((line, column.as_str()), (1, "x_m"))
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn header_only_table_has_no_samples() {
    let d = copy_without_sha();
    edit(&trial1(&d), |t| {
        t.lines().next().unwrap().to_string() + "\n"
    });
    match read_err(&d) {
        SessionError::NoSamples { file, line } => assert_eq!((file, line), (trial1(&d), 1)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn onset_after_the_trial_is_named() {
    let d = copy();
    edit(&manifest(&d), |t| {
        t.replacen("onset_s = 1.588375", "onset_s = 3.6", 1)
    });
    match read_err(&d) {
        SessionError::PerturbationOutsideTrial {
            file,
            line,
            field,
            onset_s,
            end_s,
        } => {
            assert_eq!(
                (file, line, field.as_str()),
                (manifest(&d), 31, "trial.perturbation.onset_s")
            );
            assert_eq!((onset_s, end_s), (3.6, 3.499));
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn comments_reordered_columns_crlf_and_unknown_columns_still_read() {
    let d = copy_without_sha();
    let original = Session::read(shared("example-none")).unwrap();
    // Swap the first two columns, add an unknown one, comment lines, CRLF ends.
    edit(&trial1(&d), |t| {
        let mut out = String::from("# exported by a lab tool\r\n");
        for (i, line) in t.lines().enumerate() {
            let f: Vec<&str> = line.split(',').collect();
            let extra = if i == 0 {
                "marker_v".to_string()
            } else {
                format!("{}", i % 3)
            };
            out += &format!("{},{},{},{extra}\r\n", f[1], f[0], f[2..].join(","));
            if i == 10 {
                out += "# a note in the middle\r\n";
            }
        }
        out
    });
    let s = Session::read(d.path()).unwrap();
    let (a, b) = (&s.trials[0], &original.trials[0]);
    assert_eq!(
        (&a.t_s, &a.x_m, &a.fy_n, &a.cmd_fy_n),
        (&b.t_s, &b.x_m, &b.fy_n, &b.cmd_fy_n)
    );
    assert_eq!(a.extra.len(), 1);
    assert_eq!(a.extra[0].name, "marker_v");
    assert_eq!(&a.extra[0].values[..4], &[1.0, 2.0, 0.0, 1.0]);
    // Line numbers count the comment lines: a NaN on physical line 60 is reported there.
    set_field(&trial1(&d), 60, 2, "nan");
    match read_err(&d) {
        SessionError::NonFinite { line, column, .. } => {
            assert_eq!((line, column.as_str()), (60, "y_m"))
        }
        e => panic!("{e:?}"),
    }
}

/// CRLF files (what Windows, MATLAB and Excel write) are numbered like LF files: the
/// physical line of the bad field, counted from 1, whatever ends the lines before it.
/// (The csv crate's own count was one short after CRLF lines.)
#[test]
fn crlf_files_name_the_physical_line() {
    for (line, column, value) in [(2, 1, "x"), (60, 2, "nan"), (3500, 0, "9")] {
        let d = copy_without_sha();
        set_field(&trial1(&d), line, column, value);
        edit(&trial1(&d), |t| {
            format!("# a comment\r\n{}", t.replace('\n', "\r\n"))
        });
        let e = read_err(&d);
        assert_eq!(e.line(), Some(line + 1), "{e}");
    }
}

/// `axes` is optional: a one-axis rig lists its axis, the manifest writes it back, and a
/// list that is not one of the three is an error at its line.
#[test]
fn axes_are_optional_round_trip_and_bad_lists_are_named() {
    use rigtwin_session::{Axes, Manifest};
    let d = copy();
    assert_eq!(Session::read(d.path()).unwrap().manifest.axes, Axes::Both);
    edit(&manifest(&d), |t| {
        t.replace("rate_hz = 1000.0", "rate_hz = 1000.0\naxes = [\"x\"]")
    });
    let m = Session::read(d.path()).unwrap().manifest;
    assert_eq!(m.axes, Axes::X);
    assert!(m.axes.has(0) && !m.axes.has(1));
    let again = Manifest::from_toml(&m.to_toml(), Path::new("again.toml")).unwrap();
    assert_eq!(again, m, "axes must survive a write and a read");
    for bad in ["[\"z\"]", "[]", "[\"x\", \"x\"]", "[\"y\", \"x\"]"] {
        let d = copy();
        edit(&manifest(&d), |t| {
            t.replace(
                "rate_hz = 1000.0",
                &format!("rate_hz = 1000.0\naxes = {bad}"),
            )
        });
        match read_err(&d) {
            SessionError::InvalidValue { line, field, .. } => {
                assert_eq!((line, field.as_str()), (5, "axes"), "{bad}")
            }
            e => panic!("{bad}: {e:?}"),
        }
    }
}
