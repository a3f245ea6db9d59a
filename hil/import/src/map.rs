//! The map file: how a lab's log becomes a session (see the crate documentation for
//! every key). Parsed in two steps: serde with `deny_unknown_fields` into raw tables
//! whose values keep their spans, then checks that turn them into a [`Map`]; every
//! error names the map file, the line and the key path.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use rigtwin_session::{Axes, Device, TrialKind};
use serde::Deserialize;
use toml::Spanned;

use crate::error::{ImportError, MapAt};

/// The session columns a map may give, with the axis (0 = x, 1 = y) each belongs to,
/// in the order the session writes them.
pub(crate) const CHANNELS: [(&str, usize); 12] = [
    ("x_m", 0),
    ("y_m", 1),
    ("fx_n", 0),
    ("fy_n", 1),
    ("pert_fx_n", 0),
    ("pert_fy_n", 1),
    ("vx_m_per_s", 0),
    ("vy_m_per_s", 1),
    ("ref_x_m", 0),
    ("ref_y_m", 1),
    ("cmd_fx_n", 0),
    ("cmd_fy_n", 1),
];

/// The map's required top-level tables.
const TOP_LEVEL: [&str; 4] = ["time", "channels", "device", "trials"];

/// The default of `created`: a fixed instant, so that output never depends on the clock.
pub const DEFAULT_CREATED: &str = "1970-01-01T00:00:00Z";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMap {
    created: Option<Spanned<toml::Value>>,
    axes: Option<Spanned<Vec<String>>>,
    time: Spanned<RawTime>,
    csv: Option<RawCsv>,
    channels: BTreeMap<String, Spanned<RawSource>>,
    device: Spanned<RawDevice>,
    subject: Option<RawSubject>,
    trials: Spanned<RawTrials>,
    perturbation: Option<Spanned<RawPerturbation>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTime {
    rate_hz: Option<Spanned<f64>>,
    var: Option<Spanned<String>>,
    column: Option<Spanned<i64>>,
    scale: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCsv {
    delimiter: Option<Spanned<String>>,
    header: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSource {
    var: Spanned<String>,
    column: Option<Spanned<i64>>,
    scale: Option<Spanned<f64>>,
    offset: Option<Spanned<f64>>,
    unit: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDevice {
    kind: String,
    mass_kg: Spanned<Vec<f64>>,
    damping_n_s_per_m: Spanned<Vec<f64>>,
    handle_mass_kg: Option<Spanned<f64>>,
    workspace_half_width_m: Option<Spanned<f64>>,
    force_sensor: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSubject {
    id: Option<String>,
    shoulder_m: Option<Spanned<Vec<f64>>>,
    upper_arm_m: Option<Spanned<f64>>,
    forearm_m: Option<Spanned<f64>>,
    body_mass_kg: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTrials {
    cut: Spanned<String>,
    kind: Option<String>,
    marker: Option<Spanned<RawMarker>>,
    onsets_s: Option<Spanned<Vec<f64>>>,
    onsets: Option<Spanned<RawSource>>,
    length_s: Option<Spanned<f64>>,
    threshold: Option<Spanned<RawThreshold>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMarker {
    var: Spanned<String>,
    column: Option<Spanned<i64>>,
    above: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawThreshold {
    channel: Spanned<String>,
    speed_above: Spanned<f64>,
    before_s: Option<Spanned<f64>>,
    length_s: Spanned<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPerturbation {
    from: Spanned<String>,
    kind: Option<String>,
    above_n: Option<Spanned<f64>>,
    onset_s: Option<Spanned<Vec<f64>>>,
    duration_s: Option<Spanned<Vec<f64>>>,
    amplitude_n: Option<Spanned<Vec<f64>>>,
    angle_deg: Option<Spanned<Vec<f64>>>,
}

/// Where a channel's samples come from: a variable (or column) of the log, and the
/// affine map into SI units `value = raw * scale + offset`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SourceRef {
    pub var: String,
    /// 1-based column (or row, for a k×N matrix) of a matrix.
    pub column: Option<usize>,
    pub scale: f64,
    pub offset: f64,
    pub unit: Option<String>,
    /// The map key that names it.
    pub at: MapAt,
}

impl SourceRef {
    pub(crate) fn apply(&self, raw: &[f64]) -> Vec<f64> {
        raw.iter().map(|v| v * self.scale + self.offset).collect()
    }
}

/// How the log's clock is known.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Time {
    /// `time.rate_hz`.
    Rate(f64),
    /// `time.var`, in seconds after `scale`.
    Var(SourceRef),
}

/// How text logs are split.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct CsvOptions {
    /// `csv.delimiter`; sniffed when `None`.
    pub delimiter: Option<u8>,
    /// `csv.header`; sniffed when `None`.
    pub header: Option<bool>,
}

/// How the log is cut into trials.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Cut {
    Whole,
    Marker {
        source: SourceRef,
        above: f64,
        length_s: Option<f64>,
    },
    Onsets {
        onsets: Onsets,
        length_s: Option<f64>,
    },
    Threshold {
        channel: &'static str,
        speed_above: f64,
        before_s: f64,
        length_s: f64,
        at: MapAt,
    },
}

/// Trial onsets: listed in the map, or a variable of the log.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Onsets {
    /// Onsets, s, and the key that lists them.
    Table(Vec<f64>, MapAt),
    Var(SourceRef),
}

/// How each trial's perturbation is known.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum PerturbationFrom {
    Channel { above_n: f64 },
    Table(Box<PerturbationTable>),
}

/// `from = "table"`: one value per trial in each list.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PerturbationTable {
    pub onset_s: Vec<f64>,
    pub duration_s: Vec<f64>,
    pub amplitude_n: Vec<f64>,
    pub angle_deg: Vec<f64>,
    /// Keys of the four lists, in that order.
    pub at: [MapAt; 4],
}

/// `[perturbation]`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PerturbationSpec {
    pub from: PerturbationFrom,
    pub kind: String,
    pub at: MapAt,
}

/// A parsed and checked map file: how a lab's log becomes a session. The keys are
/// documented in the crate documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct Map {
    pub(crate) path: PathBuf,
    pub(crate) created: String,
    pub(crate) axes: Axes,
    pub(crate) time: Time,
    pub(crate) csv: CsvOptions,
    /// Session column → source, in session column order.
    pub(crate) channels: Vec<(&'static str, SourceRef)>,
    pub(crate) device: Device,
    pub(crate) force_sensor: bool,
    pub(crate) subject_id: Option<String>,
    pub(crate) shoulder_m: [f64; 2],
    pub(crate) upper_arm_m: Option<f64>,
    pub(crate) forearm_m: Option<f64>,
    pub(crate) body_mass_kg: Option<f64>,
    pub(crate) cut: Cut,
    pub(crate) trial_kind: TrialKind,
    pub(crate) perturbation: Option<PerturbationSpec>,
    /// `[channels]` table, for errors about channels it lacks.
    pub(crate) channels_at: MapAt,
    /// `[device]` table.
    pub(crate) device_at: MapAt,
}

/// Maps byte offsets of the map's text to lines and key paths.
struct Locator<'a> {
    text: &'a str,
    file: &'a Path,
}

impl Locator<'_> {
    fn line(&self, at: usize) -> usize {
        let at = at.min(self.text.len());
        1 + self.text.as_bytes()[..at]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    fn line_text(&self, line: usize) -> &str {
        self.text.lines().nth(line.saturating_sub(1)).unwrap_or("")
    }

    /// The table header in force at `line`, empty at top level.
    fn table_at(&self, line: usize) -> String {
        (1..=line)
            .rev()
            .map(|l| self.line_text(l).trim())
            .find(|t| t.starts_with('['))
            .map(|t| {
                t.trim_start_matches('[')
                    .split(']')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .to_string()
            })
            .unwrap_or_default()
    }

    /// The key path at `line`: table, the line's own key, and `inner` when the fault
    /// is a key inside an inline table on that line.
    fn key_at(&self, line: usize, inner: Option<&str>) -> String {
        let table = self.table_at(line);
        let text = self.line_text(line).trim();
        let own = if text.starts_with('[') {
            None
        } else {
            text.split_once('=')
                .map(|(k, _)| k.trim().trim_matches('"').trim_matches('\'').to_string())
        };
        let mut parts: Vec<String> = Vec::new();
        if !table.is_empty() {
            parts.push(table);
        }
        match (own, inner) {
            (Some(o), Some(i)) if o != i => {
                parts.push(o);
                parts.push(i.to_string());
            }
            (Some(o), _) => parts.push(o),
            (None, Some(i)) => parts.push(i.to_string()),
            (None, None) => {}
        }
        parts.join(".")
    }

    fn at(&self, span: &Range<usize>) -> MapAt {
        let line = self.line(span.start);
        MapAt {
            map: self.file.to_path_buf(),
            line,
            key: self.key_at(line, None),
        }
    }

    /// `at` with an explicit key path.
    fn at_key(&self, span: &Range<usize>, key: &str) -> MapAt {
        MapAt {
            map: self.file.to_path_buf(),
            line: self.line(span.start),
            key: key.to_string(),
        }
    }

    fn invalid(&self, at: &MapAt, message: impl Into<String>) -> ImportError {
        ImportError::MapValue {
            map: at.map.clone(),
            line: at.line,
            key: at.key.clone(),
            message: message.into(),
        }
    }

    fn toml_error(&self, e: &toml::de::Error) -> ImportError {
        let start = e.span().map_or(0, |s| s.start);
        let line = self.line(start);
        let line_start = self.text[..start.min(self.text.len())]
            .rfind('\n')
            .map_or(0, |i| i + 1);
        let column = 1 + self
            .text
            .get(line_start..start)
            .map_or(0, |s| s.chars().count());
        let message = e.message().trim().to_string();
        let quoted = message.split('`').nth(1);
        let map = self.file.to_path_buf();
        if message.starts_with("missing field") {
            // A missing table of the document is reported at the document's span.
            if let Some(q) = quoted
                && TOP_LEVEL.contains(&q)
            {
                return ImportError::MapMissingKey {
                    map,
                    line: 1,
                    key: q.to_string(),
                };
            }
            return ImportError::MapMissingKey {
                map,
                line,
                key: self.key_at(line, quoted),
            };
        }
        if message.starts_with("unknown field") {
            return ImportError::MapUnknownKey {
                map,
                line,
                key: self.key_at(line, quoted),
                allowed: message
                    .split_once(", ")
                    .map_or("", |(_, rest)| rest)
                    .to_string(),
            };
        }
        ImportError::MapSyntax {
            map,
            line,
            column,
            key: self.key_at(line, None),
            message,
        }
    }

    fn finite(&self, v: &Spanned<f64>, what: &str) -> Result<f64, ImportError> {
        let x = *v.get_ref();
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(
                &self.at(&v.span()),
                format!("{what} must be finite, found {x}"),
            ))
        }
    }

    fn positive(&self, v: &Spanned<f64>) -> Result<f64, ImportError> {
        let x = self.finite(v, "the value")?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(&self.at(&v.span()), format!("must be > 0, found {x}")))
        }
    }

    fn non_negative(&self, v: &Spanned<f64>) -> Result<f64, ImportError> {
        let x = self.finite(v, "the value")?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(&self.at(&v.span()), format!("must be ≥ 0, found {x}")))
        }
    }

    /// A pair `[x, y]` whose elements pass `check`.
    fn pair(
        &self,
        v: &Spanned<Vec<f64>>,
        check: impl Fn(f64) -> Result<(), String>,
    ) -> Result<[f64; 2], ImportError> {
        let at = self.at(&v.span());
        match v.get_ref().as_slice() {
            &[a, b] => {
                for x in [a, b] {
                    check(x).map_err(|m| self.invalid(&at, m))?;
                }
                Ok([a, b])
            }
            other => Err(self.invalid(
                &at,
                format!("expected two numbers [x, y], found {}", other.len()),
            )),
        }
    }

    fn column(&self, c: Option<&Spanned<i64>>) -> Result<Option<usize>, ImportError> {
        match c {
            None => Ok(None),
            Some(c) => match usize::try_from(*c.get_ref()) {
                Ok(v) if v >= 1 => Ok(Some(v)),
                _ => Err(self.invalid(
                    &self.at(&c.span()),
                    format!("`column` is 1-based, found {}", c.get_ref()),
                )),
            },
        }
    }

    fn source(&self, s: &Spanned<RawSource>, key: &str) -> Result<SourceRef, ImportError> {
        let at = self.at_key(&s.span(), key);
        let raw = s.get_ref();
        let scale = match &raw.scale {
            Some(v) => {
                let x = self.finite(v, "scale")?;
                if x == 0.0 {
                    return Err(self.invalid(&at, "scale 0 would write a constant"));
                }
                x
            }
            None => 1.0,
        };
        let offset = match &raw.offset {
            Some(v) => self.finite(v, "offset")?,
            None => 0.0,
        };
        let var = raw.var.get_ref().trim().to_string();
        if var.is_empty() {
            return Err(self.invalid(&at, "`var` is empty"));
        }
        Ok(SourceRef {
            var,
            column: self.column(raw.column.as_ref())?,
            scale,
            offset,
            unit: raw.unit.clone(),
            at,
        })
    }

    /// The line of the `[name]` header, or of `span` when there is none.
    fn table_line(&self, name: &str, span: &Range<usize>) -> usize {
        let header = format!("[{name}]");
        self.text
            .lines()
            .position(|l| l.trim().replace(' ', "") == header)
            .map_or_else(|| self.line(span.start), |i| i + 1)
    }
}

fn parse_delimiter(s: &str) -> Option<u8> {
    match s {
        "," | "comma" => Some(b','),
        "\t" | "tab" => Some(b'\t'),
        ";" | "semicolon" => Some(b';'),
        " " | "space" => Some(b' '),
        "|" | "pipe" => Some(b'|'),
        _ => None,
    }
}

impl Map {
    /// Reads and checks a map file.
    ///
    /// # Errors
    /// [`ImportError::Io`]; [`ImportError::MapSyntax`], [`ImportError::MapMissingKey`],
    /// [`ImportError::MapUnknownKey`] or [`ImportError::MapValue`], each naming the map
    /// file, the line and the key.
    pub fn read(path: &Path) -> Result<Map, ImportError> {
        let text = rigtwin_session::files::read_regular_text(
            path,
            rigtwin_session::files::MAX_CONFIG_BYTES,
        )
        .map_err(|e| ImportError::Io {
            file: path.to_path_buf(),
            source: e,
        })?;
        Map::parse(&text, path)
    }

    /// Parses a map's text; `path` is used in errors and to resolve nothing else.
    ///
    /// # Errors
    /// As [`Map::read`], without I/O.
    #[allow(clippy::too_many_lines)]
    pub fn parse(text: &str, path: &Path) -> Result<Map, ImportError> {
        let loc = Locator { text, file: path };
        let raw: RawMap = toml::from_str(text).map_err(|e| loc.toml_error(&e))?;

        let created = match &raw.created {
            None => DEFAULT_CREATED.to_string(),
            Some(c) => match c.get_ref() {
                toml::Value::String(s) => s.clone(),
                toml::Value::Datetime(d) => d.to_string(),
                other => {
                    return Err(loc.invalid(
                        &loc.at(&c.span()),
                        format!("expected a date-time string, found {other}"),
                    ));
                }
            },
        };
        if created.contains(['"', '\n', '\\']) {
            return Err(loc.invalid(
                &loc.at_key(&raw.created.as_ref().map_or(0..0, Spanned::span), "created"),
                "quotes, backslashes and line breaks are not allowed",
            ));
        }
        let axes = match &raw.axes {
            None => Axes::Both,
            Some(a) => {
                let names: Vec<&str> = a.get_ref().iter().map(String::as_str).collect();
                match names.as_slice() {
                    ["x", "y"] => Axes::Both,
                    ["x"] => Axes::X,
                    ["y"] => Axes::Y,
                    other => {
                        return Err(loc.invalid(
                            &loc.at_key(&a.span(), "axes"),
                            format!("expected [\"x\"], [\"y\"] or [\"x\", \"y\"], found {other:?}"),
                        ));
                    }
                }
            }
        };

        // [time]
        let time_line = loc.table_line("time", &raw.time.span());
        let time_at = |key: &str| MapAt {
            map: path.to_path_buf(),
            line: time_line,
            key: key.to_string(),
        };
        let t = raw.time.get_ref();
        let time = match (&t.rate_hz, &t.var) {
            (Some(r), None) => {
                if t.column.is_some() || t.scale.is_some() {
                    return Err(loc.invalid(
                        &time_at("time"),
                        "`column` and `scale` go with `var`, not with `rate_hz`",
                    ));
                }
                Time::Rate(loc.positive(r)?)
            }
            (None, Some(v)) => {
                let scale = match &t.scale {
                    Some(s) => loc.positive(s)?,
                    None => 1.0,
                };
                Time::Var(SourceRef {
                    var: v.get_ref().trim().to_string(),
                    column: loc.column(t.column.as_ref())?,
                    scale,
                    offset: 0.0,
                    unit: Some("s".into()),
                    at: loc.at_key(&v.span(), "time.var"),
                })
            }
            (Some(_), Some(_)) => {
                return Err(loc.invalid(&time_at("time"), "give `rate_hz` or `var`, not both"));
            }
            (None, None) => {
                return Err(ImportError::MapMissingKey {
                    map: path.to_path_buf(),
                    line: time_line,
                    key: "time.rate_hz".into(),
                });
            }
        };

        // [csv]
        let csv = match &raw.csv {
            None => CsvOptions::default(),
            Some(c) => CsvOptions {
                delimiter: match &c.delimiter {
                    None => None,
                    Some(d) => Some(parse_delimiter(d.get_ref()).ok_or_else(|| {
                        loc.invalid(
                            &loc.at_key(&d.span(), "csv.delimiter"),
                            format!(
                                "{:?} is not a delimiter: use \",\", \"\\t\" (or \"tab\"), \";\", \" \" or \"|\"",
                                d.get_ref()
                            ),
                        )
                    })?),
                },
                header: c.header,
            },
        };

        // [channels]
        let channels_line = text
            .lines()
            .position(|l| l.trim().replace(' ', "") == "[channels]")
            .map_or(1, |i| i + 1);
        let channels_at = MapAt {
            map: path.to_path_buf(),
            line: channels_line,
            key: "channels".into(),
        };
        let mut channels = Vec::new();
        for (name, axis) in CHANNELS {
            if let Some(src) = raw.channels.get(name) {
                let key = format!("channels.{name}");
                let s = loc.source(src, &key)?;
                if !axes.has(axis) {
                    return Err(loc.invalid(
                        &s.at,
                        format!(
                            "the rig has no {} axis (axes = {:?})",
                            ["x", "y"][axis],
                            axes.names()
                        ),
                    ));
                }
                channels.push((name, s));
            }
        }
        if let Some((name, src)) = raw
            .channels
            .iter()
            .find(|(n, _)| !CHANNELS.iter().any(|(c, _)| c == n))
        {
            let names: Vec<&str> = CHANNELS.iter().map(|(c, _)| *c).collect();
            return Err(ImportError::MapUnknownKey {
                map: path.to_path_buf(),
                line: loc.line(src.span().start),
                key: format!("channels.{name}"),
                allowed: format!("the session columns are {}", names.join(", ")),
            });
        }

        // [device]
        let d = raw.device.get_ref();
        let device_at = MapAt {
            map: path.to_path_buf(),
            line: loc.table_line("device", &raw.device.span()),
            key: "device".into(),
        };
        let device = Device {
            kind: d.kind.clone(),
            mass_kg: loc.pair(&d.mass_kg, |x| {
                if x.is_finite() && x > 0.0 {
                    Ok(())
                } else {
                    Err(format!("each mass must be > 0, found {x}"))
                }
            })?,
            damping_n_s_per_m: loc.pair(&d.damping_n_s_per_m, |x| {
                if x.is_finite() && x >= 0.0 {
                    Ok(())
                } else {
                    Err(format!("each damping must be ≥ 0, found {x}"))
                }
            })?,
            handle_mass_kg: d
                .handle_mass_kg
                .as_ref()
                .map(|v| loc.non_negative(v))
                .transpose()?,
            workspace_half_width_m: d
                .workspace_half_width_m
                .as_ref()
                .map(|v| loc.positive(v))
                .transpose()?,
        };
        let force_sensor = d.force_sensor.unwrap_or(true);

        // [subject]
        let (subject_id, shoulder_m, upper_arm_m, forearm_m, body_mass_kg) = match &raw.subject {
            None => (None, [0.0; 2], None, None, None),
            Some(s) => (
                s.id.clone(),
                match &s.shoulder_m {
                    Some(p) => loc.pair(p, |x| {
                        if x.is_finite() {
                            Ok(())
                        } else {
                            Err(format!("{x} is not finite"))
                        }
                    })?,
                    None => [0.0; 2],
                },
                s.upper_arm_m
                    .as_ref()
                    .map(|v| loc.positive(v))
                    .transpose()?,
                s.forearm_m.as_ref().map(|v| loc.positive(v)).transpose()?,
                s.body_mass_kg
                    .as_ref()
                    .map(|v| loc.positive(v))
                    .transpose()?,
            ),
        };

        // [trials]
        let tr = raw.trials.get_ref();
        let cut_name = tr.cut.get_ref().as_str();
        let cut_at = loc.at_key(&tr.cut.span(), "trials.cut");
        // Keys that belong to another cut are errors, not silently ignored.
        let stray = |key: &str, span: Range<usize>, allowed: &str| {
            Err::<Cut, _>(loc.invalid(
                &loc.at_key(&span, &format!("trials.{key}")),
                format!("`{key}` is for {allowed}, and this map has cut = {cut_name:?}"),
            ))
        };
        let length_s = tr.length_s.as_ref().map(|v| loc.positive(v)).transpose()?;
        let cut = match cut_name {
            "whole" => {
                if let Some(m) = &tr.marker {
                    stray("marker", m.span(), "cut = \"marker\"")?
                } else if let Some(o) = &tr.onsets_s {
                    stray("onsets_s", o.span(), "cut = \"onsets\"")?
                } else if let Some(o) = &tr.onsets {
                    stray("onsets", o.span(), "cut = \"onsets\"")?
                } else if let Some(o) = &tr.threshold {
                    stray("threshold", o.span(), "cut = \"threshold\"")?
                } else if let Some(o) = &tr.length_s {
                    stray("length_s", o.span(), "cut = \"marker\" or \"onsets\"")?
                } else {
                    Cut::Whole
                }
            }
            "marker" => {
                let Some(m) = &tr.marker else {
                    return Err(ImportError::MapMissingKey {
                        map: path.to_path_buf(),
                        line: cut_at.line,
                        key: "trials.marker".into(),
                    });
                };
                if let Some(o) = &tr.onsets_s {
                    stray("onsets_s", o.span(), "cut = \"onsets\"")?;
                } else if let Some(o) = &tr.onsets {
                    stray("onsets", o.span(), "cut = \"onsets\"")?;
                } else if let Some(o) = &tr.threshold {
                    stray("threshold", o.span(), "cut = \"threshold\"")?;
                }
                let mk = m.get_ref();
                let at = loc.at_key(&m.span(), "trials.marker");
                let var = mk.var.get_ref().trim().to_string();
                Cut::Marker {
                    source: SourceRef {
                        var,
                        column: loc.column(mk.column.as_ref())?,
                        scale: 1.0,
                        offset: 0.0,
                        unit: None,
                        at,
                    },
                    above: match &mk.above {
                        Some(a) => loc.finite(a, "above")?,
                        None => 0.5,
                    },
                    length_s,
                }
            }
            "onsets" => {
                if let Some(m) = &tr.marker {
                    stray("marker", m.span(), "cut = \"marker\"")?;
                } else if let Some(o) = &tr.threshold {
                    stray("threshold", o.span(), "cut = \"threshold\"")?;
                }
                let onsets = match (&tr.onsets_s, &tr.onsets) {
                    (Some(list), None) => {
                        let at = loc.at_key(&list.span(), "trials.onsets_s");
                        let v = list.get_ref().clone();
                        if v.is_empty() {
                            return Err(loc.invalid(&at, "the list of onsets is empty"));
                        }
                        if let Some(w) = v.windows(2).find(|w| w[1] <= w[0]) {
                            return Err(loc.invalid(
                                &at,
                                format!("onsets must increase: {} then {}", w[0], w[1]),
                            ));
                        }
                        if let Some(x) = v.iter().find(|x| !x.is_finite() || **x < 0.0) {
                            return Err(
                                loc.invalid(&at, format!("onsets are times ≥ 0 s, found {x}"))
                            );
                        }
                        Onsets::Table(v, at)
                    }
                    (None, Some(src)) => Onsets::Var(loc.source(src, "trials.onsets")?),
                    (Some(o), Some(_)) => {
                        return Err(loc.invalid(
                            &loc.at_key(&o.span(), "trials.onsets_s"),
                            "give `onsets_s` or `onsets`, not both",
                        ));
                    }
                    (None, None) => {
                        return Err(ImportError::MapMissingKey {
                            map: path.to_path_buf(),
                            line: cut_at.line,
                            key: "trials.onsets_s".into(),
                        });
                    }
                };
                Cut::Onsets { onsets, length_s }
            }
            "threshold" => {
                if let Some(m) = &tr.marker {
                    stray("marker", m.span(), "cut = \"marker\"")?;
                } else if let Some(o) = &tr.onsets_s {
                    stray("onsets_s", o.span(), "cut = \"onsets\"")?;
                } else if let Some(o) = &tr.onsets {
                    stray("onsets", o.span(), "cut = \"onsets\"")?;
                } else if let Some(o) = &tr.length_s {
                    stray(
                        "length_s",
                        o.span(),
                        "cut = \"marker\" or \"onsets\" (the threshold cut has its own `length_s`)",
                    )?;
                }
                let Some(th) = &tr.threshold else {
                    return Err(ImportError::MapMissingKey {
                        map: path.to_path_buf(),
                        line: cut_at.line,
                        key: "trials.threshold".into(),
                    });
                };
                let r = th.get_ref();
                let ch_at = loc.at_key(&r.channel.span(), "trials.threshold.channel");
                let Some(&(channel, _)) = CHANNELS
                    .iter()
                    .find(|(c, _)| *c == r.channel.get_ref().as_str())
                else {
                    return Err(loc.invalid(
                        &ch_at,
                        format!("{:?} is not a session column", r.channel.get_ref()),
                    ));
                };
                if !raw.channels.contains_key(channel) {
                    return Err(
                        loc.invalid(&ch_at, format!("`{channel}` is not mapped in [channels]"))
                    );
                }
                Cut::Threshold {
                    channel,
                    speed_above: loc.positive(&r.speed_above)?,
                    before_s: r
                        .before_s
                        .as_ref()
                        .map(|v| loc.non_negative(v))
                        .transpose()?
                        .unwrap_or(0.0),
                    length_s: loc.positive(&r.length_s)?,
                    at: loc.at_key(&th.span(), "trials.threshold"),
                }
            }
            other => {
                return Err(loc.invalid(
                    &cut_at,
                    format!(
                        "unknown cut {other:?}: use \"whole\", \"marker\", \"onsets\" or \"threshold\""
                    ),
                ));
            }
        };
        let trial_kind = TrialKind::from(tr.kind.clone().unwrap_or_else(|| "reach".into()));

        // [perturbation]
        let perturbation = match &raw.perturbation {
            None => None,
            Some(p) => {
                let r = p.get_ref();
                let at = MapAt {
                    map: path.to_path_buf(),
                    line: loc.table_line("perturbation", &p.span()),
                    key: "perturbation".into(),
                };
                let from_at = loc.at_key(&r.from.span(), "perturbation.from");
                let lists = [&r.onset_s, &r.duration_s, &r.amplitude_n, &r.angle_deg];
                let names = ["onset_s", "duration_s", "amplitude_n", "angle_deg"];
                let from = match r.from.get_ref().as_str() {
                    "channel" => {
                        if let Some((l, name)) = lists
                            .iter()
                            .zip(names)
                            .find_map(|(l, n)| l.as_ref().map(|l| (l, n)))
                        {
                            return Err(loc.invalid(
                                &loc.at_key(&l.span(), &format!("perturbation.{name}")),
                                format!("`{name}` is for from = \"table\""),
                            ));
                        }
                        PerturbationFrom::Channel {
                            above_n: match &r.above_n {
                                Some(a) => loc.positive(a)?,
                                None => 0.5,
                            },
                        }
                    }
                    "table" => {
                        if let Some(a) = &r.above_n {
                            return Err(loc.invalid(
                                &loc.at_key(&a.span(), "perturbation.above_n"),
                                "`above_n` is for from = \"channel\"",
                            ));
                        }
                        let mut vals: Vec<Vec<f64>> = Vec::new();
                        let mut ats: Vec<MapAt> = Vec::new();
                        for (l, name) in lists.iter().zip(names) {
                            let key = format!("perturbation.{name}");
                            let Some(l) = l else {
                                return Err(ImportError::MapMissingKey {
                                    map: path.to_path_buf(),
                                    line: at.line,
                                    key,
                                });
                            };
                            let a = loc.at_key(&l.span(), &key);
                            if let Some(x) = l.get_ref().iter().find(|x| !x.is_finite()) {
                                return Err(loc.invalid(&a, format!("{x} is not finite")));
                            }
                            vals.push(l.get_ref().clone());
                            ats.push(a);
                        }
                        let n = vals[0].len();
                        for (v, a) in vals.iter().zip(&ats) {
                            if v.len() != n {
                                return Err(loc.invalid(
                                    a,
                                    format!("{} values, but perturbation.onset_s has {n}", v.len()),
                                ));
                            }
                        }
                        let [o, d, am, an]: [Vec<f64>; 4] = vals.try_into().unwrap_or_default();
                        let [ao, ad, aam, aan]: [MapAt; 4] = ats.try_into().unwrap_or_default();
                        if let Some(x) = d.iter().find(|x| **x < 0.0) {
                            return Err(loc.invalid(&ad, format!("durations are ≥ 0, found {x}")));
                        }
                        PerturbationFrom::Table(Box::new(PerturbationTable {
                            onset_s: o,
                            duration_s: d,
                            amplitude_n: am,
                            angle_deg: an,
                            at: [ao, ad, aam, aan],
                        }))
                    }
                    other => {
                        return Err(loc.invalid(
                            &from_at,
                            format!("unknown source {other:?}: use \"channel\" or \"table\""),
                        ));
                    }
                };
                Some(PerturbationSpec {
                    from,
                    kind: r.kind.clone().unwrap_or_else(|| "force-pulse".into()),
                    at,
                })
            }
        };

        Ok(Map {
            path: path.to_path_buf(),
            created,
            axes,
            time,
            csv,
            channels,
            device,
            force_sensor,
            subject_id,
            shoulder_m,
            upper_arm_m,
            forearm_m,
            body_mass_kg,
            cut,
            trial_kind,
            perturbation,
            channels_at,
            device_at,
        })
    }

    /// The map file this was read from.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The session columns the map gives a source, in session column order.
    #[must_use]
    pub fn mapped_columns(&self) -> Vec<&'static str> {
        self.channels.iter().map(|(c, _)| *c).collect()
    }
}
