//! Golden digests of `rigtwin diagnose --json` on the four shared sessions: a refactor of
//! the diagnosis (moving it into a crate of its own, splitting the hand balance by idea,
//! typing its effects) must not move one byte of what it says about measured data; a
//! change meant to change the diagnosis changes these digests, and its commit says why
//! and what moved. The output is deterministic (same input, same bytes; no wall-clock
//! field), so any difference is a change of the numbers or their text.
//!
//! The digests are printed by this test with `GOLDEN_PRINT=1`. When they moved, and
//! what moved with them: `hil/docs/notes/2026-12-03-diagnosis-tests.md`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::process::Command;

use rigtwin::session::Sha256;

const WANT: [(&str, &str); 4] = [
    (
        "example-none",
        "b5a49a28e42ae8e228d9d00c420bb862bc12a66862d42cf556d1569dd874446b",
    ),
    (
        "example-friction",
        "ce43962203f3908e2c4bf5181e291a1c35557a77279954c1914031dc55623dfc",
    ),
    (
        "example-nuisance",
        "bbe513fff703447e06e77ad82a15ef7ff6fcbe4a3db4642dfe18383815c0da45",
    ),
    (
        "example-rotation-mass",
        "2e0c08a36e5ef8d90d3f89975769e067447c1f11d36e2796888b896fe30925a9",
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
