//! A real-time rehearsal: two reaches (3.5 s each, 28 000 ticks) paced by the wall clock
//! at 4 kHz. Whatever this shared machine gives, no recorded sample is lost (a missed
//! deadline is held, not dropped), the session reads back with its `[timing]`, and every
//! deadline is accounted for: ticks run plus ticks skipped is the trial's length. Where
//! no deadline was missed, the trial's bytes are the lock-step trial's.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::atomic::AtomicBool;

use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options, Pacing, RealTime, trial};
use rigtwin::session::Session;

#[test]
fn a_real_time_rehearsal_keeps_every_sample_and_reports_its_clock() {
    let protocol = Protocol::builtin("reach-perturb").unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let run = |dir: &std::path::Path, pacing: Pacing| {
        let opts = Options {
            subjects: 1,
            seed: 42,
            out_dir: dir.to_path_buf(),
            jobs: 1,
            max_trials: Some(2),
        };
        rehearse::rehearse_paced(
            &protocol,
            &opts,
            pacing,
            &|_| {},
            &AtomicBool::new(false),
            &mut (),
        )
        .unwrap()
    };
    let rt = run(
        &tmp.path().join("rt"),
        Pacing::RealTime(RealTime::default()),
    );
    let lock = run(&tmp.path().join("lock"), Pacing::LockStep);
    let timing = rt.subjects[0]
        .timing
        .expect("a real-time session has its timing");
    let trial_ticks = trial::trial_ticks(&protocol);
    // Every deadline of both trials is either run or counted as missed.
    assert_eq!(
        timing.ticks + timing.missed_deadlines,
        2 * trial_ticks,
        "{timing:?}"
    );
    let period_us = rigtwin_device::Rate::CONTROL.period_s() * 1e6;
    assert!((timing.period_us - period_us).abs() < 1e-9);
    assert!(timing.wake_latency.p50_us <= timing.wake_latency.p99_us);
    assert!(timing.wake_latency.p99_us <= timing.wake_latency.max_us);
    assert!(timing.loop_time.max_us > 0.0);
    // The session reads back, with the same timing in its manifest and every row there.
    let s = Session::read(rt.subjects[0].dir.as_path()).unwrap();
    assert_eq!(s.manifest.timing, Some(timing));
    let l = Session::read(lock.subjects[0].dir.as_path()).unwrap();
    for (a, b) in rt.subjects[0].trials.iter().zip(&lock.subjects[0].trials) {
        let (_, ta) = s.trial(a.id).unwrap();
        let (_, tb) = l.trial(b.id).unwrap();
        assert_eq!(ta.len(), tb.len(), "trial {}: rows", a.id);
        if timing.missed_deadlines == 0 {
            assert_eq!(a.sha256, b.sha256, "trial {}: no miss, same bytes", a.id);
        }
    }
    assert!(lock.subjects[0].timing.is_none());
}
