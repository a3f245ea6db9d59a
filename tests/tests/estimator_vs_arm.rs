//! Börner involuntary-impedance estimator against the simulated arm's intrinsic
//! impedance (issue 4, part 4).
//!
//! The nominal subject of the built-in reach-perturb protocol reaches with its delayed
//! feedback set to 200 ms, longer than T_est = 150 ms: inside the estimation window the
//! arm answers the force pulse with its intrinsic (muscle) impedance only, so the
//! simulated ground truth ("truth (intrinsic)") is the right reference. A reduced
//! session (24 trials, all perturbed: 8 angles × 3) is simulated once and estimated in
//! both variational modes, Seed and Consistent; the table prints estimate, truth, bias
//! and jackknife standard error per parameter. The assertions are facts measured on
//! this seed, each with its measured value and margin in a comment.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin::protocol::{EstimateMode, Protocol};
use rigtwin::report::{self, ParamRow};

fn row<'a>(rows: &'a [ParamRow], name: &str) -> &'a ParamRow {
    rows.iter().find(|r| r.name == name).unwrap()
}

#[test]
fn borner_estimator_vs_intrinsic_arm_with_feedback_delay_beyond_t_est() {
    let mut p = Protocol::builtin("reach-perturb").unwrap();
    p.subjects.arm.feedback.delay_ms = 200.0;
    assert!(p.subjects.arm.feedback.delay_ms * 1e-3 > p.estimate.t_est_s);
    let mut reach = p.reach();
    reach.trials = u32::try_from(reach.perturbed()).unwrap();
    p.reach = Some(reach);

    let tmp = tempfile::tempdir().unwrap();
    let mut r = rigtwin_tests::rehearse_one(&p, p.seed, &tmp.path().join("r"), 4, None).unwrap();

    let mut reports = Vec::new();
    for mode in [EstimateMode::Seed, EstimateMode::Consistent] {
        r.protocol.estimate.mode = mode;
        let rep = report::build(&r);
        assert_eq!(rep.trials_per_subject, 24);
        assert_eq!(rep.perturbed_per_subject, 24);
        assert!(rep.safety.trips.is_empty(), "{:?}", rep.safety.trips);
        assert_eq!(rep.parameters.len(), 7);
        eprintln!("mode {mode:?} (24 perturbed reaches, feedback delay 200 ms, T_est 150 ms)");
        eprintln!(
            "{:>4} {:>10} {:>10} {:>10} {:>8} {:>8}  unit",
            "par", "estimate", "truth", "bias", "bias %", "se"
        );
        for row in &rep.parameters {
            eprintln!(
                "{:>4} {:>10.2} {:>10.2} {:>10.2} {:>8.1} {:>8.2}  {}",
                row.name,
                row.estimate.mean,
                row.truth.mean,
                row.bias.mean,
                100.0 * row.bias.mean / row.truth.mean.abs(),
                row.std_err,
                row.unit
            );
        }
        reports.push(rep);
    }
    let seed = &reports[0].parameters;
    let cons = &reports[1].parameters;
    let bias = |rows: &[ParamRow], n: &str| row(rows, n).bias.mean;
    let rel = |rows: &[ParamRow], n: &str| {
        let r = row(rows, n);
        r.bias.mean / r.truth.mean.abs()
    };

    // Seed mode underestimates K11 (across the movement): measured −91.3 N/m of a
    // 129.3 N/m truth (−71 %), jackknife se 8.2 N/m. Seed mode high-passes (1 Hz) the
    // jerk and integrates it with zero constants, but regresses on the raw pulse force
    // (eq. 21): the slow, stiffness-carrying part of Δx is attenuated while the force is
    // not, which reads as too little stiffness. 60 N/m leaves ~30 N/m (almost 4 se).
    let k11_seed = bias(seed, "K11");
    assert!(
        k11_seed < -60.0,
        "Seed K11 bias {k11_seed:.1} N/m, expected < −60"
    );

    // Consistent mode (the same filter on force and kinematics) halves that bias:
    // measured −41.4 N/m vs −91.3 N/m (ratio 0.45); bound 0.6.
    let k11_cons = bias(cons, "K11");
    assert!(
        k11_cons.abs() < 0.6 * k11_seed.abs(),
        "Consistent K11 bias {k11_cons:.1} not below 0.6 × Seed's {k11_seed:.1} N/m"
    );

    // Damping: Seed mode underestimates the diagonal dampings (D11 −30 %, D22 −25 %
    // measured, se 0.7 and 2.0 N s/m); bound −15 %.
    for n in ["D11", "D22"] {
        let b = rel(seed, n);
        assert!(b < -0.15, "Seed {n} relative bias {b:.3}, expected < −0.15");
    }
    // Consistent mode gets every damping element within 20 % of the intrinsic truth
    // (measured D11 −12.7 %, D12 +3.3 %, D21 +9.9 %, D22 −9.8 %; relative se ≤ 11 %
    // for D21, ≤ 6 % for the rest) and closer than Seed mode for every element
    // (measured |bias| 2.38/0.26/0.79/1.10 vs 5.64/1.24/1.58/2.84 N s/m).
    for n in ["D11", "D12", "D21", "D22"] {
        let b = rel(cons, n);
        assert!(
            b.abs() < 0.20,
            "Consistent {n} relative bias {b:.3}, expected < 0.20"
        );
        assert!(
            bias(cons, n).abs() < bias(seed, n).abs(),
            "Consistent {n} bias {:.2} not smaller than Seed's {:.2}",
            bias(cons, n),
            bias(seed, n)
        );
    }

    // K12 (coupling) in Consistent mode: measured +5.4 % (se 4.9 N/m = 6.5 %); bound 20 %.
    // (Seed mode's K12 is within 0.3 % here but with se 15 %: not asserted.)
    let k12 = rel(cons, "K12");
    assert!(k12.abs() < 0.20, "Consistent K12 relative bias {k12:.3}");

    // K22 (along the movement, best excited): within 25 % in both modes, Seed −12.0 %
    // (se 6.8 %), Consistent +15.9 % (se 3.6 %). Consistent overestimates it: measured
    // +48.5 N/m, se 11.1 N/m; bound +20 N/m.
    for (mode, rows) in [("Seed", seed), ("Consistent", cons)] {
        let b = rel(rows, "K22");
        assert!(b.abs() < 0.25, "{mode} K22 relative bias {b:.3}");
    }
    let k22_cons = bias(cons, "K22");
    assert!(
        k22_cons > 20.0,
        "Consistent K22 bias {k22_cons:.1} N/m, expected > +20"
    );
}
