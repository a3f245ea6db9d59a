//! Actuation delay on the project's plant: the delay model must remove what a hidden
//! 0.75–1.5 ms drive latency adds to the cart balance's residual, not only name it.
//!
//! On a realistic session (the generator's default nuisances) the cart balance's
//! residual has a floor no plant model removes: the current loop's noise, 0.1–0.3 N RMS,
//! is in the force but not in the logged command. The held-out gain `1 − e/b` is then
//! bounded by the floor (0.12–0.42 on seeds 1000–1009), so what is asserted is the share
//! of the excess over the floor that the delay model removes, `(b² − e²)/(b² − f²)`, with
//! `b` and `e` the baseline's and the extended model's held-out NRMSE and `f` the
//! baseline's on the same seed's session hiding nothing (the same subject, nuisances and
//! noise: the generator's seed sets them whatever is hidden). Measured on seeds
//! 1000–1019 with the motor gains bounded: 0.90–1.43, at least 0.8 on all 20 (the
//! extended model reaches the floor; 1.40–1.43 where the 0.75 ms delay adds little over
//! it; 0.90–1.45 with free gains on 1000–1009), held-out gains 0.12–0.44;
//! `sweep_delay_gain` prints the gains (`PLANT_SEEDS=1000,…,1019
//! PLANT_EFFECTS=actuation-delay,none`). How the delay became identifiable at all (the balance filter, the
//! one-tick nominal latency) is in `hil/diagnose/src/signals.rs`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use rigtwin::session::Session;
use rigtwin_diagnose::{DiagnoseOptions, Diagnosis, diagnose};
use rigtwin_tests::generate_and_diagnose;
use rigtwin_tests::generator::{Design, Hidden, generate};

/// Reaches per session: the shared sessions' 32.
const TRIALS: usize = 32;

/// Generates (or, for the sweep, reuses under `cache`) a session and diagnoses it.
fn run(effect: &str, seed: u64, cache: Option<&Path>) -> (Hidden, Diagnosis) {
    let tmp = tempfile::tempdir().unwrap();
    let out: PathBuf = cache.map_or_else(
        || tmp.path().join("out"),
        |c| c.join(format!("{effect}-{seed}")),
    );
    let marker = out.join("hidden.txt");
    let (dir, hidden) = if let Ok(text) = std::fs::read_to_string(&marker) {
        let dir = PathBuf::from(text.lines().next().unwrap());
        let g = rigtwin_tests::generator::draw(effect, &mut {
            use rand::SeedableRng;
            rand_chacha::ChaCha8Rng::seed_from_u64(seed)
        })
        .unwrap();
        (dir, g)
    } else {
        let g = generate(effect, seed, TRIALS, &out).unwrap();
        std::fs::write(&marker, format!("{}\n", g.dir.display())).unwrap();
        (g.dir, g.hidden)
    };
    let s = Session::read(&dir).unwrap();
    let d = diagnose(&s, &DiagnoseOptions::default()).unwrap().diagnosis;
    (hidden, d)
}

fn report(effect: &str, seed: u64, h: &Hidden, d: &Diagnosis) {
    println!(
        "{effect:<16} seed {seed:>5} hidden {:?} found {} {:?} baseline {:.4} extended {:.4} gain {:.3}",
        h.parameters,
        d.cause,
        d.parameters,
        d.baseline_nrmse.unwrap_or(f64::NAN),
        d.extended_nrmse.unwrap_or(f64::NAN),
        d.gain.unwrap_or(f64::NAN),
    );
    for r in &d.ranking {
        println!(
            "    {:<16} gain {:>7.3} t {:>8.1}",
            r.name, r.gain, r.t_statistic
        );
    }
}

/// Seed 1003 hides 1.25 ms. Asserted: the cause, the delay within 20 % (README
/// § Requirements; the world rounds it to whole 0.25 ms ticks, the grid is 25 µs) and at
/// least 80 % of the excess over the rig's floor removed (module docs; measured 1.03
/// here, 0.90–1.43 on seeds 1000–1019; a model that only named the delay would leave it).
#[test]
fn hidden_delay_removes_the_excess_over_the_floor() {
    let (h, d) = run("actuation-delay", 1003, None);
    report("actuation-delay", 1003, &h, &d);
    assert_eq!(d.cause, "actuation-delay");
    let truth = h.parameters["delay_ms"];
    let got = d.parameters["delay_ms"];
    assert!(
        (got - truth).abs() <= 0.2 * truth,
        "delay {got} ms, hidden {truth} ms"
    );
    let (_, none) = run("none", 1003, None);
    assert_eq!(none.cause, "none", "{:?}", none.parameters);
    let (b, e) = (d.baseline_nrmse.unwrap(), d.extended_nrmse.unwrap());
    let f = none.cart_baseline_nrmse.unwrap();
    let removed = (b * b - e * e) / (b * b - f * f);
    eprintln!("baseline {b:.4}, extended {e:.4}, floor {f:.4}: {removed:.3} of the excess removed");
    assert!(b > f, "the delay added nothing over the floor: {b} vs {f}");
    assert!(
        removed >= 0.8,
        "{removed:.3} of the excess over the floor removed"
    );
}

/// The delay the diagnosis reports is the whole lag from the logged command to the
/// force (`hil/diagnose/src/delay.rs`): the hidden drive delay plus the lag the rig has
/// of its own, which the balance sees as a fraction of a 0.25 ms tick (0.05 ms on the
/// project's plant, 0–0.05 ms on the shared rig). Without noise or nuisances (the arm's
/// motor noise off, the ideal rig) the two must add up: seed 1003 hides 1.25 ms, the
/// same seed's session hiding nothing fits its own lag, and the found delay is their sum
/// to one step of the 25 µs grid (the own lag lies between grid points). Measured on
/// seeds 1000–1003 (hidden 1.5, 1.25, 1.0, 1.25 ms; own lag 0.05 ms): 1.525, 1.30,
/// 1.075, 1.30 ms. With the arm's motor noise and the rig's current-loop noise it
/// scatters by a few steps more, which is why on realistic sessions the delay comes out
/// 0.025–0.125 ms longer than the one hidden.
#[test]
fn the_found_delay_is_the_hidden_one_plus_the_rigs_own_lag() {
    let diagnosed = |effect: &str| {
        let tmp = tempfile::tempdir().unwrap();
        let (g, d) =
            generate_and_diagnose(effect, 1003, &Design::QUIET, &tmp.path().join("out")).unwrap();
        (g.hidden, d)
    };
    let (_, none) = diagnosed("none");
    assert_eq!(none.cause, "none", "{:?}", none.parameters);
    let own = none
        .ranking
        .iter()
        .find(|r| r.name == "actuation-delay")
        .and_then(|r| r.parameters.get("delay_ms").copied())
        .expect("the delay candidate is ranked on every session");
    let (h, d) = diagnosed("actuation-delay");
    assert_eq!(d.cause, "actuation-delay");
    let hidden = h.parameters["delay_ms"];
    let found = d.parameters["delay_ms"];
    eprintln!("hidden {hidden} ms, own lag {own} ms, found {found} ms");
    // The own lag is a fraction of the world's tick, nothing like a drive delay.
    assert!((0.0..0.25).contains(&own), "own lag {own} ms");
    assert!(
        (found - (hidden + own)).abs() <= 0.025 + 1e-9,
        "found {found} ms, hidden {hidden} + own {own} ms"
    );
}

/// The held-out gains of the delay, friction and none sessions of seeds
/// `PLANT_SEEDS` (default 1000–1004), sessions kept under `PLANT_GEN_DIR` when set.
#[test]
#[ignore = "generates and diagnoses ~15 sessions; run with --ignored --nocapture"]
fn sweep_delay_gain() {
    let cache = std::env::var("PLANT_GEN_DIR").ok().map(PathBuf::from);
    let seeds: Vec<u64> = std::env::var("PLANT_SEEDS").map_or_else(
        |_| (1000..1005).collect(),
        |s| s.split(',').map(|x| x.trim().parse().unwrap()).collect(),
    );
    let effects = std::env::var("PLANT_EFFECTS")
        .unwrap_or_else(|_| "actuation-delay,rail-friction,none".into());
    for effect in effects.split(',') {
        for &seed in &seeds {
            let (h, d) = run(effect, seed, cache.as_deref());
            report(effect, seed, &h, &d);
        }
    }
}
