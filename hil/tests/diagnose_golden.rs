//! Golden digests of `rigtwin diagnose --json` on the four shared sessions: a refactor of
//! the diagnosis (moving it into a crate of its own, splitting the hand balance by idea,
//! typing its effects) must not move one byte of what it says about measured data; a
//! change meant to change the diagnosis changes these digests, and its commit says why
//! and what moved. The output is deterministic (same input, same bytes; no wall-clock
//! field), so any difference is a change of the numbers or their text.
//!
//! The digests are printed by this test with `GOLDEN_PRINT=1`. They last moved with the
//! force ripple per axis and the reflex's joint and endpoint units (every session: the
//! ranking's ripple and reflex parameters; no cause named or its parameters changed),
//! then with the bounded motor gains (`MOTOR_GAIN_TOLERANCE`; `example-friction`, whose
//! baseline gains went from 1.95 and 1.77 to the bound and its friction from 2.651 N,
//! 5.348 N s/m to 2.659 N, 5.309 N s/m for 2.66, 5.29 disclosed, and
//! `example-rotation-mass`, whose ranked candidates' fits moved; the two sessions whose
//! fits stay inside the bounds kept their bytes).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::process::Command;

use rigtwin::session::Sha256;

const WANT: [(&str, &str); 4] = [
    (
        "example-none",
        "148c4c940a5476237290498cbad20644ac82839916fc42a20b5bd3e5c8970d44",
    ),
    (
        "example-friction",
        "7579252e4ed3e797a60aa7d70af3b2ca846b0c09ffbdda86f46813eada3401ea",
    ),
    (
        "example-nuisance",
        "baf5131c7190e279abf2cca24d82f8189ebf6087b7a5c5101eac13ba4c08830c",
    ),
    (
        "example-rotation-mass",
        "42287eafff00c41a1de08927f019f42b5dfdf5cbdaa2c43b1d8c58ce05656382",
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
