//! The aborts, hangs, panics and wrong acceptances a review of hostile input found, one
//! test each, run on the `rigtwin` binary as a shell runs it. Each must end with a clear
//! refusal (exit 1, or 2 for a bad command line) that names the file, and where there is
//! one the line and the key, within a few seconds.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod hostile;

use std::path::Path;

use hostile::{Ended, mkfifo, run_in, small_session};

/// Time a refusal may take, s: each is a check before any work, measured well under
/// 1 s; the margin is for a loaded CI machine. A hang is caught by this, not timed.
const QUICK_S: f64 = 30.0;

fn protocol_with(dir: &Path, name: &str, from: &str, to: &str) -> String {
    let text = rigtwin::protocol::BUILTIN[0].1;
    assert!(text.contains(from), "{from}");
    let path = dir.join(name);
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
    path.to_str().unwrap().to_owned()
}

#[track_caller]
fn assert_refused(e: &Ended, needles: &[&str]) {
    assert_eq!(e.failed(), None, "{e:?}");
    assert!(e.refused(), "must be refused: {e:?}");
    for n in needles {
        assert!(e.stderr.contains(n), "stderr must name {n:?}: {}", e.stderr);
    }
}

/// A protocol's sizes are checked against stated limits before anything is allocated:
/// each was SIGABRT (an allocation the size of the whole run) or minutes of silence.
#[test]
fn protocol_sizes_past_their_limits_are_refused_with_the_key_and_line() {
    let d = tempfile::tempdir().unwrap();
    for (from, to, key, line) in [
        (
            "trials = 100",
            "trials = 4294967295",
            "reach.trials",
            "line 22",
        ),
        (
            "movement_s = 3.0",
            "movement_s = 1e6",
            "reach.movement_s",
            "line 20",
        ),
        (
            "still_after_s = 0.25",
            "still_after_s = 86400",
            "reach.still_after_s",
            "line 21",
        ),
    ] {
        let p = protocol_with(d.path(), "p.toml", from, to);
        let e = run_in(d.path(), &["rehearse", &p, "--dry-run"], QUICK_S, None);
        assert_refused(&e, &["p.toml", key, line]);
    }
    let e = run_in(
        d.path(),
        &[
            "rehearse",
            "reach-perturb",
            "--subjects",
            "4294967295",
            "--dry-run",
        ],
        QUICK_S,
        None,
    );
    assert_refused(&e, &["--subjects", "1..=10000"]);
}

/// A run past a day of simulation says what it would cost and does not start without
/// `--yes`.
#[test]
fn a_long_run_says_its_cost_and_waits_for_yes() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let e = run_in(
        d.path(),
        &[
            "rehearse",
            "reach-perturb",
            "--subjects",
            "400",
            "--out",
            out.to_str().unwrap(),
        ],
        QUICK_S,
        None,
    );
    // 400 subjects × 100 trials × 3.5 s = 140 000 s.
    assert_refused(&e, &["40000 trials", "38.9 h simulated", "--yes"]);
    assert!(
        !out.exists(),
        "nothing is written before the run is confirmed"
    );
}

/// Arrays longer than a key takes were cut to two without a word, in the safety section.
#[test]
fn an_array_longer_than_its_key_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let p = protocol_with(
        d.path(),
        "p.toml",
        "force_limit_n = [200.0, 200.0]",
        "force_limit_n = [900, 900, 5]",
    );
    let e = run_in(d.path(), &["rehearse", &p, "--dry-run"], QUICK_S, None);
    assert_refused(
        &e,
        &[
            "line 51",
            "`controller.safety.force_limit_n` has 3 elements; it takes 2",
        ],
    );
}

/// Protocol validation errors give a line, the same in CRLF files.
#[test]
fn validation_errors_name_the_line_in_lf_and_crlf_files() {
    let d = tempfile::tempdir().unwrap();
    let text = rigtwin::protocol::BUILTIN[0]
        .1
        .replacen("trials = 100", "trials = 0", 1);
    for (name, t) in [
        ("lf.toml", text.clone()),
        ("crlf.toml", text.replace('\n', "\r\n")),
    ] {
        let p = d.path().join(name);
        std::fs::write(&p, t).unwrap();
        let e = run_in(
            d.path(),
            &["rehearse", p.to_str().unwrap(), "--dry-run"],
            QUICK_S,
            None,
        );
        assert_refused(&e, &[name, "line 22: `reach.trials` must be > 0"]);
    }
}

/// A bad field is quoted as a short excerpt, not echoed whole; a 10 MB protocol is
/// refused by its size (configuration files are read up to 1 MiB).
#[test]
fn a_huge_bad_field_is_quoted_short() {
    let d = tempfile::tempdir().unwrap();
    for (len, needles) in [
        (500_000, ["line 22", "more bytes"]),
        (
            10_000_000,
            ["cannot read protocol", "more than the 1048576 bytes"],
        ),
    ] {
        let big = "a".repeat(len);
        let value = format!("trials = \"{big}\"");
        let p = protocol_with(d.path(), "p.toml", "trials = 100", &value);
        let e = run_in(d.path(), &["rehearse", &p, "--dry-run"], QUICK_S, None);
        assert_refused(&e, &needles);
        assert!(e.stderr.contains("p.toml"), "{}", e.stderr);
        assert!(e.stderr.len() < 2_000, "{} bytes of error", e.stderr.len());
    }
}

/// A FIFO where a file should be blocked the reader forever.
#[test]
fn fifos_are_refused_not_waited_on() {
    let d = tempfile::tempdir().unwrap();
    let fifo = d.path().join("fifo.toml");
    mkfifo(&fifo);
    let e = run_in(
        d.path(),
        &["rehearse", "fifo.toml", "--dry-run"],
        QUICK_S,
        None,
    );
    assert_refused(&e, &["fifo.toml", "is a FIFO, not a regular file"]);

    let s = d.path().join("s");
    std::fs::create_dir(&s).unwrap();
    mkfifo(&s.join("session.toml"));
    let e = run_in(d.path(), &["inspect", "s"], QUICK_S, None);
    assert_refused(&e, &["session.toml", "is a FIFO"]);

    let session = small_session(d.path(), 2);
    let trial = session.join("trials/0002.csv");
    std::fs::remove_file(&trial).unwrap();
    mkfifo(&trial);
    let e = run_in(d.path(), &["inspect", "session"], QUICK_S, None);
    assert_refused(&e, &["0002.csv", "is a FIFO"]);
}

/// A trial file bigger than an hour of rows at the manifest's rate (a sparse 20 GiB
/// file here) is refused from its size, without reading it.
#[test]
fn a_sparse_huge_trial_is_refused_by_its_size() {
    let d = tempfile::tempdir().unwrap();
    let session = small_session(d.path(), 2);
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(session.join("trials/0002.csv"))
        .unwrap();
    f.set_len(20 << 30).unwrap();
    drop(f);
    let e = run_in(d.path(), &["inspect", "session"], QUICK_S, None);
    // 1000 Hz × 3600 s × 512 bytes.
    assert_refused(
        &e,
        &[
            "0002.csv",
            "21474836480 bytes is more than the 1843200000 bytes",
        ],
    );
}

/// A trial file that a symbolic link leads out of the session folder is refused.
#[test]
fn a_symlink_out_of_the_session_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let session = small_session(d.path(), 2);
    let outside = d.path().join("elsewhere.csv");
    std::fs::rename(session.join("trials/0002.csv"), &outside).unwrap();
    std::os::unix::fs::symlink(&outside, session.join("trials/0002.csv")).unwrap();
    let e = run_in(d.path(), &["inspect", "session"], QUICK_S, None);
    assert_refused(
        &e,
        &[
            "session.toml:",
            "trial.file",
            "outside the session directory",
        ],
    );
}

/// `rate_hz = 5e-324` switched the time check off: a table missing 500 samples read.
#[test]
fn a_denormal_rate_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let session = small_session(d.path(), 1);
    let m = session.join("session.toml");
    let text = std::fs::read_to_string(&m).unwrap();
    std::fs::write(&m, text.replace("rate_hz = 1000.0", "rate_hz = 5e-324")).unwrap();
    let e = run_in(d.path(), &["inspect", "session"], QUICK_S, None);
    assert_refused(
        &e,
        &["session.toml:4", "rate_hz", "must be from 1 to 1000000 Hz"],
    );
}

/// A manifest of 200 000 entries naming missing files: read in time linear in its
/// entries, so the answer comes at once (it took minutes when each key's line was found
/// by counting from the top).
#[test]
fn a_manifest_of_200000_trials_is_answered_at_once() {
    let d = tempfile::tempdir().unwrap();
    let session = small_session(d.path(), 1);
    let m = session.join("session.toml");
    let mut text = std::fs::read_to_string(&m).unwrap();
    for k in 2..=200_000 {
        text.push_str(&format!(
            "\n[[trial]]\nid = {k}\nfile = \"trials/{k:06}.csv\"\nkind = \"reach\"\n"
        ));
    }
    std::fs::write(&m, text).unwrap();
    let e = run_in(d.path(), &["inspect", "session"], QUICK_S, None);
    assert_refused(&e, &["trial.file", "trials/000002.csv does not exist"]);
}

/// Standard output on a full device: an error and exit 1, never a panic (exit 101), and
/// what a rehearsal recorded is kept.
#[test]
fn a_full_stdout_is_an_error_not_a_panic() {
    let d = tempfile::tempdir().unwrap();
    let full = Path::new("/dev/full");
    let none = hostile::shared("example-none");
    let none = none.to_str().unwrap();
    for args in [
        vec!["inspect", none],
        vec!["inspect", none, "--json"],
        vec!["estimate", none],
    ] {
        let e = run_in(d.path(), &args, 120.0, Some(full));
        assert_refused(
            &e,
            &["writing to standard output", "No space left on device"],
        );
    }
    let e = run_in(
        d.path(),
        &[
            "rehearse",
            "reach-perturb",
            "--max-trials",
            "2",
            "--jobs",
            "1",
            "--out",
            "r",
        ],
        120.0,
        Some(full),
    );
    assert_refused(&e, &["writing to standard output"]);
    let s = rigtwin::session::Session::read(d.path().join("r/S01")).unwrap();
    assert_eq!(s.trials.len(), 2, "the recorded trials are kept");
}

/// `--rerun connect=` with no viewer listening waited forever.
#[test]
fn a_viewer_that_does_not_answer_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    // A port nobody listens on: bound, then released.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let none = hostile::shared("example-none");
    let target = format!("connect=127.0.0.1:{port}");
    let e = run_in(
        d.path(),
        &["view", none.to_str().unwrap(), "--rerun", &target],
        QUICK_S,
        None,
    );
    assert_refused(
        &e,
        &["no rerun viewer answers", &format!("127.0.0.1:{port}")],
    );
}

/// Seeds of 2^63 or more were written as TOML integers standard readers must refuse.
#[test]
fn seeds_past_i64_are_refused_and_the_largest_round_trips() {
    let d = tempfile::tempdir().unwrap();
    let e = run_in(
        d.path(),
        &[
            "rehearse",
            "reach-perturb",
            "--seed",
            "9223372036854775808",
            "--dry-run",
        ],
        QUICK_S,
        None,
    );
    assert_refused(&e, &["--seed", "9223372036854775808"]);
    let e = run_in(
        d.path(),
        &[
            "rehearse",
            "reach-perturb",
            "--seed",
            "9223372036854775807",
            "--max-trials",
            "1",
            "--out",
            "o",
        ],
        120.0,
        None,
    );
    assert_eq!(e.code, Some(0), "{e:?}");
    let text = std::fs::read_to_string(d.path().join("o/S01/session.toml")).unwrap();
    let v: toml::Table = toml::from_str(&text).unwrap();
    assert_eq!(v["sim"]["seed"].as_integer(), Some(i64::MAX));
}

/// A rehearsal killed with SIGKILL at seeded random instants: `inspect` names what the
/// kill left, `inspect --repair` finishes the manifest, and every listed trial is byte
/// for byte the uninterrupted run's.
#[test]
#[allow(clippy::disallowed_methods)] // waiting a random time before the kill is the point
fn sigkill_then_repair_gives_the_uninterrupted_runs_trials() {
    let d = tempfile::tempdir().unwrap();
    let args = |out: &str| -> Vec<String> {
        [
            "rehearse",
            "reach-perturb",
            "--max-trials",
            "40",
            "--jobs",
            "1",
            "--out",
            out,
        ]
        .map(str::to_owned)
        .to_vec()
    };
    let e = run_in(
        d.path(),
        &args("ref").iter().map(String::as_str).collect::<Vec<_>>(),
        300.0,
        None,
    );
    assert_eq!(e.code, Some(0), "{e:?}");
    // Delays in ms after the first manifest appears (seeded by hand: 0, early, late).
    for (k, delay_ms) in [0_u64, 170, 730].into_iter().enumerate() {
        let out = format!("killed{k}");
        let mut child = std::process::Command::new(hostile::exe())
            .args(args(&out))
            .current_dir(d.path())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let manifest = d.path().join(&out).join("S01/session.toml");
        let start = std::time::Instant::now();
        while !manifest.exists() && start.elapsed().as_secs() < 60 {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        let session = format!("{out}/S01");
        let leftovers = rigtwin::session::leftovers(d.path().join(&session)).unwrap();
        let e = run_in(d.path(), &["inspect", &session], QUICK_S, None);
        assert_eq!(e.code, Some(0), "a killed session reads: {e:?}");
        if leftovers
            .iter()
            .any(|f| f.to_string_lossy().ends_with(".csv.partial"))
        {
            assert!(
                e.stdout.contains("left by an interrupted run"),
                "{}",
                e.stdout
            );
            assert!(e.stdout.contains("incomplete trial table"), "{}", e.stdout);
        }
        let e = run_in(d.path(), &["inspect", &session, "--repair"], QUICK_S, None);
        assert_eq!(e.code, Some(0), "{e:?}");
        assert!(e.stderr.contains("repaired:"), "{}", e.stderr);
        let s = rigtwin::session::Session::read(d.path().join(&session)).unwrap();
        for entry in &s.manifest.trials {
            let ours = std::fs::read(entry.path_in(&d.path().join(&session))).unwrap();
            let theirs = std::fs::read(entry.path_in(&d.path().join("ref/S01"))).unwrap();
            assert!(ours == theirs, "kill {k}: trial {} differs", entry.id);
        }
        // Nothing but set-aside files is left, and none was deleted.
        let after = rigtwin::session::leftovers(d.path().join(&session)).unwrap();
        assert!(
            after.iter().all(|f| f
                .to_string_lossy()
                .contains(rigtwin::session::SET_ASIDE_DIR)),
            "{after:?}"
        );
        eprintln!(
            "kill {k} after {delay_ms} ms: {} trials listed",
            s.trials.len()
        );
    }
}

/// Two writers into one output folder: the second is refused, the first's session reads.
#[test]
fn two_rehearsals_into_one_folder_do_not_interleave() {
    let d = tempfile::tempdir().unwrap();
    let args = [
        "rehearse",
        "reach-perturb",
        "--max-trials",
        "20",
        "--jobs",
        "1",
        "--out",
        "same",
    ];
    let spawn = || {
        std::process::Command::new(hostile::exe())
            .args(args)
            .current_dir(d.path())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn(), spawn());
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    let ok = [&a, &b].iter().filter(|o| o.status.success()).count();
    assert_eq!(ok, 1, "exactly one may write: {a:?} {b:?}");
    let refused = if a.status.success() { &b } else { &a };
    assert_eq!(refused.status.code(), Some(1));
    let s = rigtwin::session::Session::read(d.path().join("same/S01")).unwrap();
    assert_eq!(s.trials.len(), 20);
}

/// A full disk mid-run: a clear error naming the file and "No space left on device",
/// exit 1, and every trial completed before it reads. The disk is a 3 MB tmpfs mounted in
/// a private mount namespace (`unshare -m`, as root: the CI machine runs as root), so it
/// vanishes with the child; the child copies the session out before it ends.
#[test]
fn a_full_disk_is_a_clear_error_and_keeps_the_completed_trials() {
    let d = tempfile::tempdir().unwrap();
    let small = d.path().join("small");
    std::fs::create_dir(&small).unwrap();
    let script = format!(
        "mount -t tmpfs -o size=3m tmpfs '{small}' && cd '{small}' && \
         '{exe}' rehearse reach-perturb --max-trials 20 --jobs 1 --out full 2> ../stderr; \
         echo $? > ../status; cp -r full/S01 ../copy",
        small = small.display(),
        exe = hostile::exe().display()
    );
    let status = std::process::Command::new("unshare")
        .args(["-m", "sh", "-c", &script])
        .status()
        .unwrap();
    assert!(status.success(), "unshare -m and mount need root: {status}");
    let code = std::fs::read_to_string(d.path().join("status")).unwrap();
    let stderr = std::fs::read_to_string(d.path().join("stderr")).unwrap();
    assert_eq!(code.trim(), "1", "{stderr}");
    assert!(stderr.contains("No space left on device"), "{stderr}");
    assert!(
        stderr.contains(".csv.partial") && !stderr.contains("panicked"),
        "{stderr}"
    );
    // Each trial is about 460 kB: 3 MB holds a few.
    let s = rigtwin::session::Session::read(d.path().join("copy")).unwrap();
    assert!(
        (1..20).contains(&s.trials.len()),
        "{} trials",
        s.trials.len()
    );
    assert!(
        s.trials.iter().all(|t| t.len() == 3500),
        "listed trials are whole"
    );
}

/// A protocol whose simulated force sensor has no noise: the reading repeats exactly at
/// rest, which the stale-force watchdog (on by default, for a live ADC) must not take for
/// a frozen bus. The calibration rig at rest tripped it in 2 of 3 trials before.
#[test]
fn a_noise_free_simulated_sensor_does_not_trip_the_stale_force_watchdog() {
    let d = tempfile::tempdir().unwrap();
    let text = rigtwin::protocol::BUILTIN[2].1;
    let line = text
        .lines()
        .find(|l| l.starts_with("force_noise_rms_n"))
        .unwrap();
    std::fs::write(
        d.path().join("p.toml"),
        text.replacen(line, "force_noise_rms_n = 0.0", 1),
    )
    .unwrap();
    let e = run_in(
        d.path(),
        &[
            "rehearse",
            "p.toml",
            "--max-trials",
            "3",
            "--out",
            "o",
            "--json",
        ],
        300.0,
        None,
    );
    assert_eq!(e.code, Some(0), "{e:?}");
    assert!(!e.stdout.contains("StaleForce"), "{}", e.stdout);
}
