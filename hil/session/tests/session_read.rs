//! Reading the shared measured-style sessions (`shared/recordings/`), checked against
//! the CSV and TOML text.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use rigtwin_session::{Amplitude, PerturbationKind, Session, Source, TrialKind};

fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/recordings")
        .join(name)
}

#[test]
fn example_none_reads_with_values_from_its_text() {
    let s = Session::read(shared("example-none")).unwrap();
    let m = &s.manifest;
    assert_eq!(m.source, Source::Rig);
    assert_eq!(m.rate_hz, 1000.0);
    assert_eq!(m.created, "2026-07-07T15:45:00Z");
    assert_eq!(m.device.kind, "admittance");
    assert_eq!(m.device.mass_kg, [5.0, 5.0]);
    assert_eq!(m.device.damping_n_s_per_m, [15.0, 15.0]);
    assert_eq!(m.device.handle_mass_kg, Some(0.35));
    assert_eq!(m.device.workspace_half_width_m, Some(0.15));
    assert_eq!(m.subject.id, "P75");
    assert_eq!(m.subject.shoulder_m, [0.0, -0.425]);
    assert_eq!(m.subject.upper_arm_m, Some(0.33));
    assert_eq!(m.subject.forearm_m, Some(0.34));
    assert_eq!(m.subject.body_mass_kg, Some(69.0));
    assert!(m.subject.extra.is_empty());
    assert_eq!(m.trials.len(), 32);
    assert_eq!(s.trials.len(), 32);

    // [[trial]] id = 1: perturbed at 300 deg, onset 1.588375 s.
    let (e, t) = s.trial(1).unwrap();
    assert_eq!(e.file, "trials/0001.csv");
    assert_eq!(
        e.sha256.map(|d| d.to_string()).as_deref(),
        Some("0a3c6a084ae5f2377612b5014ec3a87376b2e2c3a701c0155bdc37aedb6d27dc")
    );
    assert_eq!(e.kind, TrialKind::Reach);
    assert_eq!(e.start_m, Some([0.0, -0.125]));
    assert_eq!(e.goal_m, Some([0.0, 0.125]));
    let p = e.perturbation.as_ref().unwrap();
    assert_eq!(p.kind, PerturbationKind::ForcePulse);
    assert_eq!(p.onset_s, 1.588375);
    assert_eq!(p.duration_s, 0.15);
    assert_eq!(p.amplitude, Amplitude::ForceN(15.0));
    assert_eq!(p.angle_deg, 300.0);
    // Trial 2 is unperturbed.
    assert!(s.trial(2).unwrap().0.perturbation.is_none());

    // trials/0001.csv: 3500 rows at 1 kHz, all 13 columns.
    assert_eq!(t.len(), 3500);
    // Row 1: 0,0,-0.125,-0.023,0.001,0,0,0,0,0,-0.125,-0.06,0.01
    assert_eq!(t.t_s[0], 0.0);
    assert_eq!(t.y_m[0], -0.125);
    assert_eq!(t.fx_n[0], -0.023);
    assert_eq!(t.fy_n[0], 0.001);
    assert_eq!(t.cmd_fx_n.as_ref().unwrap()[0], -0.06);
    // Last row: 3.499,-0.000092,0.125268,-0.008,-0.329,0,0,0,0.004,-0.000092,0.12527,-0.29,0.06
    assert_eq!(t.t_s[3499], 3.499);
    assert_eq!(t.x_m[3499], -0.000092);
    assert_eq!(t.y_m[3499], 0.125268);
    assert_eq!(t.fy_n[3499], -0.329);
    assert_eq!(t.vy_m_per_s.as_ref().unwrap()[3499], 0.004);
    assert_eq!(t.ref_y_m.as_ref().unwrap()[3499], 0.12527);
    assert_eq!(t.cmd_fy_n.as_ref().unwrap()[3499], 0.06);
    assert!(t.extra.is_empty());
    for (_, t) in s.iter() {
        assert!(t.vx_m_per_s.is_some() && t.ref_x_m.is_some() && t.cmd_fx_n.is_some());
    }
}

#[test]
fn example_none_has_the_protocol_of_its_readme() {
    // README: 24 perturbed trials, angles 30..330 three times each, 8 unperturbed,
    // 3.5 s each.
    let s = Session::read(shared("example-none")).unwrap();
    let mut angles: Vec<f64> = s
        .manifest
        .trials
        .iter()
        .filter_map(|e| e.perturbation.as_ref())
        .map(|p| p.angle_deg)
        .collect();
    angles.sort_by(f64::total_cmp);
    let expected: Vec<f64> = [30.0, 60.0, 120.0, 150.0, 210.0, 240.0, 300.0, 330.0]
        .iter()
        .flat_map(|a| [*a; 3])
        .collect();
    assert_eq!(angles, expected);
    for (e, t) in s.iter() {
        assert_eq!(t.len(), 3500, "trial {}", e.id);
        // The perturbation column is zero before the onset and non-zero during it.
        if let Some(p) = &e.perturbation {
            let before = t
                .t_s
                .iter()
                .position(|&ts| ts >= p.onset_s - 0.002)
                .unwrap();
            assert!(
                t.pert_fx_n[..before]
                    .iter()
                    .chain(&t.pert_fy_n[..before])
                    .all(|&f| f == 0.0)
            );
            let peak = t
                .pert_fx_n
                .iter()
                .zip(&t.pert_fy_n)
                .map(|(x, y)| x.hypot(*y))
                .fold(0.0, f64::max);
            assert!(
                (peak - 15.0).abs() < 0.5,
                "trial {} pulse peak {peak} N",
                e.id
            );
        } else {
            assert!(t.pert_fx_n.iter().chain(&t.pert_fy_n).all(|&f| f == 0.0));
        }
    }
}

#[test]
fn example_friction_reads_lazily_trial_by_trial() {
    let reader = Session::open(shared("example-friction")).unwrap();
    assert_eq!(reader.manifest().trials.len(), 32);
    let mut n = 0;
    for r in reader.trials() {
        let (e, t) = r.unwrap();
        assert_eq!(t.len(), 3500, "trial {}", e.id);
        assert!((t.end_s() - 3.499).abs() < 1e-12);
        n += 1;
    }
    assert_eq!(n, 32);
    assert!(reader.read_trial(32).is_none());
    let whole = Session::read(shared("example-friction")).unwrap();
    assert_eq!(reader.read_trial(5).unwrap().unwrap(), whole.trials[5]);
}
