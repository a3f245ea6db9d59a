//! Hidden-effect discovery: sessions from the project's runtime, each hiding one
//! catalog effect, plant side or human side, with drawn parameters (or none),
//! diagnosed blind. Every session has a lab's nuisances (the generator's default,
//! `NuisanceConfig::REALISTIC`): a force sensor tared 0.05–0.3 N off and drifting up to
//! 0.1 N, motor force constants within 1 %, current-loop noise of 0.1–0.3 N RMS that is
//! not in the logged command, reaction times of 0.20–0.35 s, reach durations ±13 %, end
//! points scattered by 2–4 mm, an impedance trending by up to 10 % over the session,
//! and a trigger logged 0–1 ms before its pulse acts.
//!
//! Asserted per session: the effect's name; each hidden parameter within 20 %; a
//! held-out gain of at least 50 % (the plant effects are drawn large enough to matter
//! and the balance recovers them almost exactly); for `none`, that no cause is named.
//! Two exceptions, each measured on the sweep's seeds 1000–1009:
//!
//! - `actuation-delay` is held to a held-out gain of 10 %: the current-loop
//!   noise is a floor no plant model removes, and a 0.75–1.5 ms delay explains
//!   0.12–0.42 of the cart balance's residual above it (its delay is found within 20 %
//!   in 10 of 10). What the delay model removes of the excess over that floor is
//!   asserted in `hidden_delay.rs`.
//! - `stretch-reflex` on the shared layout (24 pulses of 150 ms) is named in 10 of 10,
//!   with both parameters within 20 % in 3 (the gain comes out high; see
//!   `hidden_stretch_reflex_is_named_under_motor_noise`), and its delay's searched range
//!   says so: wider than ±20 % on all 20 of the sweep's seeds; a session laid out to measure
//!   a reflex ([`Design::reflex_study`]: 72 pulses of 50 ms, 30 N) is what
//!   `hidden_stretch_reflex_is_found` asserts.
//!
//! Human side (hand balance, full 2×2 `D` and `K` fitted on the odd parts of each pair
//! of opposite pulses, tested on the 12 repetitions, rows whitened in time and between
//! the axes, `hil/diagnose/src/hand.rs`). The sweeps (`sweep_confusion_matrix`,
//! `sweep_false_alarms`, ignored; numbers in the README) give the confusion matrix and
//! the false-alarm rate on sessions hiding nothing.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin::session::{Session, TrialEntry};
use rigtwin_diagnose::{DiagnoseOptions, Diagnosis, diagnose, reach_groups, write_report};
use rigtwin_tests::generate_and_diagnose;
use rigtwin_tests::generator::{
    CENTRE_OUT_M, Design, EFFECTS, Generated, Hidden, OUT_OF_CATALOG, PAIRS, generate_design,
    generate_hidden, parse_pulse,
};

fn run(effect: &str, seed: u64) -> (Generated, Diagnosis) {
    run_design(effect, seed, &Design::SHARED)
}

/// Generates and diagnoses a session, and asserts that no sample of it was taken for
/// a glitch (`rigtwin_diagnose::glitch`), no row for a lost sample
/// or a frame written twice (`rigtwin_diagnose::slip`), no channel for one held
/// between its sensor's readings
/// (`rigtwin_diagnose::hold`) and no trial for a fault (`rigtwin_diagnose::faults`):
/// the rig's physics, its sensor noise and
/// encoder quantum, block means, every nuisance and every hidden effect, at every
/// layout and rate these tests use, make neither.
fn run_design(effect: &str, seed: u64, design: &Design) -> (Generated, Diagnosis) {
    let tmp = tempfile::tempdir().unwrap();
    let (g, d) = generate_and_diagnose(effect, seed, design, &tmp.path().join("out")).unwrap();
    assert!(d.glitches.is_empty(), "{:?}", d.glitches);
    assert!(d.slips.is_empty(), "{:?}", d.slips);
    assert!(d.held.is_empty(), "{:?}", d.held);
    assert!(d.repeated_frames.is_empty(), "{:?}", d.repeated_frames);
    assert!(d.cart_set_aside.is_empty(), "{:?}", d.cart_set_aside);
    (g, d)
}

/// The first named cause removes at least `at_least` of what the baseline leaves above
/// its balance's noise floor (`Cause::share_above_floor`), which the session must have.
fn assert_share_above_floor(d: &Diagnosis, at_least: f64) {
    let c = &d.causes[0];
    let share = c.share_above_floor.unwrap_or_else(|| {
        panic!(
            "{}: no floor on the {} balance, or a baseline under it",
            c.name.name(),
            c.balance
        )
    });
    eprintln!(
        "{} removes {share:.3} of the excess over the {} balance's floor",
        c.name.name(),
        c.balance
    );
    assert!(
        share >= at_least,
        "{} removes {share} of the excess over the floor",
        c.name.name()
    );
}

fn check(effect: &str, seed: u64) -> (Generated, Diagnosis) {
    check_with_gain(effect, seed, 0.5)
}

/// Each perturbed trial's lag from the logged onset to its pulse, ms: the centre of the
/// logged perturbation force's magnitude minus the logged onset plus half the pulse.
/// The pulse is symmetric in time, so its centre is where its half-duration puts it.
fn trigger_lags_ms(dir: &std::path::Path) -> Vec<f64> {
    let s = Session::read(dir).unwrap();
    s.iter()
        .filter_map(|(e, t)| {
            let p = e.perturbation.as_ref()?;
            let m: Vec<f64> = t
                .pert_fx_n
                .iter()
                .zip(&t.pert_fy_n)
                .map(|(x, y)| x.hypot(*y))
                .collect();
            let total: f64 = m.iter().sum();
            let centre = m.iter().zip(&t.t_s).map(|(a, t)| a * t).sum::<f64>() / total;
            Some((centre - p.onset_s - p.duration_s / 2.0) * 1e3)
        })
        .collect()
}

/// A realistic rig logs its trigger up to 4 ticks (1 ms) before the pulse acts, as the
/// shared realistic sessions' rig does; the perturbation columns hold the pulse where
/// it acted. Every lag is a whole number of 0.25 ms ticks within 0–1 ms (to 0.02 ms:
/// the logged force's 1 mN rounding moves the centre by less), the lags differ from
/// trial to trial, and the ideal rig's are all 0.
#[test]
fn the_logged_onset_leads_the_pulse_by_the_trigger_lag() {
    let small = Design {
        trials: 12,
        repetitions: 1,
        ..Design::SHARED
    };
    let tmp = tempfile::tempdir().unwrap();
    for (design, name) in [
        (small.clone(), "realistic"),
        (
            Design {
                nuisance: None,
                ..small
            },
            "ideal",
        ),
    ] {
        let g = generate_design("none", 7, &design, &tmp.path().join(name)).unwrap();
        let lags = trigger_lags_ms(&g.dir);
        println!("{name}: lags {lags:.3?} ms");
        assert_eq!(lags.len(), 8, "{name}: one pulse per angle");
        for l in &lags {
            let ticks = l / 0.25;
            assert!(
                (ticks - ticks.round()).abs() * 0.25 < 0.02,
                "{name}: {l} ms is not whole ticks"
            );
            assert!((-0.02..=1.02).contains(l), "{name}: {l} ms outside 0-1 ms");
        }
        let distinct = lags
            .iter()
            .map(|l| (l / 0.25).round() as i64)
            .collect::<std::collections::BTreeSet<_>>();
        if design.nuisance.is_some() {
            assert!(distinct.len() >= 2, "the lag is drawn per trial: {lags:?}");
        } else {
            assert_eq!(
                distinct.into_iter().collect::<Vec<_>>(),
                vec![0],
                "{lags:?}"
            );
        }
    }
}

fn check_with_gain(effect: &str, seed: u64, min_gain: f64) -> (Generated, Diagnosis) {
    check_design(effect, seed, &Design::SHARED, min_gain)
}

fn check_design(effect: &str, seed: u64, design: &Design, min_gain: f64) -> (Generated, Diagnosis) {
    check_within(effect, seed, design, min_gain, &|_| (0.8, 1.2))
}

/// [`check_design`] with each hidden parameter's accepted range as factors of its
/// value: `within(name)` gives `(low, high)` for `found / hidden` (README § Requirements,
/// each parameter within 20 %: `(0.8, 1.2)`).
fn check_within(
    effect: &str,
    seed: u64,
    design: &Design,
    min_gain: f64,
    within: &dyn Fn(&str) -> (f64, f64),
) -> (Generated, Diagnosis) {
    let (g, d) = run_design(effect, seed, design);
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
        return (g, d);
    }
    for (k, truth) in &g.hidden.parameters {
        let got = d.parameters.get(k).copied().unwrap_or(f64::NAN);
        let (low, high) = within(k);
        assert!(
            (low..=high).contains(&(got / truth)),
            "{k}: found {got}, hidden {truth}"
        );
    }
    assert!(d.gain.unwrap() >= min_gain, "gain {:?}", d.gain);
    (g, d)
}

/// Nothing is named, and the cart balance's baseline sits on the noise floor read from
/// the rows where the carts stand still (0.98 here, 0.93–1.06 over seeds 2000–2019;
/// 0.9–1.15 asserted): where the baseline misses nothing, its held-out error is the
/// rig's noise.
#[test]
fn hidden_none_is_not_explained() {
    let (_, d) = check("none", 11);
    let floor = d
        .cart_noise_floor_nrmse
        .expect("still rows at the trials' ends");
    let ratio = d.cart_baseline_nrmse.unwrap() / floor;
    eprintln!("cart noise floor {floor:.4}, the baseline at {ratio:.3}× it");
    assert!(
        (0.9..=1.15).contains(&ratio),
        "the cart baseline at {ratio}× its floor"
    );
}

#[test]
fn hidden_rail_friction_is_found() {
    check("rail-friction", 12);
}

/// Each motor's own magnet track: the generator draws each axis's amplitude (1–3 N) and
/// phase (uniform) apart, and both amplitudes (the check's 20 %) and both phases must
/// come back, the phases within 0.3 rad (the pitch grid's step turns the fitted
/// sinusoid by up to π/8 over the travel; measured here 0.002 and 0.001 rad).
#[test]
fn hidden_force_ripple_is_found() {
    let (g, d) = check("force-ripple", 13);
    let hidden = g.hidden.effects.force_ripple.unwrap();
    for (axis, name) in ["x", "y"].iter().enumerate() {
        let found = d.parameters[&format!("phase_{name}_rad")];
        let off = (found - hidden.phase_rad[axis] + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        eprintln!(
            "phase {name}: hidden {:.3}, found {found:.3} rad",
            hidden.phase_rad[axis]
        );
        assert!(
            off.abs() < 0.3,
            "phase {name}: found {found}, hidden {}",
            hidden.phase_rad[axis]
        );
    }
}

/// Labs log at 500 Hz to 4 kHz: the same seeds' rail friction (the cart balance) and
/// handle mass (the hand balance) recorded at 500 Hz and at 4 kHz instead of 1 kHz are
/// named, with every parameter within 20 % and a held-out gain of at least 50 %
/// (measured: at 500 Hz and 4 kHz, Coulomb 1.035 and 1.040 N for 1.004, viscous 8.03 and
/// 8.01 N s/m for 8.21, gains 0.90 and 0.91; extra mass 0.711 and 0.709 kg for 0.725,
/// gains 0.77 and 0.78).
#[test]
fn recording_rates_from_500_hz_to_4_khz_give_the_same_answer() {
    for rate_hz in [500, 4000] {
        let design = Design {
            rate_hz,
            ..Design::SHARED
        };
        check_design("rail-friction", 12, &design, 0.5);
        check_design("handle-mass", 1003, &design, 0.5);
    }
}

/// The seed's session of the shared layout with its perturbed trials left out: the
/// unperturbed reaches alone, as a lab records them in a familiarisation block.
fn run_without_pulses(effect: &str, seed: u64) -> (Generated, Diagnosis) {
    run_keeping(effect, seed, 8, |t| t.perturbation.is_none())
}

/// The seed's session of the shared layout with only the trials `keep` accepts (in
/// session order), which must be `kept` of them, diagnosed.
fn run_keeping(
    effect: &str,
    seed: u64,
    kept: usize,
    mut keep: impl FnMut(&TrialEntry) -> bool,
) -> (Generated, Diagnosis) {
    let tmp = tempfile::tempdir().unwrap();
    let g = generate_design(effect, seed, &Design::SHARED, &tmp.path().join("out")).unwrap();
    let mut s = Session::read(&g.dir).unwrap();
    let mask: Vec<bool> = s.manifest.trials.iter().map(&mut keep).collect();
    let mut k = mask.iter();
    s.manifest.trials.retain(|_| *k.next().unwrap());
    let mut k = mask.iter();
    s.trials.retain(|_| *k.next().unwrap());
    assert_eq!(s.trials.len(), kept, "trials kept");
    let d = diagnose(&s, &DiagnoseOptions::default()).unwrap().diagnosis;
    (g, d)
}

/// The seed's session of the shared layout without the first perturbed trial at 30°,
/// at 60° and at 120°: trials a lab set aside (the subject missed, the pulse came
/// late), so that three of the four pairs of opposite directions have two repetitions
/// on one side and three on the other.
fn run_without_three_pulses(effect: &str, seed: u64) -> (Generated, Diagnosis) {
    let mut left_out = Vec::new();
    run_keeping(effect, seed, 29, |t| {
        let Some(angle) = t.perturbation.as_ref().map(|p| p.angle_deg.round() as i64) else {
            return true;
        };
        if [30, 60, 120].contains(&angle) && !left_out.contains(&angle) {
            left_out.push(angle);
            return false;
        }
        true
    })
}

/// Uneven repetitions: with three pulses set aside the hand balance's units are the
/// odd parts of each pair's means over the repetitions left (3 against 2), and its
/// t-test takes the 9 repetitions that still have a match. Nothing is named on seed
/// 2000, and a heavier handle (seed 1003, 0.725 kg) is named within 20 % with a
/// held-out gain of at least 0.6. Measured with three pulses drawn at random from each
/// session: nothing named on 50 of 50 seeds 2000–2049, the handle within 10 % on 10 of
/// 10 and a grip within 3 % on 5 of 5 (README, "Sessions with pulses set aside").
#[test]
fn a_session_with_pulses_set_aside_pairs_what_is_left() {
    let (_, d) = run_without_three_pulses("none", 2000);
    assert_finds_nothing(&d, "seed 2000");
    assert_eq!(d.hand_trials_used, 21);
    assert_eq!((d.hand_units, d.hand_test_units), (4, Some(9)));
    let (g, d) = run_without_three_pulses("handle-mass", 1003);
    let (hidden, found) = (
        g.hidden.parameters["extra_mass_kg"],
        d.parameters["extra_mass_kg"],
    );
    eprintln!(
        "handle: {:?}, {found} kg for {hidden} kg, gain {:?}",
        d.cause, d.gain
    );
    assert_eq!(d.cause, "handle-mass");
    assert!((found - hidden).abs() <= 0.2 * hidden);
    assert!(d.gain.unwrap() >= 0.6, "gain {:?}", d.gain);
}

/// Reaches without pulses: the admittance then makes the carts' velocity
/// `(F − M a)/D`, so a viscous friction `b v` beside the motor gains `γ u` with
/// `b = γ D` is a mass and a term that follows the current loop's noise the command
/// answers. The baseline sat at the gains' ±10 % bound in all 50 below, and a friction
/// of `D` × 10 % = 1.4–1.6 N s/m was named in 30 of the 50 unperturbed blocks of seeds 2000–2049
/// hiding nothing, and beside (or instead of) a hidden rotation, ripple or delay in 15
/// of 30 (seeds 1000–1009; the shared `example-nuisance` and `example-rotation-mass`
/// alike). A fit at the bound must now stand with the gains at their nominal values
/// (`decide::at_gain_bound`).
/// Asserted: seeds 2001 and 2003 (each named such a friction before) name nothing and
/// reject the friction for the bound; a hidden rotation (seed 1000, −24.4°) is named
/// alone, within 20 % (−22.7°); a hidden friction (seed 1000: 3.95 N, 9.7 N s/m) is
/// still named, its Coulomb force within 20 % (3.63 N).
#[test]
fn reaches_without_pulses_name_no_friction_the_motor_gains_stand_in_for() {
    for seed in [2001, 2003] {
        let (_, d) = run_without_pulses("none", seed);
        let friction = d
            .ranking
            .iter()
            .find(|r| r.name == "rail-friction")
            .unwrap();
        eprintln!(
            "seed {seed}: {:?}, friction {:?}",
            d.cause, friction.rejected
        );
        assert!(d.causes.is_empty(), "seed {seed}: {:?}", d.cause);
        assert!(
            friction
                .rejected
                .iter()
                .any(|w| w.contains("motor gains' bound")),
            "seed {seed}: {:?}",
            friction.rejected
        );
    }
    let (g, d) = run_without_pulses("sensor-rotation", 1000);
    let names: Vec<&str> = d.causes.iter().map(|c| c.name.name()).collect();
    let (hidden, found) = (g.hidden.parameters["angle_deg"], d.parameters["angle_deg"]);
    eprintln!("rotation: {names:?}, {found}° for {hidden}°");
    assert_eq!(names, ["sensor-rotation"]);
    assert!((found - hidden).abs() <= 0.2 * hidden.abs());
    let (g, d) = run_without_pulses("rail-friction", 1000);
    let (hidden, found) = (g.hidden.parameters["coulomb_n"], d.parameters["coulomb_n"]);
    eprintln!("friction: {:?}, {found} N for {hidden} N", d.cause);
    assert_eq!(d.cause, "rail-friction");
    assert!((found - hidden).abs() <= 0.2 * hidden);
}

/// Held to a held-out gain of 10 %, not 50 %: see the module docs (the current-loop
/// noise sets the cart balance's floor). Of what the baseline leaves above that floor,
/// read from the rows where the carts stand still, the delay removes most (1.07 here,
/// 0.85–1.29 over seeds 1000–1009: above 1 where its held-out error falls below the
/// floor's estimate); at least half is asserted.
#[test]
fn hidden_actuation_delay_is_found() {
    let (_, d) = check_with_gain("actuation-delay", 14, 0.10);
    assert_share_above_floor(&d, 0.5);
}

#[test]
fn hidden_sensor_rotation_is_found() {
    check("sensor-rotation", 15);
}

#[test]
fn hidden_grip_compliance_is_found() {
    check("grip-compliance", 21);
}

/// A grip's stiffness range holds the stiffness reported and the hidden one (seed
/// 1002 of the matrix, 3721 N/m hidden). The hand balance fits on the pairs' mean
/// responses and tests on the single repetitions; here the first chose 3749 N/m and the
/// second kept only 3973–4456, so the range (3861–4588) held neither the reported value
/// nor the truth until the reported setting was added to it. The truth is held to the
/// sweep's 1 % for a value between two grid points 5.9 % apart.
#[test]
fn a_grips_searched_range_holds_the_stiffness_it_reports() {
    let (g, d) = run("grip-compliance", 1002);
    let c = d
        .causes
        .iter()
        .find(|c| c.name.name() == "grip-compliance")
        .expect("a grip named");
    let [lo, hi] = c.parameter_range["stiffness_n_per_m"];
    let (found, hidden) = (
        c.parameters["stiffness_n_per_m"],
        g.hidden.parameters["stiffness_n_per_m"],
    );
    println!("range {lo:.0}–{hi:.0} N/m, found {found:.0}, hidden {hidden:.0}");
    assert!(
        (lo..=hi).contains(&found),
        "found {found} outside {lo}–{hi}"
    );
    assert!(
        (0.99 * lo..=1.01 * hi).contains(&hidden),
        "hidden {hidden} outside {lo}–{hi}"
    );
}

/// A soft grip with heavy damping, beyond the generator's drawn range (2–6 kN/m,
/// τ 2–6 ms): 1500 N/m with 25 N s/m, a time constant of 17 ms. With the grip's time
/// constants searched up to 10 ms the stiffness came out 1991 N/m here (19.9 N s/m), and
/// 1991–2108 N/m on the six subjects of `hil/sweeps/grip-soft.toml` (33–41 % high: the
/// spring took up the damping the grid could not reach), half of which reported
/// `hand_unexplained`; searched up to 46 ms, 1581 N/m here and 1493–1675 there.
/// Asserted: the grip alone is named, its stiffness within 20 %, its damping within 30 %
/// (a time constant on a grid 13.6 % apart, traded against the stiffness), a held-out
/// gain of 50 %, nothing unexplained.
#[test]
fn a_soft_heavily_damped_grip_is_sized() {
    let (k, b) = (1500.0, 25.0);
    let (_, found_b) = a_grip_alone_is_sized(k, b, 1);
    assert!(
        (found_b / b - 1.0).abs() < 0.3,
        "damping {found_b:.1} for {b}"
    );
}

/// A rail friction that is viscous alone (2 N s/m on both rails, no Coulomb force: a
/// greased bearing, a drive's velocity loop) is named, its coefficient within 20 %,
/// and no law outside the catalog is reported in its place. Its knee shapes nothing,
/// so the folds put it anywhere, the softest setting included; judged an edge there,
/// the friction was rejected and the library reported a quadratic drag and a pull
/// instead (seeds 4, 7 and 8 of 1–8 at 2 N s/m, this one the first; 3 of 4 subjects of
/// a sweep at 1, 2 and 5 N s/m). The knee is listed in the cause's `undetermined`.
#[test]
fn a_viscous_friction_without_a_coulomb_force_is_named() {
    let b = 2.0;
    let d = named_alone(Hidden::friction(0.0, b), 4);
    let c = &d.causes[0];
    let (found_b, found_fc) = (c.parameters["viscous_n_s_per_m"], c.parameters["coulomb_n"]);
    println!(
        "viscous {found_b:.3} N s/m, Coulomb {found_fc:.4} N, gain {:.3}",
        c.gain
    );
    assert!((found_b / b - 1.0).abs() < 0.2, "viscous {found_b} for {b}");
    assert!(
        found_fc.abs() < 0.25,
        "Coulomb {found_fc} N where none is hidden"
    );
    // The knee the folds put anywhere is said to be undetermined, not reported bare.
    assert_eq!(
        c.undetermined.keys().collect::<Vec<_>>(),
        ["smooth_velocity_m_per_s"],
        "{:?}",
        c.undetermined
    );
    assert!(d.unexplained.is_none(), "{:?}", d.unexplained);
}

/// Diagnoses a shared-layout session (seed `seed`) hiding `hidden`, one catalog
/// effect, and asserts that it alone is named.
fn named_alone(hidden: Hidden, seed: u64) -> Diagnosis {
    let name = hidden.effect.clone();
    let tmp = tempfile::tempdir().unwrap();
    let g = generate_hidden(hidden, seed, &Design::SHARED, &tmp.path().join("out")).unwrap();
    let d = diagnose(&Session::read(&g.dir).unwrap(), &DiagnoseOptions::default())
        .unwrap()
        .diagnosis;
    let names: Vec<&str> = d.causes.iter().map(|c| c.name.name()).collect();
    assert_eq!(names, [name.as_str()], "{:?}", d.ranking);
    d
}

/// Diagnoses a shared-layout session (seed `seed`) hiding a grip of `k` N/m and `b`
/// N s/m alone and asserts: the grip alone is named, its stiffness within 20 %, a
/// held-out gain of 50 %, nothing unexplained. Returns its stiffness and damping.
fn a_grip_alone_is_sized(k: f64, b: f64, seed: u64) -> (f64, f64) {
    let d = named_alone(Hidden::grip(k, b), seed);
    let c = &d.causes[0];
    let (found_k, found_b) = (
        c.parameters["stiffness_n_per_m"],
        c.parameters["damping_n_s_per_m"],
    );
    println!("{found_k:.0} N/m, {found_b:.1} N s/m, gain {:.3}", c.gain);
    assert!(
        (found_k / k - 1.0).abs() < 0.2,
        "stiffness {found_k:.0} for {k}"
    );
    assert!(c.gain >= 0.5, "gain {}", c.gain);
    assert!(d.unexplained.is_none() && d.hand_unexplained.is_none());
    (found_k, found_b)
}

/// A soft grip with light damping, 1000 N/m with 10 N s/m (τ 10 ms): the hand, behind
/// its spring, rings near 4 Hz under the pulse and the handle no longer feels the arm's
/// inertia. The rival (an arm within ±20 % of the tables, its impedance following the
/// reach's activations) held at its lighter bound then explained the responses about as
/// well as the grip, and the grip was rejected as "not told from the subject's arm" on
/// this seed (2 of 6 seeds, 4 of 8 subjects of a sweep). Set free, the rival's inertia
/// comes out near 0 of the tables', an arm no table allows, so the rival does not stand.
/// Asserted: the grip alone is named, its stiffness within 20 %, a held-out gain of 50 %,
/// nothing unexplained.
#[test]
fn a_soft_lightly_damped_grip_is_not_taken_for_the_arm() {
    a_grip_alone_is_sized(1000.0, 10.0, 1);
}

/// A heavier handle is the whole of what its session hides on the hand side, so the
/// model with it reaches the noise floor read from the repetitions: it removes at least
/// 80 % of the baseline's excess over the floor (0.92–1.07 over the sweep's seeds
/// 1000–1019, 0.99 on this one; above 1 where the held-out error falls below the floor's
/// estimate), where its held-out gain, bounded by that noise, is 0.57–0.85.
#[test]
fn hidden_handle_mass_is_found() {
    let (_, d) = check("handle-mass", 1003);
    assert_share_above_floor(&d, 0.8);
}

/// Reaches along `x` (a lab studying lateral reaches, the pulse fired on the measured
/// `x`'s crossing of a line): the hand balance aligns each perturbed trial's references
/// on the axis the session's reaches travel along (`hand_signals::reach_axis`). Aligned
/// on `y`, which such reaches hardly move along, the references met the trial at
/// whatever point of their reach `y` wandered through the onset's level: seeds 2001 and
/// 2004 hiding nothing named a grip of 28 and 27 kN/m (gains 0.107 and 0.111), and seed
/// 1001's grip of 4.7 kN/m came out at 5.3 kN/m with a gain of 0.606. Aligned on `x`:
/// nothing named on the first two, the grip at 4.72 kN/m with a gain of 0.836. A gain
/// of 0.75 is asked: the matrix's grips on `y` reaches gain 0.76–0.91 over 20 seeds.
#[test]
fn lateral_reaches_are_aligned_along_x() {
    let design = Design {
        lateral: true,
        ..Design::SHARED
    };
    for seed in [2001, 2004] {
        let (_, d) = run_design("none", seed, &design);
        assert_finds_nothing(&d, &format!("seed {seed}"));
    }
    check_design("grip-compliance", 1001, &design, 0.75);
}

/// Pulses in the four cardinal directions (six each; the same 24 pulses as the shared
/// layout's eight directions) make two pairs of opposite directions, too few to hold
/// one out at a time, so the hand balance splits each pair's repetitions into two groups
/// of three and fits the odd parts of the groups' means (`hand_signals::odd_groups`).
/// Fitted on the raw responses (before, with their even terms), seed 1003's 0.725 kg
/// handle came out at 0.568 kg with a gain of 0.26; on the single odd parts at 0.632
/// kg, 0.37: the arm's motor noise moves the handle, so it is in the regressors as well
/// as the target, and only averaging takes it down. On the groups: 0.731 kg, 0.74. Over
/// seeds 1000–1019, 19 of 20 named, each within 9 % (gains 0.59–0.83; README, "Pulses in
/// four directions"). A gain of 0.6 is asked.
#[test]
fn cardinal_pulses_are_fitted_on_groups_of_repetitions() {
    let design = Design::cardinal();
    let (_, d) = run_design("none", 2000, &design);
    assert_finds_nothing(&d, "seed 2000");
    assert_eq!(d.hand_repetition_groups, Some(2));
    let (_, d) = check_design("handle-mass", 1003, &design, 0.6);
    assert_eq!((d.hand_units, d.hand_test_units), (4, Some(12)));
}

/// Centre-out reaches ([`Design::centre_out`]: the shared layout's 32 reaches to three
/// goals 0.18 m away at 45°, 90° and 135°, each goal with one pulse in each of the eight
/// directions). The hand balance's reference for a pulse must be its own goal's
/// unperturbed reaches: the mean of every reach, or of the reaches crossing the same
/// line, moves elsewhere. `reach_groups` finds the three goals from the recorded
/// positions alone, every pulse gets a reference, and nothing is named on seed 2000; a
/// grip (seed 1000, 5.93 kN/m) is found within 20 % with a held-out gain of at least
/// 0.75.
#[test]
fn centre_out_reaches_are_referenced_to_their_own_goal() {
    check_three_goals(&Design::centre_out());
}

/// Centre-out reaches out and back in one trial (`Design::back_after_s`: 0.25 s at the
/// goal, then back to the start in the reach's 3 s, as a task that logs the return
/// does). A trial's first and last samples both lie at the start, so a reach taken from
/// the one to the other is no reach: every trial fell to none, and the hand balance
/// took the three goals' reaches as one reference (seed 2000: baseline NRMSE 0.125,
/// against 0.077 with each goal's own). `reach_groups` takes the way to the farthest
/// point: every trial is in its goal's reach, all 24 pulses are referenced, nothing is
/// named on seed 2000, and seed 1000's grip (5.93 kN/m) is found within 20 % with a
/// held-out gain of at least 0.75 (5.94 kN/m, 0.84), as on reaches one way.
#[test]
fn reaches_out_and_back_are_referenced_to_their_way_out() {
    check_three_goals(&Design {
        back_after_s: Some(0.25),
        ..Design::centre_out()
    });
}

/// The three goals' sessions of `design` (centre-out, one way or out and back): nothing
/// named on seed 2000 with three reaches, every pulse referenced and the goals found
/// ([`assert_reaches_are_the_goals`]); seed 1000's grip within 20 % with a held-out
/// gain of at least 0.75 (0.84 on both layouts), with three reaches.
fn check_three_goals(design: &Design) {
    let tmp = tempfile::tempdir().unwrap();
    let (g, d) = generate_and_diagnose("none", 2000, design, &tmp.path().join("out")).unwrap();
    assert_finds_nothing(&d, "seed 2000");
    assert_eq!(d.hand_reaches, Some(3));
    assert_eq!(d.hand_trials_used, 24);
    assert_reaches_are_the_goals(&g.dir);
    let (_, d) = check_design("grip-compliance", 1000, design, 0.75);
    assert_eq!(d.hand_reaches, Some(3));
}

/// Asserts that `reach_groups` puts every trial of the session in `dir` in a reach,
/// and finds each of [`CENTRE_OUT_M`]'s goals (from the start `[0, −0.125]` m) as the
/// direction of one, within 3° (end points scatter by a few mm over 0.18 m).
fn assert_reaches_are_the_goals(dir: &std::path::Path) {
    let s = Session::read(dir).unwrap();
    let (of_trial, directions) = reach_groups(&s);
    assert!(of_trial.iter().all(Option::is_some), "{of_trial:?}");
    assert_eq!(directions.len(), CENTRE_OUT_M.len(), "{directions:?}");
    for goal in CENTRE_OUT_M {
        let want = (goal[1] + 0.125).atan2(goal[0]);
        let near = directions
            .iter()
            .any(|u| (u[1].atan2(u[0]) - want).abs() < 3f64.to_radians());
        assert!(near, "goal {goal:?} not among {directions:?}");
    }
}

/// A subject whose arm is heavier than the tables the diagnosis takes it from (every
/// segment's mass and moment of inertia 15 % more; a manifest cannot say so) is not a
/// cause. On the shared layout's long pulses it reads as a heavier handle (0.18 kg on
/// seed 2000 before the rival) or, once the handle is held to the rival, as structure
/// outside the catalog. A heavier handle must now also beat an arm within ±20 % of the
/// tables (`SubjectArm`), and the hand's library is given that arm: nothing is named,
/// nothing is reported as `hand_unexplained`, the rival is what rejected the mass, and
/// its scale is the subject's to 0.04 (measured within 0.016 on seeds 2000–2003 at
/// ×0.85 and ×1.15, the least-squares fit of a correct model).
#[test]
fn an_arm_heavier_than_the_tables_is_not_a_heavier_handle() {
    let design = Design {
        arm_inertia_scale: 1.15,
        ..Design::SHARED
    };
    let (_, d) = run_design("none", 2000, &design);
    assert_finds_nothing(&d, "seed 2000");
    assert_told_from_the_arm(&d, "handle-mass", "seed 2000");
    let fitted = d.hand_arm_inertia_scale.unwrap();
    assert!((fitted - 1.15).abs() < 0.04, "arm inertia ×{fitted:.3}");
}

/// On 1 s reaches (most reaching studies move that fast; the shared sessions take 3 s)
/// the reach's torque, and with it the muscles' activation-dependent impedance, swings
/// within the 0.3 s window after each pulse. The hand baseline's constant `D` and `K`
/// leave a misfit a heavier handle takes up: on the ideal rig without the arm's motor
/// noise, where nothing but that structure is left, seed 2001 named a handle of 0.39 kg.
/// The rival `SubjectArm` carries each joint's impedance following the torque the
/// reference holds there besides the arm's inertia, and a handle or a grip given the
/// same must beat it: nothing is named, and the handle's row says the subject's arm
/// explains it as well. (Not every quiet session: seeds 2002 and 2003 still name a
/// handle of 0.16 and 0.27 kg with a stiff grip beside it, as before; on the realistic
/// rig, with the arm's motor noise, 0 of 20 rehearsed sessions name one: README,
/// "Reaches much faster than 3 s".)
#[test]
fn fast_reaches_hiding_nothing_name_no_heavier_handle() {
    let design = Design {
        movement_s: Some(1.0),
        ..Design::QUIET
    };
    let seed = 2001;
    let (_, d) = run_design("none", seed, &design);
    assert!(d.causes.is_empty(), "seed {seed}: named {:?}", d.causes);
    assert_told_from_the_arm(&d, "handle-mass", &format!("seed {seed}"));
}

/// Asserts that a session hiding nothing (`what` names it) has no cause named and no
/// structure reported outside the catalog on the hand balance.
fn assert_finds_nothing(d: &Diagnosis, what: &str) {
    assert!(d.causes.is_empty(), "{what}: named {:?}", d.causes);
    assert!(
        d.hand_unexplained.is_none(),
        "{what}: reported {:?}",
        d.hand_unexplained
    );
}

/// Asserts that candidate `name`'s row was rejected as not told from the subject's arm
/// (the rival `SubjectArm`).
fn assert_told_from_the_arm(d: &Diagnosis, name: &str, what: &str) {
    let row = d.ranking.iter().find(|r| r.name == name).unwrap();
    assert!(
        row.rejected
            .iter()
            .any(|w| w.contains("not told from the subject's arm")),
        "{what}: {name} {:?}",
        row.rejected
    );
}

/// The arm's inertia follows the manifest's `body_mass_kg` (segment masses and moments
/// of inertia in proportion, `ArmParams::with_body_mass`): a subject 15 % heavier
/// than the tables' 69 kg, whose manifest says so (79.35 kg), fits the arm at ×1.00
/// (to 0.04), where the same session without the body mass fits it at ×1.15.
#[test]
fn the_arms_inertia_follows_the_body_mass() {
    let tmp = tempfile::tempdir().unwrap();
    let design = Design {
        arm_inertia_scale: 1.15,
        ..Design::SHARED
    };
    let g = generate_design("none", 2000, &design, &tmp.path().join("out")).unwrap();
    let fitted = |dir: &std::path::Path| {
        let s = Session::read(dir).unwrap();
        let d = diagnose(&s, &DiagnoseOptions::default()).unwrap().diagnosis;
        assert!(d.causes.is_empty(), "named {:?}", d.causes);
        d.hand_arm_inertia_scale.unwrap()
    };
    let without = fitted(&g.dir);
    let manifest = g.dir.join("session.toml");
    let text = std::fs::read_to_string(&manifest).unwrap();
    assert!(
        !text.contains("body_mass_kg"),
        "the generator wrote a body mass"
    );
    std::fs::write(
        &manifest,
        text.replacen("[subject]\n", "[subject]\nbody_mass_kg = 79.35\n", 1),
    )
    .unwrap();
    let with = fitted(&g.dir);
    assert!(
        (without - 1.15).abs() < 0.04,
        "without the body mass ×{without:.3}"
    );
    assert!((with - 1.0).abs() < 0.04, "with it ×{with:.3}");
}

/// The requirements in full (README § Requirements: named, each parameter within 20 %,
/// held-out gain at least 50 %) for a reflex, on a session laid out to measure one
/// ([`Design::reflex_study`]: 72 pulses of 50 ms, 30 N), under the arm's motor noise.
/// Seed 1000 is the sweep's first, not a chosen one: over the sweep's 20 realistic
/// sessions so laid out (the generator's nuisances on), 20 are named, 19 with both
/// parameters within 20 % and 19 reach a held-out gain of 50 % (0.48–0.75); all three
/// hold on 18 (with the references at the trial's pace; 16 before). On the shared layout (24 pulses of
/// 150 ms) the gain reaches 50 % on 1 of 20: see
/// `hidden_stretch_reflex_is_named_under_motor_noise`. The layout pins the delay: the
/// range of delays its folds cannot tell from the best holds the hidden one and lies
/// within ±20 % of the found one (34.5–36.5 ms for 35 here).
#[test]
fn hidden_stretch_reflex_is_found() {
    let (g, d) = check_design("stretch-reflex", 1000, &Design::reflex_study(), 0.5);
    let (range, found, hidden) = reflex_delay_range(&g, &d);
    assert!(
        (range[0]..=range[1]).contains(&hidden),
        "{range:?} for {hidden}"
    );
    assert!(range[1] - range[0] <= 0.4 * found, "{range:?} for {found}");
}

/// The named reflex's delay range (the delays the folds cannot tell from the best),
/// its found delay and the hidden one, ms.
fn reflex_delay_range(g: &Generated, d: &Diagnosis) -> ([f64; 2], f64, f64) {
    let c = d
        .causes
        .iter()
        .find(|c| c.name.name() == "stretch-reflex")
        .expect("a reflex named");
    println!("delay range {:?}", c.parameter_range);
    (
        c.parameter_range["delay_ms"],
        c.parameters["delay_ms"],
        g.hidden.parameters["delay_ms"],
    )
}

/// The reflex study's more numerous, sharper pulses give the replicate test more power;
/// a session so laid out that hides nothing must still name nothing (seed 1000).
#[test]
fn reflex_study_hiding_nothing_names_nothing() {
    check_design("none", 1000, &Design::reflex_study(), 0.5);
}

/// A reflex study's session hiding nothing whose hand balance a weak reflex fits
/// (seed 1002 of the sweep: 41 N s/m at 21 ms, t 3.4 on the repetitions, a held-out gain
/// of 11 %, above the reflex's 25 N s/m floor). Such a reflex makes at most 0.15 N in
/// one pulse's response, below the rig's 0.25 N force resolution, where the reflexes
/// the generator hides (100–250 N s/m) make 0.5–0.8 N: it is rejected as immaterial and
/// nothing is named.
#[test]
fn a_reflex_study_hiding_nothing_names_no_weak_reflex() {
    let (_, d) = run_design("none", 1002, &Design::reflex_study());
    assert!(d.causes.is_empty(), "named {:?}", d.causes);
    let reflex = d
        .ranking
        .iter()
        .find(|r| r.name == "stretch-reflex")
        .unwrap();
    println!("{:?} {:?}", reflex.parameters, reflex.rejected);
    assert!(
        reflex
            .rejected
            .iter()
            .any(|w| w.contains("the reflex makes at most")),
        "{:?}",
        reflex.rejected
    );
}

/// A human-side cause's report: `diagnosis.md` with the cause's figure, the held-out
/// response in newtons and weighted as the hand balance judges it (where its held-out
/// gain is measured), and the ranking, each a non-empty PNG the report links.
#[test]
fn hand_cause_report_has_the_force_and_the_weighted_response() {
    let tmp = tempfile::tempdir().unwrap();
    let g = generate_design(
        "grip-compliance",
        21,
        &Design::SHARED,
        &tmp.path().join("out"),
    )
    .unwrap();
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

/// On the shared layout (24 pulses of 150 ms) under the arm's motor noise and the rig's
/// nuisances, the reflex is named (20 of 20 on sweep seeds 1000–1019) but its delay and
/// gain trade along a ridge: the pulses are too long to tell `g` from `δ`, and what the
/// layout measures is, to first order, the inertia-like term `g δ S Δa` (module docs of
/// the hand balance). Over those seeds the delay came out 0.54–1.29 of the hidden one and
/// the gain 0.83–1.91, short delays with high gains, while `g δ` stayed within 0.90–1.41
/// of the hidden product. So this session (delay 24 ms for 33, gain 293 for 201: a
/// product 1.06 of the truth) is held to what the layout can tell: `g δ` within 0.8–1.5
/// of the hidden one, and a held-out gain of at least 25 % (0.40 here; 0.11–0.54 on the
/// sweep seeds). It also guards the feedback shape's muscle weights: with every muscle
/// at weight 1 this session's delay came out at the grid's 50 ms edge, which is not
/// named. The requirements in full (README § Requirements) are
/// `hidden_stretch_reflex_is_found`'s, on a session laid out to measure a reflex.
/// The held-out gain is bounded by the arm's motor noise; of the baseline's excess over
/// the noise floor read from the repetitions the reflex removes 0.81 here (0.47–1.11,
/// 18 of 20 at least half, over the sweep's seeds), and at least half is asserted: the
/// ridge's parameters explain the responses about as well as the hidden ones would, so
/// what the layout lacks is what tells them apart, not a law the model misses.
#[test]
fn hidden_stretch_reflex_is_named_under_motor_noise() {
    let (g, d) = check_within("stretch-reflex", 24, &Design::SHARED, 0.25, &|_| {
        (0.0, f64::INFINITY)
    });
    let product = |p: &std::collections::BTreeMap<String, f64>| {
        p.get("gain").copied().unwrap_or(f64::NAN) * p.get("delay_ms").copied().unwrap_or(f64::NAN)
    };
    let ratio = product(&d.parameters) / product(&g.hidden.parameters);
    assert!((0.8..=1.5).contains(&ratio), "g δ found / hidden {ratio}");
    assert_share_above_floor(&d, 0.5);
    // And the diagnosis says so: the delays its folds cannot tell from the best hold
    // the hidden one and span more than ±20 % of the found one (12.5–42.5 ms here).
    let (range, found, hidden) = reflex_delay_range(&g, &d);
    assert!(
        (range[0]..=range[1]).contains(&hidden),
        "{range:?} for {hidden}"
    );
    assert!(range[1] - range[0] > 0.4 * found, "{range:?} for {found}");
}

/// Without the arm's motor noise the hand balance's model must account for a reflex by
/// itself: both parameters within 20 % and a held-out gain of at least half (generator
/// seeds 1, 2, 3, 5: delays 26/23, 31/33, 27/27, 22/19 ms, gains 17 % low to 1 % high,
/// held-out gains 0.71–0.82; seed 2 is asserted). A session hiding nothing, equally
/// quiet, names nothing: with the floor gone (hand baseline NRMSE 0.009), any
/// structural error of the baseline would show as a cause.
#[test]
fn noise_free_reflex_is_found_and_nothing_else() {
    let (g, d) = run_design("stretch-reflex", 2, &Design::QUIET);
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
    // The same gain in joint units: `g Σ w_m r_m r_mᵀ` over the arm's six muscles
    // (Selen et al.'s moment arms; the biarticular pair, without tone, at half weight),
    // to rounding.
    let arms = rigtwin_arm::muscles::MuscleParams::default().moment_arms_m;
    let w = [1.0, 1.0, 1.0, 1.0, 0.5, 0.5];
    let joint = |i: usize, j: usize| -> f64 {
        d.parameters["gain"]
            * arms
                .iter()
                .zip(w)
                .map(|(r, w)| w * r[i] * r[j])
                .sum::<f64>()
    };
    for (key, want) in [
        ("joint_damping_ss_n_m_s_per_rad", joint(0, 0)),
        ("joint_damping_se_n_m_s_per_rad", joint(0, 1)),
        ("joint_damping_ee_n_m_s_per_rad", joint(1, 1)),
    ] {
        let got = d.parameters[key];
        assert!(
            (got - want).abs() <= 1e-9 * want.abs(),
            "{key}: {got} vs {want}"
        );
    }
    // At the hand it is a damping: symmetric, positive definite, tens of N s/m for a
    // gain of a few hundred (the muscles' own endpoint damping is of that order too).
    let (xx, xy, yy) = (
        d.parameters["endpoint_damping_xx_n_s_per_m"],
        d.parameters["endpoint_damping_xy_n_s_per_m"],
        d.parameters["endpoint_damping_yy_n_s_per_m"],
    );
    assert!(xx > 0.0 && yy > 0.0 && xx * yy > xy * xy, "{xx} {xy} {yy}");
    let (_, d) = run_design("none", 2, &Design::QUIET);
    assert_eq!(d.cause, "none", "{:?}", d.parameters);
}

/// The hand balance's floor on a session hiding nothing is the arm's motor noise,
/// which averages over the pulses: the same subject (seed 1000, the sweep's first) with
/// 72 pulses instead of 24 must lower the weighted hand baseline's held-out NRMSE by
/// about `√(24/72)` = 0.58. What does not average (the balance's own structural floor,
/// 0.009 without motor noise, and the unperturbed reference shared by all pulses)
/// raises the ratio, what a longer session adds (more drift of the sensor and of the
/// subject's impedance) too; measured 0.56 here (0.058 and 0.032), so 0.45–0.80 is
/// asserted; outside it the floor would not be the pulses' noise (the per-response
/// offsets, [`rigtwin_diagnose::RESPONSE_OFFSET_COLUMNS`], take up the reference mismatch
/// of a few trials; `hil/docs/notes/2026-12-03-hand-balance-settings.md`). And more pulses, which give the replicate test more power, must
/// not make it name a cause that is not there. The noise floor the diagnosis reads from
/// the repetitions' spread (`hand_noise_floor_nrmse`) must be what the baseline leaves
/// where nothing is hidden: measured 0.96 and 1.10 of it here (0.064 and 0.031), 0.96 to
/// 1.17 over the sweep's 20 seeds hiding nothing; 0.9–1.25 is asserted. A floor well
/// above the baseline would count misfit as noise, one well below would not be the
/// noise (the unit test `the_noise_floor_is_the_averaged_units_noise_not_the_misfit`
/// checks it against the noise itself).
#[test]
fn more_pulses_lower_the_hand_noise_floor() {
    let (_, few) = run("none", 1000);
    let (_, many) = run_design("none", 1000, &Design::with_pulses(9));
    let (a, b) = (
        few.hand_baseline_nrmse.unwrap(),
        many.hand_baseline_nrmse.unwrap(),
    );
    eprintln!(
        "hand baseline NRMSE: 24 pulses {a:.4}, 72 pulses {b:.4}, ratio {:.3}",
        b / a
    );
    assert_eq!(few.cause, "none", "{:?}", few.parameters);
    assert_eq!(many.cause, "none", "{:?}", many.parameters);
    assert!((0.45..=0.80).contains(&(b / a)), "ratio {}", b / a);
    // The floor read from the repetitions' spread is the noise alone, so a baseline that
    // misses little beyond it sits on it.
    for (what, d) in [("24 pulses", &few), ("72 pulses", &many)] {
        let floor = d
            .hand_noise_floor_nrmse
            .expect("repetitions of opposite pulses");
        let ratio = d.hand_baseline_nrmse.unwrap() / floor;
        eprintln!("{what}: noise floor {floor:.4}, baseline at {ratio:.3}× it");
        assert!(
            (0.9..=1.25).contains(&ratio),
            "{what}: baseline at {ratio}× the floor"
        );
    }
}

/// How a session hiding two effects was diagnosed: whether exactly the hidden effects
/// were named, and whether each one's parameters are within 20 % of the hidden ones.
fn judge_pair(g: &Generated, d: &Diagnosis) -> (bool, bool) {
    let mut hidden: Vec<&str> = g.hidden.each.iter().map(|(n, _)| n.as_str()).collect();
    let mut named: Vec<&str> = d.causes.iter().map(|c| c.name.name()).collect();
    hidden.sort_unstable();
    named.sort_unstable();
    let within = g.hidden.each.iter().all(|(name, params)| {
        d.causes
            .iter()
            .find(|c| c.name.name() == *name)
            .is_some_and(|c| {
                params.iter().all(|(k, t)| {
                    c.parameters
                        .get(k)
                        .is_some_and(|v| (v - t).abs() <= 0.2 * t.abs())
                })
            })
    });
    (hidden == named, within)
}

fn check_pair(effect: &str, seed: u64) {
    check_pair_in(effect, seed, &Design::SHARED);
}

fn check_pair_in(effect: &str, seed: u64, design: &Design) {
    let (g, d) = run_design(effect, seed, design);
    eprintln!("hidden {:?}", g.hidden.each);
    for c in &d.causes {
        eprintln!(
            "named  {} ({}, gain {:.3}, given {:?}) {:?}",
            c.name, c.balance, c.gain, c.given, c.parameters
        );
    }
    for r in &d.conditional {
        eprintln!(
            "  {:<16} given {:?} gain {:>7.3} t {:>7.1} {:?}",
            r.name, r.given, r.gain, r.t_statistic, r.rejected
        );
    }
    let (named, within) = judge_pair(&g, &d);
    assert!(named, "named {:?}", d.causes);
    assert!(within, "parameters off");
}

/// Friction and cogging on one rig (both cart balance): forward selection names the
/// stronger, then the other given it, each with its parameters within 20 % of the
/// hidden ones from the joint fit.
#[test]
fn friction_and_ripple_are_both_named() {
    check_pair("rail-friction+force-ripple", 31);
}

/// A rig with friction and a heavier handle, one effect on each balance.
#[test]
fn friction_and_a_heavier_handle_are_both_named() {
    check_pair("rail-friction+handle-mass", 32);
}

/// Friction under a delayed actuator: the delay makes the stiff position loop ring at
/// ~200 Hz (10–15 N in the command on this seed, the sweep's first), which dithers
/// the cart's velocity by as much as the friction's knee; friction is fitted on the
/// whole velocity (the fast part from the forces, matched to the encoder), and what it
/// leaves shows the delay.
#[test]
fn friction_and_delay_are_both_named() {
    check_pair("rail-friction+actuation-delay", 3000);
}

/// A delayed actuator with a rotated sensor: both reshape the balance (the command's
/// timing, the force's frame), so the joint model carries both.
#[test]
fn delay_and_rotation_are_both_named() {
    check_pair("actuation-delay+sensor-rotation", 33);
}

/// A rotated sensor turns the hand's force too: with the rotation named on the cart
/// balance, the hand balance judges the reading turned back, and finds the handle.
#[test]
fn rotation_and_a_heavier_handle_are_both_named() {
    check_pair("sensor-rotation+handle-mass", 34);
}

/// A heavier handle behind a soft grip, both on the hand balance: the grip is named
/// first, then the mass given it, with the grip's spring carrying the mass's inertial
/// force too (the load searched for the least error of the joint fit,
/// `hil/diagnose/src/hand_joint.rs`); both within 20 % on this seed.
#[test]
fn a_soft_grip_and_a_heavier_handle_are_both_named() {
    check_pair("grip-compliance+handle-mass", 37);
}

/// The same pair on a reflex study's brief pulses, where the two mask each other: a
/// soft grip lowers the response's inertia and a heavier handle raises it, so alone
/// each fits worse than the baseline and neither is named; fitted as a pair, each
/// passes given the other and both are named, within 20 % on this seed.
#[test]
fn a_soft_grip_and_a_heavier_handle_that_mask_each_other_are_named_together() {
    check_pair_in("grip-compliance+handle-mass", 3001, &Design::reflex_study());
}

/// A stiff grip (5734 N/m) behind a heavier handle (0.45 kg) on a reflex study's
/// pulses: the grip's stiffness and the load its spring carries trade along a ridge, and
/// a search for the load that stopped after two rounds left the pair at 5000 N/m and
/// 0.50 kg, with a misfit a third round named as a 42 ms reflex. Settled to its fixed
/// point, the pair is named alone, both within 20 %.
#[test]
fn a_stiff_grip_behind_a_heavier_handle_is_named_without_a_third_cause() {
    check_pair_in("grip-compliance+handle-mass", 3003, &Design::reflex_study());
}

/// A soft grip (2554 N/m) behind a heavy handle (0.99 kg) on a reflex study's pulses:
/// searched by alternating steps from no load, the grip first took the grid's stiffest
/// value and the load then the grid's 3 kg, and ten rounds walked the ridge between them
/// only to 5.6 kN/m and 1.27 kg. The load's profile starts the search in the valley, and
/// the pair is named alone, both within 20 %.
#[test]
fn a_soft_grip_behind_a_heavy_handle_is_found_from_the_load_profile() {
    check_pair_in("grip-compliance+handle-mass", 3012, &Design::reflex_study());
}

/// A heavier handle on a subject with a stretch reflex, both on the hand balance, in a
/// reflex study's layout: forward selection there names the stronger, then the other
/// given it, from one joint fit (the mass on the handle's acceleration, the reflex on
/// the hand's velocity). On the shared layout's long pulses the reflex given the mass
/// is mostly too weak to name (README "Several effects at once"). Only naming both is
/// asserted.
#[test]
fn a_reflex_and_a_heavier_handle_are_both_named() {
    let (g, d) = run_design("stretch-reflex+handle-mass", 35, &Design::reflex_study());
    let (named, _) = judge_pair(&g, &d);
    assert!(named, "hidden {:?}, named {:?}", g.hidden.each, d.causes);
}

/// How a session hiding an effect outside the catalog was diagnosed: whether no catalog
/// cause was named, and whether `unexplained` holds the term of the hidden law with
/// its coefficient on the y axis (the reach's, where the carts travel 10 cm; the x cart
/// moves only under the pulses) within 20 %: a cable spring's stiffness as the position
/// term's `−k`, a low-pass's time constant `1/(2π f_c)` as the force-rate term's. A late
/// feedback is the subject's, so it is looked for in the hand balance's `unexplained`:
/// the late-feedback term with its delay within 20 % of the subject's (its gain comes
/// out high, README).
fn judge_outside(g: &Generated, d: &Diagnosis) -> (bool, bool) {
    let p = &g.hidden.parameters;
    if g.hidden.effect == "late-feedback" {
        let want = p["feedback_delay_ms"];
        let found = d.hand_unexplained.as_ref().is_some_and(|u| {
            u.terms.iter().any(|t| {
                t.term == "late-feedback"
                    && t.settings
                        .get("delay_ms")
                        .is_some_and(|ms| (ms - want).abs() <= 0.2 * want)
            })
        });
        return (d.causes.is_empty(), found);
    }
    let (term, want) = if g.hidden.effect == "cable-spring" {
        ("position", -p["stiffness_y_n_per_m"])
    } else {
        (
            "force-rate",
            1.0 / (std::f64::consts::TAU * p["lowpass_hz"]),
        )
    };
    let found = d.unexplained.as_ref().is_some_and(|u| {
        u.terms
            .iter()
            .any(|t| t.term == term && (t.coefficient_y - want).abs() <= 0.2 * want.abs())
    });
    (d.causes.is_empty(), found)
}

fn check_outside(effect: &str, seed: u64, design: &Design) {
    let (g, d) = run_design(effect, seed, design);
    eprintln!("hidden {} {:?}", g.hidden.effect, g.hidden.parameters);
    eprintln!("named {:?}", d.causes);
    eprintln!("unexplained {:?}", d.unexplained);
    eprintln!("hand unexplained {:?}", d.hand_unexplained);
    for r in d.ranking.iter().take(3) {
        eprintln!("  {:<16} gain {:>7.3} {:?}", r.name, r.gain, r.rejected);
    }
    let (none, found) = judge_outside(&g, &d);
    assert!(none, "a catalog cause was named: {:?}", d.causes);
    assert!(found, "the hidden law is not in unexplained");
}

/// A cable carrier pulls each cart towards a rest position, a law the catalog lacks:
/// the diagnosis names no catalog effect (not a long-pitch "ripple") and reports the residual as unexplained, `force ≈ −k (y − y₀)` with `k`
/// within 20 %.
#[test]
fn a_cable_spring_is_unexplained_not_a_ripple() {
    check_outside("cable-spring", 4000, &Design::SHARED);
}

/// A force sensor read through a low-pass: no catalog effect (not a grip compliance: the
/// hand balance reads the same sensor with the lag undone), and
/// `unexplained` holds `τ · dF/dt` with `τ` within 20 % of the filter's.
#[test]
fn a_sensor_lag_is_unexplained_not_a_grip() {
    check_outside("sensor-lowpass", 4001, &Design::SHARED);
}

/// A subject whose feedback acts at 110–160 ms instead of the model's 60 ms, in a
/// session with 9 pulses per angle (the shared layout's 3 leave the late feedback's
/// gain under the test's noise, README): no catalog effect (not a reflex, not a mass),
/// and the hand balance's `unexplained` holds the late-feedback term with its delay
/// within 20 % of the subject's.
#[test]
fn a_late_feedback_is_unexplained_not_a_reflex() {
    check_outside("late-feedback", 4001, &Design::with_pulses(9));
}

/// Sessions hiding an effect outside the catalog: `SWEEP_SEEDS` (default 20) per effect
/// of [`OUT_OF_CATALOG`] (or `SWEEP_EFFECTS`), seeds 4000 on, on [`sweep_design`]'s
/// layout; prints how often no catalog cause was named, how often either balance
/// reported `unexplained` structure and how often it held the hidden law within 20 %.
#[test]
#[ignore = "about 40 sessions; run with --ignored to measure out-of-catalog sessions"]
fn sweep_out_of_catalog() {
    let seeds = sweep_seeds(20);
    let design = sweep_design();
    let only = sweep_effects();
    let mut rows = Vec::new();
    for effect in OUT_OF_CATALOG {
        if !only.includes(effect) {
            continue;
        }
        let (mut none, mut found, mut any) = (0, 0, 0);
        for seed in 0..seeds {
            let (g, d) = run_design(effect, 4000 + seed, &design);
            let (n, f) = judge_outside(&g, &d);
            none += usize::from(n);
            found += usize::from(f);
            any += usize::from(d.unexplained_structures().next().is_some());
            eprintln!(
                "{effect} seed {seed}: hidden {:?}; named {:?}; unexplained {:?}; hand {:?}",
                g.hidden.parameters,
                d.causes.iter().map(|c| &c.name).collect::<Vec<_>>(),
                d.unexplained.as_ref().map(|u| &u.hint),
                d.hand_unexplained.as_ref().map(|u| &u.hint)
            );
        }
        rows.push(format!(
            "{effect:<16} no catalog cause {none}/{seeds}, unexplained {any}/{seeds}, the hidden law within 20 % {found}/{seeds}"
        ));
    }
    for r in rows {
        println!("{r}");
    }
}

/// Sessions hiding two effects at once: `SWEEP_SEEDS` (default 20) per pair of
/// [`PAIRS`] (or `SWEEP_EFFECTS`), seeds 3000 on, on [`sweep_design`]'s layout; prints
/// per pair how often exactly both were named and how often both parameter sets were
/// within 20 %.
#[test]
#[ignore = "about 100 sessions; run with --ignored to measure two-effect detection"]
fn sweep_two_effects() {
    let seeds = sweep_seeds(20);
    let only = sweep_effects();
    let design = sweep_design();
    let mut rows = Vec::new();
    for pair in PAIRS {
        if !only.includes(pair) {
            continue;
        }
        let (mut named, mut within) = (0, 0);
        for seed in 0..seeds {
            let (g, d) = run_design(pair, 3000 + seed, &design);
            let (n, w) = judge_pair(&g, &d);
            named += usize::from(n);
            within += usize::from(n && w);
            eprintln!(
                "{pair} seed {seed}: hidden {:?}; named {:?}",
                g.hidden.each,
                d.causes
                    .iter()
                    .map(|c| (&c.name, c.gain, &c.parameters))
                    .collect::<Vec<_>>()
            );
        }
        rows.push(format!(
            "{pair:<34} both named {named}/{seeds}, and both within 20 % {within}/{seeds}"
        ));
    }
    for r in rows {
        println!("{r}");
    }
}

/// The false-alarm rate: `SWEEP_SEEDS` (default 60) realistic sessions hiding nothing
/// (seeds 2000 on, on [`sweep_design`]'s layout), each diagnosed blind; prints every
/// named cause and either balance's `unexplained`, and the rate with its exact
/// one-sided 95 % upper bound, and asserts at most 5 %.
#[test]
#[ignore = "about 60 sessions; run with --ignored to measure the false-alarm rate"]
fn sweep_false_alarms() {
    let seeds = sweep_seeds(60);
    let mut alarms = 0;
    let mut unexplained = 0;
    let design = sweep_design();
    for seed in 0..seeds {
        let (_, d) = run_design("none", 2000 + seed, &design);
        if d.unexplained_structures().next().is_some() {
            unexplained += 1;
        }
        for u in d.unexplained_structures() {
            eprintln!(
                "seed {}: unexplained ({}) {}",
                2000 + seed,
                u.balance,
                u.hint
            );
        }
        if !d.causes.is_empty() {
            alarms += 1;
            eprintln!("seed {}: named {:?}", 2000 + seed, d.causes);
        }
    }
    // Exact binomial upper bound for `alarms` in `seeds`: p with P(X ≤ alarms) = 0.05.
    let n = seeds as f64;
    let cdf = |p: f64| {
        (0..=alarms)
            .map(|k: u64| {
                let k = k as f64;
                let ln_c = (1..=alarms.min(seeds))
                    .take(k as usize)
                    .fold(0.0, |a, i| a + ((n - i as f64 + 1.0) / i as f64).ln());
                (ln_c + k * p.ln() + (n - k) * (1.0 - p).ln()).exp()
            })
            .sum::<f64>()
    };
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) > 0.05 { lo = mid } else { hi = mid }
    }
    println!(
        "false alarms: {alarms} of {seeds} sessions hiding nothing ({:.1} %, 95 % upper bound {:.1} %); unexplained reported in {unexplained}",
        100.0 * alarms as f64 / n,
        100.0 * hi
    );
    assert!(alarms as f64 <= 0.05 * n, "{alarms} of {seeds}");
}

/// The rows a sweep runs: those `SWEEP_EFFECTS` names (comma-separated), or all.
struct SweepEffects(Option<Vec<String>>);

impl SweepEffects {
    /// Whether the row `name` runs.
    fn includes(&self, name: &str) -> bool {
        self.0.as_ref().is_none_or(|o| o.iter().any(|e| e == name))
    }
}

fn sweep_effects() -> SweepEffects {
    SweepEffects(
        std::env::var("SWEEP_EFFECTS")
            .ok()
            .map(|v| v.split(',').map(str::to_string).collect()),
    )
}

/// Sessions per row of a sweep: `SWEEP_SEEDS`, or `default`.
fn sweep_seeds(default: u64) -> u64 {
    std::env::var("SWEEP_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The sweeps' session layout: the shared one, or with `SWEEP_REPETITIONS=9` 9 pulses
/// per angle (72 in 96 reaches) and with `SWEEP_PULSE=0.05,30` pulses of 50 ms at 30 N
/// (both: `Design::reflex_study`).
fn sweep_design() -> Design {
    let mut design = std::env::var("SWEEP_REPETITIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|n: &u32| *n > 0)
        .map_or(Design::SHARED, Design::with_pulses);
    if let Ok(v) = std::env::var("SWEEP_PULSE") {
        design.pulse = Some(parse_pulse(&v).unwrap_or_else(|e| panic!("SWEEP_PULSE: {e}")));
    }
    design
}

/// Whether every hidden parameter a cause's searched range covers lies in it (widened
/// by 1 % for a hidden value between two grid points); `None` when the cause has no
/// range of a hidden parameter.
fn range_covers(
    ranges: &std::collections::BTreeMap<String, [f64; 2]>,
    hidden: &std::collections::BTreeMap<String, f64>,
) -> Option<bool> {
    ranges
        .iter()
        .filter_map(|(k, [lo, hi])| {
            let t = hidden.get(k)?;
            let pad = 0.01 * t.abs();
            Some((lo - pad..=hi + pad).contains(t))
        })
        .reduce(|a, b| a && b)
}

#[test]
#[ignore = "about 160 sessions; run with --ignored to print the confusion matrix"]
fn sweep_confusion_matrix() {
    // `SWEEP_SEEDS=5 SWEEP_EFFECTS=none,handle-mass` runs a smaller sweep.
    let seeds = sweep_seeds(20);
    let design = sweep_design();
    let only = sweep_effects();
    let mut names: Vec<&str> = EFFECTS.to_vec();
    let mut matrix = vec![vec![0usize; EFFECTS.len() + 1]; EFFECTS.len()];
    let mut within = vec![0usize; EFFECTS.len()];
    // Sessions where more causes were named than the one hidden (forward selection's
    // false alarms).
    let mut extra = vec![0usize; EFFECTS.len()];
    // Sessions where structure outside the catalog was reported.
    let mut unexplained = vec![0usize; EFFECTS.len()];
    // Sessions whose named cause has a searched parameter's range, and those where the
    // hidden value lies in it.
    let mut ranged = vec![(0usize, 0usize); EFFECTS.len()];
    for (i, effect) in EFFECTS.iter().enumerate() {
        if !only.includes(effect) {
            continue;
        }
        for seed in 0..seeds {
            let (g, d) = run_design(effect, 1000 + seed, &design);
            let j = EFFECTS
                .iter()
                .position(|e| *e == d.cause)
                .unwrap_or(EFFECTS.len());
            matrix[i][j] += 1;
            extra[i] += usize::from(d.causes.len() > usize::from(i > 0));
            unexplained[i] += usize::from(d.unexplained_structures().next().is_some());
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
            if let Some(c) = d.causes.iter().find(|c| c.name.name() == *effect) {
                let covered = range_covers(&c.parameter_range, &g.hidden.parameters);
                if let Some(inside) = covered {
                    ranged[i].0 += 1;
                    ranged[i].1 += usize::from(inside);
                }
                eprintln!("    ranges {:?}", c.parameter_range);
            }
        }
    }
    names.push("other");
    println!(
        "hidden \\ found   {}",
        names.iter().map(|n| format!("{n:>16}")).collect::<String>()
    );
    for (i, row) in matrix.iter().enumerate() {
        println!(
            "{:<16} {}   params within 20 %: {}/{seeds}, a further cause named: {}/{seeds}, unexplained: {}/{seeds}, hidden in the searched range: {}/{}",
            EFFECTS[i],
            row.iter().map(|c| format!("{c:>16}")).collect::<String>(),
            within[i],
            extra[i],
            unexplained[i],
            ranged[i].1,
            ranged[i].0
        );
    }
}
