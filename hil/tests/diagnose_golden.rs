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
//! structure left that a library term explains, so no `unexplained`).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::process::Command;

use rigtwin::session::Sha256;

const WANT: [(&str, &str); 4] = [
    (
        "example-none",
        "cccddf64f41b8f2dec8396aeb88c39e06641d5b978cecef050bfe2ad479aaf4e",
    ),
    (
        "example-friction",
        "54826f94a84e3b722be701c4d56bc2ac569600186e92613d3b89240d7dfe007f",
    ),
    (
        "example-nuisance",
        "01e0c59344319cf97da2e8a39eb9ba49769508ae13cc7baa099e84e106baea5c",
    ),
    (
        "example-rotation-mass",
        "a23f2629c7dfd9986e450989f60dfa1ff642fa9493bc5388537f289292aae6e3",
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
