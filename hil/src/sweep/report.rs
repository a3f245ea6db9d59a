//! `sweep.md` and its figures, from the merged table alone (so a local run and a merge
//! of shards write the same report).
//!
//! - **Precision of D and K.** Per grid point, the error `estimate − truth` of each
//!   element across the population's runs: its bias, its standard deviation `sd`, and
//!   the interval `bias ± 1.96 sd` where 95 % of subjects' errors fall (normal
//!   approximation). `precision.png` draws it against the pulses per subject.
//! - **The sentence.** "Known to ±X" is `X = 1.96·√(bias² + sd²)` (the bias included).
//!   Across grid points that differ in pulses, `X²/1.96² = a + b/pulses` is fitted by
//!   least squares (`a ≥ 0`: the floor more pulses cannot remove, the estimator's bias
//!   and the spread of its error across subjects; `b/pulses`: the noise, averaging out);
//!   the pulses a target ±Y needs follow from it, or the floor says no number of pulses
//!   reaches Y. With one pulse count, `a = 0` is assumed and said.
//! - **Detection.** Per effect size, the share of runs whose diagnosis named the hidden
//!   effect with its Wilson 95 % interval, the parameter's relative error where named,
//!   the other causes named, `unexplained`. `detection.png` draws the share against size.
//! - **Session and safety.** Session length, closest approach to the wall, peak command,
//!   trips and failed runs per grid point.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::file::{ELEMENTS, SweepFile, element_unit};
use super::table::element_column;

/// z of a two-sided 95 % interval.
const Z95: f64 = 1.959_963_984_540_054;

/// The table's records, looked up by column name.
struct Table<'a> {
    columns: BTreeMap<&'a str, usize>,
    rows: &'a [Vec<String>],
}

impl<'a> Table<'a> {
    fn new(records: &'a [Vec<String>]) -> Table<'a> {
        let (header, rows) = records
            .split_first()
            .map_or((&[][..], &[][..]), |(h, r)| (h.as_slice(), r));
        Table {
            columns: header
                .iter()
                .enumerate()
                .map(|(i, h)| (h.as_str(), i))
                .collect(),
            rows,
        }
    }

    fn text<'r>(&self, row: &'r [String], column: &str) -> &'r str {
        self.columns
            .get(column)
            .and_then(|&i| row.get(i))
            .map_or("", String::as_str)
    }

    fn num(&self, row: &[String], column: &str) -> Option<f64> {
        self.text(row, column).parse().ok()
    }
}

/// Mean, standard deviation (n − 1) and count.
fn mean_sd(v: &[f64]) -> (f64, f64, usize) {
    let n = v.len();
    if n == 0 {
        return (f64::NAN, f64::NAN, 0);
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    (mean, sd, n)
}

/// Three significant digits, as a report writes a measured number.
fn sig(v: f64) -> String {
    if !v.is_finite() {
        return "—".to_owned();
    }
    if v == 0.0 {
        return "0".to_owned();
    }
    if v.fract() == 0.0 && v.abs() < 1e15 {
        return format!("{v:.0}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

/// Wilson 95 % interval of `k` successes in `n`.
#[must_use]
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let z2 = Z95 * Z95;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = Z95 * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / (1.0 + z2 / n);
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// One grid point's precision of one element.
#[derive(Debug, Clone, Copy)]
struct Precision {
    pulses: f64,
    bias: f64,
    sd: f64,
    n: usize,
}

impl Precision {
    fn known_to(&self) -> f64 {
        Z95 * (self.bias * self.bias
            + if self.sd.is_finite() {
                self.sd * self.sd
            } else {
                0.0
            })
        .sqrt()
    }
}

/// A series: the grid points that differ only in pulses (the `reach.*` keys).
#[derive(Debug, Clone)]
struct Series {
    label: String,
    /// Per element, per grid point (sorted by pulses).
    points: Vec<[Precision; 8]>,
}

fn series_key(sweep: &SweepFile, t: &Table<'_>, row: &[String]) -> String {
    let mut parts: Vec<String> = sweep
        .grid
        .iter()
        .filter(|(k, _)| !k.starts_with("reach."))
        .map(|(k, _)| format!("{k} = {}", t.text(row, k)))
        .collect();
    if let Some(e) = &sweep.effect {
        parts.push(format!("{} = {}", e.key, t.text(row, &e.key)));
    }
    series_label(&parts)
}

/// A series' label from its `key = value` parts, or `all` for a sweep without any.
fn series_label(parts: &[String]) -> String {
    if parts.is_empty() {
        "all".to_owned()
    } else {
        parts.join(", ")
    }
}

fn precision_series(sweep: &SweepFile, t: &Table<'_>) -> Vec<Series> {
    // (series, point) → rows.
    let mut groups: BTreeMap<(String, usize), Vec<&Vec<String>>> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for row in t.rows {
        let key = series_key(sweep, t, row);
        if !order.contains(&key) {
            order.push(key.clone());
        }
        let point = t.num(row, "point").unwrap_or(0.0) as usize;
        groups.entry((key, point)).or_default().push(row);
    }
    let mut out = Vec::new();
    for label in order {
        let mut points: Vec<[Precision; 8]> = groups
            .iter()
            .filter(|((s, _), _)| *s == label)
            .filter_map(|(_, rows)| {
                let pulses: Vec<f64> = rows.iter().filter_map(|r| t.num(r, "perturbed")).collect();
                let pulses = mean_sd(&pulses).0;
                let mut out = [Precision {
                    pulses,
                    bias: f64::NAN,
                    sd: f64::NAN,
                    n: 0,
                }; 8];
                for (i, e) in ELEMENTS.iter().enumerate() {
                    let errors: Vec<f64> = rows
                        .iter()
                        .filter_map(|r| {
                            Some(
                                t.num(r, &element_column(e, "est"))?
                                    - t.num(r, &element_column(e, "true"))?,
                            )
                        })
                        .collect();
                    let (bias, sd, n) = mean_sd(&errors);
                    out[i] = Precision {
                        pulses,
                        bias,
                        sd,
                        n,
                    };
                }
                (out[0].n > 0).then_some(out)
            })
            .collect();
        points.sort_by(|a, b| a[0].pulses.total_cmp(&b[0].pulses));
        if !points.is_empty() {
            out.push(Series { label, points });
        }
    }
    out
}

/// `X²/z² = a + b/pulses` over a series' points for element `i`: `(a, b, assumed)`,
/// `assumed` when one pulse count forced `a = 0`.
fn fit_floor(points: &[[Precision; 8]], i: usize) -> (f64, f64, bool) {
    let data: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (1.0 / p[i].pulses, (p[i].known_to() / Z95).powi(2)))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    let distinct = {
        let mut xs: Vec<f64> = data.iter().map(|d| d.0).collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        xs.len()
    };
    let through_origin = |data: &[(f64, f64)]| {
        let sxx: f64 = data.iter().map(|d| d.0 * d.0).sum();
        let sxy: f64 = data.iter().map(|d| d.0 * d.1).sum();
        if sxx > 0.0 { sxy / sxx } else { f64::NAN }
    };
    if distinct < 2 {
        return (0.0, through_origin(&data), true);
    }
    let n = data.len() as f64;
    let mx = data.iter().map(|d| d.0).sum::<f64>() / n;
    let my = data.iter().map(|d| d.1).sum::<f64>() / n;
    let sxx: f64 = data.iter().map(|d| (d.0 - mx).powi(2)).sum();
    let sxy: f64 = data.iter().map(|d| (d.0 - mx) * (d.1 - my)).sum();
    let b = sxy / sxx;
    let a = my - b * mx;
    if a < 0.0 {
        (0.0, through_origin(&data), false)
    } else {
        (a, b, false)
    }
}

/// The sentence a lab acts on, for element `i` of a series.
fn sentence(sweep: &SweepFile, s: &Series, i: usize) -> Option<String> {
    let e = ELEMENTS[i];
    let unit = element_unit(e);
    let last = s.points.last()?[i];
    if last.n == 0 {
        return None;
    }
    let x = last.known_to();
    let target = sweep.report.targets.get(e).copied().unwrap_or(x / 2.0);
    let (a, b, assumed) = fit_floor(&s.points, i);
    let first = s.points.first()?[i].pulses;
    let fitted = if assumed {
        "assuming the error shrinks as 1/√pulses; the sweep measured one pulse count".to_owned()
    } else {
        format!(
            "error² = a + b/pulses fitted over {}–{} pulses",
            sig(first),
            sig(last.pulses)
        )
    };
    let head = format!(
        "With {} pulses per subject, {e} is known to ±{} {unit} across this population \
         (bias {}, spread ±{}; {} runs)",
        sig(last.pulses),
        sig(x),
        sig(last.bias),
        sig(Z95 * last.sd),
        last.n
    );
    let floor = Z95 * a.sqrt();
    let need = (target / Z95).powi(2) - a;
    Some(if b.is_nan() || b <= 0.0 {
        format!(
            "{head}; more pulses did not narrow it over the sweep ({fitted}), so ±{} {unit} needs another protocol, not more pulses.",
            sig(target)
        )
    } else if need <= 0.0 {
        format!(
            "{head}; ±{} {unit} is below the floor of ±{} {unit} that more pulses leave (the estimator's bias and its error's spread across subjects; {fitted}).",
            sig(target),
            sig(floor)
        )
    } else {
        let pulses = (b / need).ceil();
        format!(
            "{head}; ±{} {unit} needs about {} pulses ({fitted}{}).",
            sig(target),
            sig(pulses),
            if pulses > last.pulses * 1.5 {
                ", extrapolated"
            } else {
                ""
            }
        )
    })
}

/// Writes `sweep.md` and its figures into `out`; returns the files.
///
/// # Errors
/// A file that cannot be written, said with its path.
pub fn write(
    sweep: &SweepFile,
    records: &[Vec<String>],
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    let t = Table::new(records);
    let mut md = String::new();
    let mut files = Vec::new();
    let runs = t.rows.len();
    let _ = writeln!(md, "# Sweep `{}`\n", sweep.name);
    let _ = writeln!(
        md,
        "{runs} runs: {} grid point(s) × {} effect size(s) × {} subjects × {} replicate(s); \
         seed {}; {}; {}. The table is `sweep.csv` (one row per run; units in the column names).\n",
        sweep.points(),
        sweep.sizes(),
        sweep.population.subjects,
        sweep.replicates,
        sweep.seed,
        sweep
            .max_trials
            .map_or("whole sessions".to_owned(), |m| format!(
                "the first {m} trials of each session"
            )),
        if sweep.realistic {
            "a lab's rig and subject (sensor offset and drift, motor gain and noise, reaches varying)"
        } else {
            "an ideal rig"
        }
    );
    if !sweep.grid.is_empty() {
        let _ = writeln!(md, "| grid key | values |\n|---|---|");
        for (k, v) in &sweep.grid {
            let vals: Vec<String> = v.iter().map(super::table::cell).collect();
            let _ = writeln!(md, "| `{k}` | {} |", vals.join(", "));
        }
        md.push('\n');
    }
    let failed = t
        .rows
        .iter()
        .filter(|r| !t.text(r, "error").is_empty())
        .count();
    if failed > 0 {
        let _ = writeln!(
            md,
            "**{failed} of {runs} runs failed** (the simulation refused its protocol or diverged); their `error` column says why.\n"
        );
    }
    if sweep.estimate {
        let series = precision_series(sweep, &t);
        if !series.is_empty() {
            precision_section(sweep, &series, &mut md);
            let png = out.join("precision.png");
            draw_precision(&series, &png)?;
            md.push_str(
                "![95 % interval of the error of D and K against pulses](precision.png)\n\n",
            );
            files.push(png);
        }
    }
    if sweep.diagnose
        && let Some(e) = &sweep.effect
    {
        let rows = detection_rows(sweep, &t);
        let _ = writeln!(
            md,
            "## Detection of {} (`{}`)\n\n| series | size | runs | named | 95 % interval | `{}` within 20 % | median held-out gain | other causes named | unexplained |\n|---|---|---|---|---|---|---|---|---|",
            e.name.name(),
            e.key,
            e.parameter
        );
        for d in &rows {
            let (lo, hi) = wilson(d.named, d.runs);
            let _ = writeln!(
                md,
                "| {} | {} | {} | {}/{} ({:.0} %) | {:.0}–{:.0} % | {}/{} | {} | {} | {} |",
                d.series,
                sig(d.size),
                d.runs,
                d.named,
                d.runs,
                100.0 * d.named as f64 / d.runs.max(1) as f64,
                100.0 * lo,
                100.0 * hi,
                d.within,
                d.named,
                d.gain.map_or("—".to_owned(), sig),
                d.others,
                d.unexplained
            );
        }
        md.push_str(
            "\nAt size 0 the effect is absent: \"named\" there is the false-alarm rate. \
             \"Other causes\" counts runs where the diagnosis named a catalog effect other than the hidden one.\n\n",
        );
        let png = out.join("detection.png");
        draw_detection(&rows, &e.key, &png)?;
        md.push_str("![detection rate against effect size](detection.png)\n\n");
        files.push(png);
    }
    if sweep.diagnose && sweep.effect.is_none() {
        quiet_section(sweep, &t, &mut md);
    }
    session_section(sweep, &t, &mut md);
    let path = out.join("sweep.md");
    std::fs::write(&path, md).map_err(|e| format!("{}: {e}", path.display()))?;
    files.insert(0, path);
    Ok(files)
}

fn precision_section(sweep: &SweepFile, series: &[Series], md: &mut String) {
    let _ = writeln!(
        md,
        "## Precision of D and K\n\nError of the estimate against the simulated arm's intrinsic D and K at the onsets, across the population: bias ± 1.96 sd (95 % of subjects, normal approximation). D in N s/m, K in N/m.\n"
    );
    let _ = writeln!(
        md,
        "| series | pulses | runs | {} |\n|---|---|---|{}",
        ELEMENTS.join(" | "),
        "---|".repeat(ELEMENTS.len())
    );
    for s in series {
        for p in &s.points {
            let cells: Vec<String> = p
                .iter()
                .map(|e| format!("{} ± {}", sig(e.bias), sig(Z95 * e.sd)))
                .collect();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} |",
                s.label,
                sig(p[0].pulses),
                p[0].n,
                cells.join(" | ")
            );
        }
    }
    md.push_str("\n### What it means for the protocol\n\n");
    const SHOWN: usize = 4;
    for s in series.iter().take(SHOWN) {
        if series.len() > 1 {
            let _ = writeln!(md, "{}:\n", s.label);
        }
        for i in 0..ELEMENTS.len() {
            if let Some(line) = sentence(sweep, s, i) {
                let _ = writeln!(md, "- {line}");
            }
        }
        md.push('\n');
    }
    if series.len() > SHOWN {
        let _ = writeln!(
            md,
            "({} more series in the table above; the sentences follow from it the same way.)\n",
            series.len() - SHOWN
        );
    }
}

struct DetectionRow {
    series: String,
    size: f64,
    runs: usize,
    named: usize,
    within: usize,
    gain: Option<f64>,
    others: usize,
    unexplained: usize,
}

/// A row's grid point as `key = value` over every grid key (the session layout's too),
/// or `all` for a sweep without a grid: the series of the detection and false-alarm
/// tables.
fn grid_series(sweep: &SweepFile, t: &Table<'_>, row: &[String]) -> String {
    let parts: Vec<String> = sweep
        .grid
        .iter()
        .map(|(k, _)| format!("{k} = {}", t.text(row, k)))
        .collect();
    series_label(&parts)
}

/// The median of sorted values: the middle one, or the mean of the two middle ones for
/// an even count; `None` for none.
fn median_of_sorted(v: &[f64]) -> Option<f64> {
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

fn detection_rows(sweep: &SweepFile, t: &Table<'_>) -> Vec<DetectionRow> {
    let Some(e) = &sweep.effect else {
        return Vec::new();
    };
    let found = format!("found_{}", e.parameter);
    let mut groups: BTreeMap<(String, usize), Vec<&Vec<String>>> = BTreeMap::new();
    let mut order: Vec<(String, usize)> = Vec::new();
    for row in t.rows {
        let series = grid_series(sweep, t, row);
        let size = e
            .sizes
            .iter()
            .position(|s| t.num(row, &e.key) == Some(*s))
            .unwrap_or(0);
        let key = (series, size);
        if !order.contains(&key) {
            order.push(key.clone());
        }
        groups.entry(key).or_default().push(row);
    }
    order
        .into_iter()
        .map(|key| {
            let rows = &groups[&key];
            let size = e.sizes[key.1];
            let named: Vec<&&Vec<String>> = rows
                .iter()
                .filter(|r| t.text(r, "named") == "true")
                .collect();
            let within = named
                .iter()
                .filter(|r| {
                    t.num(r, &found)
                        .is_some_and(|f| size != 0.0 && ((f - size) / size).abs() <= 0.2)
                })
                .count();
            let mut gains: Vec<f64> = named.iter().filter_map(|r| t.num(r, "gain")).collect();
            gains.sort_by(f64::total_cmp);
            let others = rows
                .iter()
                .filter(|r| {
                    let c = t.text(r, "causes");
                    !c.is_empty() && c != "none" && c.split('+').any(|c| c != e.name.name())
                })
                .count();
            DetectionRow {
                series: key.0,
                size,
                runs: rows.len(),
                named: named.len(),
                within,
                gain: median_of_sorted(&gains),
                others,
                unexplained: rows
                    .iter()
                    .filter(|r| t.text(r, "unexplained") == "true")
                    .count(),
            }
        })
        .collect()
}

/// What the diagnosis named in each grid point of a sweep that hides nothing: every
/// cause it names there is a false alarm, and its rate gets Wilson's 95 % interval.
/// Runs whose simulation or diagnosis failed are counted apart, not as quiet.
fn quiet_section(sweep: &SweepFile, t: &Table<'_>, md: &mut String) {
    let mut groups: Vec<(String, Vec<&Vec<String>>)> = Vec::new();
    for row in t.rows {
        let key = grid_series(sweep, t, row);
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, rows)) => rows.push(row),
            None => groups.push((key, vec![row])),
        }
    }
    md.push_str(
        "## What the diagnosis named (nothing hidden)\n\n\
         | series | runs | diagnosed | a cause named | 95 % interval | causes | unexplained |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for (key, rows) in &groups {
        let diagnosed: Vec<&&Vec<String>> = rows
            .iter()
            .filter(|r| t.text(r, "error").is_empty() && t.text(r, "diagnose_error").is_empty())
            .collect();
        let mut causes: BTreeMap<&str, usize> = BTreeMap::new();
        for r in &diagnosed {
            let c = t.text(r, "causes");
            if !c.is_empty() && c != "none" {
                *causes.entry(c).or_default() += 1;
            }
        }
        let named: usize = causes.values().sum();
        let (lo, hi) = wilson(named, diagnosed.len());
        let which = if causes.is_empty() {
            "—".to_owned()
        } else {
            causes
                .iter()
                .map(|(c, n)| format!("{c} ({n})"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let unexplained = diagnosed
            .iter()
            .filter(|r| t.text(r, "unexplained") == "true")
            .count();
        let _ = writeln!(
            md,
            "| {key} | {} | {} | {named}/{} | {:.0}–{:.0} % | {which} | {unexplained} |",
            rows.len(),
            diagnosed.len(),
            diagnosed.len(),
            100.0 * lo,
            100.0 * hi,
        );
    }
    md.push_str(
        "\nNothing is hidden, so every cause named is a false alarm; \"unexplained\" counts runs \
         where structure outside the catalog was reported. Runs that failed (`error`, \
         `diagnose_error`) are not diagnosed.\n\n",
    );
}

fn session_section(sweep: &SweepFile, t: &Table<'_>, md: &mut String) {
    let _ = writeln!(
        md,
        "## Session length and safety\n\n| point | {} | runs | session, s | closest to the wall, mm | peak command, N | trips | failed |\n|---|---|---|---|---|---|---|---|",
        if sweep.grid.is_empty() {
            "grid".to_owned()
        } else {
            sweep
                .grid
                .iter()
                .map(|(k, _)| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    let mut points: BTreeMap<usize, Vec<&Vec<String>>> = BTreeMap::new();
    for row in t.rows {
        points
            .entry(t.num(row, "point").unwrap_or(0.0) as usize)
            .or_default()
            .push(row);
    }
    for (point, rows) in &points {
        let values = sweep
            .point_values(*point)
            .iter()
            .map(|(_, v)| super::table::cell(v))
            .collect::<Vec<_>>()
            .join(", ");
        // A failed run has no session: its zeros would pull the mean length down and
        // the margin to the wall to 0.
        let col = |c: &str| {
            rows.iter()
                .filter(|r| t.text(r, "error").is_empty())
                .filter_map(|r| t.num(r, c))
                .collect::<Vec<f64>>()
        };
        let length = mean_sd(&col("session_length_s")).0;
        let margin = col("wall_margin_m")
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        let peak = col("peak_command_n").into_iter().fold(0.0, f64::max);
        let trips: f64 = col("trips").iter().sum();
        let failed = rows
            .iter()
            .filter(|r| !t.text(r, "error").is_empty())
            .count();
        let _ = writeln!(
            md,
            "| {point} | {} | {} | {} | {} | {} | {trips} | {failed} |",
            if values.is_empty() {
                "—".to_owned()
            } else {
                values
            },
            rows.len(),
            sig(length),
            sig(margin * 1e3),
            sig(peak)
        );
    }
    md.push('\n');
}

const PALETTE: [(u8, u8, u8); 6] = [
    (31, 119, 180),
    (214, 39, 40),
    (44, 160, 44),
    (148, 103, 189),
    (255, 127, 14),
    (23, 190, 207),
];

fn draw_precision(series: &[Series], path: &Path) -> Result<(), String> {
    draw_either(path, (1400, 720), |root, text| {
        let panels = root.split_evenly((2, 4));
        for (i, panel) in panels.iter().enumerate() {
            let e = ELEMENTS[i];
            let pts: Vec<(f64, f64, f64, f64)> = series
                .iter()
                .flat_map(|s| s.points.iter().map(move |p| p[i]))
                .map(|p| (p.pulses, p.bias, p.bias - Z95 * p.sd, p.bias + Z95 * p.sd))
                .collect();
            let (x0, x1) = span(pts.iter().map(|p| p.0), true);
            let (y0, y1) = span(pts.iter().flat_map(|p| [p.1, p.2, p.3]).chain([0.0]), false);
            let mut b = ChartBuilder::on(panel);
            b.margin(10);
            if text {
                b.caption(
                    format!("{e} error, {}", element_unit(e)),
                    ("sans-serif", 18),
                )
                .x_label_area_size(30)
                .y_label_area_size(50);
            }
            let mut chart = b
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| e.to_string())?;
            let mut mesh = chart.configure_mesh();
            if text {
                mesh.x_desc("pulses per subject");
            } else {
                mesh.x_labels(0).y_labels(0);
            }
            mesh.draw().map_err(|e| e.to_string())?;
            chart
                .draw_series(LineSeries::new([(x0, 0.0), (x1, 0.0)], BLACK.mix(0.4)))
                .map_err(|e| e.to_string())?;
            for (k, s) in series.iter().enumerate() {
                let (r, g, bl) = PALETTE[k % PALETTE.len()];
                let c = RGBColor(r, g, bl);
                // Series side by side, so their bars do not hide each other.
                let dx = (x1 - x0) * 0.01 * (k as f64 - (series.len() as f64 - 1.0) / 2.0);
                for p in &s.points {
                    let p = p[i];
                    if !(p.sd.is_finite() && p.bias.is_finite()) {
                        continue;
                    }
                    let x = p.pulses + dx;
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            vec![(x, p.bias - Z95 * p.sd), (x, p.bias + Z95 * p.sd)],
                            c.stroke_width(2),
                        )))
                        .map_err(|e| e.to_string())?;
                    chart
                        .draw_series(std::iter::once(Circle::new((x, p.bias), 4, c.filled())))
                        .map_err(|e| e.to_string())?;
                }
                let line: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .map(|p| (p[i].pulses + dx, p[i].bias))
                    .filter(|p| p.1.is_finite())
                    .collect();
                let anno = chart
                    .draw_series(LineSeries::new(line, c.mix(0.5)))
                    .map_err(|e| e.to_string())?;
                if text && i == 0 && series.len() > 1 {
                    let label = s.label.clone();
                    anno.label(label).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(3))
                    });
                }
            }
            if text && i == 0 && series.len() > 1 {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| e.to_string())?;
            }
        }
        Ok(())
    })
}

fn draw_detection(rows: &[DetectionRow], key: &str, path: &Path) -> Result<(), String> {
    draw_either(path, (900, 560), |root, text| {
        let (x0, x1) = span(rows.iter().map(|r| r.size), true);
        let mut b = ChartBuilder::on(root);
        b.margin(16);
        if text {
            b.caption(
                "Detection rate against effect size (Wilson 95 %)",
                ("sans-serif", 20),
            )
            .x_label_area_size(44)
            .y_label_area_size(60);
        }
        let mut chart = b
            .build_cartesian_2d(x0..x1, 0.0..1.05)
            .map_err(|e| e.to_string())?;
        let mut mesh = chart.configure_mesh();
        if text {
            mesh.x_desc(key).y_desc("share of runs naming the effect");
        } else {
            mesh.x_labels(0).y_labels(0);
        }
        mesh.draw().map_err(|e| e.to_string())?;
        let mut names: Vec<&str> = Vec::new();
        for r in rows {
            if !names.contains(&r.series.as_str()) {
                names.push(&r.series);
            }
        }
        for (k, name) in names.iter().enumerate() {
            let (r, g, bl) = PALETTE[k % PALETTE.len()];
            let c = RGBColor(r, g, bl);
            let mine: Vec<&DetectionRow> = rows.iter().filter(|r| r.series == *name).collect();
            for d in &mine {
                let (lo, hi) = wilson(d.named, d.runs);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(d.size, lo), (d.size, hi)],
                        c.stroke_width(2),
                    )))
                    .map_err(|e| e.to_string())?;
            }
            chart
                .draw_series(mine.iter().map(|d| {
                    Circle::new(
                        (d.size, d.named as f64 / d.runs.max(1) as f64),
                        4,
                        c.filled(),
                    )
                }))
                .map_err(|e| e.to_string())?;
            let anno = chart
                .draw_series(LineSeries::new(
                    mine.iter()
                        .map(|d| (d.size, d.named as f64 / d.runs.max(1) as f64)),
                    c.stroke_width(2),
                ))
                .map_err(|e| e.to_string())?;
            if text && names.len() > 1 {
                let label = (*name).to_owned();
                anno.label(label).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(3))
                });
            }
        }
        if text && names.len() > 1 {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    })
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// Draws with text, and again without it when no font can be loaded (as the
/// diagnosis's figures do).
fn draw_either(
    path: &Path,
    size: (u32, u32),
    draw: impl Fn(&Area<'_>, bool) -> Result<(), String>,
) -> Result<(), String> {
    let attempt = |text: bool| -> Result<(), String> {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        draw(&root, text)?;
        root.present().map_err(|e| e.to_string())
    };
    attempt(true).or_else(|first| {
        attempt(false)
            .map_err(|second| format!("{}: {first}; without text: {second}", path.display()))
    })
}

fn span(vals: impl Iterator<Item = f64>, pad_one: bool) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        0.08 * (hi - lo)
    } else if pad_one {
        lo.abs().max(1.0) * 0.25
    } else {
        lo.abs().max(1.0) * 0.05
    };
    (lo - pad, hi + pad)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wilson's interval against its closed form at two textbook points (Newcombe 1998,
    /// table I: 81/263 → 0.2553–0.3662; 15/148 → 0.0624–0.1605), to 1e-4.
    #[test]
    fn wilson_matches_newcombe() {
        let (lo, hi) = wilson(81, 263);
        assert!(
            (lo - 0.2553).abs() < 1e-4 && (hi - 0.3662).abs() < 1e-4,
            "{lo} {hi}"
        );
        let (lo, hi) = wilson(15, 148);
        assert!(
            (lo - 0.0624).abs() < 1e-4 && (hi - 0.1605).abs() < 1e-4,
            "{lo} {hi}"
        );
        assert_eq!(wilson(0, 0), (0.0, 1.0));
    }

    /// The median held-out gain of a grid point: the mean of the two middle runs for
    /// an even count (numpy's `median` of [0.1, 0.2, 0.4, 0.8] is 0.3), the middle one
    /// for an odd count.
    #[test]
    fn median_of_sorted_is_the_textbook_median() {
        assert_eq!(median_of_sorted(&[]), None);
        assert_eq!(median_of_sorted(&[0.5]), Some(0.5));
        let even = median_of_sorted(&[0.1, 0.2, 0.4, 0.8]).unwrap();
        assert!((even - 0.3).abs() < 1e-15, "{even}");
        assert_eq!(median_of_sorted(&[0.1, 0.2, 0.4]), Some(0.2));
    }

    /// A sweep hiding nothing reports what was named as false alarms: of four runs one
    /// failed to simulate, one named friction and one reported `unexplained`, so 1 of 3
    /// diagnosed runs named a cause, with Wilson's interval of 1/3 (6–79 %); the failed
    /// run's zeros stay out of the session length and the margin to the wall.
    #[test]
    fn a_sweep_hiding_nothing_counts_its_false_alarms() {
        let sweep = SweepFile::from_toml(
            "name = \"quiet\"\nprotocol = \"reach-perturb\"\nseed = 1\n\
             [population]\nsubjects = 4\n[measure]\nestimate = false\ndiagnose = true\n",
            Path::new("quiet.toml"),
        )
        .unwrap();
        let header = super::super::table::header(&sweep);
        let row = |error: &str, causes: &str, unexplained: &str| {
            let ran = error.is_empty();
            header
                .iter()
                .map(|h| match h.as_str() {
                    "error" => error.to_owned(),
                    "causes" => causes.to_owned(),
                    "unexplained" => unexplained.to_owned(),
                    "point" | "trips" => "0".to_owned(),
                    "session_length_s" => if ran { "100" } else { "0" }.to_owned(),
                    "wall_margin_m" => if ran { "0.02" } else { "0" }.to_owned(),
                    "peak_command_n" => if ran { "40" } else { "0" }.to_owned(),
                    _ => String::new(),
                })
                .collect::<Vec<String>>()
        };
        let records = vec![
            header.clone(),
            row("", "none", "false"),
            row("", "rail-friction", "false"),
            row("", "none", "true"),
            row("plant: invalid config key", "", ""),
        ];
        let dir = tempfile::tempdir().unwrap();
        write(&sweep, &records, dir.path()).unwrap();
        let md = std::fs::read_to_string(dir.path().join("sweep.md")).unwrap();
        let (lo, hi) = wilson(1, 3);
        let line = format!(
            "| all | 4 | 3 | 1/3 | {:.0}–{:.0} % | rail-friction (1) | 1 |",
            100.0 * lo,
            100.0 * hi
        );
        assert!(md.contains(&line), "{line}\nnot in\n{md}");
        // The failed run's zeros are not in the session table: the three sessions ran
        // 100 s and came within 20 mm of the wall at the closest.
        let session = "| 0 | — | 4 | 100 | 20 | 40 | 0 | 1 |";
        assert!(md.contains(session), "{session}\nnot in\n{md}");
        assert!(
            (100.0 * lo).round() == 6.0 && (100.0 * hi).round() == 79.0,
            "{lo} {hi}"
        );
    }

    fn point(pulses: f64, sd: f64) -> [Precision; 8] {
        [Precision {
            pulses,
            bias: 0.0,
            sd,
            n: 8,
        }; 8]
    }

    /// Noise alone (sd ∝ 1/√pulses) fits a zero floor and the pulses a target needs
    /// follow 1/√n exactly: sd 10 at 8 pulses → ±1.96·10 at 8; ±9.8 (half) needs 32.
    #[test]
    fn a_pure_noise_error_needs_four_times_the_pulses_for_half_the_interval() {
        let points = vec![
            point(8.0, 10.0),
            point(16.0, 10.0 / 2f64.sqrt()),
            point(32.0, 5.0),
        ];
        let (a, b, assumed) = fit_floor(&points, 7);
        assert!(!assumed);
        assert!(a.abs() < 1e-9, "{a}");
        assert!((b - 800.0).abs() < 1e-6, "{b}");
        let needed = (b / (Z95 * 5.0 / Z95).powi(2)).ceil();
        assert_eq!(needed, 32.0);
    }

    /// A floor that more pulses cannot remove: sd² = 25 + 800/n. A target below
    /// 1.96·5 is said to be out of reach.
    #[test]
    fn a_floor_is_found_and_a_target_below_it_is_refused() {
        let points: Vec<_> = [8.0, 16.0, 32.0, 64.0]
            .iter()
            .map(|&n: &f64| point(n, (25.0 + 800.0 / n).sqrt()))
            .collect();
        let (a, b, _) = fit_floor(&points, 0);
        assert!(
            (a - 25.0).abs() < 1e-6 && (b - 800.0).abs() < 1e-6,
            "{a} {b}"
        );
    }
}
