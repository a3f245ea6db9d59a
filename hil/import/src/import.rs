//! [`import`]: logs and a map in, a session out.

use std::fmt;
use std::path::{Path, PathBuf};

use rigtwin_session::{
    Amplitude, Axes, Manifest, Perturbation, PerturbationKind, SessionWriter, Source, Subject,
    Trial, TrialMeta,
};

use crate::error::{ImportError, MapAt};
use crate::log::{Log, UniformFit, time_tolerance, uniform_rate};
use crate::map::{CHANNELS, Cut, Map, Onsets, PerturbationFrom, SourceRef, Time};

/// A session column and where its samples came from.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedChannel {
    /// The session column (`x_m`).
    pub column: String,
    /// The log variable or CSV column.
    pub var: String,
    /// The matrix column, 1-based, when the variable is a matrix.
    pub var_column: Option<usize>,
    /// `value = raw * scale + offset`.
    pub scale: f64,
    /// `value = raw * scale + offset`, SI.
    pub offset: f64,
    /// The raw unit the map states (documentation only).
    pub unit: Option<String>,
}

/// A session column written as zeros, and why that is allowed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ZeroedChannel {
    /// The session column.
    pub column: String,
    /// Why: the axis is absent, the device has no force sensor, or the map names no
    /// perturbation channel.
    pub reason: String,
}

/// What [`import`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Imported {
    /// The session directory.
    pub dir: PathBuf,
    /// The logs read, in order.
    pub files: Vec<PathBuf>,
    /// Sampling rate of every trial, Hz.
    pub rate_hz: f64,
    /// The rig's axes.
    pub axes: Axes,
    /// Samples in each trial, in trial order (trial ids are 1, 2, …).
    pub samples: Vec<usize>,
    /// Trials with a perturbation entry.
    pub perturbed: usize,
    /// Session columns given by the map.
    pub mapped: Vec<MappedChannel>,
    /// Required session columns written as zeros.
    pub zeroed: Vec<ZeroedChannel>,
}

impl Imported {
    /// Number of trials written.
    #[must_use]
    pub fn trials(&self) -> usize {
        self.samples.len()
    }
}

impl fmt::Display for Imported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let files: Vec<String> = self.files.iter().map(|p| p.display().to_string()).collect();
        writeln!(
            f,
            "wrote {}: {} trial{} at {} Hz, axes {}, from {}",
            self.dir.display(),
            self.trials(),
            if self.trials() == 1 { "" } else { "s" },
            self.rate_hz,
            self.axes.names().join(", "),
            files.join(", ")
        )?;
        let min = self.samples.iter().min().copied().unwrap_or(0);
        let max = self.samples.iter().max().copied().unwrap_or(0);
        if min == max {
            writeln!(
                f,
                "  samples per trial: {min} ({} s)",
                min as f64 / self.rate_hz
            )?;
        } else {
            writeln!(
                f,
                "  samples per trial: {min} to {max} ({} to {} s)",
                min as f64 / self.rate_hz,
                max as f64 / self.rate_hz
            )?;
        }
        writeln!(f, "  perturbed trials: {}", self.perturbed)?;
        writeln!(f, "  channels:")?;
        let w = self
            .mapped
            .iter()
            .map(|m| m.column.len())
            .chain(self.zeroed.iter().map(|z| z.column.len()))
            .max()
            .unwrap_or(0);
        for m in &self.mapped {
            let col = m
                .var_column
                .map(|c| format!(" column {c}"))
                .unwrap_or_default();
            let unit = m
                .unit
                .as_ref()
                .map(|u| format!(" [{u}]"))
                .unwrap_or_default();
            let mut affine = String::new();
            if m.scale != 1.0 {
                affine.push_str(&format!(" × {}", m.scale));
            }
            if m.offset != 0.0 {
                affine.push_str(&format!(" + {}", m.offset));
            }
            writeln!(f, "    {:w$} = {}{col}{unit}{affine}", m.column, m.var)?;
        }
        for z in &self.zeroed {
            writeln!(f, "    {:w$} = 0 ({})", z.column, z.reason)?;
        }
        Ok(())
    }
}

/// One file's trials, ready to write.
struct Cutout {
    trials: Vec<Trial>,
    /// The file's sampling rate, Hz.
    rate_hz: f64,
}

/// Whether `out` may be written: absent, or an empty directory.
fn check_out(out: &Path) -> Result<(), ImportError> {
    match std::fs::read_dir(out) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                Err(ImportError::OutputNotEmpty {
                    dir: out.to_path_buf(),
                })
            } else {
                Ok(())
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(_) if out.exists() => Err(ImportError::OutputNotEmpty {
            dir: out.to_path_buf(),
        }),
        Err(e) => Err(ImportError::Io {
            file: out.to_path_buf(),
            source: e,
        }),
    }
}

/// Reads the logs `files` (each a `.mat` or a CSV/TSV log), cuts each into trials as the
/// map at `map` says, and writes them, numbered 1, 2, … across the files in order, as a
/// new session in `out` (`source = "rig"`). Everything is read and checked before
/// anything is written; the same inputs give the same bytes.
///
/// # Errors
/// Any [`ImportError`]: a map fault names the map file, line and key; a log fault names
/// the log file, the variable (and line, for text) and the map key that uses it;
/// [`ImportError::OutputNotEmpty`] if `out` exists and is not an empty directory.
pub fn import(files: &[PathBuf], map: &Path, out: &Path) -> Result<Imported, ImportError> {
    let map = Map::read(map)?;
    check_out(out)?;
    if files.is_empty() {
        return Err(ImportError::NoInput);
    }
    let (zeroed, zero_cols) = zeroed_channels(&map)?;
    let mut cutouts: Vec<Cutout> = Vec::new();
    let mut first_rate: Option<(PathBuf, f64)> = None;
    for file in files {
        let log = crate::read::read_log(file, &map.csv)?;
        let c = cut_file(&log, &map, &zero_cols)?;
        if let Some((first, r)) = &first_rate {
            if ((c.rate_hz - r) / r).abs() > 1e-6 {
                let at = match &map.time {
                    Time::Var(s) => s.at.clone(),
                    Time::Rate(_) => MapAt::default(),
                };
                return Err(ImportError::RateMismatch {
                    file: file.clone(),
                    rate_hz: c.rate_hz,
                    first: first.clone(),
                    first_rate_hz: *r,
                    at,
                });
            }
        } else {
            first_rate = Some((file.clone(), c.rate_hz));
        }
        cutouts.push(c);
    }
    let rate_hz = first_rate.map_or(1.0, |(_, r)| r);
    let trials: Vec<Trial> = cutouts.into_iter().flat_map(|c| c.trials).collect();
    let perturbations = perturbations(&map, &trials, rate_hz)?;

    let subject_id = map.subject_id.clone().unwrap_or_else(|| {
        files[0]
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "subject".into())
    });
    let manifest = Manifest {
        source: Source::Rig,
        rate_hz,
        axes: map.axes,
        created: map.created.clone(),
        device: map.device.clone(),
        subject: Subject {
            id: subject_id,
            shoulder_m: map.shoulder_m,
            upper_arm_m: map.upper_arm_m,
            forearm_m: map.forearm_m,
            body_mass_kg: map.body_mass_kg,
            extra: std::collections::BTreeMap::new(),
        },
        sim: None,
        timing: None,
        trials: Vec::new(),
    };
    let mut writer = SessionWriter::create(out, manifest)?;
    let mut samples = Vec::with_capacity(trials.len());
    let mut perturbed = 0;
    for (k, (trial, pert)) in trials.iter().zip(perturbations).enumerate() {
        perturbed += usize::from(pert.is_some());
        let id = u32::try_from(k + 1).unwrap_or(u32::MAX);
        writer.write_trial(
            TrialMeta {
                id,
                kind: map.trial_kind.clone(),
                start_m: None,
                goal_m: None,
                perturbation: pert,
            },
            trial,
        )?;
        samples.push(trial.len());
    }
    writer.finish()?;
    let mapped = map
        .channels
        .iter()
        .map(|(c, s)| MappedChannel {
            column: (*c).to_string(),
            var: s.var.clone(),
            var_column: s.column,
            scale: s.scale,
            offset: s.offset,
            unit: s.unit.clone(),
        })
        .collect();
    Ok(Imported {
        dir: out.to_path_buf(),
        files: files.to_vec(),
        rate_hz,
        axes: map.axes,
        samples,
        perturbed,
        mapped,
        zeroed,
    })
}

/// The required columns the map does not give, each allowed as zeros or an error.
fn zeroed_channels(map: &Map) -> Result<(Vec<ZeroedChannel>, Vec<&'static str>), ImportError> {
    let mut zeroed = Vec::new();
    let pert_channel = matches!(
        map.perturbation.as_ref().map(|p| &p.from),
        Some(PerturbationFrom::Channel { .. })
    );
    for (col, axis) in CHANNELS.iter().take(6) {
        if map.channels.iter().any(|(c, _)| c == col) {
            continue;
        }
        let is_force = col.starts_with('f');
        let is_pert = col.starts_with("pert_");
        let reason = if !map.axes.has(*axis) {
            Some(format!("the rig has no {} axis", ["x", "y"][*axis]))
        } else if is_force && !map.force_sensor {
            Some("device.force_sensor = false".to_string())
        } else if is_pert && !pert_channel {
            Some(
                "no perturbation channel: [perturbation] is absent or from = \"table\"".to_string(),
            )
        } else {
            None
        };
        match reason {
            Some(reason) => zeroed.push(ZeroedChannel {
                column: (*col).to_string(),
                reason,
            }),
            None => {
                let reason = if is_force {
                    "map it, or set `force_sensor = false` in [device] if the rig has no force sensor"
                } else if is_pert {
                    "map it: [perturbation] from = \"channel\" reads the perturbation from it"
                } else {
                    "map it, or list only the rig's axes in `axes`"
                };
                return Err(ImportError::MissingChannel {
                    column: (*col).to_string(),
                    reason: reason.to_string(),
                    at: MapAt {
                        key: format!("channels.{col}"),
                        ..map.channels_at.clone()
                    },
                });
            }
        }
    }
    let cols = zeroed
        .iter()
        .filter_map(|z| {
            CHANNELS
                .iter()
                .find(|(c, _)| *c == z.column)
                .map(|(c, _)| *c)
        })
        .collect();
    Ok((zeroed, cols))
}

/// Reads every source the map names from one log, checks lengths, and cuts the trials.
fn cut_file(log: &Log, map: &Map, zero_cols: &[&'static str]) -> Result<Cutout, ImportError> {
    // The first source read sets the length every other must have.
    let mut first: Option<(String, String, usize)> = None;
    let mut read = |src: &SourceRef| -> Result<Vec<f64>, ImportError> {
        let raw = log.channel(src)?;
        match &first {
            None => first = Some((src.var.clone(), src.at.key.clone(), raw.len())),
            Some((var, key, n)) if *n != raw.len() => {
                return Err(ImportError::LengthMismatch {
                    file: log.path.clone(),
                    var: src.var.clone(),
                    len: raw.len(),
                    at: src.at.clone(),
                    other_var: var.clone(),
                    other_key: key.clone(),
                    other_len: *n,
                });
            }
            Some(_) => {}
        }
        Ok(src.apply(&raw))
    };

    let mut columns: Vec<(&'static str, Vec<f64>)> = Vec::new();
    for (col, src) in &map.channels {
        columns.push((col, read(src)?));
    }
    // The log's clock: (rate, time of its first sample).
    let (rate_hz, t0) = match &map.time {
        Time::Rate(r) => (*r, 0.0),
        Time::Var(src) => {
            let t = read(src)?;
            let decimals = if log.row_lines.is_some() {
                log.decimals(&src.var)
            } else {
                None
            };
            match uniform_rate(&t, time_tolerance(decimals, src.scale)) {
                UniformFit::Rate(r) => (r, t[0]),
                UniformFit::TooShort => {
                    return Err(ImportError::WrongShape {
                        file: log.path.clone(),
                        var: src.var.clone(),
                        shape: "1 sample".into(),
                        message: "a time vector needs at least two samples".into(),
                        at: src.at.clone(),
                    });
                }
                UniformFit::Off {
                    index,
                    expected_s,
                    found_s,
                } => {
                    return Err(ImportError::NonUniformTime {
                        file: log.path.clone(),
                        var: src.var.clone(),
                        sample: log.sample_at(index),
                        expected_s,
                        found_s,
                        at: src.at.clone(),
                    });
                }
            }
        }
    };
    let marker = match &map.cut {
        Cut::Marker { source, .. } => Some(read(source)?),
        _ => None,
    };
    let n = first.as_ref().map_or(0, |f| f.2);
    if n == 0 {
        return Err(ImportError::MissingChannel {
            column: "x_m".into(),
            reason: "the map gives no channel".into(),
            at: map.channels_at.clone(),
        });
    }
    let ranges = cut_ranges(log, map, &columns, marker.as_deref(), rate_hz, t0, n)?;

    let get = |name: &str| columns.iter().find(|(c, _)| *c == name).map(|(_, v)| v);
    let mut trials = Vec::with_capacity(ranges.len());
    for (a, b) in ranges {
        let slice = |name: &str| -> Option<Vec<f64>> { get(name).map(|v| v[a..b].to_vec()) };
        let zeros = vec![0.0; b - a];
        let required = |name: &str| -> Vec<f64> {
            slice(name).unwrap_or_else(|| {
                debug_assert!(zero_cols.contains(&name));
                zeros.clone()
            })
        };
        // Optional pairs: the present axis's member as mapped; on a one-axis rig the
        // absent axis's member is written as zeros alongside it.
        let optional = |x: &str, y: &str| -> (Option<Vec<f64>>, Option<Vec<f64>>) {
            let (sx, sy) = (slice(x), slice(y));
            match map.axes {
                Axes::Both => (sx, sy),
                Axes::X => {
                    let z = sx.as_ref().map(|_| zeros.clone());
                    (sx, z)
                }
                Axes::Y => {
                    let z = sy.as_ref().map(|_| zeros.clone());
                    (z, sy)
                }
            }
        };
        let (vx, vy) = optional("vx_m_per_s", "vy_m_per_s");
        let (rx, ry) = optional("ref_x_m", "ref_y_m");
        let (cx, cy) = optional("cmd_fx_n", "cmd_fy_n");
        trials.push(Trial {
            t_s: (0..b - a).map(|i| i as f64 / rate_hz).collect(),
            x_m: required("x_m"),
            y_m: required("y_m"),
            fx_n: required("fx_n"),
            fy_n: required("fy_n"),
            pert_fx_n: required("pert_fx_n"),
            pert_fy_n: required("pert_fy_n"),
            vx_m_per_s: vx,
            vy_m_per_s: vy,
            ref_x_m: rx,
            ref_y_m: ry,
            cmd_fx_n: cx,
            cmd_fy_n: cy,
            extra: Vec::new(),
        });
    }
    Ok(Cutout { trials, rate_hz })
}

/// Samples of `s` seconds at `rate_hz`.
fn samples(s: f64, rate_hz: f64) -> usize {
    let n = (s * rate_hz).round();
    if n.is_finite() && n > 0.0 {
        // A finite positive count of samples of a log that fits in memory.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let n = n as usize;
        n
    } else {
        0
    }
}

/// The trials' sample ranges `[a, b)` in a log of `n` samples.
#[allow(clippy::too_many_arguments)]
fn cut_ranges(
    log: &Log,
    map: &Map,
    columns: &[(&'static str, Vec<f64>)],
    marker: Option<&[f64]>,
    rate_hz: f64,
    t0: f64,
    n: usize,
) -> Result<Vec<(usize, usize)>, ImportError> {
    let log_end_s = (n - 1) as f64 / rate_hz;
    let outside = |trial: usize, a: f64, b: f64, at: &MapAt| ImportError::TrialOutsideLog {
        file: log.path.clone(),
        trial,
        start_s: a,
        end_s: b,
        log_end_s,
        at: at.clone(),
    };
    // Trials from start indices: to the next start, or `length` samples.
    let from_starts = |starts: &[usize],
                       length_s: Option<f64>,
                       at: &MapAt|
     -> Result<Vec<(usize, usize)>, ImportError> {
        let mut out = Vec::with_capacity(starts.len());
        for (k, &a) in starts.iter().enumerate() {
            let b = match length_s {
                Some(l) => a + samples(l, rate_hz).max(1),
                None => starts.get(k + 1).copied().unwrap_or(n),
            };
            if b > n {
                return Err(outside(k + 1, a as f64 / rate_hz, b as f64 / rate_hz, at));
            }
            out.push((a, b));
        }
        Ok(out)
    };
    match &map.cut {
        Cut::Whole => Ok(vec![(0, n)]),
        Cut::Marker {
            source,
            above,
            length_s,
        } => {
            let m = marker.unwrap_or(&[]);
            // A log that starts with the marker high starts with a trial (a logger
            // armed by the trigger itself).
            let starts: Vec<usize> = (0..m.len())
                .filter(|&i| m[i] > *above && (i == 0 || m[i - 1] <= *above))
                .collect();
            if starts.is_empty() {
                return Err(ImportError::MarkerNeverRises {
                    file: log.path.clone(),
                    var: source.var.clone(),
                    above: *above,
                    at: source.at.clone(),
                });
            }
            from_starts(&starts, *length_s, &source.at)
        }
        Cut::Onsets { onsets, length_s } => {
            let (times, at) = match onsets {
                Onsets::Table(v, at) => (v.clone(), at.clone()),
                Onsets::Var(src) => {
                    let raw = log.channel(src)?;
                    (src.apply(&raw), src.at.clone())
                }
            };
            let mut starts = Vec::with_capacity(times.len());
            for (k, &t) in times.iter().enumerate() {
                let i = (t - t0) * rate_hz;
                let idx = i.round();
                if !(idx >= 0.0 && idx < n as f64) {
                    return Err(outside(k + 1, t - t0, t - t0, &at));
                }
                #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                let idx = idx as usize;
                if let Some(&prev) = starts.last()
                    && idx <= prev
                {
                    return Err(ImportError::MapValue {
                        map: at.map.clone(),
                        line: at.line,
                        key: at.key.clone(),
                        message: format!(
                            "onset {} ({t} s) does not come after the one before it",
                            k + 1
                        ),
                    });
                }
                starts.push(idx);
            }
            from_starts(&starts, *length_s, &at)
        }
        Cut::Threshold {
            channel,
            speed_above,
            before_s,
            length_s,
            at,
        } => {
            let x = columns
                .iter()
                .find(|(c, _)| c == channel)
                .map(|(_, v)| v.as_slice())
                .unwrap_or(&[]);
            let before = samples(*before_s, rate_hz);
            let length = samples(*length_s, rate_hz).max(1);
            let fast = |i: usize| (x[i] - x[i - 1]).abs() * rate_hz > *speed_above;
            let mut out = Vec::new();
            let mut i = 1;
            while i < x.len() {
                if fast(i) {
                    let k = out.len() + 1;
                    let Some(a) = i.checked_sub(before) else {
                        return Err(outside(
                            k,
                            i as f64 / rate_hz - before_s,
                            (i - before + length) as f64 / rate_hz,
                            at,
                        ));
                    };
                    let b = a + length;
                    if b > n {
                        return Err(outside(k, a as f64 / rate_hz, b as f64 / rate_hz, at));
                    }
                    out.push((a, b));
                    // The next movement starts after this trial and after the speed
                    // has fallen back below the threshold.
                    i = b.max(i + 1);
                    while i < x.len() && fast(i) {
                        i += 1;
                    }
                } else {
                    i += 1;
                }
            }
            if out.is_empty() {
                return Err(ImportError::NoMovement {
                    file: log.path.clone(),
                    channel: (*channel).to_string(),
                    speed_above: *speed_above,
                    at: at.clone(),
                });
            }
            Ok(out)
        }
    }
}

/// Each trial's perturbation entry, from the channel or the map's table.
fn perturbations(
    map: &Map,
    trials: &[Trial],
    rate_hz: f64,
) -> Result<Vec<Option<Perturbation>>, ImportError> {
    let Some(spec) = &map.perturbation else {
        return Ok(vec![None; trials.len()]);
    };
    let kind = PerturbationKind::from(spec.kind.clone());
    match &spec.from {
        PerturbationFrom::Channel { above_n } => Ok(trials
            .iter()
            .map(|t| {
                let mag: Vec<f64> = t
                    .pert_fx_n
                    .iter()
                    .zip(&t.pert_fy_n)
                    .map(|(x, y)| x.hypot(*y))
                    .collect();
                let onset = mag.iter().position(|m| m > above_n)?;
                let end = mag[onset..]
                    .iter()
                    .position(|m| m <= above_n)
                    .map_or(mag.len(), |k| onset + k);
                let (peak, _) = mag[onset..end].iter().enumerate().fold(
                    (onset, 0.0_f64),
                    |(bi, bm), (k, &m)| {
                        if m > bm { (onset + k, m) } else { (bi, bm) }
                    },
                );
                Some(Perturbation {
                    kind: kind.clone(),
                    onset_s: onset as f64 / rate_hz,
                    duration_s: (end - onset) as f64 / rate_hz,
                    amplitude: Amplitude::ForceN(mag[peak]),
                    angle_deg: t.pert_fy_n[peak].atan2(t.pert_fx_n[peak]).to_degrees(),
                })
            })
            .collect()),
        PerturbationFrom::Table(table) => {
            if table.onset_s.len() != trials.len() {
                let at = &table.at[0];
                return Err(ImportError::MapValue {
                    map: at.map.clone(),
                    line: at.line,
                    key: at.key.clone(),
                    message: format!(
                        "{} values, but the logs were cut into {} trials (one value per trial)",
                        table.onset_s.len(),
                        trials.len()
                    ),
                });
            }
            let mut out = Vec::with_capacity(trials.len());
            for (k, t) in trials.iter().enumerate() {
                let amplitude = table.amplitude_n[k];
                if amplitude == 0.0 {
                    out.push(None);
                    continue;
                }
                let onset = table.onset_s[k];
                let end_s = t.len() as f64 / rate_hz;
                if !(0.0..end_s).contains(&onset) {
                    let at = &table.at[0];
                    return Err(ImportError::MapValue {
                        map: at.map.clone(),
                        line: at.line,
                        key: at.key.clone(),
                        message: format!(
                            "trial {}: onset {onset} s is outside the trial (0 to {end_s} s)",
                            k + 1
                        ),
                    });
                }
                let duration = table.duration_s[k];
                if duration <= 0.0 {
                    let at = &table.at[1];
                    return Err(ImportError::MapValue {
                        map: at.map.clone(),
                        line: at.line,
                        key: at.key.clone(),
                        message: format!(
                            "trial {}: a perturbed trial (amplitude {amplitude} N) needs a duration > 0",
                            k + 1
                        ),
                    });
                }
                out.push(Some(Perturbation {
                    kind: kind.clone(),
                    onset_s: onset,
                    duration_s: duration,
                    amplitude: Amplitude::ForceN(amplitude),
                    angle_deg: table.angle_deg[k],
                }));
            }
            Ok(out)
        }
    }
}
