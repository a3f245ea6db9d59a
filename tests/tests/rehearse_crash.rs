//! Crash safety: a rehearsal killed with SIGKILL at random instants leaves a session
//! that reads back (finished trials only, each with a matching digest), and `recover`
//! turns what is left into a readable session too.
//!
//! The test re-runs its own binary as the child that rehearses (the `child` test,
//! which does nothing unless `RIGTWIN_CRASH_CHILD_DIR` is set) and kills it.
#![allow(clippy::unwrap_used, clippy::expect_used)]
// The crash tests wait before killing a rehearsal at a random moment: a relative sleep
// is what they mean.
#![allow(clippy::disallowed_methods)]

use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options};
use rigtwin::session::{Session, recover};

const CHILD_ENV: &str = "RIGTWIN_CRASH_CHILD_DIR";

#[test]
fn child() {
    let Ok(dir) = std::env::var(CHILD_ENV) else {
        return;
    };
    let p = Protocol::builtin("reach-perturb").unwrap();
    let opts = Options {
        subjects: 1,
        seed: 5,
        out_dir: dir.into(),
        jobs: 1,
        max_trials: Some(60),
    };
    rehearse::rehearse(&p, &opts, &|_| {}, &AtomicBool::new(false)).unwrap();
}

fn check(dir: &Path) -> usize {
    let session_dir = dir.join("S01");
    if !session_dir.join("session.toml").exists() {
        // Killed before the manifest was first written: nothing to read.
        return 0;
    }
    let before =
        Session::read(&session_dir).unwrap_or_else(|e| panic!("killed session does not read: {e}"));
    for (i, (entry, trial)) in before.iter().enumerate() {
        assert_eq!(entry.id as usize, i + 1, "trials are listed in order");
        assert_eq!(
            trial.len(),
            3500,
            "a listed trial is complete (3.5 s at 1 kHz)"
        );
    }
    recover(&session_dir).unwrap_or_else(|e| panic!("recover failed: {e}"));
    let after = Session::read(&session_dir)
        .unwrap_or_else(|e| panic!("recovered session does not read: {e}"));
    assert!(after.trials.len() >= before.trials.len());
    before.trials.len()
}

#[test]
fn sigkill_at_random_instants_leaves_a_readable_session() {
    let exe = std::env::current_exe().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let tmp = tempfile::tempdir().unwrap();
    let mut listed = Vec::new();
    for k in 0..5 {
        let dir = tmp.path().join(format!("run{k}"));
        let mut child = Command::new(&exe)
            .args(["--exact", "child", "--nocapture", "--test-threads", "1"])
            .env(CHILD_ENV, &dir)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // Kill somewhere between start-up and a few trials in; waiting for the first
        // manifest keeps most kills inside the recording.
        let start = Instant::now();
        while !dir.join("S01/session.toml").exists() && start.elapsed() < Duration::from_secs(30) {
            std::thread::sleep(Duration::from_millis(5));
        }
        let delay = rng.random_range(0..1500);
        std::thread::sleep(Duration::from_millis(delay));
        child.kill().unwrap(); // SIGKILL on Unix
        let _ = child.wait();
        listed.push(check(&dir));
    }
    eprintln!("trials listed after each kill: {listed:?}");
}
