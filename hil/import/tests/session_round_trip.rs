//! A session out and back in: the shared `example-none` session (32 trials of a planar
//! rig, 1 kHz, force pulses) is exported by Python — as a lab's logger would hold it,
//! one continuous log with a trigger channel, positions in millimetres — to a MATLAB
//! level-5 file (scipy, compressed) and to a continuous CSV, then imported with a map
//! that cuts at the trigger and reads each trial's pulse from the perturbation channel.
//! Every sample must come back, and every pulse's metadata within what the sampled
//! channel can tell.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::PathBuf;

use rigtwin_session::{Amplitude, Session};

fn shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/recordings/example-none")
}

const MAP: &str = r#"
created = "2026-07-07T15:45:00Z"
[time]
var = "rig.t"
[channels]
x_m = { var = "rig.x", scale = 1e-3, unit = "mm" }
y_m = { var = "rig.y", scale = 1e-3, unit = "mm" }
fx_n = { var = "rig.fx" }
fy_n = { var = "rig.fy" }
pert_fx_n = { var = "rig.pfx" }
pert_fy_n = { var = "rig.pfy" }
cmd_fx_n = { var = "rig.ux" }
cmd_fy_n = { var = "rig.uy" }
[device]
kind = "admittance"
mass_kg = [5.0, 5.0]
damping_n_s_per_m = [15.0, 15.0]
handle_mass_kg = 0.35
[subject]
id = "P75"
shoulder_m = [0.0, -0.425]
[trials]
cut = "marker"
marker = { var = "rig.trigger", above = 0.5 }
[perturbation]
from = "channel"
above_n = 0.5
"#;

/// Python: the session's trials laid end to end, as `rig.*` in a `.mat` and as the
/// columns of a CSV (the CSV's names are the struct's fields).
const EXPORT: &str = r#"
import csv, glob, os, sys
import numpy as np, scipy.io
src, out = sys.argv[1], sys.argv[2]
cols = {k: [] for k in ['x','y','fx','fy','pfx','pfy','ux','uy','trigger']}
for f in sorted(glob.glob(os.path.join(src, 'trials', '*.csv'))):
    rows = [r for r in csv.DictReader(open(f))]
    for i, r in enumerate(rows):
        cols['x'].append(float(r['x_m']) * 1e3); cols['y'].append(float(r['y_m']) * 1e3)
        cols['fx'].append(float(r['fx_n'])); cols['fy'].append(float(r['fy_n']))
        cols['pfx'].append(float(r['pert_fx_n'])); cols['pfy'].append(float(r['pert_fy_n']))
        cols['ux'].append(float(r['cmd_fx_n'])); cols['uy'].append(float(r['cmd_fy_n']))
        cols['trigger'].append(1 if i == 0 else 0)
n = len(cols['x'])
rig = {k: np.array(v, dtype=np.uint8 if k == 'trigger' else float).reshape(-1, 1) for k, v in cols.items()}
rig['t'] = (np.arange(n) / 1000.0).reshape(-1, 1)
scipy.io.savemat(os.path.join(out, 'rig.mat'), {'rig': rig}, format='5', do_compression=True)
with open(os.path.join(out, 'rig.csv'), 'w') as f:
    names = ['t'] + list(cols)
    f.write(','.join('rig.' + k for k in names) + '\n')
    for i in range(n):
        f.write(','.join(repr(float(rig[k][i, 0])) for k in names) + '\n')
"#;

#[test]
fn a_session_exported_to_mat_and_csv_imports_back_sample_for_sample() {
    let dir = tempfile::tempdir().unwrap();
    let script = format!(
        "import sys; sys.argv = ['x', {:?}, {:?}]\n{EXPORT}",
        shared().display().to_string(),
        dir.path().display().to_string()
    );
    common::python(&script);
    let map = common::write(dir.path(), "map.toml", MAP);
    let original = Session::read(shared()).unwrap();
    for log in ["rig.mat", "rig.csv"] {
        let out = dir.path().join(format!("{log}.session"));
        let imported = rigtwin_import::import(&[dir.path().join(log)], &map, &out).unwrap();
        assert_eq!(
            imported.trials(),
            original.trials.len(),
            "{log}: {imported}"
        );
        let back = Session::read(&out).unwrap();
        for ((e0, t0), (e1, t1)) in original.iter().zip(back.iter()) {
            assert_eq!(t0.len(), t1.len(), "{log}: trial {} length", e0.id);
            // Positions went to millimetres and back (×1e3, ×1e-3): a few ulps of a
            // 0.1 m coordinate; the CSV's text is Python's shortest round-trip repr.
            for (a, b) in t0.x_m.iter().zip(&t1.x_m).chain(t0.y_m.iter().zip(&t1.y_m)) {
                assert!((a - b).abs() <= 1e-15, "{log}: trial {}: {a} vs {b}", e0.id);
            }
            // Forces are copied, bit for bit.
            assert_eq!(t0.fx_n, t1.fx_n, "{log}: trial {}", e0.id);
            assert_eq!(t0.fy_n, t1.fy_n, "{log}: trial {}", e0.id);
            assert_eq!(t0.pert_fx_n, t1.pert_fx_n, "{log}: trial {}", e0.id);
            assert_eq!(t0.cmd_fy_n, t1.cmd_fy_n, "{log}: trial {}", e0.id);
            let (p0, p1) = (e0.perturbation.as_ref(), e1.perturbation.as_ref());
            assert_eq!(
                p0.is_some(),
                p1.is_some(),
                "{log}: trial {} perturbed?",
                e0.id
            );
            if let (Some(p0), Some(p1)) = (p0, p1) {
                // The channel is sampled at 1 kHz and the pulse is smooth: its 0.5 N
                // threshold is crossed some milliseconds after the true onset and left as
                // long before its end; the sampled peak is within a sample of the
                // pulse's; the direction is the force's own.
                let Amplitude::ForceN(a0) = p0.amplitude else {
                    panic!()
                };
                let Amplitude::ForceN(a1) = p1.amplitude else {
                    panic!()
                };
                assert!(
                    p1.onset_s >= p0.onset_s && p1.onset_s - p0.onset_s < 0.02,
                    "{log}: trial {} onset {} for {}",
                    e0.id,
                    p1.onset_s,
                    p0.onset_s
                );
                assert!(
                    (p1.onset_s + p1.duration_s) <= p0.onset_s + p0.duration_s + 1e-3
                        && p1.duration_s > p0.duration_s - 0.04,
                    "{log}: trial {} duration {} for {}",
                    e0.id,
                    p1.duration_s,
                    p0.duration_s
                );
                assert!(
                    (a1 - a0).abs() < 0.01 * a0,
                    "{log}: amplitude {a1} for {a0}"
                );
                let turn = (p1.angle_deg - p0.angle_deg).rem_euclid(360.0);
                assert!(
                    turn.min(360.0 - turn) < 0.5,
                    "{log}: trial {} angle {} for {}",
                    e0.id,
                    p1.angle_deg,
                    p0.angle_deg
                );
            }
        }
    }
}
