//! `rigtwin compare --rerun` and `rigtwin diagnose --rerun` read back with rerun's decoder:
//! the measured and simulated channels land under their prefixes sample for sample, and the
//! diagnosis's predicted commands are there for the baseline and the cause.
#![cfg(feature = "rerun")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use rerun::log::Chunk;
use rigtwin::session::Session;
use rigtwin::viz::paths;

mod common;
use common::{assert_reproducible, recording_chunks};

fn temporal<'a>(chunks: &'a [Chunk], entity: &'a str) -> impl Iterator<Item = &'a Chunk> + 'a {
    chunks
        .iter()
        .filter(move |c| !c.is_static() && c.entity_path().to_string() == format!("/{entity}"))
}

/// Samples logged at an entity (temporal rows).
fn rows(chunks: &[Chunk], entity: &str) -> usize {
    temporal(chunks, entity).map(Chunk::num_rows).sum()
}

/// The scalar values logged at an entity, in order.
fn scalars(chunks: &[Chunk], entity: &str) -> Vec<f64> {
    temporal(chunks, entity)
        .flat_map(|c| {
            c.iter_slices::<f64>("Scalars:scalars".into())
                .flat_map(|s| s.to_vec())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The `time` timeline of an entity's rows, s.
fn times_s(chunks: &[Chunk], entity: &str) -> Vec<f64> {
    temporal(chunks, entity)
        .flat_map(|c| {
            let col = c.timelines().get(&"time".into()).expect("a time column");
            col.times_raw()
                .iter()
                .map(|ns| *ns as f64 * 1e-9)
                .collect::<Vec<_>>()
        })
        .collect()
}

/// A shared recording: they sit next to the repository (`../shared/recordings`, or where
/// RIGTWIN_SHARED_RECORDINGS says); a checkout without them skips with a message.
fn shared(name: &str) -> Option<PathBuf> {
    let base = std::env::var_os("RIGTWIN_SHARED_RECORDINGS").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/recordings"),
        PathBuf::from,
    );
    let dir = base.join(name);
    if dir.join("session.toml").is_file() {
        Some(dir)
    } else {
        eprintln!("skipped: {} not present", dir.display());
        None
    }
}

fn run_saving(args: &[&str], rrd: &Path) -> Vec<Chunk> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(args)
        .arg("--rerun")
        .arg(format!("save={}", rrd.display()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    recording_chunks(&std::fs::read(rrd).unwrap())
}

#[test]
fn compare_overlays_every_measured_and_simulated_sample_on_one_timeline() {
    let Some(session_dir) = shared("example-none") else {
        return;
    };
    let session = Session::read(&session_dir).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("compare.rrd");
    // A one-evaluation fit keeps the test fast; the overlay does not depend on the fit.
    let chunks = run_saving(
        &[
            "compare",
            session_dir.to_str().unwrap(),
            "--fit-trials",
            "1",
            "--fit-evaluations",
            "1",
        ],
        &rrd,
    );
    let measured_samples: usize = session.trials.iter().map(|t| t.len()).sum();
    let measured_x: Vec<f64> = session.trials.iter().flat_map(|t| t.x_m.clone()).collect();
    for column in ["x_m", "y_m", "fx_n", "fy_n", "cmd_fx_n", "cmd_fy_n"] {
        let m = paths::overlay_series(paths::MEASURED, column).unwrap();
        let s = paths::overlay_series(paths::SIMULATED, column).unwrap();
        // A saved file holds every sample: the session's count exactly.
        assert_eq!(rows(&chunks, &m), measured_samples, "{m}");
        // The replay is planned as long as the measured table (whole 4 kHz ticks of a
        // 1 kHz table), so it has the same count.
        assert_eq!(rows(&chunks, &s), measured_samples, "{s}");
        // Same trial spans: every simulated sample sits at the measured sample's time, to
        // well under one 1 ms sample (0.1 ms).
        let (tm, ts) = (times_s(&chunks, &m), times_s(&chunks, &s));
        let worst = tm
            .iter()
            .zip(&ts)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-4, "{column}: times differ by {worst} s");
    }
    // The measured curve is the session's own data (f64 scalars, exact).
    let x = scalars(&chunks, "measured/plots/position/x");
    assert_eq!(x, measured_x);
    // The simulated reach covers the same travel: its y spans the measured start-to-goal
    // distance (0.25 m) within 2 cm, and it is not a copy of the measurement.
    let ys = scalars(&chunks, "simulated/plots/position/y");
    let span =
        ys.iter().copied().fold(f64::MIN, f64::max) - ys.iter().copied().fold(f64::MAX, f64::min);
    assert!((span - 0.25).abs() < 0.02, "simulated y travel {span} m");
    let ym = scalars(&chunks, "measured/plots/position/y");
    assert_ne!(ys, ym);

    // Reproducible: the same command saves the same chunks.
    let again = run_saving(
        &[
            "compare",
            session_dir.to_str().unwrap(),
            "--fit-trials",
            "1",
            "--fit-evaluations",
            "1",
        ],
        &dir.path().join("again.rrd"),
    );
    let fx = paths::overlay_series(paths::SIMULATED, "fx_n").unwrap();
    assert_eq!(scalars(&chunks, &fx).len(), measured_samples, "{fx}");
    assert_eq!(scalars(&again, &fx), scalars(&chunks, &fx));
    // The whole file: the same messages (not the same length: see `assert_reproducible`;
    // CI once saw the two lengths 64 bytes apart).
    assert_reproducible(
        &std::fs::read(&rrd).unwrap(),
        &std::fs::read(dir.path().join("again.rrd")).unwrap(),
    );
}

#[test]
fn diagnose_overlays_the_session_and_the_predicted_command_of_baseline_and_cause() {
    let Some(session_dir) = shared("example-friction") else {
        return;
    };
    let session = Session::read(&session_dir).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let chunks = run_saving(
        &["diagnose", session_dir.to_str().unwrap(), "--no-report"],
        &dir.path().join("diagnose.rrd"),
    );
    // The session itself, sample for sample.
    let samples: usize = session.trials.iter().map(|t| t.len()).sum();
    // (each x/y pair is one entity with one row per sample)
    assert_eq!(rows(&chunks, paths::POSITION), samples);
    assert_eq!(rows(&chunks, paths::COMMAND), samples);

    // The predicted commands, on the same evaluated rows for every model.
    let measured = paths::predicted_command(1, paths::MEASURED);
    let baseline = paths::predicted_command(1, "baseline");
    let friction = paths::predicted_command(1, "rail-friction");
    let n = rows(&chunks, &measured);
    assert!(n > 0, "no evaluated rows at {measured}");
    assert_eq!(rows(&chunks, &baseline), n);
    assert_eq!(rows(&chunks, &friction), n);
    assert_eq!(
        rows(&chunks, &paths::predicted_command(0, "rail-friction")),
        n
    );

    // This session has rail friction: on held-out trials the friction model's prediction
    // is closer to the command than the nominal balance's, by at least a tenth (the
    // friction's held-out gain is far above that on this session).
    let u = scalars(&chunks, &measured);
    let rms = |pred: &[f64]| {
        (u.iter()
            .zip(pred)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / u.len() as f64)
            .sqrt()
    };
    let (rb, rf) = (
        rms(&scalars(&chunks, &baseline)),
        rms(&scalars(&chunks, &friction)),
    );
    assert!(rf < 0.9 * rb, "friction {rf} N vs baseline {rb} N");
}
