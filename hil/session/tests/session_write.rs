//! Writing sessions: round trip, identical bytes, streaming flush policy, misuse, and
//! the replay of a written trial through `RigIo`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::fs;
use std::path::{Path, PathBuf};

use rigtwin_device::{ErrorKind, MotorCommand, RigIo, RigIoError, Tick};
use rigtwin_session::replay::{Interpolation, ReplayError, ReplayRig};
use rigtwin_session::{
    Axes, Channels, Device, Manifest, Sample, Session, SessionError, SessionWriter, SimInfo,
    Source, Subject, Trial, TrialKind, TrialMeta,
};

fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/recordings")
        .join(name)
}

fn meta_of(e: &rigtwin_session::TrialEntry) -> TrialMeta {
    TrialMeta {
        id: e.id,
        kind: e.kind.clone(),
        start_m: e.start_m,
        goal_m: e.goal_m,
        perturbation: e.perturbation.clone(),
    }
}

/// Writes `s` into `dir` with `write_trial`.
fn rewrite(s: &Session, dir: &Path) {
    let header = Manifest {
        trials: Vec::new(),
        ..s.manifest.clone()
    };
    let mut w = SessionWriter::create(dir, header).unwrap();
    for (e, t) in s.iter() {
        w.write_trial(meta_of(e), t).unwrap();
    }
    w.finish().unwrap();
}

/// Every file of a session directory, by relative path.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = vec![(
        "session.toml".to_string(),
        fs::read(dir.join("session.toml")).unwrap(),
    )];
    let mut trials: Vec<_> = fs::read_dir(dir.join("trials"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    trials.sort();
    for p in trials {
        out.push((
            p.file_name().unwrap().to_string_lossy().into_owned(),
            fs::read(&p).unwrap(),
        ));
    }
    out
}

#[test]
fn shared_session_round_trips_to_identical_data_then_identical_bytes() {
    let original = Session::read(shared("example-none")).unwrap();
    let a = tempfile::tempdir().unwrap();
    rewrite(&original, a.path());
    let read_a = Session::read(a.path()).unwrap();
    assert_eq!(
        read_a.trials, original.trials,
        "every sample reads back bit for bit"
    );
    let strip = |m: &Manifest| {
        let mut m = m.clone();
        m.trials.iter_mut().for_each(|t| t.sha256 = None);
        m
    };
    assert_eq!(strip(&read_a.manifest), strip(&original.manifest));
    assert!(
        read_a.manifest.trials.iter().all(|t| t.sha256.is_some()),
        "digests are always written"
    );
    // The 1 kHz shared files are written by `{}` formatting exactly as they came.
    assert_eq!(
        fs::read(a.path().join("trials/0001.csv")).unwrap(),
        fs::read(shared("example-none").join("trials/0001.csv")).unwrap()
    );

    let b = tempfile::tempdir().unwrap();
    rewrite(&read_a, b.path());
    assert_eq!(
        files(a.path()),
        files(b.path()),
        "rewriting what was read gives the same bytes"
    );
}

fn header(rate_hz: f64) -> Manifest {
    let mut extra = std::collections::BTreeMap::new();
    extra.insert("noise_n".to_string(), toml::Value::Float(0.05));
    Manifest {
        source: Source::Sim,
        rate_hz,
        axes: Axes::Both,
        created: "2026-11-22T00:00:00Z".into(),
        device: Device {
            kind: "admittance".into(),
            mass_kg: [5.0, 5.0],
            damping_n_s_per_m: [15.0, 15.0],
            handle_mass_kg: Some(0.35),
            workspace_half_width_m: None,
        },
        subject: Subject {
            id: "sim \"01\"".into(),
            shoulder_m: [0.0, -0.425],
            upper_arm_m: Some(0.31),
            forearm_m: None,
            body_mass_kg: None,
            extra: std::collections::BTreeMap::new(),
        },
        sim: Some(SimInfo {
            seed: Some(42),
            protocol: Some("reach-perturb".into()),
            model: None,
            extra,
        }),
        timing: None,
        trials: Vec::new(),
    }
}

/// A deterministic, awkward sample: values that need all 17 significant digits.
fn sample(trial: u32, i: u64) -> Sample {
    let k = f64::from(trial) + i as f64 * 1e-3;
    Sample {
        pos_m: [(k * 1.1).sin() * 0.1, -0.125 + k.cos() / 3.0],
        force_n: [k.sqrt() * 1e-7, -1.0 / (k + 7.0)],
        pert_force_n: [0.0, -0.0],
        vel_m_per_s: Some([k * 1e10, std::f64::consts::PI]),
        ref_m: None,
        cmd_n: Some([1e-300, -2.5e17]),
    }
}

fn stream(dir: &Path, trials: u32, rows: u64) {
    let channels = Channels {
        velocity: true,
        reference: false,
        command: true,
        extra: vec!["tick".into()],
    };
    let mut w = SessionWriter::create(dir, header(4000.0)).unwrap();
    for id in 1..=trials {
        w.begin_trial(
            TrialMeta {
                id,
                kind: TrialKind::Hold,
                start_m: None,
                goal_m: None,
                perturbation: None,
            },
            channels.clone(),
        )
        .unwrap();
        for i in 0..rows {
            w.push_with_extra(&sample(id, i), &[i as f64]).unwrap();
        }
        w.finish_trial().unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn streamed_session_is_deterministic_and_lossless() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    stream(a.path(), 3, 1001);
    stream(b.path(), 3, 1001);
    assert_eq!(files(a.path()), files(b.path()));
    let s = Session::read(a.path()).unwrap();
    assert_eq!(s.manifest.sim.as_ref().and_then(|m| m.seed), Some(42));
    assert_eq!(
        s.manifest.sim.as_ref().unwrap().extra.get("noise_n"),
        Some(&toml::Value::Float(0.05))
    );
    assert_eq!(s.manifest.subject.id, "sim \"01\"");
    for (e, t) in s.iter() {
        assert_eq!(t.len(), 1001);
        assert!(t.ref_x_m.is_none() && t.vx_m_per_s.is_some());
        for i in [0_usize, 1, 500, 1000] {
            let want = sample(e.id, i as u64);
            assert_eq!(t.t_s[i], i as f64 / 4000.0);
            assert_eq!([t.x_m[i], t.y_m[i]], want.pos_m);
            assert_eq!([t.fx_n[i], t.fy_n[i]], want.force_n);
            assert_eq!(
                t.pert_fy_n[i].to_bits(),
                (-0.0_f64).to_bits(),
                "signed zero survives"
            );
            assert_eq!(
                t.vx_m_per_s.as_ref().unwrap()[i],
                want.vel_m_per_s.unwrap()[0]
            );
            assert_eq!(t.cmd_fy_n.as_ref().unwrap()[i], -2.5e17);
            assert_eq!(t.cmd_fx_n.as_ref().unwrap()[i], 1e-300);
            assert_eq!(t.column("tick").unwrap()[i], i as f64);
        }
    }
}

#[test]
fn unfinished_trial_is_on_disk_within_10_ms_and_invisible_to_readers() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = SessionWriter::create(dir.path(), header(4000.0)).unwrap();
    let meta = |id| TrialMeta {
        id,
        kind: TrialKind::Reach,
        start_m: None,
        goal_m: None,
        perturbation: None,
    };
    let channels = Channels {
        velocity: true,
        reference: false,
        command: true,
        extra: Vec::new(),
    };
    w.begin_trial(meta(1), channels.clone()).unwrap();
    (0..10).for_each(|i| w.push(&sample(1, i)).unwrap());
    w.finish_trial().unwrap();
    w.begin_trial(meta(2), channels).unwrap();
    for i in 0..1234 {
        w.push(&sample(2, i)).unwrap();
        if i % 97 == 0 {
            // Rows on disk (header excluded) lag the pushed ones by < 10 ms = 40 rows.
            let on_disk = fs::read_to_string(dir.path().join("trials/0002.csv.partial")).unwrap();
            let rows = on_disk.lines().count() as u64 - 1;
            let pushed = i + 1;
            assert!(
                (pushed.saturating_sub(40)..=pushed).contains(&rows),
                "pushed {pushed}, {rows} on disk"
            );
        }
    }
    // A reader sees the finished trial only.
    let s = Session::read(dir.path()).unwrap();
    assert_eq!(s.trials.len(), 1);
    assert_eq!(s.trials[0].len(), 10);
}

#[test]
fn writer_refuses_what_would_break_the_format() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = SessionWriter::create(dir.path(), header(1000.0)).unwrap();
    let meta = TrialMeta {
        id: 7,
        kind: TrialKind::Reach,
        start_m: None,
        goal_m: None,
        perturbation: None,
    };
    let is_invalid =
        |r: Result<(), SessionError>| matches!(r, Err(SessionError::InvalidWrite { .. }));
    assert!(is_invalid(w.push(&sample(7, 0))), "push before begin_trial");
    w.begin_trial(meta.clone(), Channels::default()).unwrap();
    assert!(
        is_invalid(w.push(&sample(7, 0))),
        "velocity given but not in the channels"
    );
    let plain = Sample {
        pos_m: [0.0, f64::NAN],
        ..Sample::default()
    };
    assert!(is_invalid(w.push(&plain)), "NaN");
    assert!(
        is_invalid(w.begin_trial(meta.clone(), Channels::default())),
        "trial in progress"
    );
    w.push(&Sample::default()).unwrap();
    w.finish_trial().unwrap();
    assert!(
        is_invalid(w.begin_trial(meta.clone(), Channels::default())),
        "id 7 taken"
    );
    let ragged = Trial {
        t_s: vec![0.0, 0.001],
        x_m: vec![0.0],
        ..Trial::default()
    };
    assert!(matches!(
        w.write_trial(
            TrialMeta {
                id: 8,
                ..meta.clone()
            },
            &ragged
        ),
        Err(SessionError::InvalidWrite { .. })
    ));
    assert!(matches!(
        SessionWriter::create(dir.path(), header(1000.0)),
        Err(SessionError::InvalidWrite { .. })
    ));
    drop(w);
    // What the refused calls left is still a valid session with trial 7.
    let s = Session::read(dir.path()).unwrap();
    assert_eq!(
        s.manifest.trials.iter().map(|t| t.id).collect::<Vec<_>>(),
        vec![7]
    );
    // And it can be continued.
    let mut w = SessionWriter::resume(dir.path()).unwrap();
    w.write_trial(TrialMeta { id: 8, ..meta }, &s.trials[0])
        .unwrap();
    assert_eq!(Session::read(dir.path()).unwrap().trials.len(), 2);
}

fn small_trial() -> Trial {
    let n = 5;
    Trial {
        t_s: (0..n).map(|i| f64::from(i) / 1000.0).collect(),
        x_m: vec![0.0, 1e-5, 2e-5, 3.4e-6, -0.1],
        y_m: vec![-0.125, -0.124, -0.123, -0.122, -0.121],
        fx_n: vec![1.0, 2.0, 3.0, 4.0, 5.0],
        fy_n: vec![-1.0, -2.0, -3.0, -4.0, -5.0],
        pert_fx_n: vec![0.0; 5],
        pert_fy_n: vec![0.0; 5],
        ..Trial::default()
    }
}

#[test]
fn replay_holds_each_row_for_four_ticks_and_records_commands() {
    let mut rig =
        ReplayRig::at_control_rate(&small_trial(), 1000.0, Interpolation::SampleAndHold).unwrap();
    assert_eq!(rig.last_tick(), Tick(19));
    for n in 0..20_u64 {
        let f = rig.read(Tick(n)).unwrap();
        let row = (n / 4) as usize;
        let t = small_trial();
        assert_eq!(
            f.encoder_counts,
            [
                (t.x_m[row] * 1e6).round() as i64,
                (t.y_m[row] * 1e6).round() as i64
            ]
        );
        assert_eq!(f.force_raw_n, [t.fx_n[row], t.fy_n[row]]);
        assert!(!f.estop);
        rig.write(
            Tick(n),
            MotorCommand {
                force_n: [n as f64, 0.5],
            },
        )
        .unwrap();
    }
    assert_eq!(rig.read(Tick(1)).unwrap().encoder_counts, [0, -125_000]);
    assert_eq!(rig.read(Tick(4)).unwrap().encoder_counts, [10, -124_000]);
    assert_eq!(
        rig.read(Tick(12)).unwrap().encoder_counts,
        [3, -122_000],
        "3.4 µm rounds to 3 counts"
    );
    let end = rig.read(Tick(20)).unwrap_err();
    assert_eq!(end.kind(), ErrorKind::EndOfData);
    assert!(matches!(
        end,
        ReplayError::EndOfData {
            tick: 20,
            samples: 5,
            ..
        }
    ));
    let commands = rig.into_commands();
    assert_eq!(commands.len(), 20);
    assert_eq!(
        commands[13],
        (
            Tick(13),
            MotorCommand {
                force_n: [13.0, 0.5]
            }
        )
    );
}

#[test]
fn replay_interpolates_linearly_between_rows() {
    let mut rig =
        ReplayRig::at_control_rate(&small_trial(), 1000.0, Interpolation::Linear).unwrap();
    assert_eq!(rig.last_tick(), Tick(16));
    let f = rig.read(Tick(2)).unwrap();
    assert_eq!(f.encoder_counts, [5, -124_500]);
    approx::assert_relative_eq!(f.force_raw_n[0], 1.5, epsilon = 1e-12);
    approx::assert_relative_eq!(
        rig.read(Tick(5)).unwrap().force_raw_n[1],
        -2.25,
        epsilon = 1e-12
    );
    assert_eq!(rig.read(Tick(16)).unwrap().force_raw_n, [5.0, -5.0]);
    assert_eq!(rig.read(Tick(17)).unwrap_err().kind(), ErrorKind::EndOfData);
}

#[test]
fn replay_of_a_shared_trial_covers_its_3_5_s() {
    let s = Session::read(shared("example-friction")).unwrap();
    let mut rig = ReplayRig::at_control_rate(
        &s.trials[0],
        s.manifest.rate_hz,
        Interpolation::SampleAndHold,
    )
    .unwrap();
    assert_eq!(rig.last_tick(), Tick(13_999));
    let last = rig.read(Tick(13_999)).unwrap();
    assert_eq!(
        last.encoder_counts[1],
        (s.trials[0].y_m[3499] * 1e6).round() as i64
    );
    assert!(rig.read(Tick(14_000)).is_err());
    assert!(matches!(
        ReplayRig::at_control_rate(&Trial::default(), 1000.0, Interpolation::Linear),
        Err(ReplayError::Setup(_))
    ));
}
