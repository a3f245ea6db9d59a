//! Determinism: the same protocol and seed give byte-identical sessions, whatever the
//! number of worker threads (trials are simulated from seeds derived from their
//! position and written in trial order).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::AtomicBool;

use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options};

fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    rigtwin_tests::files(dir).unwrap()
}

fn run(p: &Protocol, dir: &Path, jobs: usize, subjects: u32) {
    let opts = Options {
        subjects,
        seed: 42,
        out_dir: dir.to_path_buf(),
        jobs,
        // Ten trials: the schedule's first ten hold perturbed and unperturbed ones.
        max_trials: Some(10),
    };
    rehearse::rehearse(p, &opts, &|_| {}, &AtomicBool::new(false)).unwrap();
}

#[test]
fn same_seed_same_bytes_whatever_the_jobs() {
    let p = Protocol::builtin("reach-perturb").unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        tmp.path().join("a"),
        tmp.path().join("b"),
        tmp.path().join("c"),
    );
    run(&p, &a, 1, 2);
    run(&p, &b, 2, 2);
    run(&p, &c, 3, 2);
    let (fa, fb, fc) = (files(&a), files(&b), files(&c));
    // Two subjects, each a manifest and ten trial tables.
    assert_eq!(fa.len(), 2 * 11, "{:?}", fa.keys().collect::<Vec<_>>());
    assert_eq!(fa.keys().collect::<Vec<_>>(), fb.keys().collect::<Vec<_>>());
    for (name, bytes) in &fa {
        assert!(
            fb[name] == *bytes,
            "{name} differs between --jobs 1 and --jobs 2"
        );
        assert!(
            fc[name] == *bytes,
            "{name} differs between --jobs 1 and --jobs 3"
        );
    }
    // And the sessions read back, with their digests.
    for s in ["S01", "S02"] {
        let session = rigtwin::session::Session::read(a.join(s)).unwrap();
        assert_eq!(session.trials.len(), 10);
    }
}

#[test]
fn a_different_seed_gives_different_bytes() {
    let p = Protocol::builtin("reach-perturb").unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let a = tmp.path().join("a");
    run(&p, &a, 2, 1);
    let b = tmp.path().join("b");
    let opts = Options {
        subjects: 1,
        seed: 43,
        out_dir: b.clone(),
        jobs: 2,
        max_trials: Some(10),
    };
    rehearse::rehearse(&p, &opts, &|_| {}, &AtomicBool::new(false)).unwrap();
    let (fa, fb) = (files(&a), files(&b));
    assert_ne!(fa["S01/trials/0001.csv"], fb["S01/trials/0001.csv"]);
}

#[test]
fn output_folder_is_never_overwritten() {
    let p = Protocol::builtin("reach-perturb").unwrap();
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("keep.txt"), "x").unwrap();
    let opts = Options {
        subjects: 1,
        seed: 1,
        out_dir: tmp.path().to_path_buf(),
        jobs: 1,
        max_trials: Some(1),
    };
    let e = rehearse::rehearse(&p, &opts, &|_| {}, &AtomicBool::new(false)).unwrap_err();
    assert!(e.to_string().contains("not empty"), "{e}");
    assert_eq!(
        std::fs::read_to_string(tmp.path().join("keep.txt")).unwrap(),
        "x"
    );
    // A fresh folder is picked next to a taken one.
    std::fs::create_dir(tmp.path().join("reach-perturb-1")).unwrap();
    let fresh = rehearse::fresh_dir(tmp.path(), "reach-perturb", 1);
    assert_eq!(fresh, tmp.path().join("reach-perturb-1-2"));
}
