//! Golden digests: short rehearsals of the three shipped protocols give the very bytes
//! they gave when these digests were taken (rapier's `snapshot_portability.rs` style).
//! A refactor of the loop (the co-simulation step, the clock, the plant) must not move
//! one byte; a change that is meant to change the output changes these digests, and its
//! commit says why.
//!
//! The digests were taken from the lock-step rehearsal as it was before the loop became
//! `rigtwin::cosim` (commit d923eed), by running this test with `GOLDEN_PRINT=1`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::Path;

use rigtwin::protocol::Protocol;
use rigtwin::session::Sha256;

/// The SHA-256 of every file under `dir`, by relative path.
fn digests(dir: &Path) -> BTreeMap<String, String> {
    rigtwin_tests::files(dir)
        .unwrap()
        .into_iter()
        .map(|(k, v)| (k, Sha256::of(&v).to_string()))
        .collect()
}

/// Rehearses the first `trials` trials of `protocol` (one subject, seed 42) and checks
/// the session's files against `want` (path, sha256).
fn check(protocol: &str, trials: usize, want: &[(&str, &str)]) {
    let p = Protocol::builtin(protocol).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    rigtwin_tests::rehearse_one(&p, 42, &dir, 2, Some(trials)).unwrap();
    let got = digests(&dir);
    if std::env::var_os("GOLDEN_PRINT").is_some() {
        for (k, v) in &got {
            println!("(\"{k}\", \"{v}\"),");
        }
    }
    let want: BTreeMap<String, String> = want
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    assert_eq!(got, want, "{protocol}: the rehearsal's bytes moved");
}

#[test]
fn reach_perturb_rehearsal_bytes_are_pinned() {
    check(
        "reach-perturb",
        6,
        &[
            (
                "S01/session.toml",
                "abb516200148afe5b828f9e2ed476a3b23f870e66c2cb2b8215d9c194f68c354",
            ),
            (
                "S01/trials/0001.csv",
                "858259b570449f38ed053c1eeb156d853277aaf01153e3b32dc1f9d226b86a6e",
            ),
            (
                "S01/trials/0002.csv",
                "97e6ddaef6379243e86351f1f34718ef896273bdc9af322bdc9a192533a92969",
            ),
            (
                "S01/trials/0003.csv",
                "91e8b866b9bb432459c2c7714c739c21836f328fe1be96026f4ab0fa8bd193bf",
            ),
            (
                "S01/trials/0004.csv",
                "5cd966f587638f834ee4ae27f397696c85f69936dc2037d351d60002f4c141bc",
            ),
            (
                "S01/trials/0005.csv",
                "b256ef476a3ccaa336164bf6d6e90fb011213559bc09d6045a3793ab83515954",
            ),
            (
                "S01/trials/0006.csv",
                "ea35dc6d25c0e963428eda924191f033f802068a59dc25f2b080380290e96396",
            ),
        ],
    );
}

#[test]
fn hold_sinusoid_rehearsal_bytes_are_pinned() {
    check(
        "hold-sinusoid",
        2,
        &[
            (
                "S01/session.toml",
                "18366878c61b1ddab4a65a2fd1d4237a99f21c903ca892619653f1716d31139c",
            ),
            (
                "S01/trials/0001.csv",
                "c60c9e2587e332abc56da51ece499964b60537d3da60bfab7b14c8a07c967e0b",
            ),
            (
                "S01/trials/0002.csv",
                "fb3e90e84e7b84d68cba429566f4f98fbb1c174e59117470ed62f35d9615548f",
            ),
        ],
    );
}

#[test]
fn calibration_rig_rehearsal_bytes_are_pinned() {
    check(
        "calibration-rig",
        1,
        &[
            (
                "S01/session.toml",
                "752471a9a6a36831babd2490a105756554568762cc4358c8b175dcaf3d1f37b6",
            ),
            (
                "S01/trials/0001.csv",
                "c95f13a1a5b5c03185706f75f98f0cd09bb2235cb2fdedb45a4dffe926fb8bf2",
            ),
        ],
    );
}
