//! The viewer's output read back with rerun's own decoder: entity paths, sample counts,
//! timelines, an ellipse against the matrix it draws, and byte-for-byte reproducibility.
#![cfg(feature = "rerun")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::Path;

use rerun::external::re_log_types::StoreKind;
use rerun::log::Chunk;
use rigtwin::session::Session;
use rigtwin::viz::{
    self, Elbow, EventLevel, PerturbationMeta, PerturbationSize, RigGeometry, Stamp, Target,
    TrialColumns, TrialMeta, Viewer, paths,
};

mod common;
use common::assert_reproducible;

/// Every chunk of every store in an `.rrd` byte stream, in order.
fn decode(bytes: &[u8]) -> Vec<(StoreKind, Chunk)> {
    common::chunks(bytes)
}

/// Rows per entity of the recording store.
fn rows_per_entity(chunks: &[(StoreKind, Chunk)]) -> BTreeMap<String, usize> {
    let mut rows = BTreeMap::new();
    for (kind, chunk) in chunks {
        if *kind == StoreKind::Recording {
            *rows.entry(chunk.entity_path().to_string()).or_default() += chunk.num_rows();
        }
    }
    rows
}

fn recording_chunks<'a>(
    chunks: &'a [(StoreKind, Chunk)],
    entity: &'a str,
) -> impl Iterator<Item = &'a Chunk> + 'a {
    chunks.iter().filter_map(move |(kind, c)| {
        (*kind == StoreKind::Recording && c.entity_path().to_string() == format!("/{entity}"))
            .then_some(c)
    })
}

fn f64_values(chunks: &[(StoreKind, Chunk)], entity: &str, component: &'static str) -> Vec<f64> {
    recording_chunks(chunks, entity)
        .flat_map(|c| {
            c.iter_slices::<f64>(component.into())
                .flat_map(|s| s.to_vec())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Line `k` of a series entity: the `k`-th scalar of every temporal row, after checking that
/// each row holds `width` scalars (one per named line).
fn series_line(chunks: &[(StoreKind, Chunk)], entity: &str, k: usize, width: usize) -> Vec<f64> {
    recording_chunks(chunks, entity)
        .filter(|c| !c.is_static())
        .flat_map(|c| {
            c.iter_slices::<f64>("Scalars:scalars".into())
                .map(|row| {
                    assert_eq!(row.len(), width, "{entity}: scalars per row");
                    row[k]
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The line names of a series entity, from its static `SeriesLines` row.
fn line_names(chunks: &[(StoreKind, Chunk)], entity: &str) -> Vec<String> {
    common::static_line_names(recording_chunks(chunks, entity))
}

/// Every per-sample series entity: the six x/y pairs of a trial and the arm angles, two lines
/// each.
const PAIRED_SERIES: [&str; 7] = [
    paths::POSITION,
    paths::VELOCITY,
    paths::FORCE_SENSOR,
    paths::FORCE_PERT,
    paths::REFERENCE,
    paths::COMMAND,
    paths::ARM_ANGLES_DEG,
];

fn f32x2_values(
    chunks: &[(StoreKind, Chunk)],
    entity: &str,
    component: &'static str,
) -> Vec<[f32; 2]> {
    recording_chunks(chunks, entity)
        .flat_map(|c| {
            c.iter_slices::<[f32; 2]>(component.into())
                .flat_map(|s| s.to_vec())
                .collect::<Vec<_>>()
        })
        .collect()
}

fn strip_points(chunks: &[(StoreKind, Chunk)], entity: &str) -> Vec<[f32; 2]> {
    recording_chunks(chunks, entity)
        .flat_map(|c| {
            c.iter_slices::<&[[f32; 2]]>("LineStrips2D:strips".into())
                .flat_map(|strips| strips.into_iter().flat_map(|s| s.to_vec()))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// A small synthetic session: two trials at 1 kHz, the second perturbed.
struct Synthetic {
    t: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
    f: Vec<f64>,
    pert: Vec<f64>,
}

fn synthetic(n: usize) -> Synthetic {
    let t: Vec<f64> = (0..n).map(|i| i as f64 / 1000.0).collect();
    Synthetic {
        x: t.iter().map(|t| 0.01 * (3.0 * t).sin()).collect(),
        y: t.iter().map(|t| -0.125 + 0.25 * t / 3.5).collect(),
        f: t.iter().map(|t| (2.0 * t).cos()).collect(),
        pert: t
            .iter()
            .map(|&t| if (1.0..1.15).contains(&t) { 15.0 } else { 0.0 })
            .collect(),
        t,
    }
}

/// K = R(30°) diag(400, 100) R(30°)ᵀ, N/m.
fn stiffness() -> [[f64; 2]; 2] {
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    [
        [400.0 * c * c + 100.0 * s * s, 300.0 * c * s],
        [300.0 * c * s, 400.0 * s * s + 100.0 * c * c],
    ]
}

const SCALE: f64 = 1e-4;

fn log_synthetic(viewer: &mut Viewer, data: &Synthetic) {
    viewer
        .log_rig_geometry(&RigGeometry::with_workspace(0.15).with_shoulder([0.0, -0.425]))
        .unwrap();
    let cols = TrialColumns::required(
        &data.t, &data.x, &data.y, &data.f, &data.f, &data.pert, &data.pert,
    );
    let mut last = None;
    for trial in 0..2u32 {
        let mut meta = TrialMeta::new(trial, 1000.0);
        meta.start_m = Some([0.0, -0.125]);
        meta.goal_m = Some([0.0, 0.125]);
        if trial == 1 {
            meta.perturbation = Some(PerturbationMeta {
                onset_s: 1.0,
                duration_s: 0.15,
                size: PerturbationSize::ForceN(15.0),
                angle_deg: 30.0,
            });
        }
        let span = viewer.log_trial(&meta, &cols).unwrap();
        let arm = viz::two_link_inverse([0.0, -0.425], 0.33, 0.34, &data.x, &data.y, Elbow::Down);
        assert_eq!(arm.out_of_reach, 0);
        viewer.log_arm(&span, &data.t, &arm.columns()).unwrap();
        last = Some(span);
    }
    let span = last.unwrap();
    let axes = viewer
        .log_ellipse(
            "stiffness",
            Some(span.stamp(1.0)),
            [0.0, 0.0],
            stiffness(),
            SCALE,
            "K (N/m)",
        )
        .unwrap();
    assert!((axes.lengths[0] - 400.0).abs() < 1e-9);
    viewer
        .log_event(
            Stamp::from_tick(12_345),
            EventLevel::Warn,
            "force limit approached",
        )
        .unwrap();
}

fn synthetic_rrd() -> Vec<u8> {
    let mut viewer = Viewer::in_memory("rigtwin", "synthetic-0001").unwrap();
    log_synthetic(&mut viewer, &synthetic(3500));
    viewer.finish().unwrap().expect("memory sink returns bytes")
}

#[test]
fn every_sample_lands_on_its_entity() {
    let chunks = decode(&synthetic_rrd());
    let rows = rows_per_entity(&chunks);
    let per_sample = [paths::CARRIAGE, paths::ARM_LINKS];
    for entity in per_sample {
        // Style or size rows are static (one row); the samples are the rest.
        let temporal: usize = recording_chunks(&chunks, entity)
            .filter(|c| !c.is_static())
            .map(Chunk::num_rows)
            .sum();
        assert_eq!(temporal, 2 * 3500, "{entity}: {rows:?}");
    }
    // The carriage holds, per sample, the lower cart under the handle on its rail, the upper
    // cart at the handle, and the handle itself (f32, as drawn).
    let data = synthetic(3500);
    let geometry = RigGeometry::with_workspace(0.15);
    let centers = f32x2_values(&chunks, paths::CARRIAGE, "Boxes2D:centers");
    let handle = f32x2_values(&chunks, paths::CARRIAGE, "Points2D:positions");
    assert_eq!(centers.len(), 2 * 2 * 3500);
    assert_eq!(handle.len(), 2 * 3500);
    for (i, (boxes, hand)) in centers.chunks(2).zip(&handle).enumerate() {
        let (x, y) = (data.x[i % 3500] as f32, data.y[i % 3500] as f32);
        assert_eq!(
            boxes,
            [[x, geometry.lower_rail_y_m as f32], [x, y]],
            "sample {i}"
        );
        assert_eq!(*hand, [x, y], "sample {i}");
    }
    let sizes = recording_chunks(&chunks, paths::CARRIAGE)
        .filter(|c| c.is_static())
        .flat_map(|c| {
            c.iter_slices::<[f32; 2]>("Boxes2D:half_sizes".into())
                .flat_map(|s| s.to_vec())
                .collect::<Vec<_>>()
        })
        .count();
    assert_eq!(sizes, 2, "one static size per cart");
    // Each x/y pair is one entity with two named lines; every sample of each column lands,
    // exactly (f64), on its line, trial after trial.
    let twice = |c: &[f64]| [c, c].concat();
    let arm = viz::two_link_inverse([0.0, -0.425], 0.33, 0.34, &data.x, &data.y, Elbow::Down);
    let deg = |c: &[f64]| twice(&c.iter().map(|r| r.to_degrees()).collect::<Vec<_>>());
    let recorded = [
        (paths::POSITION, paths::XY, [twice(&data.x), twice(&data.y)]),
        (
            paths::FORCE_SENSOR,
            paths::XY,
            [twice(&data.f), twice(&data.f)],
        ),
        (
            paths::FORCE_PERT,
            paths::XY,
            [twice(&data.pert), twice(&data.pert)],
        ),
        (
            paths::ARM_ANGLES_DEG,
            paths::ARM_ANGLE_NAMES,
            [deg(&arm.shoulder_rad), deg(&arm.elbow_rad)],
        ),
    ];
    for (entity, names, lines) in recorded {
        assert_eq!(line_names(&chunks, entity), names, "{entity}");
        for (k, want) in lines.iter().enumerate() {
            assert_eq!(
                &series_line(&chunks, entity, k, 2),
                want,
                "{entity} line {k}"
            );
        }
    }
    for entity in [paths::VELOCITY, paths::REFERENCE, paths::COMMAND] {
        assert!(
            !rows.contains_key(&format!("/{entity}")),
            "{entity} was not recorded"
        );
    }
    // One response window (150 ms at 1 kHz, both ends) for the one perturbed trial.
    let response = f64_values(&chunks, paths::RESPONSE_X, "Scalars:scalars");
    assert!((150..=151).contains(&response.len()), "{}", response.len());
    assert_eq!(response[0], 0.0);
    for entity in [
        paths::WORKSPACE,
        paths::RAIL_X,
        paths::SHOULDER,
        paths::TRIAL_PATH,
        paths::EVENTS,
    ] {
        assert!(
            rows.contains_key(&format!("/{entity}")),
            "{entity} missing: {rows:?}"
        );
    }
}

#[test]
fn samples_carry_tick_time_and_trial_and_no_wall_clock() {
    let chunks = decode(&synthetic_rrd());
    let mut position = recording_chunks(&chunks, paths::POSITION);
    let first = position.find(|c| !c.is_static()).unwrap();
    let second = position.find(|c| !c.is_static()).unwrap();
    for chunk in chunks.iter().map(|(_, c)| c) {
        let names: Vec<String> = chunk.timelines().keys().map(ToString::to_string).collect();
        assert!(
            !names.iter().any(|n| n == "log_time" || n == "log_tick"),
            "{names:?}"
        );
    }
    let timeline = |c: &Chunk, name: &str| {
        c.timelines()
            .iter()
            .find(|(k, _)| k.as_str() == name)
            .map(|(_, col)| col.times_raw().to_vec())
            .unwrap()
    };
    // 1 kHz samples are 4 control ticks apart; the second trial starts where the first ended.
    let ticks = timeline(first, "tick");
    assert_eq!(&ticks[..3], &[0, 4, 8]);
    assert_eq!(timeline(second, "tick")[0], 3500 * 4);
    assert_eq!(timeline(second, "time")[0], 3_500_000_000);
    assert!(timeline(first, "trial").iter().all(|&t| t == 0));
    assert!(timeline(second, "trial").iter().all(|&t| t == 1));
}

#[test]
fn the_ellipse_drawn_has_the_axes_of_its_matrix() {
    let chunks = decode(&synthetic_rrd());
    let vectors = f32x2_values(
        &chunks,
        &paths::ellipse_axes("stiffness"),
        "Arrows2D:vectors",
    );
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let expected = [
        [400.0 * SCALE * c, 400.0 * SCALE * s],
        [-100.0 * SCALE * s, 100.0 * SCALE * c],
    ];
    assert_eq!(vectors.len(), 2);
    for (got, want) in vectors.iter().zip(expected) {
        for k in 0..2 {
            assert!(
                (f64::from(got[k]) - want[k]).abs() < 1e-7,
                "{got:?} vs {want:?}"
            );
        }
    }
    // The outline is the image of the unit circle: its farthest and nearest points from the
    // centre are the semi-axes.
    let outline = strip_points(&chunks, &paths::ellipse_outline("stiffness"));
    assert!(outline.len() > 100);
    let radii: Vec<f64> = outline
        .iter()
        .map(|p| f64::from(p[0]).hypot(f64::from(p[1])))
        .collect();
    let max = radii.iter().copied().fold(f64::MIN, f64::max);
    let min = radii.iter().copied().fold(f64::MAX, f64::min);
    assert!((max - 400.0 * SCALE).abs() < 1e-6, "{max}");
    assert!((min - 100.0 * SCALE).abs() < 2e-6, "{min}");
}

#[test]
fn saving_twice_gives_the_same_messages_and_a_file_equals_the_buffer() {
    let a = synthetic_rrd();
    let b = synthetic_rrd();
    assert_reproducible(&a, &b);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("synthetic.rrd");
    let target: Target = format!("save={}", path.display()).parse().unwrap();
    let mut viewer = Viewer::new(&target, "rigtwin", "synthetic-0001").unwrap();
    log_synthetic(&mut viewer, &synthetic(3500));
    assert_eq!(viewer.finish().unwrap(), None);
    assert_reproducible(&std::fs::read(&path).unwrap(), &a);
}

#[test]
fn the_layout_travels_in_the_file_as_a_blueprint_store() {
    let chunks = decode(&synthetic_rrd());
    let blueprint: Vec<String> = chunks
        .iter()
        .filter(|(kind, _)| *kind == StoreKind::Blueprint)
        .map(|(_, c)| c.entity_path().to_string())
        .collect();
    assert!(blueprint.iter().any(|p| p == "/viewport"), "{blueprint:?}");
    assert!(
        blueprint
            .iter()
            .filter(|p| p.starts_with("/view/") && !p.ends_with("ViewContents"))
            .count()
            >= 8
    );
}

#[test]
fn bad_inputs_are_refused_with_a_reason() {
    let mut viewer = Viewer::in_memory("rigtwin", "bad").unwrap();
    let t = [0.0, 0.001];
    let short = [0.0];
    let cols = TrialColumns::required(&t, &t, &short, &t, &t, &t, &t);
    let err = viewer
        .log_trial(&TrialMeta::new(0, 1000.0), &cols)
        .unwrap_err();
    assert!(
        err.to_string()
            .contains("`y_m` has 1 samples but `t_s` has 2"),
        "{err}"
    );
    let cols = TrialColumns::required(&t, &t, &t, &t, &t, &t, &t);
    let err = viewer
        .log_trial(&TrialMeta::new(0, 0.0), &cols)
        .unwrap_err();
    assert!(err.to_string().contains("rate_hz"), "{err}");
    let err = viewer
        .log_ellipse("k", None, [0.0; 2], stiffness(), f64::NAN, "K")
        .unwrap_err();
    assert!(err.to_string().contains("scale"), "{err}");
    assert!(Viewer::in_memory("", "x").is_err());
}

#[test]
fn rerun_targets_parse_and_bad_ones_say_what_is_expected() {
    assert_eq!("spawn".parse::<Target>().unwrap(), Target::Spawn);
    assert_eq!(
        "save=out/m.rrd".parse::<Target>().unwrap(),
        Target::Save("out/m.rrd".into())
    );
    assert_eq!(
        "connect".parse::<Target>().unwrap(),
        Target::Connect("rerun+http://127.0.0.1:9876/proxy".into())
    );
    assert_eq!(
        "connect=10.0.0.2:9000".parse::<Target>().unwrap(),
        Target::Connect("rerun+http://10.0.0.2:9000/proxy".into())
    );
    for bad in [
        "",
        "spawn=1",
        "save=",
        "save=m.csv",
        "connect=host",
        "connect=h:port",
        "sav=m.rrd",
        "connect=ftp://x",
    ] {
        let err = bad.parse::<Target>().unwrap_err().to_string();
        assert!(
            err.contains("expected `spawn`, `save=<file.rrd>`"),
            "{bad}: {err}"
        );
    }
}

/// Rows of every trial table of a recorded session, counted from the CSV files themselves.
fn csv_rows(session: &Path) -> Vec<usize> {
    let mut files: Vec<_> = std::fs::read_dir(session.join("trials"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| {
            std::fs::read_to_string(f)
                .unwrap()
                .lines()
                .filter(|l| !l.is_empty() && !l.starts_with('#'))
                .count()
                - 1
        })
        .collect()
}

fn example_session() -> &'static Path {
    Path::new("/work/shared/recordings/example-friction")
}

fn assert_session_counts(chunks: &[(StoreKind, Chunk)], session: &Path) {
    let expected: usize = csv_rows(session).iter().sum();
    let rows = rows_per_entity(chunks);
    for entity in PAIRED_SERIES {
        for k in 0..2 {
            let line = series_line(chunks, entity, k, 2);
            assert_eq!(line.len(), expected, "{entity} line {k}: {rows:?}");
        }
    }
    // The handle's x and y, sample for sample as the CSV files hold them.
    let session = Session::read(session).unwrap();
    for (k, column) in [(0, "x_m"), (1, "y_m")] {
        let want: Vec<f64> = session
            .trials
            .iter()
            .flat_map(|t| t.column(column).unwrap().to_vec())
            .collect();
        assert_eq!(series_line(chunks, paths::POSITION, k, 2), want, "{column}");
    }
}

#[test]
fn a_measured_session_is_logged_sample_for_sample_with_the_arm_solved() {
    let session = Session::read(example_session()).unwrap();
    let mut viewer = Viewer::in_memory("rigtwin", &viz::recording_id(&session).unwrap()).unwrap();
    let logged = viz::log_session(&mut viewer, &session).unwrap();
    assert_eq!((logged.trials, logged.perturbed), (32, 24));
    assert!(logged.arm);
    assert_eq!(logged.out_of_reach, 0);
    let bytes = viewer.finish().unwrap().unwrap();
    let chunks = decode(&bytes);
    assert_session_counts(&chunks, example_session());
    // One response window per perturbed trial.
    let windows = recording_chunks(&chunks, paths::RESPONSE_X)
        .filter(|c| !c.is_static())
        .count();
    assert_eq!(windows, 24);
}

#[test]
fn rigtwin_view_saves_a_reproducible_rrd_of_a_session() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str| {
        let path = dir.path().join(name);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_rigtwin"))
            .arg("view")
            .arg(example_session())
            .arg("--rerun")
            .arg(format!("save={}", path.display()))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(stdout.contains("32 trials, 24 perturbed"), "{stdout}");
        std::fs::read(path).unwrap()
    };
    let a = run("a.rrd");
    assert_reproducible(&a, &run("b.rrd"));
    assert_session_counts(&decode(&a), example_session());
}

#[test]
fn rigtwin_view_refuses_a_bad_rerun_value_with_the_accepted_forms() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["view", "/nonexistent", "--rerun", "save=m.txt"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("expected `spawn`, `save=<file.rrd>`"),
        "{stderr}"
    );
}

#[test]
fn a_lone_column_of_a_pair_keeps_its_line_and_the_other_is_empty() {
    let data = synthetic(100);
    let mut viewer = Viewer::in_memory("rigtwin", "lone").unwrap();
    let cols = TrialColumns {
        vy_m_per_s: Some(&data.f),
        ..TrialColumns::required(
            &data.t, &data.x, &data.y, &data.f, &data.f, &data.pert, &data.pert,
        )
    };
    viewer.log_trial(&TrialMeta::new(0, 1000.0), &cols).unwrap();
    let chunks = decode(&viewer.finish().unwrap().unwrap());
    // Only vy was recorded: it stays the second line (y), the first holds NaN, which rerun
    // draws as no point.
    assert_eq!(series_line(&chunks, paths::VELOCITY, 1, 2), data.f);
    let x = series_line(&chunks, paths::VELOCITY, 0, 2);
    assert_eq!(x.len(), 100);
    assert!(x.iter().all(|v| v.is_nan()), "{x:?}");
}
