//! Record A, replay A (the copper-rs determinism test): the rig's controller, driven
//! through `ReplayRig` by the sensor columns of a rehearsed session, writes the motor
//! commands the session recorded. The session is the shipped reach protocol recorded at
//! the control rate (4 kHz, one row per tick), four trials, one of them perturbed. The
//! controller sees the encoder counts it saw (positions are whole micrometres and round
//! back to the same counts) and the force rounded to the 0.1 mN the file keeps; that
//! rounding, integrated by the admittance into the reference and multiplied by the
//! position loop's stiffness, makes the commands differ from the recorded ones by
//! 23-79 mN at most over a trial (measured), on commands that swing by tens of newtons
//! from tick to tick. The bound, 0.25 N, is three times that; a controller change, a
//! pulse armed a tick off or rows shifted by one tick show as tens of newtons (comparing
//! with the next row's command gives 37 N).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::atomic::AtomicBool;

use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options, TrialTask, trial};
use rigtwin::replay::{Interpolation, ReplayRig};
use rigtwin::session::Session;
use rigtwin_device::{Rate, Tick};

#[test]
fn the_controller_replayed_on_its_own_session_writes_the_recorded_commands() {
    let tmp = tempfile::tempdir().unwrap();
    let text = include_str!("../../hil/protocols/reach-perturb.toml");
    // Recorded at the control rate: one row per tick.
    let at_4k = text.replacen(
        "rate_hz = 1000 ",
        &format!("rate_hz = {} ", Rate::CONTROL.hz()),
        1,
    );
    assert_ne!(text, at_4k, "the shipped protocol records at 1000 Hz");
    let path = tmp.path().join("reach-4k.toml");
    std::fs::write(&path, at_4k).unwrap();
    let protocol = Protocol::load(&path).unwrap();
    let opts = Options {
        subjects: 1,
        seed: 42,
        out_dir: tmp.path().join("out"),
        jobs: 2,
        max_trials: Some(4),
    };
    let run = rehearse::rehearse(&protocol, &opts, &|_| {}, &AtomicBool::new(false)).unwrap();
    let session = Session::read(&run.subjects[0].dir).unwrap();
    let subject = &run.subjects[0].subject;
    let plans = rehearse::schedule(&protocol, 42, subject.index);
    let n_ticks = trial::trial_ticks(&protocol);
    let mut perturbed = 0;
    for (plan, table) in plans.iter().zip(&session.trials) {
        assert_eq!(table.t_s.len() as u64, n_ticks, "one row per tick");
        if matches!(
            plan.task,
            TrialTask::Reach {
                angle_deg: Some(_),
                ..
            }
        ) {
            perturbed += 1;
        }
        let mut replay = ReplayRig::at_control_rate(
            table,
            f64::from(Rate::CONTROL.hz()),
            Interpolation::SampleAndHold,
        )
        .unwrap();
        let mut parts = trial::controller_parts(&protocol, subject, 42, plan, true).unwrap();
        let recorded = (
            table.cmd_fx_n.as_ref().unwrap(),
            table.cmd_fy_n.as_ref().unwrap(),
        );
        let mut worst = 0.0_f64;
        for n in 0..n_ticks {
            parts
                .driver
                .before_tick(&mut parts.controller, Tick(n))
                .unwrap();
            let r = parts.controller.tick(&mut replay, Tick(n));
            let k = n as usize;
            worst = worst
                .max((r.command_n[0] - recorded.0[k]).abs())
                .max((r.command_n[1] - recorded.1[k]).abs());
        }
        eprintln!(
            "trial {}: max |cmd_replay - cmd_recorded| = {worst:e} N",
            plan.index + 1
        );
        assert!(worst < 0.25, "trial {}: {worst} N", plan.index + 1);
    }
    assert!(perturbed >= 1, "a perturbed trial among the four");
}
