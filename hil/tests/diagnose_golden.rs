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
        "fcfb897f6e34e836b4bcac6c7f15bb4d86efc6056fafa3a99f58bf24679f3342",
    ),
    (
        "example-friction",
        "958414f8728492b402c074203b9c9312b98657464d04c8b22a90e060a4981cd0",
    ),
    (
        "example-nuisance",
        "be1b25070daec06faca9907a2961bfe2ad752d9c30a11f97f8340683f4e0b360",
    ),
    (
        "example-rotation-mass",
        "bad1828052394c7254cd0f90484103a6aaf0a147dac6c59e46b01ad62d5d1482",
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
