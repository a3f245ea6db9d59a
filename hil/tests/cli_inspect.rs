//! `rigtwin inspect` as a person runs it: exit status, the trial table, the error.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::process::Command;

fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/recordings")
        .join(name)
}

fn rigtwin(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn inspect_lists_32_trials_of_a_shared_session() {
    let dir = shared("example-none");
    let out = rigtwin(&["inspect".as_ref(), dir.as_os_str()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("trials    32 (24 perturbed, 8 unperturbed), 112.0 s in all"),
        "{text}"
    );
    let header = text
        .lines()
        .position(|l| l.starts_with("id  kind"))
        .unwrap();
    let rows: Vec<&str> = text.lines().skip(header + 1).collect();
    assert_eq!(rows.len(), 32);
    // Trial 1: reach, 3.5 s, 3500 samples, 300 deg at 1.588375 s, 15 N.
    let first: Vec<&str> = rows[0].split_whitespace().collect();
    assert_eq!(
        &first[..8],
        &[
            "1", "reach", "3.500", "3500", "300.0", "1.588375", "15.00", "N"
        ]
    );
    // Aligned: every row as wide as the header line.
    let width = text.lines().nth(header).unwrap().len();
    assert!(rows.iter().all(|r| r.len() == width), "{text}");
}

#[test]
fn inspect_json_has_every_trial() {
    let dir = shared("example-friction");
    let out = rigtwin(&["inspect".as_ref(), dir.as_os_str(), "--json".as_ref()]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let trials = v["trials"].as_array().unwrap();
    assert_eq!(trials.len(), 32);
    assert_eq!(trials[0]["samples"], 3500);
    assert_eq!(v["rate_hz"], 1000.0);
    assert_eq!(v["channels"].as_array().unwrap().len(), 13);
}

#[test]
fn inspect_of_a_corrupted_session_fails_naming_the_file_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let src = shared("example-none");
    std::fs::create_dir(tmp.path().join("trials")).unwrap();
    let manifest = std::fs::read_to_string(src.join("session.toml")).unwrap();
    std::fs::write(
        tmp.path().join("session.toml"),
        manifest.replace("rate_hz = 1000.0", "rate_hz = \"fast\""),
    )
    .unwrap();
    let out = rigtwin(&["inspect".as_ref(), tmp.path().as_os_str()]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    let file = tmp.path().join("session.toml");
    assert!(err.contains(&format!("{}:4", file.display())), "{err}");
    assert!(err.contains("rate_hz"), "{err}");
}

#[test]
fn help_shows_examples() {
    let out = rigtwin(&["inspect".as_ref(), "--help".as_ref()]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("Examples:")
            && text.contains("rigtwin inspect ../shared/recordings/example-none"),
        "{text}"
    );
}

/// A reader that is gone before the command prints (`rigtwin inspect ... | head` after
/// head has quit): no panic message, a zero exit. The pipe's read end is closed right
/// after the spawn, while the command is still reading the session's 32 trials, so its
/// first line already meets a broken pipe.
#[test]
fn inspect_into_a_closed_pipe_exits_quietly() {
    let dir = shared("example-none");
    let mut child = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .arg("inspect")
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
}
