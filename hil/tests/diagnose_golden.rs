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
//! fits stay inside the bounds kept their bytes), then with forward selection, the
//! friction knee's finer grid and the hand balance judged on the force turned back by
//! a named rotation (every session: the `conditional` rounds or the friction knee's
//! settings in the ranking; `example-rotation-mass`'s handle from 0.8205 to 0.7992 kg
//! for 0.7812 disclosed, its gain from 0.57 to 0.75; no cause added or dropped), then
//! with the library of laws outside the catalog (the rule's text; no session has
//! structure left that a library term explains, so no `unexplained`), then with the
//! final model's nominal parameters (`model`, added beside `baseline`; with that block
//! taken out every session's output is the former bytes: the two-axis path did not
//! move for the one-axis rigs).
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
