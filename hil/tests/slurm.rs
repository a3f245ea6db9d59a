//! A sweep as a real Slurm job array: a single-node cluster (Debian's `slurm-wlm` and
//! `munge`, started by `tests/slurm/cluster.sh` under a temporary folder and stopped at
//! the end) runs `rigtwin sweep --emit slurm`'s array of 4 tasks and the merge that
//! depends on it; the merged table equals a run on one machine, byte for byte.
//!
//! Ignored by default because it needs the daemons and root; `.ci/run` installs them
//! and runs it: `cargo test --release -p rigtwin --test slurm -- --ignored`.

// A failed set-up is a failed test.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use rigtwin::sweep::{self, SweepFile};

/// The sweep tests' small sweep with three subjects and its own seed: 6 runs.
fn sweep_text() -> String {
    include_str!("slurm/small-sweep.toml")
        .replace("name = \"small\"", "name = \"slurm-test\"")
        .replace("seed = 5", "seed = 9")
        .replace("subjects = 2", "subjects = 3")
}

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/slurm/cluster.sh")
}

/// Stops the cluster however the test ends.
struct Cluster(PathBuf);

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(script())
            .args(["stop"])
            .arg(&self.0)
            .status();
    }
}

fn slurm_conf(dir: &Path) -> PathBuf {
    dir.join("slurm.conf")
}

#[test]
#[ignore = "needs slurm-wlm, munge and root: .ci/run installs them and runs it with --ignored"]
fn a_slurm_job_array_and_its_dependent_merge_give_the_local_table() {
    let tmp = tempfile::tempdir().unwrap();
    let sweep_file = tmp.path().join("sweep.toml");
    std::fs::write(&sweep_file, sweep_text()).unwrap();
    let s = SweepFile::load(&sweep_file).unwrap();
    assert_eq!(s.runs(), 6);
    let local = sweep::run_local(&s, &tmp.path().join("local"), 2, false, &|_, _| {}).unwrap();

    let cluster = tmp.path().join("cluster");
    let up = Command::new("bash")
        .arg(script())
        .arg("start")
        .arg(&cluster)
        .status()
        .unwrap();
    let _guard = Cluster(cluster.clone());
    assert!(up.success(), "the cluster did not start");

    let out = tmp.path().join("out");
    let emit = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .arg("sweep")
        .arg(&sweep_file)
        .args([
            "--emit",
            "slurm",
            "--tasks",
            "4",
            "--max-running",
            "2",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let said =
        String::from_utf8_lossy(&emit.stderr).into_owned() + &String::from_utf8_lossy(&emit.stdout);
    assert!(emit.status.success(), "{said}");
    assert!(
        said.contains("run 0:"),
        "the requests come from a measured run: {said}"
    );
    let array = std::fs::read_to_string(out.join("slurm/array.sbatch")).unwrap();
    assert!(array.contains("#SBATCH --array=0-3%2"), "{array}");
    let merge = std::fs::read_to_string(out.join("slurm/merge.sbatch")).unwrap();
    assert!(merge.contains("sweep merge"), "{merge}");

    let submitted = Command::new("bash")
        .arg(out.join("slurm/submit.sh"))
        .env("SLURM_CONF", slurm_conf(&cluster))
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&submitted.stdout).into_owned()
        + &String::from_utf8_lossy(&submitted.stderr);
    assert!(submitted.status.success(), "{said}");

    // Wait for the merge: its table appears when it has run, and the queue empties.
    let started = Instant::now();
    loop {
        let queue = Command::new("squeue")
            .args(["-h", "-o", "%i %T"])
            .env("SLURM_CONF", slurm_conf(&cluster))
            .output()
            .unwrap();
        let queue = String::from_utf8_lossy(&queue.stdout).into_owned();
        if queue.trim().is_empty() {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(600),
            "still queued after 10 min:\n{queue}"
        );
        // A relative wait on another process's work: the clock bans are about the loop.
        #[allow(clippy::disallowed_methods)]
        std::thread::sleep(Duration::from_millis(500));
    }
    let logs: Vec<_> = std::fs::read_dir(out.join("slurm/logs"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let tasks = logs.iter().filter(|l| l.starts_with("task-")).count();
    let merged = out.join("sweep.csv");
    assert!(
        merged.exists(),
        "no merged table; logs: {logs:?}\n{}",
        logs.iter()
            .map(|l| std::fs::read_to_string(out.join("slurm/logs").join(l)).unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n---\n")
    );
    assert_eq!(tasks, 4, "one log per array task: {logs:?}");
    assert_eq!(
        sweep::table::shard_files(&sweep::shards_dir(&out))
            .unwrap()
            .len(),
        4
    );
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&local.table).unwrap(),
        "the cluster's merged table differs from the local run's"
    );
}
