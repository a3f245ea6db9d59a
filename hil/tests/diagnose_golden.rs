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
        "3d027b7c0c35982be1d985e1a196360c87e5a1f0b5d17c24996db6ed3d78db53",
    ),
    (
        "example-friction",
        "00fb1bb453bdb6b9ab1140317eeaab63dd1280e21799b1cc23a74c4e548f5d41",
    ),
    (
        "example-nuisance",
        "28f38c552d5f8756f9e17c436904a0b8853583097946e6249d089a66792579ce",
    ),
    (
        "example-rotation-mass",
        "79f8fd2b00fe95eff2773461b01731645ba7c35ccde67117c471745b91e838d4",
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
