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
        "fa0569ce02c2dead1c4503f966cf3b4b0bf5d564d73d42d0cda3b06ad7470ba4",
    ),
    (
        "example-friction",
        "1bb20d6f7ba76574ceed1d4dad636a50d9479ccafc5e228f24675dda8c61fbf3",
    ),
    (
        "example-nuisance",
        "1d22235903dcbd3a1d9f920eb7b50954ee3595087a2345c2bb98d2e353b61dda",
    ),
    (
        "example-rotation-mass",
        "10e3715bfea98f3e9faeb5062b9d5df99364a7c3f233034ff3ad4a1f3f052652",
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
