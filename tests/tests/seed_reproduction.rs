//! Seed reproduction: the default reach-perturb rehearsal (000_*, the whole protocol:
//! 100 reaches, 24 perturbed, default subject, seed 1) against the seed's figures.
//!
//! - Max deviations within the 150 ms window, mean over the perturbed trials, inside the
//!   seed's bands 6.1 ± 1.8 mm (x) and 5.9 ± 1.7 mm (y) (section 4.2).
//! - NRMSE of the estimated variational dynamics against the simulated truth (each
//!   perturbed reach re-run unperturbed on the same random streams), mean over trials,
//!   below the seed's bounds 5 % (Δx, Δẋ), 7.5 % (Δẍ), 15 % (Δu_ext) (section 4.3).
//! - The estimated D and K of the default subject within one std of Table 1 for every
//!   element; the default subject's damping times are calibrated for this (see
//!   `hil/protocols/reach-perturb.toml`).
//! - K22, the stiffness along the movement, within 10 % of the arm's intrinsic ground
//!   truth: the axis best excited by the pulses, where feedback and filtering bias least.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin::protocol::Protocol;
use rigtwin::report::{self, seed000};

#[test]
fn default_reach_perturb_rehearsal_reproduces_the_seed() {
    let p = Protocol::builtin("reach-perturb").unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let r = rigtwin_tests::rehearse_one(&p, p.seed, &tmp.path().join("r"), 2, None).unwrap();
    let rep = report::build(&r);
    eprintln!("{}", report::summary_text(&rep));

    assert_eq!(rep.trials_per_subject, 100);
    assert_eq!(rep.perturbed_per_subject, 24);
    assert!(rep.safety.trips.is_empty(), "{:?}", rep.safety.trips);
    assert!(rep.workspace.suffices);

    let [dx, dy] = rep.deviation_mm.unwrap();
    assert_eq!(dx.n, 24);
    let (mx, sx) = seed000::DEV_X_MM;
    let (my, sy) = seed000::DEV_Y_MM;
    assert!(
        (dx.mean - mx).abs() <= sx,
        "x deviation {dx:?} outside {mx} ± {sx} mm"
    );
    assert!(
        (dy.mean - my).abs() <= sy,
        "y deviation {dy:?} outside {my} ± {sy} mm"
    );

    let n = rep.nrmse.unwrap();
    let b = seed000::NRMSE_BOUNDS;
    for (name, (mean, _max), bound) in [
        ("Δx", n.position, b[0]),
        ("Δẋ", n.velocity, b[1]),
        ("Δẍ", n.acceleration, b[2]),
        ("Δu_ext", n.force, b[3]),
    ] {
        assert!(mean < bound, "NRMSE {name}: mean {mean} >= {bound}");
    }

    assert_eq!(rep.parameters.len(), 7);
    for row in &rep.parameters {
        let (m, s) = row.table1;
        assert!(
            (row.estimate.mean - m).abs() <= s,
            "{} = {:.2} {} outside Table 1 {m} ± {s}",
            row.name,
            row.estimate.mean,
            row.unit
        );
    }
    let k22 = rep.parameters.iter().find(|r| r.name == "K22").unwrap();
    assert!(
        k22.bias.mean.abs() <= 0.10 * k22.truth.mean,
        "K22 estimate {:.1} vs intrinsic truth {:.1} N/m",
        k22.estimate.mean,
        k22.truth.mean
    );
}
