//! `rigtwin inspect`: what is in a session, checked on the way (every file is read and
//! verified, so a clean `inspect` means the session reads).

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::session::{Amplitude, Manifest, Session, Trial, TrialEntry};
use serde::Serialize;

/// Summarise a session: its manifest, its channels and one line per trial (id, kind,
/// duration, samples, perturbation, peak hand force, path length). Reads and checks
/// every trial file; exits non-zero naming the file, line and field of the first fault.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin inspect ../shared/recordings/example-none
  rigtwin inspect ../shared/recordings/example-friction --json | jq '.trials[0]'
  rigtwin inspect ../shared/recordings/example-friction --rerun save=f.rrd  # also to the viewer
  rigtwin inspect out/reach-perturb-1/S01 --repair  # after a killed rehearsal

A run killed while recording leaves files beside the session (session.toml.tmp,
trials/NNNN.csv.partial, trials/NNNN.partial.toml). Readers ignore them and inspect lists
them. --repair lists every complete trial in the manifest, moves the trial that was being
recorded into set-aside/ unchanged (never deletes it) and removes copies that hold nothing
new.")]
pub struct Args {
    /// Session directory (holds session.toml and trials/).
    pub session: PathBuf,

    /// Print the summary as JSON instead of a table.
    #[arg(long)]
    pub json: bool,

    /// Finish the manifest of a killed session first: list complete trials, set the
    /// incomplete one aside (moved to set-aside/, never deleted).
    #[arg(long)]
    pub repair: bool,

    #[cfg(feature = "rerun")]
    #[command(flatten)]
    pub rerun: rigtwin::viz::RerunArgs,
}

/// One trial's line.
#[derive(Debug, Serialize)]
struct TrialSummary {
    id: u32,
    kind: String,
    file: String,
    samples: usize,
    duration_s: f64,
    perturbation: Option<PerturbationSummary>,
    peak_force_n: f64,
    path_length_m: f64,
}

#[derive(Debug, Serialize)]
struct PerturbationSummary {
    kind: String,
    onset_s: f64,
    duration_s: f64,
    angle_deg: f64,
    amplitude_n: Option<f64>,
    amplitude_m: Option<f64>,
}

#[derive(Debug, Serialize)]
struct Summary {
    session: PathBuf,
    source: &'static str,
    rate_hz: f64,
    /// The rig's axes (`axes` in the manifest).
    axes: &'static [&'static str],
    created: String,
    device_kind: String,
    mass_kg: [f64; 2],
    damping_n_s_per_m: [f64; 2],
    handle_mass_kg: Option<f64>,
    workspace_half_width_m: Option<f64>,
    subject_id: String,
    shoulder_m: [f64; 2],
    upper_arm_m: Option<f64>,
    forearm_m: Option<f64>,
    body_mass_kg: Option<f64>,
    /// Each column with the number of trials that have it.
    channels: Vec<(String, usize)>,
    trials: Vec<TrialSummary>,
    /// Files an interrupted run left beside the session (readers ignore them).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    leftovers: Vec<Leftover>,
}

/// A file an interrupted run left: what it is and how much is in it.
#[derive(Debug, Serialize)]
struct Leftover {
    file: PathBuf,
    what: &'static str,
    bytes: u64,
    /// Complete rows of a partial trial table (lines ending in a newline, less the header).
    complete_rows: Option<usize>,
}

/// Complete rows of a partial trial table: lines ended by `\n`, less the header. Counted
/// block by block, so a large table is never held in memory, and only in a regular file
/// of at most what a trial may be.
fn complete_rows(file: &std::path::Path) -> Option<usize> {
    use std::io::Read as _;
    let limit = rigtwin::session::files::MAX_TRIAL_BYTES;
    rigtwin::session::files::check_regular(file, limit, "a trial may have").ok()?;
    let mut reader = std::fs::File::open(file).ok()?.take(limit);
    let mut block = vec![0_u8; 1 << 16];
    let mut lines = 0_usize;
    loop {
        let n = reader.read(&mut block).ok()?;
        if n == 0 {
            return Some(lines.saturating_sub(1));
        }
        lines += block[..n].iter().filter(|&&c| c == b'\n').count();
    }
}

/// The leftovers of `dir`, each described.
fn leftovers(dir: &std::path::Path) -> anyhow::Result<Vec<Leftover>> {
    let files = rigtwin::session::leftovers(dir)
        .with_context(|| format!("listing leftovers in {}", dir.display()))?;
    let mut out = Vec::with_capacity(files.len());
    for file in files {
        let name = file.to_string_lossy().into_owned();
        let bytes = std::fs::symlink_metadata(&file).map_or(0, |m| m.len());
        let in_set_aside = file
            .parent()
            .and_then(|p| p.file_name())
            .is_some_and(|n| n == rigtwin::session::SET_ASIDE_DIR);
        let (what, complete_rows) = if name.contains(".csv.partial") {
            let rows = complete_rows(&file);
            let what = if in_set_aside {
                "incomplete trial table, set aside"
            } else {
                "incomplete trial table (the run was killed while recording it)"
            };
            (what, rows)
        } else if name.ends_with(".partial.toml") {
            ("manifest entry of an incomplete trial", None)
        } else if name.ends_with(".tmp") {
            ("manifest being replaced when the run stopped", None)
        } else {
            ("set aside by --repair", None)
        };
        out.push(Leftover {
            file,
            what,
            bytes,
            complete_rows,
        });
    }
    Ok(out)
}

fn summarise_trial(entry: &TrialEntry, trial: &Trial, rate_hz: f64) -> TrialSummary {
    TrialSummary {
        id: entry.id,
        kind: entry.kind.as_str().to_string(),
        file: entry.file.clone(),
        samples: trial.len(),
        duration_s: trial.len() as f64 / rate_hz,
        perturbation: entry.perturbation.as_ref().map(|p| PerturbationSummary {
            kind: p.kind.as_str().to_string(),
            onset_s: p.onset_s,
            duration_s: p.duration_s,
            angle_deg: p.angle_deg,
            amplitude_n: match p.amplitude {
                Amplitude::ForceN(a) => Some(a),
                Amplitude::PositionM(_) => None,
            },
            amplitude_m: match p.amplitude {
                Amplitude::PositionM(a) => Some(a),
                Amplitude::ForceN(_) => None,
            },
        }),
        peak_force_n: trial.peak_force_n(),
        path_length_m: trial.path_length_m(),
    }
}

fn summarise(args: &Args) -> anyhow::Result<Summary> {
    let reader = Session::open(&args.session)
        .with_context(|| format!("reading session {}", args.session.display()))?;
    let m: &Manifest = reader.manifest();
    let mut channels: Vec<(String, usize)> = Vec::new();
    let mut trials = Vec::with_capacity(m.trials.len());
    // One trial in memory at a time: sessions can be bigger than memory.
    for item in reader.trials() {
        let (entry, trial) =
            item.with_context(|| format!("reading session {}", args.session.display()))?;
        for (name, _) in trial.columns() {
            match channels.iter_mut().find(|(n, _)| n == name) {
                Some((_, count)) => *count += 1,
                None => channels.push((name.to_string(), 1)),
            }
        }
        trials.push(summarise_trial(entry, &trial, m.rate_hz));
    }
    Ok(Summary {
        session: args.session.clone(),
        source: m.source.as_str(),
        rate_hz: m.rate_hz,
        axes: m.axes.names(),
        created: m.created.clone(),
        device_kind: m.device.kind.clone(),
        mass_kg: m.device.mass_kg,
        damping_n_s_per_m: m.device.damping_n_s_per_m,
        handle_mass_kg: m.device.handle_mass_kg,
        workspace_half_width_m: m.device.workspace_half_width_m,
        subject_id: m.subject.id.clone(),
        shoulder_m: m.subject.shoulder_m,
        upper_arm_m: m.subject.upper_arm_m,
        forearm_m: m.subject.forearm_m,
        body_mass_kg: m.subject.body_mass_kg,
        channels,
        trials,
        leftovers: leftovers(&args.session)?,
    })
}

fn opt(label: &str, v: Option<f64>, unit: &str) -> String {
    v.map_or_else(String::new, |v| format!(", {label} {v} {unit}"))
}

fn render(s: &Summary) -> String {
    let mut out = String::new();
    let n = s.trials.len();
    let perturbed = s.trials.iter().filter(|t| t.perturbation.is_some()).count();
    let total_s: f64 = s.trials.iter().map(|t| t.duration_s).sum();
    let _ = writeln!(out, "session   {}", s.session.display());
    let _ = writeln!(
        out,
        "format    rig-session v1, source {}, {} Hz, created {}{}",
        s.source,
        s.rate_hz,
        s.created,
        if s.axes.len() == 2 {
            String::new()
        } else {
            format!(
                ", one axis ({}; the other's columns are zero)",
                s.axes.join("")
            )
        }
    );
    let _ = writeln!(
        out,
        "device    {}, mass [{}, {}] kg, damping [{}, {}] N s/m{}{}",
        s.device_kind,
        s.mass_kg[0],
        s.mass_kg[1],
        s.damping_n_s_per_m[0],
        s.damping_n_s_per_m[1],
        opt("handle", s.handle_mass_kg, "kg"),
        opt("workspace ±", s.workspace_half_width_m, "m").replace("± ", "±"),
    );
    let _ = writeln!(
        out,
        "subject   {}, shoulder [{}, {}] m{}{}{}",
        s.subject_id,
        s.shoulder_m[0],
        s.shoulder_m[1],
        opt("upper arm", s.upper_arm_m, "m"),
        opt("forearm", s.forearm_m, "m"),
        opt("body", s.body_mass_kg, "kg"),
    );
    let channels: Vec<String> = s
        .channels
        .iter()
        .map(|(name, count)| {
            if *count == n {
                name.clone()
            } else {
                format!("{name} ({count} of {n} trials)")
            }
        })
        .collect();
    let _ = writeln!(out, "channels  {}", channels.join(" "));
    let _ = writeln!(
        out,
        "trials    {n} ({perturbed} perturbed, {} unperturbed), {total_s:.1} s in all",
        n - perturbed
    );
    let _ = writeln!(out);
    let header = [
        "id",
        "kind",
        "duration_s",
        "samples",
        "angle_deg",
        "onset_s",
        "amplitude",
        "peak_|F|_N",
        "path_m",
    ];
    let rows: Vec<[String; 9]> = s
        .trials
        .iter()
        .map(|t| {
            let (angle, onset, amplitude) = match &t.perturbation {
                None => ("-".to_string(), "-".to_string(), "-".to_string()),
                Some(p) => (
                    format!("{:.1}", p.angle_deg),
                    format!("{:.6}", p.onset_s),
                    match (p.amplitude_n, p.amplitude_m) {
                        (Some(a), _) => format!("{a:.2} N"),
                        (_, Some(a)) => format!("{:.2} mm", a * 1e3),
                        _ => "-".to_string(),
                    },
                ),
            };
            [
                t.id.to_string(),
                t.kind.clone(),
                format!("{:.3}", t.duration_s),
                t.samples.to_string(),
                angle,
                onset,
                amplitude,
                format!("{:.2}", t.peak_force_n),
                format!("{:.4}", t.path_length_m),
            ]
        })
        .collect();
    let widths: Vec<usize> = (0..header.len())
        .map(|c| {
            rows.iter()
                .map(|r| r[c].chars().count())
                .chain([header[c].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: &[&str]| {
        let mut l = String::new();
        for (c, (cell, w)) in cells.iter().zip(&widths).enumerate() {
            // Text columns (kind) to the left, numbers to the right.
            let _ = if c == 1 {
                write!(l, "{cell:<w$}  ")
            } else {
                write!(l, "{cell:>w$}  ")
            };
        }
        l.trim_end().to_string()
    };
    let _ = writeln!(out, "{}", line(&header));
    for r in &rows {
        let cells: Vec<&str> = r.iter().map(String::as_str).collect();
        let _ = writeln!(out, "{}", line(&cells));
    }
    if !s.leftovers.is_empty() {
        let _ = writeln!(
            out,
            "\nleft by an interrupted run (readers ignore these; `rigtwin inspect --repair` lists complete trials and sets the rest aside):"
        );
        for l in &s.leftovers {
            let rows = l
                .complete_rows
                .map_or_else(String::new, |r| format!(", {r} complete rows"));
            let _ = writeln!(
                out,
                "  {}  {}, {} bytes{rows}",
                l.file.display(),
                l.what,
                l.bytes
            );
        }
    }
    out
}

/// Runs `rigtwin inspect`.
///
/// # Errors
/// The session does not read (the message names file, line and field).
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.repair {
        let done = rigtwin::session::repair(&args.session)
            .with_context(|| format!("repairing session {}", args.session.display()))?;
        let ids: Vec<String> = done.listed.iter().map(u32::to_string).collect();
        errln!(
            "repaired: {} trial(s) listed{}, {} file(s) set aside, {} copy(ies) removed",
            done.listed.len(),
            if ids.is_empty() {
                String::new()
            } else {
                format!(" ({})", ids.join(", "))
            },
            done.set_aside.len(),
            done.removed.len()
        );
        for f in &done.set_aside {
            errln!("  set aside: {}", f.display());
        }
    }
    let summary = summarise(args)?;
    if args.json {
        let text =
            serde_json::to_string_pretty(&summary).context("formatting the summary as JSON")?;
        outln!("{text}");
    } else {
        out!("{}", render(&summary));
    }
    #[cfg(feature = "rerun")]
    if let Some(target) = &args.rerun.rerun {
        let session = Session::read(&args.session)
            .with_context(|| format!("reading session {}", args.session.display()))?;
        let streamed = super::view::stream_session(
            target,
            &session,
            rigtwin::viz::DEFAULT_LIVE_RATE_HZ,
            &rigtwin::protocol::EstimateConfig::default(),
            None,
        )?;
        super::view::report_streamed(&streamed, target, args.json)?;
    }
    Ok(())
}
