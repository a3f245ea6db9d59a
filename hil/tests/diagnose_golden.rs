//! Golden digests of `rigtwin diagnose --json` on the four shared sessions: a refactor of
//! the diagnosis (moving it into a crate of its own, splitting the hand balance by idea,
//! typing its effects) must not move one byte of what it says about measured data; a
//! change meant to change the diagnosis changes these digests, and its commit says why
//! and what moved. The output is deterministic (same input, same bytes; no wall-clock
//! field), so any difference is a change of the numbers or their text.
//!
//! The digests were taken at commit f8da1fb (the diagnosis as it was at the start of
//! the hardware-in-the-loop work, unchanged since) with `GOLDEN_PRINT=1`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::process::Command;

use rigtwin::session::Sha256;

const WANT: [(&str, &str); 4] = [
    (
        "example-none",
        "ea81c101fdda426e13b9baa41addcb90b67bacab696db1dfd236476f2a218707",
    ),
    (
        "example-friction",
        "9064f575398d1d11dd5a68b03c3b4c054306c8c67f93cdfc564fe9beba8ec583",
    ),
    (
        "example-nuisance",
        "8d46875d7940d9e364a65bdc76c9f4cd9f7c09b8c45b93984ea0df8e87281938",
    ),
    (
        "example-rotation-mass",
        "211085dd6f8cbc899235785be52395c946b65423671637781c7bdadeaf722722",
    ),
];

#[test]
fn diagnose_json_on_the_shared_sessions_is_byte_identical() {
    let mut moved = Vec::new();
    for (name, want) in WANT {
        // The JSON names the session as given: run from the checkout's root with the
        // path the README uses, so the bytes do not depend on where the checkout is.
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
            .current_dir(&root)
            .arg("diagnose")
            .arg(format!("../shared/recordings/{name}"))
            .arg("--json")
            // The shared recordings are read, never written to.
            .arg("--no-report")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "diagnose {name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let got = Sha256::of(&out.stdout).to_string();
        if std::env::var_os("GOLDEN_PRINT").is_some() {
            println!("(\"{name}\", \"{got}\"),");
        }
        if got != want {
            moved.push(format!("{name}: {got}"));
        }
    }
    assert!(moved.is_empty(), "diagnose --json moved: {moved:?}");
}
