//! What a person reads: the ranking table of `rigtwin diagnose` and `diagnosis.md`
//! with its figures (the plot that shows the cause, a held-out trial measured vs
//! baseline vs extended, the ranking).

use super::effect::EffectKind;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::candidate::{Baseline, Candidate as _};
use super::diagnose::{Analysis, CandidateFit, Diagnosis, Ranked};
use super::error::DiscrepancyError;
use super::hand::{HandBaseline, HandFit, HandJudgement, hand_fit_rows};
use super::plots::{Drawn, Figure, Series, Style};

fn fmt_params(
    r: &std::collections::BTreeMap<String, f64>,
    se: &std::collections::BTreeMap<String, f64>,
) -> String {
    r.iter()
        .map(|(k, v)| match se.get(k) {
            Some(s) if s.is_finite() => format!("{k} {} ± {}", sig(*v), sig(*s)),
            _ => format!("{k} {}", sig(*v)),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Four significant digits, plain for ordinary magnitudes.
/// `W` of the hand balance's weighting as `[[w11, w12], [w21, w22]]`.
fn weighting_matrix(w: &std::collections::BTreeMap<String, f64>) -> String {
    let g = |k: &str| w.get(k).copied().unwrap_or(f64::NAN);
    format!(
        "[[{:.3}, {:.3}], [{:.3}, {:.3}]]",
        g("w11"),
        g("w12"),
        g("w21"),
        g("w22")
    )
}

fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if (-3..5).contains(&mag) {
        let decimals = (3 - mag).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

/// What a balance's baseline at held-out NRMSE `b` over a noise floor `f` allows: no
/// model gains more than `1 − f/b` on the session, since the floor is what none
/// removes. Empty where the baseline is not above the floor.
fn gain_bound(b: f64, f: f64) -> String {
    if b > f && f > 0.0 {
        format!(
            ", so no model gains more than {:.0} % on this session",
            100.0 * (1.0 - f / b)
        )
    } else {
        String::new()
    }
}

/// The masses and the nuisances' parameters of a nominal fit (`Diagnosis::baseline`
/// or `model`), in the fit's axes: "moving mass x 3.196 kg, offset x 1.52 N".
fn nominal_text(p: &std::collections::BTreeMap<String, f64>) -> String {
    let mut parts = Vec::new();
    for axis in ["x", "y"] {
        if let Some(m) = p.get(&format!("moving_mass_{axis}_kg")) {
            parts.push(format!("moving mass {axis} {m:.3} kg"));
        }
        if let Some(g) = p.get(&format!("motor_force_gain_{axis}")) {
            parts.push(format!("motor force gain {axis} {g:.3}"));
        }
        if let Some(o) = p.get(&format!("offset_{axis}_n")) {
            parts.push(format!("offset {axis} {o:.3} N"));
        }
    }
    parts.join(", ")
}

/// The ranking table printed by `rigtwin diagnose`.
#[must_use]
pub fn table(d: &Diagnosis) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "session {}  ({} of {} trials with motor command, {} Hz, {} folds)",
        d.session, d.trials_used, d.trials_total, d.rate_hz, d.folds
    );
    if !d.cart_set_aside.is_empty() {
        let ids: Vec<String> = d
            .cart_set_aside
            .iter()
            .map(|a| a.trial.to_string())
            .collect();
        let _ = writeln!(
            out,
            "set aside  trial(s) {} from the cart balance as faults: the cart model cannot hold there, judged again without them (the evidence says how far)",
            ids.join(", ")
        );
    }
    if let Some(r) = d.repeated_frames.first() {
        let _ = writeln!(
            out,
            "repeated frames  {} taken out (a logger that wrote a frame twice), the first {} row {} (all in the evidence and `repeated_frames` of --json)",
            d.repeated_frames.len(),
            r.file,
            r.row
        );
    }
    if let Some(s) = d.slips.first() {
        let _ = writeln!(
            out,
            "lost samples  {} in {} run(s) put back (a logger that dropped frames and kept its clock), the first {} after row {} (all in the evidence and `slips` of --json)",
            d.slips.iter().map(|s| s.samples).sum::<usize>(),
            d.slips.len(),
            s.file,
            s.after_row
        );
    }
    if let Some(s) = d.skipped_readings.first() {
        let _ = writeln!(
            out,
            "skipped readings  {} (a position sensor on a clock faster than the log's), the position retimed to the log's rows, the first {} row {} (all in the evidence and `skipped_readings` of --json)",
            d.skipped_readings.len(),
            s.file,
            s.row
        );
    }
    if let Some(j) = d.encoder_jumps.first() {
        let _ = writeln!(
            out,
            "encoder jumps  {} levelled (a position that stepped once and stayed off: counts gained or lost), the first {} {} row {} by {:+.3} mm (all in the evidence and `encoder_jumps` of --json)",
            d.encoder_jumps.len(),
            j.file,
            j.channel,
            j.row,
            j.step_m * 1e3
        );
    }
    for h in &d.held {
        let caveat = h
            .timing_caveat()
            .map_or_else(String::new, |c| format!("; {c}"));
        let _ = writeln!(
            out,
            "held  {} read every {} rows ({:.0} Hz) in {} of {} trials: each reading repeated until the next, the repeated rows filled between the readings before the fits (`held` in --json){caveat}",
            h.channel, h.rows_per_reading, h.reading_rate_hz, h.trials, h.judged
        );
    }
    if let Some(g) = d.glitches.first() {
        let _ = writeln!(
            out,
            "glitches  {} sample(s) that no physics made (runs of one to three, stale runs of up to 20) bridged before the fits, the first {} {} at {:.4} s (all in the evidence and `glitches` of --json)",
            d.glitches.len(),
            g.file,
            g.channel,
            g.t_s
        );
    }
    if let (Some(b), false) = (
        d.cart_baseline_nrmse,
        d.baseline.contains_key("moving_mass_x_kg") && d.baseline.contains_key("moving_mass_y_kg"),
    ) {
        // A rig of one axis, or without a force sensor: its axis's mass and offset.
        let _ = writeln!(
            out,
            "cart balance  {}, latency {:.3} ms, held-out NRMSE {:.4}",
            nominal_text(&d.baseline),
            d.baseline.get("latency_ms").copied().unwrap_or(f64::NAN),
            b
        );
        if d.model != d.baseline && !d.model.is_empty() {
            let _ = writeln!(out, "with the causes  {}", nominal_text(&d.model));
        }
    } else if let Some(b) = d.cart_baseline_nrmse {
        let g = |k: &str| d.baseline.get(k).copied().unwrap_or(f64::NAN);
        let _ = writeln!(
            out,
            "cart balance  moving mass x {:.3} kg, y {:.3} kg, latency {:.3} ms, held-out NRMSE {:.4}",
            g("moving_mass_x_kg"),
            g("moving_mass_y_kg"),
            g("latency_ms"),
            b
        );
    }
    if let (Some(b), Some(f)) = (d.cart_baseline_nrmse, d.cart_noise_floor_nrmse) {
        let _ = writeln!(
            out,
            "cart noise floor  held-out NRMSE {f:.4} (the rig's noise under the named causes' model, from the rows where the carts stand still): the baseline is at {:.2}× it{}",
            b / f,
            gain_bound(b, f)
        );
    }
    if let Some(b) = d.hand_baseline_nrmse {
        let _ = writeln!(
            out,
            "hand balance  {} perturbed trials as {} responses{}, arm inertia from segment lengths and body mass{}, feedback delay {:.0} ms, rows whitened ({:.0} ms noise time, W {} from the {}), held-out NRMSE {:.4}",
            d.hand_trials_used,
            d.hand_units,
            match (d.hand_test_units, d.hand_repetition_groups) {
                (Some(n), None) =>
                    format!(" (odd parts of opposite pulses; t-test on {n} repetitions)"),
                (Some(n), Some(g)) => format!(
                    " (odd parts of opposite pulses, each pair's repetitions in {g} groups; t-test on {n} repetitions)"
                ),
                (None, _) => String::new(),
            } + &d
                .hand_reaches
                .map(|n| format!(" on {n} reaches, each with its own references"))
                .unwrap_or_default(),
            d.hand_arm_inertia_scale
                .map(|f| format!(" (×{f:.2} of it fits best given the named effects)"))
                .unwrap_or_default(),
            d.hand_baseline
                .get("feedback_delay_ms")
                .copied()
                .unwrap_or(f64::NAN),
            d.hand_weighting
                .get("noise_time_ms")
                .copied()
                .unwrap_or(f64::NAN),
            weighting_matrix(&d.hand_weighting),
            d.hand_weighting_source.as_deref().unwrap_or("time only"),
            b
        );
        if let Some(f) = d.hand_noise_floor_nrmse {
            let _ = writeln!(
                out,
                "hand noise floor  held-out NRMSE {f:.4} (the responses' noise under the named causes' model, from the repetitions' spread about their mean): the baseline is at {:.2}× it{}",
                b / f,
                gain_bound(b, f)
            );
        }
    }
    if !d.ranking.is_empty() {
        let _ = writeln!(out);
        let _ = writeln!(
            out,
            "{:<4} {:<16} {:<7} {:>8} {:>9} {:>8}  {:<8} parameters",
            "rank", "candidate", "balance", "gain %", "NRMSE", "t", "verdict"
        );
        for (i, r) in d.ranking.iter().enumerate() {
            // A cause named only given others (forward selection) is "jointly" here,
            // where it stands alone; its CAUSE line is in the rounds below.
            let alone = d
                .causes
                .iter()
                .any(|c| Some(c.name) == r.kind && c.given.is_empty());
            let later = d.causes.iter().any(|c| Some(c.name) == r.kind);
            let verdict = if later && !alone && !r.significant {
                "jointly"
            } else {
                verdict(r, later)
            };
            let _ = writeln!(
                out,
                "{:<4} {:<16} {:<7} {:>8.1} {:>9.4} {:>8.1}  {:<8} {}",
                i + 1,
                r.name,
                r.balance,
                100.0 * r.gain,
                r.extended_nrmse,
                r.t_statistic,
                verdict,
                fmt_params(&r.parameters, &r.parameter_se)
            );
        }
        if d.ranking.iter().any(|r| {
            !r.significant
                && d.causes
                    .iter()
                    .any(|c| Some(c.name) == r.kind && !c.given.is_empty())
        }) {
            let _ = writeln!(
                out,
                "(jointly: nothing alone, named given the causes before it; see the forward selection)"
            );
        }
        for r in d
            .ranking
            .iter()
            .filter(|r| !r.rejected.is_empty() && r.gain > 0.0)
        {
            let _ = writeln!(out, "{:<21} {}", r.name, r.rejected.join("; "));
        }
        let _ = writeln!(out);
    }
    if !d.conditional.is_empty() {
        let _ = writeln!(
            out,
            "forward selection on each balance: each candidate fitted jointly with the causes named before it on its balance, its gain against them alone"
        );
        for r in &d.conditional {
            let verdict = verdict(
                r,
                d.causes
                    .iter()
                    .any(|c| Some(c.name) == r.kind && c.given == r.given),
            );
            let _ = writeln!(
                out,
                "  given {:<30} {:<16} {:<7} {:>8.1} {:>9.4} {:>8.1}  {:<8} {}",
                r.given.join(" + "),
                r.name,
                r.balance,
                100.0 * r.gain,
                r.extended_nrmse,
                r.t_statistic,
                verdict,
                fmt_params(&r.parameters, &r.parameter_se)
            );
        }
        let _ = writeln!(out);
    }
    if d.causes.len() > 1 {
        let _ = writeln!(
            out,
            "causes: {}",
            d.causes
                .iter()
                .map(|c| format!(
                    "{} ({} balance, held-out gain {:.1} %{}: {})",
                    c.name,
                    c.balance,
                    100.0 * c.gain,
                    if c.given.is_empty() {
                        String::new()
                    } else {
                        format!(" given {}", c.given.join(" + "))
                    },
                    fmt_params(&c.parameters, &c.parameter_se)
                ))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    let _ = writeln!(
        out,
        "cause: {}{}",
        d.cause,
        match (d.gain, &d.runner_up) {
            (Some(g), Some(r)) if d.cause != "none" =>
                format!("  held-out gain {:.1} %  (runner-up {r})", 100.0 * g),
            (_, Some(r)) => format!("  (best candidate {r} stays below the threshold)"),
            _ => String::new(),
        }
    );
    if !d.parameters.is_empty() {
        let _ = writeln!(
            out,
            "parameters: {}",
            fmt_params(&d.parameters, &d.parameter_se)
        );
    }
    for c in &d.causes {
        if let Some(text) = convention(c.name) {
            let _ = writeln!(out, "convention: {}: {text}", c.name);
        }
        for (k, why) in &c.undetermined {
            let _ = writeln!(out, "not determined: {}: {k}: {why}", c.name);
        }
    }
    for c in &d.causes {
        for (k, [lo, hi]) in &c.parameter_range {
            let v = c.parameters.get(k).copied().unwrap_or(f64::NAN);
            let line = format!(
                "the folds cannot tell {} to {} from it{}",
                sig(*lo),
                sig(*hi),
                // Beyond ±20 % of the value: what a lab comparing subjects needs.
                if hi - lo > 0.4 * v.abs() {
                    " (wider than ±20 % of it: this session does not pin it)"
                } else {
                    ""
                }
            );
            let _ = writeln!(out, "range: {}: {k} {}: {line}", c.name, sig(v));
        }
    }
    for c in &d.causes {
        if let Some(share) = c.share_above_floor {
            let _ = writeln!(
                out,
                "above the floor: {}: removes {:.0} % of what {} leaves above the {} balance's noise floor (its held-out gain of {:.1} % is bounded by that noise)",
                c.name,
                100.0 * share,
                if c.given.is_empty() {
                    "the baseline".to_string()
                } else {
                    format!("the model with {}", c.given.join(" + "))
                },
                c.balance,
                100.0 * c.gain
            );
        }
    }
    for u in d.unexplained_structures() {
        let mut corr: Vec<(&String, &f64)> = u.correlations.iter().collect();
        corr.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        let _ = writeln!(
            out,
            "unexplained ({} balance{}): held-out gain {:.1} % from laws outside the catalog: {}; the residual correlates with {}; its power by band: {}",
            u.balance,
            if u.given.is_empty() {
                String::new()
            } else {
                format!(", given {}", u.given.join(" + "))
            },
            100.0 * u.gain,
            u.hint,
            corr.iter()
                .map(|(k, r)| format!("{k} {r:+.2}"))
                .collect::<Vec<_>>()
                .join(", "),
            u.band_shares
                .iter()
                .map(|(k, v)| format!("{k} {:.0} %", 100.0 * v))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if let Some(t) = &d.threshold {
        let _ = writeln!(out, "rule: {}", t.rule);
    }
    for n in &d.not_judged {
        let _ = writeln!(out, "not judged: {:<16} {}", n.effect, n.reason);
    }
    out
}

/// A ranked row's verdict in the table: `CAUSE` when `named`, `also` when it passed
/// every test but another was named, `rejected` when it gained but failed a check.
fn verdict(r: &Ranked, named: bool) -> &'static str {
    if named {
        "CAUSE"
    } else if r.significant {
        "also"
    } else if r.t_statistic > 0.0 && r.gain > 0.0 && !r.rejected.is_empty() {
        "rejected"
    } else {
        "-"
    }
}

/// What a named effect's parameters mean where a sign, a frame or a unit could be read
/// two ways; printed under every cause that has one (`None` for the others).
#[must_use]
pub fn convention(kind: EffectKind) -> Option<&'static str> {
    match kind {
        EffectKind::SensorRotation => Some(
            "angle_deg is how far the reading is turned from the true force, counter-clockwise \
             positive: reading = R(angle_deg) · F, i.e. the sensor frame is yawed by −angle_deg; \
             the correction is R(−angle_deg) applied to the reading (the world's \
             sensor.rotation_deg has the same sign)",
        ),
        EffectKind::ForceRipple => Some(
            "the cogging amplitude_i · sin(2π q_i / pitch_m + phase_i_rad) is added to the motor \
             force of axis i at its cart's rail position q_i (m, rig frame); each axis has its \
             own magnet track, so its own amplitude and phase",
        ),
        EffectKind::StretchReflex => Some(
            "gain is the arm model's (N of muscle activation per m/s of muscle stretch velocity); \
             joint_damping_* is the joint damping it adds after delay_ms (N m s/rad: shoulder ss, \
             cross se, elbow ee), endpoint_damping_* the same at the hand at the pulse onsets \
             (N s/m, rig axes)",
        ),
        EffectKind::RailFriction
        | EffectKind::ActuationDelay
        | EffectKind::GripCompliance
        | EffectKind::HandleMass => None,
    }
}

/// The figure that shows the candidate `cf` at work.
fn cause_figure(a: &Analysis, cf: &CandidateFit) -> Result<Option<Figure>, DiscrepancyError> {
    let Some(base) = &a.baseline else {
        return Ok(None);
    };
    let c = cf.candidate.as_ref();
    let fit = &cf.fit;
    let (name, value) = c.setting(fit.setting);
    if c.effect_force(fit.setting, &fit.beta, 1, 0.0, 0.0)
        .is_some()
    {
        // Against the state: velocity for friction, position of the long axis otherwise.
        let by_velocity = c.kind() == Some(EffectKind::RailFriction);
        let axes: Vec<usize> = if by_velocity { vec![0, 1] } else { vec![1] };
        let mut cloud = Vec::new();
        for sig in &a.signals {
            let r = Baseline.residual(sig, 0, &base.beta, a.latency_s)?;
            for &axis in &axes {
                let st = if by_velocity {
                    sig.at_rows(&sig.v[axis])
                } else {
                    sig.at_rows(&sig.q[axis])
                };
                cloud.extend(st.iter().zip(&r[axis]).map(|(s, r)| (*s, -r)));
            }
        }
        let step = (cloud.len() / 20_000).max(1);
        let dots: Vec<(f64, f64)> = cloud.iter().step_by(step).copied().collect();
        let (lo, hi) = cloud
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p.0), h.max(p.0))
            });
        let bins = 120;
        let mut sums = vec![(0.0, 0usize); bins];
        for (s, e) in &cloud {
            let b = (((s - lo) / (hi - lo).max(1e-12)) * bins as f64)
                .floor()
                .clamp(0.0, (bins - 1) as f64) as usize;
            sums[b].0 += e;
            sums[b].1 += 1;
        }
        let mean: Vec<(f64, f64)> = sums
            .iter()
            .enumerate()
            .filter(|(_, (_, n))| *n >= 5)
            .map(|(i, (s, n))| {
                (
                    lo + (i as f64 + 0.5) * (hi - lo) / bins as f64,
                    s / *n as f64,
                )
            })
            .collect();
        let model: Vec<(f64, f64)> = (0..=400)
            .filter_map(|i| {
                let s = lo + (hi - lo) * f64::from(i) / 400.0;
                let e = if by_velocity {
                    c.effect_force(fit.setting, &fit.beta, 1, 0.0, s)
                } else {
                    c.effect_force(fit.setting, &fit.beta, 1, s, 0.0)
                };
                e.map(|e| (s, e))
            })
            .collect();
        return Ok(Some(Figure {
            title: format!(
                "{}: unexplained cart force of the nominal balance",
                c.name()
            ),
            x_desc: if by_velocity {
                "cart velocity (m/s)".into()
            } else {
                "y cart position (m)".into()
            },
            y_desc: "m·a − u − F (N)".into(),
            series: vec![
                Series {
                    label: "samples".into(),
                    points: dots,
                    style: Style::Dots,
                    rgb: (120, 120, 120),
                },
                Series {
                    label: "bin means".into(),
                    points: mean,
                    style: Style::Line,
                    rgb: (30, 90, 200),
                },
                Series {
                    label: format!("fitted {}", c.name()),
                    points: model,
                    style: Style::Bold,
                    rgb: (210, 50, 40),
                },
            ],
            bars: Vec::new(),
            hline: None,
        }));
    }
    // A search over a timing or angle: NRMSE on all trials against the setting.
    let norm: f64 = fit.folds.iter().map(|f| f.test_norm_sq).sum();
    let curve: Vec<(f64, f64)> = fit
        .curve
        .iter()
        .enumerate()
        .map(|(s, sse)| (c.setting(s).1, (sse / norm).sqrt()))
        .collect();
    Ok(Some(search_figure(
        format!("{}: balance error against {name}", c.name()),
        "NRMSE of the balance, all trials",
        name,
        value,
        curve,
        ranked_range(&a.diagnosis, c.name()),
    )))
}

/// A held-out trial of fold 0 (a perturbed one if there is), y axis (or a one-axis rig's
/// axis): measured motor
/// command against what the baseline and the extended model say it must have been.
fn heldout_figure(a: &Analysis, cf: &CandidateFit) -> Result<Option<Figure>, DiscrepancyError> {
    let Some(folds) = &a.folds else {
        return Ok(None);
    };
    let held: Vec<usize> = (0..a.signals.len())
        .filter(|i| folds.of_trial.get(*i) == Some(&0))
        .collect();
    let Some(&ti) = held
        .iter()
        .find(|i| a.signals[**i].perturbed)
        .or(held.first())
    else {
        return Ok(None);
    };
    let sig = &a.signals[ti];
    let Some(h) = a.held_out_trial(ti)? else {
        return Ok(None);
    };
    // The y axis (it carries the reach on the planar rig), or the only axis a rig has.
    let axis = usize::from(sig.present(1));
    let t: Vec<f64> = sig.rows.iter().map(|i| *i as f64 / sig.rate_hz).collect();
    let line = |values: &[f64]| -> Vec<(f64, f64)> {
        t.iter().zip(values).map(|(t, v)| (*t, *v)).collect()
    };
    let model = |name: &str| {
        h.models
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, p)| &p[axis])
    };
    let (Some(rb), Some(re)) = (model("baseline"), model(cf.candidate.name())) else {
        return Ok(None);
    };
    Ok(Some(Figure {
        title: format!(
            "held-out trial {} ({} axis): motor command",
            sig.id,
            ["x", "y"][axis]
        ),
        x_desc: "time (s)".into(),
        y_desc: "motor force (N)".into(),
        series: vec![
            Series {
                label: "measured".into(),
                points: line(&h.command_n[axis]),
                style: Style::Bold,
                rgb: (40, 40, 40),
            },
            Series {
                label: "baseline".into(),
                points: line(rb),
                style: Style::Line,
                rgb: (30, 90, 200),
            },
            Series {
                label: format!("extended ({})", cf.candidate.name()),
                points: line(re),
                style: Style::Line,
                rgb: (210, 50, 40),
            },
        ],
        bars: Vec::new(),
        hline: None,
    }))
}

/// The figure of a human-side candidate: for `handle-mass` the hand balance's baseline
/// residual against the handle's acceleration (its slope is the unlisted mass), for the
/// others the search of the nonlinear parameter (reflex delay; grip stiffness at the
/// chosen damping time).
fn hand_cause_figure(h: &HandJudgement, hf: &HandFit, d: &Diagnosis) -> Figure {
    let c = hf.candidate.as_ref();
    let fit = &hf.fit;
    if c.kind() == Some(EffectKind::HandleMass) {
        let mut cloud = Vec::new();
        for r in &h.responses {
            let rows = hand_fit_rows(&HandBaseline, r, 0, &h.baseline.beta, h.fb_delay_s, None);
            for (k, (y, f, _)) in rows.iter().enumerate() {
                let (j, axis) = (r.rows[k / 2], k % 2);
                cloud.push((r.da[axis][j], y - f));
            }
        }
        let m = fit.beta.last().copied().unwrap_or(0.0);
        let (lo, hi) = cloud
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), p| {
                (l.min(p.0), u.max(p.0))
            });
        return Figure {
            title: format!(
                "handle-mass: hand balance residual against acceleration (slope {m:.3} kg)"
            ),
            x_desc: "handle acceleration Δa (m/s²)".into(),
            y_desc: "−ΔF − M_arm Δa − baseline fit (N)".into(),
            series: vec![
                Series {
                    label: "samples (both axes)".into(),
                    points: cloud,
                    style: Style::Dots,
                    rgb: (120, 120, 120),
                },
                Series {
                    label: format!("extra mass {m:.3} kg"),
                    points: vec![(lo, m * lo), (hi, m * hi)],
                    style: Style::Bold,
                    rgb: (210, 50, 40),
                },
            ],
            bars: Vec::new(),
            hline: None,
        };
    }
    let norm: f64 = fit.folds.iter().map(|f| f.test_norm_sq).sum();
    let curve: Vec<(f64, f64)> = fit
        .curve
        .iter()
        .enumerate()
        .filter(|(s, _)| c.on_the_line_of(*s, fit.setting))
        .map(|(s, sse)| (c.setting(s).1, (sse / norm).sqrt()))
        .collect();
    let (name, value) = c.setting(fit.setting);
    search_figure(
        format!("{}: hand balance error against {name}", c.name()),
        "NRMSE of the hand balance, all perturbed trials",
        name,
        value,
        curve,
        ranked_range(d, c.name()),
    )
}

/// The searched range of candidate `name`'s ranking row ([`Ranked::parameter_range`]).
fn ranked_range(d: &Diagnosis, name: &str) -> Option<[f64; 2]> {
    d.ranking
        .iter()
        .find(|r| r.name == name)
        .and_then(|r| r.parameter_range.values().next().copied())
}

/// The error of a search over a nonlinear parameter against its setting (`curve`), with
/// the fitted `value` of `name` marked by a vertical bar over the curve's range, and the
/// settings the folds cannot tell from the best (`range`) between two thin bars.
fn search_figure(
    title: String,
    y_desc: &str,
    name: &str,
    value: f64,
    curve: Vec<(f64, f64)>,
    range: Option<[f64; 2]>,
) -> Figure {
    let (y0, y1) = curve
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.1), h.max(p.1))
        });
    Figure {
        title,
        x_desc: name.replace('_', " "),
        y_desc: y_desc.into(),
        series: vec![
            Series {
                label: "search".into(),
                points: curve,
                style: Style::Line,
                rgb: (30, 90, 200),
            },
            Series {
                label: format!("fit {name} = {}", sig(value)),
                points: vec![(value, y0), (value, y1)],
                style: Style::Bold,
                rgb: (210, 50, 40),
            },
        ]
        .into_iter()
        .chain(range.into_iter().flat_map(|[lo, hi]| {
            [
                (format!("the folds cannot tell it from {}", sig(lo)), lo),
                (format!("… to {}", sig(hi)), hi),
            ]
            .map(|(label, x)| Series {
                label,
                points: vec![(x, y0), (x, y1)],
                style: Style::Line,
                rgb: (235, 140, 20),
            })
        }))
        .collect(),
        bars: Vec::new(),
        hline: None,
    }
}

/// A held-out unit of fold 0 (the odd response to a pair of opposite pulses, or a
/// direction's mean response), second axis: the hand's response force, measured vs
/// baseline vs extended (each fitted without it). `weighted`: as the balance judges it
/// ([`super::hand::Whitening`]: whitened in time, the second row of `W`), where the
/// held-out gain is measured; else in newtons along y.
fn hand_heldout_figure(h: &HandJudgement, hf: &HandFit, weighted: bool) -> Option<Figure> {
    let ti = (0..h.responses.len()).find(|i| h.folds.of_trial.get(*i) == Some(&0))?;
    let r = &h.responses[ti];
    let (bf, ef) = (h.baseline.folds.first()?, hf.fit.folds.first()?);
    let w = weighted.then_some(&h.whitening);
    let base = hand_fit_rows(&HandBaseline, r, 0, &bf.beta, h.fb_delay_s, w);
    let ext = hand_fit_rows(
        hf.candidate.as_ref(),
        r,
        ef.setting,
        &ef.beta,
        h.fb_delay_s,
        w,
    );
    // The weighted rows start one sample later.
    let first = usize::from(weighted);
    let t = |k: usize| (r.rows[k / 2 + first] as f64 - r.onset as f64) / r.rate_hz;
    // Each model's prediction of −ΔF_hand: its fit plus its own known inertia term
    // (`−ΔF − y`, which differs between models when the grip moves the hand).
    let pick = |rows: &[(f64, f64, f64)], measured: bool| -> Vec<(f64, f64)> {
        rows.iter()
            .enumerate()
            .filter(|(k, _)| k % 2 == 1)
            .map(|(k, (y, f, n))| (t(k), if measured { -n } else { f - n - y }))
            .collect()
    };
    let what = if weighted {
        "weighted (as judged)"
    } else {
        "y axis: hand force"
    };
    Some(Figure {
        title: if h.replicates.is_some() {
            format!(
                "held-out odd response to the pulses at {:.0}° and {:.0}° (trials {:?}), {what}",
                r.angle_deg,
                r.angle_deg + 180.0,
                r.trials
            )
        } else {
            format!(
                "held-out response to the pulse at {:.0}° (trials {:?}), {what}",
                r.angle_deg, r.trials
            )
        },
        x_desc: "time since the pulse onset (s)".into(),
        y_desc: if weighted {
            "W (1 − φ z⁻¹) (−ΔF_hand), second row (N)".into()
        } else {
            "−ΔF_hand (N)".into()
        },
        series: vec![
            Series {
                label: "measured".into(),
                points: pick(&base, true),
                style: Style::Bold,
                rgb: (40, 40, 40),
            },
            Series {
                label: "hand baseline".into(),
                points: pick(&base, false),
                style: Style::Line,
                rgb: (30, 90, 200),
            },
            Series {
                label: format!("extended ({})", hf.candidate.name()),
                points: pick(&ext, false),
                style: Style::Line,
                rgb: (210, 50, 40),
            },
        ],
        bars: Vec::new(),
        hline: None,
    })
}

fn ranking_figure(d: &Diagnosis) -> Figure {
    Figure {
        title: "held-out gain of each candidate (line: material floor)".into(),
        x_desc: "candidate".into(),
        y_desc: "gain (%)".into(),
        series: Vec::new(),
        bars: d
            .ranking
            .iter()
            .map(|r| (r.name.clone(), 100.0 * r.gain, r.name == d.cause))
            .collect(),
        hline: d.threshold.as_ref().map(|t| 100.0 * t.min_gain),
    }
}

/// Writes `diagnosis.md` and its PNG figures into `dir` (created if missing); returns
/// the files written.
///
/// # Errors
/// [`DiscrepancyError::Write`] when a file cannot be written.
pub fn write_report(a: &Analysis, dir: &Path) -> Result<Vec<PathBuf>, DiscrepancyError> {
    let werr = |p: &Path, e: std::io::Error| DiscrepancyError::Write {
        path: p.to_path_buf(),
        reason: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(|e| werr(dir, e))?;
    let d = &a.diagnosis;
    let mut written = Vec::new();
    let mut figs: Vec<(String, &str, Figure)> = Vec::new();
    let cause = d.causes.first().map(|c| c.name);
    let hand_cause = a.hand.as_ref().and_then(|h| {
        h.fits
            .iter()
            .find(|f| cause.is_some() && f.candidate.kind() == cause)
            .map(|f| (h, f))
    });
    let shown = a
        .fits
        .iter()
        .find(|f| cause.is_some() && f.candidate.kind() == cause)
        .or(a.fits.first());
    if let Some((h, hf)) = hand_cause {
        figs.push((
            "cause.png".into(),
            "What the cause looks like",
            hand_cause_figure(h, hf, d),
        ));
        if let Some(f) = hand_heldout_figure(h, hf, false) {
            figs.push((
                "heldout.png".into(),
                "A held-out pulse response: measured vs hand baseline vs extended",
                f,
            ));
        }
        if let Some(f) = hand_heldout_figure(h, hf, true) {
            figs.push((
                "heldout-weighted.png".into(),
                "The same response weighted as the hand balance judges it (whitened in time and between the axes; the held-out gain is measured here)",
                f,
            ));
        }
    } else if let Some(cf) = shown {
        if let Some(f) = cause_figure(a, cf)? {
            figs.push(("cause.png".into(), "What the cause looks like", f));
        }
        if let Some(f) = heldout_figure(a, cf)? {
            figs.push((
                "heldout.png".into(),
                "A held-out trial: measured vs baseline vs extended",
                f,
            ));
        }
    }
    if !d.ranking.is_empty() {
        figs.push(("ranking.png".into(), "Ranking", ranking_figure(d)));
    }
    let mut md = String::new();
    let _ = writeln!(md, "# Diagnosis of `{}`\n", d.session);
    let _ = writeln!(
        md,
        "**Cause: {}**{}\n",
        d.cause,
        match (d.baseline_nrmse, d.extended_nrmse, d.gain) {
            (Some(b), Some(e), Some(g)) => format!(
                " — held-out NRMSE of the {} balance {b:.4} (baseline) → {e:.4} (extended), gain {:.1} %",
                if hand_cause.is_some() {
                    "hand"
                } else {
                    "cart force"
                },
                100.0 * g
            ),
            _ => String::new(),
        }
    );
    let _ = writeln!(md, "```text\n{}```\n", table(d));
    let _ = writeln!(md, "## Evidence\n");
    for e in &d.evidence {
        let _ = writeln!(md, "- {e}");
    }
    let _ = writeln!(md, "\n## Figures\n");
    for (file, caption, fig) in &figs {
        let path = dir.join(file);
        let drawn = fig.draw(&path)?;
        let note = if drawn == Drawn::WithoutText {
            " (drawn without text: no system font)"
        } else {
            ""
        };
        let _ = writeln!(md, "### {caption}{note}\n\n![{caption}]({file})\n");
        written.push(path);
    }
    let _ = writeln!(
        md,
        "## Method\n\nThe carts obey `m·a = u(t − τ) + F + effects` per axis (x: both carts, y: upper cart; the \
         sensor is under the handle, so its reading already carries the handle's inertia). Masses and a nominal \
         latency (≤ 0.25 ms, one control tick) are fitted; each candidate adds its terms; all fits are made on training trials and \
         judged on held-out trials ({} folds of whole trials).\n\nThe human-side effects are judged on the hand \
         balance: the response to each force pulse against the mean of the unperturbed trials aligned at the same \
         point of the reach (along the axis the reaches span more), `−ΔF_hand = M_arm Δa + D Δv + K Δx + S (p Δx + d Δv)(t − τ) + effect`, with the arm's endpoint inertia \
         `M_arm` and feedback shape `S` known from the segment lengths (muscles without tone at half weight in \
         `S`: they answer only their stretch) and `D`, `K` full 2×2 matrices, over {} s \
         after the onset. With opposite pulse directions in the session it is fitted on the odd part of each \
         pair's mean responses (half the difference of the responses to θ and θ + 180°, which drops the terms \
         even in the pulse and the reference's noise), one pair held out at a time, and tested on the single \
         repetitions of the pairs, one held out at a time (with fewer than four pairs of directions, each pair's \
         repetitions are split into groups, at least four units in all, and the groups' means take the pairs' \
         place); otherwise on responses averaged by direction, in \
         folds of directions. Every row of the hand balance is weighted (generalised least squares): filtered by \
         `1 − φ z⁻¹` in time, `φ = exp(−Δt/τ)` with τ the arm's motor-noise correlation time, and multiplied \
         between the axes by `W`, `WᵀW ∝ Σ⁻¹` with `Σ` the covariance between the axes of the noise so filtered: \
         the spread of the single repetitions' residuals about their pair's mean (what the model misses cancels \
         there), or, without repetitions, the baseline's residual; its NRMSEs and gains are those of the weighted \
         force.",
        d.folds,
        super::hand_signals::HAND_WINDOW_S
    );
    let md_path = dir.join("diagnosis.md");
    std::fs::write(&md_path, md).map_err(|e| werr(&md_path, e))?;
    written.insert(0, md_path);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::gain_bound;

    /// The bound is `1 − f/b`: seed 1000's delay session (cart baseline 0.0454 over a
    /// floor of 0.0289) allows 36 %; a baseline at or under its floor allows nothing
    /// worth a line (the floor's own sampling error puts it there).
    #[test]
    fn the_gain_bound_is_one_minus_the_floor_over_the_baseline() {
        assert_eq!(
            gain_bound(0.0454, 0.0289),
            ", so no model gains more than 36 % on this session"
        );
        assert_eq!(gain_bound(0.0802, 0.0811), "");
        assert_eq!(gain_bound(0.05, 0.05), "");
    }
}
