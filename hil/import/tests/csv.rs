//! Continuous text logs: cut by a marker column, by a table of onsets and by movement
//! starts; header or not, comma or tab, comments and CRLF.

#![allow(clippy::unwrap_used, clippy::expect_used)] // a panic in a test is its failure message

mod common;

use common::{DEVICE, tree, write};
use rigtwin_import::{import, inspect};
use rigtwin_session::{Amplitude, Session};

const RATE: f64 = 500.0;
const N: usize = 2000;

fn x_mm(i: usize) -> f64 {
    (i % 200) as f64 * 0.5 - 20.0
}
fn y_mm(i: usize) -> f64 {
    (i % 31) as f64 * 0.25
}
fn marker(i: usize) -> u8 {
    // Rises at 150, 650, 1150, 1650; high for 10 samples.
    u8::from(i >= 150 && (i - 150) % 500 < 10)
}
/// A perturbation pulse in the second trial: 40 samples from 700, up to 8 N at 30°.
fn pert(i: usize) -> (f64, f64) {
    if (700..740).contains(&i) {
        let m = 8.0 - (i as f64 - 720.0).abs() * 0.25;
        let a = 30_f64.to_radians();
        (m * a.cos(), m * a.sin())
    } else {
        (0.0, 0.0)
    }
}

/// The log as text: `sep`-separated, with or without header, CRLF line ends, comments.
fn log_text(sep: &str, header: bool) -> String {
    let mut s = String::from("# rig A, block 1\r\n# exported by the lab's logger\r\n");
    if header {
        s.push_str(&["time_s", "x", "y", "fx", "fy", "pfx", "pfy", "trig", "idx"].join(sep));
        s.push_str("\r\n");
    }
    for i in 0..N {
        let (px, py) = pert(i);
        let row = [
            format!("{:.3}", i as f64 / RATE),
            format!("{}", x_mm(i)),
            format!("{}", y_mm(i)),
            format!("{}", i as f64 * 0.01),
            format!("{}", -(i as f64) * 0.02),
            format!("{px}"),
            format!("{py}"),
            format!("{}", marker(i)),
            format!("{i}"),
        ];
        s.push_str(&row.join(sep));
        s.push_str("\r\n");
        if i == 500 {
            s.push_str("# a comment in the middle\r\n");
        }
    }
    s
}

fn map_text(names: [&str; 9], cut: &str, extra: &str) -> String {
    let [t, x, y, fx, fy, pfx, pfy, trig, idx] = names;
    format!(
        r#"
[time]
var = "{t}"

[channels]
x_m = {{ var = "{x}", scale = 1e-3, unit = "mm" }}
y_m = {{ var = "{y}", scale = 1e-3, unit = "mm" }}
fx_n = {{ var = "{fx}" }}
fy_n = {{ var = "{fy}" }}
pert_fx_n = {{ var = "{pfx}" }}
pert_fy_n = {{ var = "{pfy}" }}
ref_x_m = {{ var = "{idx}" }}   # the sample index, to find where each trial starts

[device]
kind = "admittance"
mass_kg = [5.0, 5.0]
damping_n_s_per_m = [15.0, 15.0]
handle_mass_kg = 0.35

[trials]
{cut}
marker = {{ var = "{trig}" }}

{extra}
"#
    )
}

const HEADER_NAMES: [&str; 9] = ["time_s", "x", "y", "fx", "fy", "pfx", "pfy", "trig", "idx"];
const NO_HEADER_NAMES: [&str; 9] = [
    "col1", "col2", "col3", "col4", "col5", "col6", "col7", "col8", "col9",
];

fn check_marker_session(s: &Session) {
    let starts = [150, 650, 1150, 1650];
    assert_eq!(s.trials.len(), 4);
    for (k, (entry, trial)) in s.iter().enumerate() {
        let a = starts[k];
        let b = starts.get(k + 1).copied().unwrap_or(N);
        assert_eq!(trial.len(), b - a, "trial {}", k + 1);
        assert_eq!(trial.ref_x_m.as_ref().unwrap()[0], a as f64);
        for (j, &x) in trial.x_m.iter().enumerate() {
            assert_eq!(x, x_mm(a + j) * 1e-3);
            assert_eq!(trial.y_m[j], y_mm(a + j) * 1e-3);
            assert_eq!(trial.fx_n[j], (a + j) as f64 * 0.01);
        }
        // Only trial 2 has the pulse.
        assert_eq!(entry.perturbation.is_some(), k == 1, "trial {}", k + 1);
    }
    let p = s.manifest.trials[1].perturbation.as_ref().unwrap();
    // |F| = 8 - |i - 720| / 4 exceeds 0.5 N from sample 700 (3 N) to 739 (3.25 N).
    approx::assert_abs_diff_eq!(p.onset_s, (700.0 - 650.0) / RATE, epsilon = 1e-12);
    approx::assert_abs_diff_eq!(p.duration_s, 40.0 / RATE, epsilon = 1e-12);
    assert_eq!(p.amplitude, Amplitude::ForceN(8.0));
    approx::assert_abs_diff_eq!(p.angle_deg, 30.0, epsilon = 1e-9);
}

#[test]
fn csv_with_header_comments_and_crlf_is_cut_by_its_marker() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "block1.csv", &log_text(",", true));
    let map = write(
        dir.path(),
        "map.toml",
        &map_text(
            HEADER_NAMES,
            r#"cut = "marker""#,
            "[perturbation]\nfrom = \"channel\"\nabove_n = 0.5",
        ),
    );
    let out = dir.path().join("s");
    let imported = import(std::slice::from_ref(&log), &map, &out).unwrap();
    assert_eq!(imported.rate_hz, RATE);
    assert_eq!(imported.perturbed, 1);
    check_marker_session(&Session::read(&out).unwrap());

    let inv = inspect(&log).unwrap();
    assert_eq!(inv.entries.len(), 9);
    assert_eq!(inv.entries[0].name, "time_s");
    assert_eq!(inv.entries[0].rate_hz, Some(RATE));
    assert_eq!(inv.entries[1].shape, vec![N, 1]);
    assert!(inv.format.contains("comma"), "{}", inv.format);
}

#[test]
fn headerless_tsv_names_columns_col1_col2() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "block1.txt", &log_text("\t", false));
    let map = write(
        dir.path(),
        "map.toml",
        &map_text(
            NO_HEADER_NAMES,
            r#"cut = "marker""#,
            "[perturbation]\nfrom = \"channel\"",
        ),
    );
    let out = dir.path().join("s");
    import(std::slice::from_ref(&log), &map, &out).unwrap();
    check_marker_session(&Session::read(&out).unwrap());
    let inv = inspect(&log).unwrap();
    assert_eq!(inv.entries[8].name, "col9");
    assert!(inv.format.contains("TSV"), "{}", inv.format);

    // The same log with the delimiter and header stated in the map.
    let semi = write(dir.path(), "block1.ssv", &log_text(";", false));
    let stated = map_text(
        NO_HEADER_NAMES,
        r#"cut = "marker""#,
        "[perturbation]\nfrom = \"channel\"",
    ) + "\n[csv]\ndelimiter = \";\"\nheader = false\n";
    let map2 = write(dir.path(), "map2.toml", &stated);
    let out2 = dir.path().join("s2");
    import(&[semi], &map2, &out2).unwrap();
    check_marker_session(&Session::read(&out2).unwrap());
}

/// Position at rest, then constant-speed ramps starting at known samples.
fn ramp_log(starts: &[usize]) -> String {
    let mut s = String::from("t,x,idx\n");
    let rate = 1000.0;
    let mut x = 0.0_f64;
    for i in 0..6000 {
        // 0.1 m/s for 400 samples after each start (a step of 1e-4 m per sample).
        if starts.iter().any(|&k| i > k && i <= k + 400) {
            x += 0.1 / rate;
        }
        s.push_str(&format!("{:.3},{x},{i}\n", i as f64 / rate));
    }
    s
}

#[test]
fn threshold_cut_finds_movement_starts_within_one_sample() {
    let starts = [1000, 2500, 4100];
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "reach.csv", &ramp_log(&starts));
    let map = write(
        dir.path(),
        "map.toml",
        &format!(
            r#"
axes = ["x"]
[time]
var = "t"
[channels]
x_m = {{ var = "x" }}
ref_x_m = {{ var = "idx" }}
{DEVICE}
[trials]
cut = "threshold"
threshold = {{ channel = "x_m", speed_above = 0.01, before_s = 0.2, length_s = 1.0 }}
"#
        ),
    );
    let out = dir.path().join("s");
    let imported = import(&[log], &map, &out).unwrap();
    assert_eq!(imported.samples, vec![1000; 3]);
    let s = Session::read(&out).unwrap();
    assert_eq!(s.trials.len(), starts.len());
    for (trial, &known) in s.trials.iter().zip(&starts) {
        let found = trial.ref_x_m.as_ref().unwrap()[0] + 200.0;
        assert!(
            (found - known as f64).abs() <= 1.0,
            "movement start found at {found}, known {known}"
        );
    }
}

#[test]
fn onsets_table_cuts_fixed_length_trials_with_table_perturbations() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "block1.csv", &log_text(",", true));
    let text = map_text(
        HEADER_NAMES,
        "cut = \"onsets\"\nonsets_s = [0.5, 2.0, 3.5]\nlength_s = 0.4",
        r#"[perturbation]
from = "table"
kind = "force-pulse"
onset_s = [0.1, 0.0, 0.2]
duration_s = [0.15, 0.0, 0.1]
amplitude_n = [12.0, 0.0, 5.0]
angle_deg = [90.0, 0.0, -45.0]"#,
    )
    .replace("marker = { var = \"trig\" }", "");
    let map = write(dir.path(), "map.toml", &text);
    let out = dir.path().join("s");
    let imported = import(&[log], &map, &out).unwrap();
    assert_eq!(imported.samples, vec![200; 3]);
    assert_eq!(imported.perturbed, 2);
    let s = Session::read(&out).unwrap();
    let firsts: Vec<f64> = s
        .trials
        .iter()
        .map(|t| t.ref_x_m.as_ref().unwrap()[0])
        .collect();
    assert_eq!(firsts, [250.0, 1000.0, 1750.0]);
    let p = s.manifest.trials[0].perturbation.as_ref().unwrap();
    assert_eq!((p.onset_s, p.duration_s, p.angle_deg), (0.1, 0.15, 90.0));
    assert_eq!(p.amplitude, Amplitude::ForceN(12.0));
    assert!(s.manifest.trials[1].perturbation.is_none());
}

#[test]
fn importing_twice_gives_byte_identical_sessions() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "block1.csv", &log_text(",", true));
    let map = write(
        dir.path(),
        "map.toml",
        &map_text(
            HEADER_NAMES,
            r#"cut = "marker""#,
            "[perturbation]\nfrom = \"channel\"",
        ),
    );
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    import(std::slice::from_ref(&log), &map, &a).unwrap();
    import(&[log], &map, &b).unwrap();
    let (ta, tb) = (tree(&a), tree(&b));
    assert_eq!(ta.len(), 5, "session.toml and four trials: {ta:?}");
    assert!(ta == tb, "the two imports differ");
    let manifest = String::from_utf8(ta[0].1.clone()).unwrap();
    assert!(
        manifest.contains("created = \"1970-01-01T00:00:00Z\""),
        "{manifest}"
    );
    assert!(manifest.contains("sha256"), "{manifest}");
}

#[test]
fn several_logs_number_their_trials_in_order_and_must_share_a_rate() {
    let dir = tempfile::tempdir().unwrap();
    let a = write(dir.path(), "block1.csv", &log_text(",", true));
    let b = write(dir.path(), "block2.tsv", &log_text("\t", true));
    let map = write(
        dir.path(),
        "map.toml",
        &map_text(HEADER_NAMES, r#"cut = "marker""#, ""),
    );
    let out = dir.path().join("s");
    let imported = import(&[a.clone(), b], &map, &out).unwrap();
    assert_eq!(imported.trials(), 8);
    let s = Session::read(&out).unwrap();
    let ids: Vec<u32> = s.manifest.trials.iter().map(|t| t.id).collect();
    assert_eq!(ids, (1..=8).collect::<Vec<_>>());
    assert_eq!(s.manifest.subject.id, "block1");
    assert_eq!(s.trials[4], s.trials[0]);

    // A log at another rate.
    let slow = log_text(",", true);
    let mut slow_text = String::from("time_s,x,y,fx,fy,pfx,pfy,trig,idx\n");
    for line in slow.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let (t, rest) = line.split_once(',').unwrap();
        let t: f64 = t.parse().unwrap();
        slow_text.push_str(&format!("{:.3},{rest}\n", t * 2.0));
    }
    let c = write(dir.path(), "slow.csv", &slow_text);
    let e = import(&[a, c], &map, &dir.path().join("s2")).unwrap_err();
    assert!(
        matches!(
            e,
            rigtwin_import::ImportError::RateMismatch {
                rate_hz: 250.0,
                first_rate_hz: 500.0,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("slow.csv"), "{e}");
}

/// A log of over 4 MiB is parsed in two halves on two threads: the same values, and
/// faults in the second half name their own line of the file.
#[test]
fn a_large_log_parsed_in_two_halves_keeps_values_and_line_numbers() {
    const ROWS: usize = 200_000;
    let dir = tempfile::tempdir().unwrap();
    let value = |i: usize| (i % 1000) as f64 * 0.001_25 - 0.5 + (i / 1000) as f64 * 0.25;
    // Line of each row: two comment lines and the header come first; comments and a
    // blank line sit after row 100 400 (around the middle byte) and CRLF ends every
    // line.
    let mut text = String::from("# big log\r\n# second comment\r\nt,x,idx\r\n");
    let mut line_of = Vec::with_capacity(ROWS);
    let mut line = 3;
    let mut block = (0, 0);
    for i in 0..ROWS {
        line += 1;
        line_of.push(line);
        text.push_str(&format!("{:.6},{},{i}\r\n", i as f64 / 1000.0, value(i)));
        if i == 100_400 {
            // A comment, a blank line and 200 kB of two-byte characters, where the
            // halves are cut: the cut must fall on a line end, not inside a character.
            text.push_str("# a comment in the middle\r\n\r\n");
            line += 2;
            block.0 = text.len();
            for _ in 0..50 {
                text.push_str(&format!("# {}\r\n", "é".repeat(2000)));
                line += 1;
            }
            block.1 = text.len();
        }
    }
    assert!(text.len() > 4 << 20, "{} bytes", text.len());
    let header = "# big log\r\n# second comment\r\nt,x,idx\r\n".len();
    let mid = header + (text.len() - header) / 2;
    assert!((block.0..block.1).contains(&mid), "{mid} outside {block:?}");
    let csv = write(dir.path(), "big.csv", &text);
    let map = write(
        dir.path(),
        "map.toml",
        &format!(
            "axes = [\"x\"]\n[time]\nvar = \"t\"\n[channels]\nx_m = {{ var = \"x\", scale = 1e-3 }}\n\
             ref_x_m = {{ var = \"idx\" }}\n{DEVICE}\n[trials]\ncut = \"whole\"\n"
        ),
    );
    let inv = inspect(&csv).unwrap();
    assert_eq!(inv.entries[0].rate_hz, Some(1000.0));
    assert_eq!(inv.entries[1].shape, vec![ROWS, 1]);
    let out = dir.path().join("s");
    import(std::slice::from_ref(&csv), &map, &out).unwrap();
    let s = Session::read(&out).unwrap();
    let t = &s.trials[0];
    assert_eq!(t.len(), ROWS);
    for i in 0..ROWS {
        assert_eq!(t.x_m[i], value(i) * 1e-3, "row {i}");
        assert_eq!(t.ref_x_m.as_ref().unwrap()[i], i as f64, "row {i}");
    }

    // A row of the second half with a field too many, and one that is not a number:
    // each named by its own line.
    for (row, bad, expect) in [
        (
            150_000,
            "1.0,2.0,3,4",
            "4 fields, the header (line 3) has 3",
        ),
        (190_000, "190.000000,oops,190000", "\"oops\""),
        (1_000, "1.000000,oops,1000", "\"oops\""),
    ] {
        let mut lines: Vec<&str> = text.split("\r\n").collect();
        let k = line_of[row] - 1;
        lines[k] = bad;
        let broken = write(dir.path(), "broken.csv", &lines.join("\r\n"));
        let out = dir.path().join(format!("broken{row}"));
        let e = import(std::slice::from_ref(&broken), &map, &out).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("broken.csv:{}:", line_of[row])),
            "row {row}: {msg}"
        );
        assert!(msg.contains(expect), "row {row}: {msg}");
    }
}
