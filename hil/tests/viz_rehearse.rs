//! `rigtwin rehearse --rerun save=` read back with rerun's decoder: the rehearsal's sessions
//! sample for sample, the Börner estimate and the simulated arm's ground truth as ellipses
//! (values exactly the report's), the windowed regression per window, reproducible messages;
//! and `rehearse --model` putting an extended model's rail friction into the motor commands.
#![cfg(feature = "rerun")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use rerun::log::Chunk;
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, TrialTask};
use rigtwin::report::piovesan_on_session;
use rigtwin::session::Session;
use rigtwin::viz::impedance::{
    DAMPING_SCALE_M_PER_N_S_PER_M, STIFFNESS_SCALE_M_PER_N_PER_M, ellipse_names,
};
use rigtwin::viz::{Which, ellipse_axes, paths};
use rigtwin_diagnose::ExtendedModel;
use rigtwin_world::PlantEffects;
use rigtwin_world::config::RailFriction;

mod common;
use common::{messages, recording_chunks, static_line_names};

/// Trials of the reach-perturb schedule rehearsed: seed 1's first 16 hold 5 force pulses in
/// different directions, enough for the seven Börner parameters.
const REACH_TRIALS: usize = 16;

fn rigtwin(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rigtwin {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `rigtwin rehearse <protocol> --max-trials <n> --jobs 2 --out <dir>/<name> --rerun
/// save=<dir>/<name>.rrd`; returns the rehearsal folder and the .rrd bytes. Two workers, so
/// that trials finish out of order and the logging must put them back in order.
fn rehearse_saved(dir: &Path, protocol: &str, trials: usize, name: &str) -> (PathBuf, Vec<u8>) {
    let out = dir.join(name);
    let rrd = dir.join(format!("{name}.rrd"));
    let stdout = rigtwin(&[
        "rehearse",
        protocol,
        "--max-trials",
        &trials.to_string(),
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap(),
        "--rerun",
        &format!("save={}", rrd.display()),
    ]);
    assert!(stdout.contains("viewer: 1 sessions"), "{stdout}");
    (out, std::fs::read(rrd).unwrap())
}

fn of<'a>(chunks: &'a [Chunk], entity: &str) -> impl Iterator<Item = &'a Chunk> {
    let path = format!("/{entity}");
    chunks
        .iter()
        .filter(move |c| c.entity_path().to_string() == path)
}

fn temporal_rows(chunks: &[Chunk], entity: &str) -> usize {
    of(chunks, entity)
        .filter(|c| !c.is_static())
        .map(Chunk::num_rows)
        .sum()
}

/// The rows of scalars logged on `entity`, in order (a matrix is one row of four).
fn scalar_rows(chunks: &[Chunk], entity: &str) -> Vec<Vec<f64>> {
    of(chunks, entity)
        .filter(|c| !c.is_static())
        .flat_map(|c| {
            c.iter_slices::<f64>("Scalars:scalars".into())
                .map(|s| s.to_vec())
                .collect::<Vec<_>>()
        })
        .collect()
}

fn arrow_vectors(chunks: &[Chunk], entity: &str) -> Vec<Vec<[f32; 2]>> {
    of(chunks, entity)
        .filter(|c| !c.is_static())
        .flat_map(|c| {
            c.iter_slices::<[f32; 2]>("Arrows2D:vectors".into())
                .map(|s| s.to_vec())
                .collect::<Vec<_>>()
        })
        .collect()
}

fn flat(m: [[f64; 2]; 2]) -> Vec<f64> {
    vec![m[0][0], m[0][1], m[1][0], m[1][1]]
}

fn mat(v: &serde_json::Value) -> [[f64; 2]; 2] {
    let e = |r: usize, c: usize| v[r][c].as_f64().unwrap();
    [[e(0, 0), e(0, 1)], [e(1, 0), e(1, 1)]]
}

/// `got` equals `want` entry by entry within `rel` of the largest |entry| (the matrices are
/// stored as f64; only the decimal round trip of the report's JSON may differ, in the last
/// bit).
fn assert_close(got: &[f64], want: &[f64], rel: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}");
    let scale = want.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() <= rel * scale, "{what}: {got:?} vs {want:?}");
    }
}

/// The arrows of an ellipse are its semi-axes times the drawing scale, in f32: each within
/// f32 resolution (1e-6 relative) of the axes of the matrix.
fn assert_arrows_are_axes(arrows: &[[f32; 2]], m: [[f64; 2]; 2], scale: f64, what: &str) {
    let axes = ellipse_axes(m);
    assert_eq!(arrows.len(), 2, "{what}");
    for (k, a) in arrows.iter().enumerate() {
        let length = f64::from(a[0]).hypot(f64::from(a[1])) / scale;
        assert!(
            (length - axes.lengths[k]).abs() <= 1e-6 * axes.lengths[0],
            "{what}: axis {k} {length} vs {}",
            axes.lengths[k]
        );
    }
}

/// The names of the lines of a series entity (its static `SeriesLines` row).
fn series_names(chunks: &[Chunk], entity: &str) -> Vec<String> {
    static_line_names(of(chunks, entity))
}

fn csv_rows(session: &Path) -> usize {
    let session = Session::read(session).unwrap();
    session.trials.iter().map(|t| t.t_s.len()).sum()
}

#[test]
fn a_saved_rehearsal_holds_every_sample_and_the_reports_ellipses() {
    let dir = tempfile::tempdir().unwrap();
    let (out, bytes) = rehearse_saved(dir.path(), "reach-perturb", REACH_TRIALS, "a");
    let chunks = recording_chunks(&bytes);
    let session_dir = out.join("S01");

    // Every sample of the written session, on every per-sample entity.
    let samples = csv_rows(&session_dir);
    assert!(samples > REACH_TRIALS * 3000, "{samples}");
    for entity in [paths::CARRIAGE, paths::ARM_LINKS] {
        assert_eq!(temporal_rows(&chunks, entity), samples, "{entity}");
    }
    // Each pair of series is one entity with two scalars per row: both lines hold every
    // sample.
    for entity in [
        paths::POSITION,
        paths::FORCE_SENSOR,
        paths::FORCE_PERT,
        paths::VELOCITY,
        paths::REFERENCE,
        paths::COMMAND,
        paths::ARM_ANGLES_DEG,
    ] {
        let rows = scalar_rows(&chunks, entity);
        assert_eq!(rows.len(), samples, "{entity}");
        assert!(rows.iter().all(|r| r.len() == 2), "{entity}: two lines");
    }
    // A lock-step rehearsal has no real-time timing to show.
    assert_eq!(temporal_rows(&chunks, paths::TIMING_WAKE_US), 0);
    // The trials are logged from memory as they are written: the values are exactly the
    // files' (each written value is the double its text parses to).
    let session = Session::read(&session_dir).unwrap();
    let from_files: Vec<Vec<f64>> = session
        .trials
        .iter()
        .flat_map(|t| t.x_m.iter().zip(&t.y_m).map(|(x, y)| vec![*x, *y]))
        .collect();
    assert!(
        scalar_rows(&chunks, paths::POSITION) == from_files,
        "logged positions differ from the session files"
    );

    // The simulated arm's muscle activations: one entity, six named lines, every sample.
    let activations = scalar_rows(&chunks, paths::MUSCLE_ACTIVATIONS_N);
    assert_eq!(activations.len(), samples, "activation rows");
    assert!(
        activations.iter().all(|r| r.len() == 6),
        "six muscles per row"
    );
    assert_eq!(
        series_names(&chunks, paths::MUSCLE_ACTIVATIONS_N),
        paths::MUSCLE_NAMES.map(str::to_owned).to_vec()
    );
    // Muscles only pull: the arm model clamps every activation at zero.
    assert!(
        activations
            .iter()
            .flatten()
            .all(|a| *a >= 0.0 && a.is_finite())
    );

    // The report's estimate and the arm's truth, as the report wrote them.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let est = &report["estimates"][0];
    assert!(est["estimate"].is_object(), "{est}");
    let k_est = mat(&est["estimate"]["k_n_per_m"]);
    let d_est = mat(&est["estimate"]["d_ns_per_m"]);
    let k_true = mat(&est["truth_k_n_per_m"]);
    let d_true = mat(&est["truth_d_ns_per_m"]);
    for (which, k, d) in [
        (Which::Estimate, k_est, d_est),
        (Which::Truth, k_true, d_true),
    ] {
        let [k_path, d_path] = which.matrix_paths();
        for (path, m) in [(k_path, k), (d_path, d)] {
            let rows = scalar_rows(&chunks, path);
            assert_eq!(rows.len(), 1, "{path}: one session estimate");
            assert_close(&rows[0], &flat(m), 1e-9, path);
        }
        let [k_name, d_name] = ellipse_names(which);
        for (name, m, scale) in [
            (k_name, k, STIFFNESS_SCALE_M_PER_N_PER_M),
            (d_name, d, DAMPING_SCALE_M_PER_N_S_PER_M),
        ] {
            let arrows = arrow_vectors(&chunks, &paths::ellipse_axes(&name));
            assert_eq!(arrows.len(), 1, "{name}");
            assert_arrows_are_axes(&arrows[0], m, scale, &name);
            assert_eq!(temporal_rows(&chunks, &paths::ellipse_outline(&name)), 1);
        }
    }

    // The arm's impedance at each onset: one per perturbed trial, the first equal to what
    // the lock-step simulation of that trial gives (it is a pure function of its plan).
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let plans: Vec<_> = rehearse::schedule(&protocol, protocol.seed, 1)
        .into_iter()
        .take(REACH_TRIALS)
        .collect();
    let perturbed: Vec<_> = plans
        .iter()
        .filter(|p| {
            matches!(
                p.task,
                TrialTask::Reach {
                    angle_deg: Some(_),
                    ..
                }
            )
        })
        .collect();
    assert!(perturbed.len() >= 3, "{}", perturbed.len());
    let [k_onset, d_onset] = Which::TruthAtOnset.matrix_paths();
    let onset_k = scalar_rows(&chunks, k_onset);
    assert_eq!(onset_k.len(), perturbed.len());
    assert_eq!(scalar_rows(&chunks, d_onset).len(), perturbed.len());
    let subject = protocol.subjects.draw(protocol.seed, 1);
    let sim =
        rehearse::trial::simulate(&protocol, &subject, protocol.seed, perturbed[0], true).unwrap();
    let truth = sim.onset_truth.expect("the pulse fired");
    assert_close(
        &onset_k[0],
        &flat(truth.stiffness_n_per_m),
        1e-12,
        "K at the first onset",
    );
    // The activations logged for that trial at its onset row equal the fresh simulation's
    // (the same pure function of the plan; stored as f64, so within 1e-9 N means equal up
    // to the last bits). The trial's rows start after those of the trials before it.
    let first = session.trials[..perturbed[0].index as usize]
        .iter()
        .map(|t| t.len())
        .sum::<usize>();
    let rate = session.manifest.rate_hz;
    let onset_row = (truth.tick as f64 * rate / rehearse::TICK_HZ as f64).floor() as usize;
    for row in [onset_row, onset_row + 50] {
        let fresh = sim.rows[row].activations_n();
        let logged = &activations[first + row];
        for (m, (a, b)) in logged.iter().zip(fresh).enumerate() {
            assert!(
                (a - b).abs() <= 1e-9,
                "muscle {} at row {row}: logged {a} vs simulated {b}",
                paths::MUSCLE_NAMES[m]
            );
        }
    }
    // Around the force pulse the feedback changes the activations: the check is not on a
    // constant.
    let before = &activations[first + onset_row];
    let after = &activations[first + onset_row + 50];
    assert!(
        before.iter().zip(after).any(|(a, b)| (a - b).abs() > 1e-3),
        "{before:?} vs {after:?}"
    );

    assert!(temporal_rows(&chunks, paths::EVENTS) > REACH_TRIALS);

    // Same protocol and seed, another folder, two workers again: the same messages.
    let (_, again) = rehearse_saved(dir.path(), "reach-perturb", REACH_TRIALS, "b");
    assert!(messages(&bytes) == messages(&again), "messages differ");
}

#[test]
fn a_saved_calibration_rehearsal_draws_one_ellipse_per_window() {
    let dir = tempfile::tempdir().unwrap();
    let (out, bytes) = rehearse_saved(dir.path(), "calibration-rig", 1, "cal");
    let chunks = recording_chunks(&bytes);
    let session = Session::read(out.join("S01")).unwrap();
    let mass = Protocol::builtin("calibration-rig")
        .unwrap()
        .calibration()
        .mass_kg;
    let trials = piovesan_on_session(&session, Some(mass)).unwrap();
    let windows = &trials[0].as_ref().unwrap().window_estimates;
    // 25 cycles, 10-cycle windows.
    assert_eq!(windows.len(), 16);
    let [k_path, b_path] = Which::Estimate.matrix_paths();
    let k_rows = scalar_rows(&chunks, k_path);
    let b_rows = scalar_rows(&chunks, b_path);
    assert_eq!(k_rows.len(), windows.len());
    for ((k, b), w) in k_rows.iter().zip(&b_rows).zip(windows) {
        assert_close(k, &flat(w.k_n_per_m), 1e-12, "window K");
        assert_close(b, &flat(w.b_ns_per_m), 1e-12, "window B");
    }
    let arrows = arrow_vectors(&chunks, &paths::ellipse_axes("stiffness/estimate"));
    assert_eq!(arrows.len(), windows.len());
    assert_arrows_are_axes(
        &arrows[0],
        windows[0].k_n_per_m,
        STIFFNESS_SCALE_M_PER_N_PER_M,
        "first window",
    );
    // No ground truth drawn for the rig's windows, and no truth in a measured session.
    assert!(scalar_rows(&chunks, Which::Truth.matrix_paths()[0]).is_empty());
}

#[test]
fn view_of_a_measured_session_draws_the_estimate_only() {
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("m.rrd");
    let session = "/work/shared/recordings/example-friction";
    rigtwin(&[
        "view",
        session,
        "--rerun",
        &format!("save={}", rrd.display()),
    ]);
    let chunks = recording_chunks(&std::fs::read(&rrd).unwrap());
    let json = rigtwin(&["estimate", session, "--json"]);
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    let [k_path, d_path] = Which::Estimate.matrix_paths();
    let k = scalar_rows(&chunks, k_path);
    assert_eq!(k.len(), 1);
    assert_close(&k[0], &flat(mat(&json["result"]["k_n_per_m"])), 1e-9, "K");
    let d = scalar_rows(&chunks, d_path);
    assert_close(&d[0], &flat(mat(&json["result"]["d_ns_per_m"])), 1e-9, "D");
    for which in [Which::Truth, Which::TruthAtOnset] {
        for path in which.matrix_paths() {
            assert!(scalar_rows(&chunks, path).is_empty(), "{path}");
        }
    }
}

#[test]
fn estimate_and_inspect_take_rerun_too() {
    let dir = tempfile::tempdir().unwrap();
    let session = "/work/shared/recordings/example-none";
    for command in ["estimate", "inspect"] {
        let rrd = dir.path().join(format!("{command}.rrd"));
        let stdout = rigtwin(&[
            command,
            session,
            "--rerun",
            &format!("save={}", rrd.display()),
        ]);
        assert!(stdout.contains("open it with: rerun"), "{stdout}");
        let chunks = recording_chunks(&std::fs::read(&rrd).unwrap());
        assert_eq!(
            temporal_rows(&chunks, paths::POSITION),
            csv_rows(Path::new(session)),
            "{command}"
        );
        assert_eq!(
            scalar_rows(&chunks, Which::Estimate.matrix_paths()[0]).len(),
            1
        );
    }
}

/// Rail friction `F = −(F_c tanh(v/v_s) + b v)` on each cart: the position loop holds the
/// rendered admittance motion, so the motor must supply the friction on top. Over the
/// reach's moving samples (|v_y| > 0.05 m/s) the y command with the model minus the one
/// without, signed by the motion, equals the friction predicted from the recorded velocity
/// within 15 % (the arm and the loop's small tracking error change the motion a little).
#[test]
fn rehearse_with_a_model_adds_its_rail_friction_to_the_motor_commands() {
    let dir = tempfile::tempdir().unwrap();
    let friction = RailFriction {
        coulomb_n: 3.0,
        viscous_n_s_per_m: 5.0,
        smooth_velocity_m_per_s: 0.01,
    };
    let model = ExtendedModel {
        fitted_to: "test".to_owned(),
        cause: "rail-friction".to_owned(),
        causes: vec![rigtwin_diagnose::EffectKind::RailFriction],
        gain: 0.9,
        moving_mass_x_kg: 12.35,
        moving_mass_y_kg: 4.35,
        effects: PlantEffects {
            rail_friction: Some(friction),
            ..PlantEffects::default()
        },
        stretch_reflex: None,
    };
    let model_path = dir.path().join("model.toml");
    model.write(&model_path).unwrap();
    let run = |name: &str, model: Option<&Path>| {
        let out = dir.path().join(name);
        let mut args = vec![
            "rehearse".to_owned(),
            "reach-perturb".to_owned(),
            "--max-trials".to_owned(),
            "2".to_owned(),
            "--out".to_owned(),
            out.display().to_string(),
        ];
        if let Some(m) = model {
            args.extend(["--model".to_owned(), m.display().to_string()]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        rigtwin(&args);
        Session::read(out.join("S01")).unwrap()
    };
    let nominal = run("nominal", None);
    let with = run("friction", Some(&model_path));
    let (a, b) = (&nominal.trials[0], &with.trials[0]);
    let cmd_a = a.cmd_fy_n.as_ref().unwrap();
    let cmd_b = b.cmd_fy_n.as_ref().unwrap();
    let vy = b.vy_m_per_s.as_ref().unwrap();
    let (mut measured, mut predicted, mut n) = (0.0, 0.0, 0);
    for i in 0..cmd_a.len().min(cmd_b.len()) {
        if vy[i].abs() > 0.05 {
            let sign = vy[i].signum();
            measured += (cmd_b[i] - cmd_a[i]) * sign;
            predicted += (friction.coulomb_n * (vy[i] / friction.smooth_velocity_m_per_s).tanh()
                + friction.viscous_n_s_per_m * vy[i])
                * sign;
            n += 1;
        }
    }
    assert!(n > 1000, "{n} moving samples");
    let (measured, predicted) = (measured / n as f64, predicted / n as f64);
    assert!(
        (measured / predicted - 1.0).abs() < 0.15,
        "mean command change {measured:.3} N vs friction {predicted:.3} N"
    );
    // A model file that does not parse is refused naming the file.
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "cause = 3\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["rehearse", "reach-perturb", "--max-trials", "1", "--model"])
        .arg(&bad)
        .arg("--out")
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bad.toml"), "{stderr}");
}

/// `rehearse --realtime --rerun save=`: the loop's timing is on the timeline, one value
/// per sample on each of the two entities, and it accounts for the session's `[timing]`:
/// the held shares of the samples add up to exactly the deadlines the loop missed
/// (a sample is a block of 4 ticks; shares are multiples of 1/4, exact in f64), and every
/// latency but the last sample's is under one period: it is measured from the deadline of
/// the latest tick that is due, so a later wake-up skips ticks instead. The trial's last
/// tick has none left to skip to, so a loaded machine can wake it more than a period late;
/// that latency is real, and only asked to be non-negative.
#[test]
fn a_real_time_rehearsal_puts_its_clock_on_the_timeline() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rt");
    let rrd = dir.path().join("rt.rrd");
    let stdout = rigtwin(&[
        "rehearse",
        "reach-perturb",
        "--realtime",
        "--max-trials",
        "1",
        "--out",
        out.to_str().unwrap(),
        "--rerun",
        &format!("save={}", rrd.display()),
    ]);
    assert!(stdout.contains("with loop timing"), "{stdout}");
    let chunks = recording_chunks(&std::fs::read(rrd).unwrap());
    let session = Session::read(out.join("S01")).unwrap();
    let samples = session.trials[0].t_s.len();
    let timing = session.manifest.timing.unwrap();
    let wake = scalar_rows(&chunks, paths::TIMING_WAKE_US);
    let held = scalar_rows(&chunks, paths::TIMING_HELD);
    assert_eq!(wake.len(), samples);
    assert_eq!(held.len(), samples);
    assert!(wake.iter().all(|r| r.len() == 1 && r[0] >= 0.0), "{wake:?}");
    let (last, before) = wake.split_last().unwrap();
    let period_us = rigtwin_device::Rate::CONTROL.period_s() * 1e6;
    let over: Vec<f64> = before
        .iter()
        .map(|r| r[0])
        .filter(|&us| us >= period_us)
        .collect();
    assert!(over.is_empty(), "latencies of a period or more: {over:?}");
    assert!(last[0].is_finite());
    assert!(held.iter().all(|r| (0.0..=1.0).contains(&r[0])));
    let held_ticks: f64 = held.iter().map(|r| r[0] * 4.0).sum();
    assert_eq!(held_ticks, timing.missed_deadlines as f64, "{timing:?}");
}
