//! Text of the report: aligned tables for the terminal and `report.md`.

use std::fmt::Write as _;

use super::{HoldSummary, PiovesanSummary, Report, Safety, Workspace, seed000, seed001};

/// A table whose columns are padded to their widest cell; rendered as Markdown, which
/// reads as an aligned table in a terminal too.
struct Table {
    head: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    fn new(head: &[&str]) -> Table {
        Table {
            head: head.iter().map(|s| (*s).to_owned()).collect(),
            rows: Vec::new(),
        }
    }

    fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    fn render(&self) -> String {
        let n = self.head.len();
        let width = |i: usize| {
            self.rows
                .iter()
                .filter_map(|r| r.get(i))
                .chain(self.head.get(i))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        };
        let w: Vec<usize> = (0..n).map(width).collect();
        let line = |cells: &[String]| {
            let mut s = String::from("|");
            for (i, wi) in w.iter().enumerate() {
                let c = cells.get(i).map_or("", String::as_str);
                let pad = wi.saturating_sub(c.chars().count());
                // Numbers right-aligned, text left-aligned.
                let numeric = c
                    .chars()
                    .next()
                    .is_some_and(|ch| ch.is_ascii_digit() || ch == '-' || ch == '+');
                if numeric {
                    let _ = write!(s, " {}{} |", " ".repeat(pad), c);
                } else {
                    let _ = write!(s, " {}{} |", c, " ".repeat(pad));
                }
            }
            s.push('\n');
            s
        };
        let mut out = line(&self.head);
        out.push('|');
        for wi in &w {
            let _ = write!(out, "{}|", "-".repeat(wi + 2));
        }
        out.push('\n');
        for r in &self.rows {
            out.push_str(&line(r));
        }
        out
    }
}

fn ms(m: &super::MeanStd, digits: usize) -> String {
    format!("{:.digits$} ({:.digits$})", m.mean, m.std)
}

fn yes(b: bool) -> &'static str {
    if b { "yes" } else { "NO" }
}

/// The summary: session, safety, workspace, deviations, NRMSE, estimates vs truth vs
/// the seed. This is what the command prints.
#[must_use]
pub fn summary_text(r: &Report) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Rehearsal of {} ({}), seed {}, {} subject(s), {} trials each ({} perturbed)\n",
        r.protocol, r.kind, r.seed, r.subjects, r.trials_per_subject, r.perturbed_per_subject
    );
    let mut t = Table::new(&["quantity", "value", "limit / seed", "ok"]);
    overview_rows(&mut t, r);
    safety_rows(&mut t, &r.safety);
    workspace_row(&mut t, &r.workspace);
    seed000_rows(&mut t, r);
    if let Some(h) = &r.hold {
        hold_rows(&mut t, h);
    }
    out.push_str(&t.render());
    if !r.parameters.is_empty() {
        out.push_str(&impedance_text(r));
    }
    for e in &r.estimates {
        if let Some(err) = &e.error {
            let _ = writeln!(out, "estimator failed for {}: {err}", e.subject);
        }
    }
    if let Some(pv) = &r.piovesan {
        out.push_str(&piovesan_text(pv));
    }
    if !r.timing.is_empty() {
        out.push_str(&timing_text(&r.timing));
    }
    out
}

/// Session length, and simulated against wall time.
fn overview_rows(t: &mut Table, r: &Report) {
    t.row(vec![
        "session length (trial time)".into(),
        format!(
            "{:.1} s ({:.1} min)",
            r.session_length_s,
            r.session_length_s / 60.0
        ),
        String::new(),
        String::new(),
    ]);
    t.row(vec![
        "simulated / wall time".into(),
        format!("{:.1} s / {:.1} s", r.simulated_s, r.wall_s),
        format!("{:.0}x real time on {} job(s)", r.real_time_factor, r.jobs),
        String::new(),
    ]);
}

/// Peak force, command and speed against their limits, and the trips.
fn safety_rows(t: &mut Table, s: &Safety) {
    t.row(vec![
        "peak hand force".into(),
        format!("{:.1} N", s.peak_force_n),
        String::new(),
        String::new(),
    ]);
    let cmd_ok =
        s.peak_command_n[0] < s.force_limit_n[0] && s.peak_command_n[1] < s.force_limit_n[1];
    t.row(vec![
        "peak motor command x / y".into(),
        format!("{:.1} / {:.1} N", s.peak_command_n[0], s.peak_command_n[1]),
        format!(
            "limit {:.0} / {:.0} N",
            s.force_limit_n[0], s.force_limit_n[1]
        ),
        yes(cmd_ok).into(),
    ]);
    t.row(vec![
        "peak speed".into(),
        format!("{:.3} m/s", s.peak_speed_m_per_s),
        format!("trip at {:.2} m/s", s.velocity_limit_m_per_s),
        yes(s.peak_speed_m_per_s < s.velocity_limit_m_per_s).into(),
    ]);
    t.row(vec![
        "safety trips".into(),
        format!("{}", s.trips.len()),
        "0".into(),
        yes(s.trips.is_empty()).into(),
    ]);
}

/// How far the handle went against the walls.
fn workspace_row(t: &mut Table, w: &Workspace) {
    t.row(vec![
        "workspace: peak |x| / |y|".into(),
        format!(
            "{:.1} / {:.1} mm",
            w.peak_position_m[0] * 1e3,
            w.peak_position_m[1] * 1e3
        ),
        format!(
            "walls at ±{:.0} mm, margin {:.1} mm",
            w.wall_m * 1e3,
            w.margin_m * 1e3
        ),
        yes(w.suffices).into(),
    ]);
}

/// The 000_* figures: deviations at 150 ms and the NRMSE of the perturbation response.
fn seed000_rows(t: &mut Table, r: &Report) {
    if let Some([dx, dy]) = &r.deviation_mm {
        for (name, m, (sm, ss)) in [
            ("max deviation x, 150 ms", dx, seed000::DEV_X_MM),
            ("max deviation y, 150 ms", dy, seed000::DEV_Y_MM),
        ] {
            let inside = (m.mean - sm).abs() <= ss;
            t.row(vec![
                name.into(),
                format!("{} mm", ms(m, 2)),
                format!("000_*: {sm} ({ss}) mm"),
                yes(inside).into(),
            ]);
        }
    }
    if let Some(n) = &r.nrmse {
        for (name, (mean, max), bound) in [
            ("NRMSE Δx mean / max", n.position, seed000::NRMSE_BOUNDS[0]),
            ("NRMSE Δẋ mean / max", n.velocity, seed000::NRMSE_BOUNDS[1]),
            (
                "NRMSE Δẍ mean / max",
                n.acceleration,
                seed000::NRMSE_BOUNDS[2],
            ),
            ("NRMSE Δu_ext mean / max", n.force, seed000::NRMSE_BOUNDS[3]),
        ] {
            t.row(vec![
                name.into(),
                format!("{:.1} / {:.1} %", mean * 100.0, max * 100.0),
                format!("000_*: < {:.1} %", bound * 100.0),
                yes(mean < bound).into(),
            ]);
        }
    }
}

/// The 001_* position perturbations.
fn hold_rows(t: &mut Table, h: &HoldSummary) {
    t.row(vec![
        "position perturbations".into(),
        format!("{}", h.pushes),
        String::new(),
        String::new(),
    ]);
    t.row(vec![
        "|x − anchor| x / y, window".into(),
        format!(
            "{} / {} mm",
            ms(&h.deviation_x_mm, 2),
            ms(&h.deviation_y_mm, 2)
        ),
        format!("001_*: 8 mm pushes"),
        String::new(),
    ]);
}

/// The Börner estimates against ground truth and 000_* Table 1.
fn impedance_text(r: &Report) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\nInvoluntary impedance (Börner, M_BSP = arm endpoint inertia) vs ground truth vs 000_* Table 1"
    );
    let mut t = Table::new(&[
        "param",
        "estimate",
        "± s.e.",
        "truth (intrinsic)",
        "bias",
        "Table 1",
        "within 1 std",
    ]);
    for p in &r.parameters {
        let inside = (p.estimate.mean - p.table1.0).abs() <= p.table1.1;
        t.row(vec![
            format!("{} [{}]", p.name, p.unit),
            format!("{:.2}", p.estimate.mean),
            format!("{:.2}", p.std_err),
            format!("{:.2}", p.truth.mean),
            if p.bias.n > 1 {
                ms(&p.bias, 2)
            } else {
                format!("{:.2}", p.bias.mean)
            },
            format!("{:.2} ({:.2})", p.table1.0, p.table1.1),
            yes(inside).into(),
        ]);
    }
    out.push_str(&t.render());
    if r.subjects > 1 {
        let _ = writeln!(
            out,
            "(estimate, truth and bias are mean (std) over {} subjects)",
            r.subjects
        );
    }
    out
}

/// The windowed regression (001_*) against the known stiffness.
fn piovesan_text(pv: &PiovesanSummary) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\nWindowed regression (Piovesan, 10-cycle windows), {} windows, M̂ = [[{:.2}, {:.2}], [{:.2}, {:.2}]] kg",
        pv.windows, pv.m_hat_kg[0][0], pv.m_hat_kg[0][1], pv.m_hat_kg[1][0], pv.m_hat_kg[1][1]
    );
    let mut t = Table::new(&["param", "mean (std over windows)", "seed / known", "ok"]);
    let names = [["K11", "K12"], ["K21", "K22"]];
    for (i, row_names) in names.iter().enumerate() {
        for (j, name) in row_names.iter().enumerate() {
            let (known, ok) = match (pv.k_true_n_per_m, pv.k_rel_error) {
                (Some(k), Some(e)) if i == j => (
                    format!(
                        "{} N/m (App. B: within {:.1} %)",
                        k[i],
                        seed001::K_TOLERANCE * 100.0
                    ),
                    yes(e[i].abs() <= seed001::K_TOLERANCE).to_owned(),
                ),
                (Some(_), _) => ("0 N/m".to_owned(), String::new()),
                _ => (String::new(), String::new()),
            };
            t.row(vec![
                format!("{name} [N/m]"),
                ms(&pv.k_n_per_m[i][j], 1),
                known,
                ok,
            ]);
        }
    }
    for i in 0..2 {
        for j in 0..2 {
            t.row(vec![
                format!("B{}{} [N s/m]", i + 1, j + 1),
                ms(&pv.b_ns_per_m[i][j], 2),
                String::new(),
                String::new(),
            ]);
        }
    }
    let r2_seed = if pv.k_true_n_per_m.is_some() {
        format!("App. B: {}", seed001::R2)
    } else {
        "001_*: 0.80 (subjects)".to_owned()
    };
    t.row(vec![
        "canonical r²".into(),
        ms(&pv.r2, 3),
        r2_seed,
        String::new(),
    ]);
    if let (Some(e), Some(d)) = (pv.k_rel_error, pv.k_max_rel_drift) {
        t.row(vec![
            "K11 / K22 error of the mean".into(),
            format!("{:+.2} / {:+.2} %", e[0] * 100.0, e[1] * 100.0),
            String::new(),
            String::new(),
        ]);
        t.row(vec![
            "largest window drift K11 / K22".into(),
            format!("{:.2} / {:.2} %", d[0] * 100.0, d[1] * 100.0),
            format!("App. B: ±{:.1} %", seed001::K_TOLERANCE * 100.0),
            yes(d[0] <= seed001::K_TOLERANCE && d[1] <= seed001::K_TOLERANCE).into(),
        ]);
    }
    out.push_str(&t.render());
    for e in &pv.errors {
        let _ = writeln!(out, "windowed regression failed: {e}");
    }
    out
}

/// `report.md`: the summary and the per-trial table.
#[must_use]
pub fn markdown(r: &Report) -> String {
    let mut out = format!("# Rehearsal report: {}\n\n", r.protocol);
    out.push_str(&summary_text(r));
    out.push_str("\n## Trials\n\n");
    let mut t = Table::new(&[
        "subject",
        "trial",
        "task",
        "peak force [N]",
        "peak speed [m/s]",
        "dev x [mm]",
        "dev y [mm]",
        "trip",
    ]);
    for row in &r.trials {
        let (dx, dy) = row
            .deviation_mm
            .map_or((String::new(), String::new()), |d| {
                (format!("{:.2}", d[0]), format!("{:.2}", d[1]))
            });
        t.row(vec![
            row.subject.clone(),
            row.id.to_string(),
            row.task.clone(),
            format!("{:.2}", row.peak_force_n),
            format!("{:.3}", row.peak_speed_m_per_s),
            dx,
            dy,
            row.trip.clone().unwrap_or_default(),
        ]);
    }
    out.push_str(&t.render());
    out
}

/// The real-time timing table: wake-up latency and loop time per subject, µs.
#[must_use]
pub fn timing_text(timing: &[super::SubjectTiming]) -> String {
    let mut out = String::from(
        "\nReal-time timing (wake-up latency: start of a tick after its deadline; loop time: one tick's work)\n",
    );
    let mut t = Table::new(&[
        "subject",
        "ticks",
        "missed (per 1e5)",
        "longest run",
        "wake p50 / p99 / p99.9 / max",
        "loop p50 / p99 / p99.9 / max",
    ]);
    let p = |q: &crate::session::Percentiles| {
        format!(
            "{:.1} / {:.1} / {:.1} / {:.1} µs",
            q.p50_us, q.p99_us, q.p999_us, q.max_us
        )
    };
    for s in timing {
        let tm = &s.timing;
        t.row(vec![
            s.subject.clone(),
            tm.ticks.to_string(),
            format!("{} ({:.1})", tm.missed_deadlines, tm.misses_per_1e5()),
            tm.max_consecutive_misses.to_string(),
            p(&tm.wake_latency),
            p(&tm.loop_time),
        ]);
    }
    out.push_str(&t.render());
    out
}
