//! Crash safety: a writer killed (SIGKILL) at any instant leaves a session that reads
//! back; after `session::recover`, it holds everything pushed except at most the last
//! 10 ms of samples, and every value is the one that was pushed.
//!
//! The writer runs in a child process: this test binary itself, re-run with
//! `RIGTWIN_CRASH_DIR` set, which makes `child_writer` write instead of returning.
#![allow(clippy::unwrap_used, clippy::expect_used)]
// The crash tests wait for a child process to get going before killing it: a relative
// sleep is what they mean.
#![allow(clippy::disallowed_methods)]

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rigtwin_session::{
    Axes, Channels, Device, Manifest, Sample, Session, SessionWriter, Source, Subject, TrialKind,
    TrialMeta,
};

const RATE_HZ: f64 = 1000.0;
const TRIALS: u32 = 4;
const ROWS: u64 = 600;
/// 10 ms of samples at `RATE_HZ`: what a kill may lose.
const LOSS: u64 = 10;

fn sample(trial: u32, i: u64) -> Sample {
    let k = f64::from(trial) * 10.0 + i as f64 / 7.0;
    Sample {
        pos_m: [k.sin() / 10.0, k.cos() / 10.0],
        force_n: [k, -k / 3.0],
        pert_force_n: [0.0, 1.0 / (1.0 + k)],
        vel_m_per_s: None,
        ref_m: None,
        cmd_n: Some([k * 1e-3, -k * 1e-3]),
    }
}

fn header() -> Manifest {
    Manifest {
        source: Source::Sim,
        rate_hz: RATE_HZ,
        axes: Axes::Both,
        created: "2026-11-22T00:00:00Z".into(),
        device: Device {
            kind: "admittance".into(),
            mass_kg: [5.0, 5.0],
            damping_n_s_per_m: [15.0, 15.0],
            handle_mass_kg: None,
            workspace_half_width_m: None,
        },
        subject: Subject {
            id: "crash".into(),
            shoulder_m: [0.0, -0.425],
            upper_arm_m: None,
            forearm_m: None,
            body_mass_kg: None,
            extra: Default::default(),
        },
        sim: None,
        timing: None,
        trials: Vec::new(),
    }
}

/// The child's work; a no-op unless run by `kill_*` below with `RIGTWIN_CRASH_DIR`.
#[test]
fn child_writer() {
    let Some(dir) = std::env::var_os("RIGTWIN_CRASH_DIR") else {
        return;
    };
    let dir = Path::new(&dir);
    let pause_at: Option<u64> = std::env::var("RIGTWIN_CRASH_PAUSE_AT")
        .ok()
        .and_then(|s| s.parse().ok());
    let mut w = SessionWriter::create(dir.join("s"), header()).unwrap();
    let mut pushed = 0_u64;
    let channels = Channels {
        command: true,
        ..Channels::default()
    };
    for id in 1..=TRIALS {
        let meta = TrialMeta {
            id,
            kind: TrialKind::Reach,
            start_m: None,
            goal_m: None,
            perturbation: None,
        };
        w.begin_trial(meta, channels.clone()).unwrap();
        for i in 0..ROWS {
            w.push(&sample(id, i)).unwrap();
            pushed += 1;
            if Some(pushed) == pause_at {
                std::fs::write(dir.join("ready"), pushed.to_string()).unwrap();
                loop {
                    std::thread::sleep(Duration::from_secs(1));
                }
            }
            if pause_at.is_none() && pushed.is_multiple_of(40) {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        w.finish_trial().unwrap();
    }
    w.finish().unwrap();
}

fn spawn(dir: &Path, pause_at: Option<u64>) -> std::process::Child {
    let mut cmd = Command::new(std::env::current_exe().unwrap());
    cmd.args(["--exact", "child_writer", "--test-threads=1"])
        .env("RIGTWIN_CRASH_DIR", dir)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    if let Some(n) = pause_at {
        cmd.env("RIGTWIN_CRASH_PAUSE_AT", n.to_string());
    }
    cmd.spawn().unwrap()
}

/// A child writer in `dir`, paused (alive, holding its files) after `n` samples.
fn paused(dir: &Path, n: u64) -> std::process::Child {
    let child = spawn(dir, Some(n));
    let start = Instant::now();
    while !dir.join("ready").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "child never reached {n} samples"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    child
}

/// Every trial is a prefix of what was pushed, ids 1, 2, ... in order; returns the
/// total number of samples.
fn check_prefix(s: &Session) -> u64 {
    let mut total = 0;
    for (k, (e, t)) in s.iter().enumerate() {
        assert_eq!(e.id, k as u32 + 1);
        assert!(t.len() as u64 <= ROWS);
        for i in 0..t.len() {
            let want = sample(e.id, i as u64);
            assert_eq!(t.t_s[i], i as f64 / RATE_HZ);
            assert_eq!(
                [t.x_m[i], t.y_m[i], t.fx_n[i], t.fy_n[i]],
                [
                    want.pos_m[0],
                    want.pos_m[1],
                    want.force_n[0],
                    want.force_n[1]
                ]
            );
            assert_eq!(t.pert_fy_n[i], want.pert_force_n[1]);
            assert_eq!(t.cmd_fx_n.as_ref().unwrap()[i], want.cmd_n.unwrap()[0]);
        }
        total += t.len() as u64;
    }
    // Only the last trial may be short.
    let n = s.trials.len();
    assert!(
        s.trials
            .iter()
            .take(n.saturating_sub(1))
            .all(|t| t.len() as u64 == ROWS)
    );
    total
}

#[test]
fn kill_after_n_samples_loses_at_most_10_ms() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let total = u64::from(TRIALS) * ROWS;
    let mut points = vec![
        1,
        LOSS - 1,
        LOSS,
        LOSS + 1,
        ROWS - 1,
        ROWS,
        ROWS + 1,
        2 * ROWS + 3,
        total,
    ];
    points.extend((0..4).map(|_| rng.random_range(1..=total)));
    for n in points {
        let tmp = tempfile::tempdir().unwrap();
        let mut child = paused(tmp.path(), n);
        child.kill().unwrap();
        child.wait().unwrap();
        let dir = tmp.path().join("s");

        // Before recovery: the finished trials read back; the one in progress is absent.
        let before = Session::read(&dir).unwrap_or_else(|e| panic!("killed at {n}: {e}"));
        assert_eq!(before.trials.len() as u64, (n - 1) / ROWS, "killed at {n}");
        check_prefix(&before);

        let recovered = rigtwin_session::recover(&dir).unwrap();
        let after = Session::read(&dir).unwrap();
        let kept = check_prefix(&after);
        assert!(kept <= n && kept + LOSS >= n, "killed at {n}: kept {kept}");
        assert!(recovered.len() <= 1);
        // Recovery is idempotent.
        assert!(rigtwin_session::recover(&dir).unwrap().is_empty());
        assert_eq!(Session::read(&dir).unwrap(), after);
    }
}

#[test]
fn kill_at_random_instants_always_leaves_a_readable_session() {
    // A whole child run takes about 0.35 s here (fsyncs dominate); kills land anywhere
    // from start-up to the last manifest write.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for _ in 0..10 {
        let tmp = tempfile::tempdir().unwrap();
        let mut child = spawn(tmp.path(), None);
        std::thread::sleep(Duration::from_micros(rng.random_range(0..400_000)));
        child.kill().unwrap();
        child.wait().unwrap();
        let dir = tmp.path().join("s");
        if !dir.join("session.toml").exists() {
            // Killed before the first manifest was written: nothing was recorded.
            continue;
        }
        check_prefix(&Session::read(&dir).unwrap());
        rigtwin_session::recover(&dir).unwrap();
        check_prefix(&Session::read(&dir).unwrap());
    }
}

/// Runs the child to completion in `dir`: the uninterrupted run.
fn uninterrupted(dir: &Path) {
    let status = spawn(dir, None).wait().unwrap();
    assert!(status.success());
}

/// Kills a writer paused at sample `n`; while it lives, a second writer and a repair are
/// refused (the directory's lock), and after the kill `repair` lists every complete
/// trial — byte for byte the uninterrupted run's files — and sets the cut one aside
/// without deleting it.
#[test]
fn repair_after_a_kill_gives_the_uninterrupted_runs_trials_and_sets_the_cut_one_aside() {
    let reference = tempfile::tempdir().unwrap();
    uninterrupted(reference.path());
    // Mid trial 2, at the last row of trial 2, and inside trial 4.
    for n in [ROWS + 250, 2 * ROWS, 3 * ROWS + 1] {
        let tmp = tempfile::tempdir().unwrap();
        let mut child = paused(tmp.path(), n);
        let dir = tmp.path().join("s");
        let busy = SessionWriter::resume(&dir).unwrap_err().to_string();
        assert!(busy.contains("another writer"), "{busy}");
        let busy = rigtwin_session::repair(&dir).unwrap_err().to_string();
        assert!(busy.contains("another writer"), "{busy}");
        child.kill().unwrap();
        child.wait().unwrap();

        let left = rigtwin_session::leftovers(&dir).unwrap();
        assert_eq!(left.len(), 2, "the partial table and its sidecar: {left:?}");
        let done = rigtwin_session::repair(&dir).unwrap();
        let complete = (n - 1) / ROWS;
        assert_eq!(done.set_aside.len(), 2, "{done:?}");
        let s = Session::read(&dir).unwrap();
        assert_eq!(s.trials.len() as u64, complete, "killed at {n}");
        for e in &s.manifest.trials {
            let ours = std::fs::read(e.path_in(&dir)).unwrap();
            let theirs = std::fs::read(e.path_in(&reference.path().join("s"))).unwrap();
            assert!(
                ours == theirs,
                "trial {} differs from the uninterrupted run",
                e.id
            );
        }
        // The cut trial's rows are kept, set aside.
        let cut = dir.join(format!(
            "{}/{:04}.csv.partial",
            rigtwin_session::SET_ASIDE_DIR,
            complete + 1
        ));
        let rows = std::fs::read_to_string(&cut).unwrap().lines().count() as u64 - 1;
        let pushed = n - complete * ROWS;
        assert!(
            rows <= pushed && rows + LOSS >= pushed,
            "{rows} rows of {pushed}"
        );
        // Twice changes nothing.
        assert_eq!(rigtwin_session::repair(&dir).unwrap(), Default::default());
        assert_eq!(Session::read(&dir).unwrap(), s);
        assert!(!dir.join(rigtwin_session::LOCK_FILE).exists());
    }
}
