//! `session.toml`: the typed manifest, its parser (every error names file, line, key)
//! and its deterministic writer.
//!
//! Which tables accept keys that version 1 does not define:
//! - top level, `[device]`, `[[trial]]`, `[trial.perturbation]`: **no**. These keys
//!   drive models and analyses; a misspelt optional key (`handle_mass = 0.35`) would
//!   otherwise be dropped without a word. An unknown key is [`SessionError::UnknownKey`].
//!   The project's own additions are declared here: `[sim]`, `amplitude_m` for position
//!   perturbations, trial kinds and perturbation kinds beyond the spec's.
//! - `[subject]` and `[sim]`: **yes**. Labs record subject metadata (age, handedness)
//!   and the simulator records whatever reproduces a run; unknown keys are kept in
//!   `extra`, in name order, and written back.

use std::collections::BTreeMap;
use std::fmt::{self, Write as _};
use std::ops::Range;
use std::path::{Component, Path, PathBuf};
use std::str::FromStr;

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::SessionError;

/// The value of `format`.
pub const FORMAT: &str = "rig-session";
/// The only `format_version` this module reads and writes.
pub const FORMAT_VERSION: i64 = 1;

/// A parsed `session.toml`.
#[derive(Debug, Clone, PartialEq)]
pub struct Manifest {
    /// Measured (`rig`) or simulated (`sim`).
    pub source: Source,
    /// Sampling rate of every trial table, Hz (> 0).
    pub rate_hz: f64,
    /// When the session was recorded, as written (RFC 3339 in practice). Passed in by
    /// the writer, never read from the clock, so output is deterministic.
    pub created: String,
    /// `[device]`.
    pub device: Device,
    /// `[subject]`.
    pub subject: Subject,
    /// `[sim]`: present on simulator output.
    pub sim: Option<SimInfo>,
    /// `[timing]`: present on sessions recorded in real time (an extension of version 1
    /// that readers of the spec skip as an unknown table).
    pub timing: Option<Timing>,
    /// `[[trial]]`, in file order.
    pub trials: Vec<TrialEntry>,
}

/// A distribution of durations, µs.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Percentiles {
    /// Median, µs.
    pub p50_us: f64,
    /// 99th percentile, µs.
    pub p99_us: f64,
    /// 99.9th percentile, µs.
    pub p999_us: f64,
    /// Largest, µs.
    pub max_us: f64,
}

/// `[timing]`: how the real-time loop that recorded the session kept its clock.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Timing {
    /// Period of the control clock, µs (250 at 4 kHz).
    pub period_us: f64,
    /// Ticks the loop ran.
    pub ticks: u64,
    /// Deadlines missed: ticks the loop skipped (the plant moved on under the held
    /// command; every recorded sample is still there).
    pub missed_deadlines: u64,
    /// Longest run of consecutive missed deadlines.
    pub max_consecutive_misses: u64,
    /// Wake-up latency: how late after its deadline each tick started.
    pub wake_latency: Percentiles,
    /// Loop time: from one wake-up to the next request for a tick.
    pub loop_time: Percentiles,
}

impl Timing {
    /// Missed deadlines per 10⁵ deadlines.
    #[must_use]
    pub fn misses_per_1e5(&self) -> f64 {
        let due = self.ticks + self.missed_deadlines;
        if due == 0 {
            0.0
        } else {
            self.missed_deadlines as f64 * 1e5 / due as f64
        }
    }
}

/// Where the data came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// Measured on the rig.
    Rig,
    /// Simulator output.
    Sim,
}

impl Source {
    /// The manifest spelling.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Source::Rig => "rig",
            Source::Sim => "sim",
        }
    }
}

/// `[device]`: the admittance `M a + D v = F_hand + F_pert`.
#[derive(Debug, Clone, PartialEq)]
pub struct Device {
    /// Controller kind, e.g. `admittance`.
    pub kind: String,
    /// Admittance inertia per axis (x, y), kg (> 0).
    pub mass_kg: [f64; 2],
    /// Admittance damping per axis (x, y), N s/m (≥ 0).
    pub damping_n_s_per_m: [f64; 2],
    /// Mass between the force sensor and the hand, kg (≥ 0).
    pub handle_mass_kg: Option<f64>,
    /// Half the side of the square workspace, m (> 0).
    pub workspace_half_width_m: Option<f64>,
}

/// `[subject]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Subject {
    /// Subject code.
    pub id: String,
    /// Shoulder joint centre in the rig frame, m.
    pub shoulder_m: [f64; 2],
    /// Upper arm length, m (> 0).
    pub upper_arm_m: Option<f64>,
    /// Forearm length (elbow to handle), m (> 0).
    pub forearm_m: Option<f64>,
    /// Body mass, kg (> 0).
    pub body_mass_kg: Option<f64>,
    /// Keys version 1 does not define, kept and written back in name order.
    pub extra: BTreeMap<String, toml::Value>,
}

/// `[sim]`: how a simulated session was produced (a project addition).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SimInfo {
    /// Seed of every random draw.
    pub seed: Option<u64>,
    /// Protocol file or name that was run.
    pub protocol: Option<String>,
    /// Model name or description.
    pub model: Option<String>,
    /// Further keys, kept and written back in name order.
    pub extra: BTreeMap<String, toml::Value>,
}

/// One `[[trial]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialEntry {
    /// Trial id, unique in the session.
    pub id: u32,
    /// Path of the trial table relative to the session directory, `/`-separated.
    pub file: String,
    /// Digest of the trial file; optional on input, always written on output.
    pub sha256: Option<Sha256>,
    /// What the subject did.
    pub kind: TrialKind,
    /// Movement start, rig frame, m.
    pub start_m: Option<[f64; 2]>,
    /// Movement goal, rig frame, m.
    pub goal_m: Option<[f64; 2]>,
    /// The perturbation, if the trial was perturbed.
    pub perturbation: Option<Perturbation>,
}

impl TrialEntry {
    /// The trial file's path under the session directory `dir`.
    #[must_use]
    pub fn path_in(&self, dir: &Path) -> PathBuf {
        self.file
            .split('/')
            .fold(dir.to_path_buf(), |p, part| p.join(part))
    }
}

/// The trial's task.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TrialKind {
    /// A point-to-point reach.
    Reach,
    /// Holding a posture.
    Hold,
    /// Anything else (free text in the spec).
    Other(String),
}

impl TrialKind {
    /// The manifest spelling.
    #[must_use]
    pub fn as_str(&self) -> &str {
        match self {
            TrialKind::Reach => "reach",
            TrialKind::Hold => "hold",
            TrialKind::Other(s) => s,
        }
    }
}

impl From<String> for TrialKind {
    fn from(s: String) -> Self {
        match s.as_str() {
            "reach" => TrialKind::Reach,
            "hold" => TrialKind::Hold,
            _ => TrialKind::Other(s),
        }
    }
}

/// `[trial.perturbation]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Perturbation {
    /// Its shape.
    pub kind: PerturbationKind,
    /// Onset within the trial, on the `t_s` clock, s.
    pub onset_s: f64,
    /// Duration, s (> 0).
    pub duration_s: f64,
    /// Peak size: `amplitude_n` (force) or `amplitude_m` (position, a project addition).
    pub amplitude: Amplitude,
    /// Direction in the rig frame, from +x toward +y, degrees.
    pub angle_deg: f64,
}

/// The perturbation's shape.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PerturbationKind {
    /// `force-pulse`: the three-section smooth-jerk force pulse (Börner eqs. 22-23).
    ForcePulse,
    /// `position-min-snap`: a minimum-snap position displacement (Piovesan).
    PositionMinSnap,
    /// Any other name.
    Other(String),
}

impl PerturbationKind {
    /// The manifest spelling.
    #[must_use]
    pub fn as_str(&self) -> &str {
        match self {
            PerturbationKind::ForcePulse => "force-pulse",
            PerturbationKind::PositionMinSnap => "position-min-snap",
            PerturbationKind::Other(s) => s,
        }
    }
}

impl From<String> for PerturbationKind {
    fn from(s: String) -> Self {
        match s.as_str() {
            "force-pulse" => PerturbationKind::ForcePulse,
            "position-min-snap" => PerturbationKind::PositionMinSnap,
            _ => PerturbationKind::Other(s),
        }
    }
}

/// A perturbation's peak size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Amplitude {
    /// `amplitude_n`: peak force, N.
    ForceN(f64),
    /// `amplitude_m`: peak displacement, m.
    PositionM(f64),
}

/// A SHA-256 digest, written as 64 lower-case hex digits.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Sha256(pub [u8; 32]);

impl fmt::Debug for Sha256 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Sha256({self})")
    }
}

impl fmt::Display for Sha256 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.iter().try_for_each(|b| write!(f, "{b:02x}"))
    }
}

impl FromStr for Sha256 {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bytes = s.as_bytes();
        if bytes.len() != 64 {
            return Err(format!(
                "a SHA-256 digest has 64 hex digits, found {}",
                bytes.len()
            ));
        }
        let mut out = [0_u8; 32];
        for (o, pair) in out.iter_mut().zip(bytes.chunks_exact(2)) {
            let hex = |c: u8| char::from(c).to_digit(16);
            match (hex(pair[0]), hex(pair[1])) {
                (Some(h), Some(l)) => *o = (h * 16 + l) as u8,
                _ => return Err(format!("{s:?} is not hexadecimal")),
            }
        }
        Ok(Sha256(out))
    }
}

impl Sha256 {
    /// The digest of `bytes`.
    #[must_use]
    pub fn of(bytes: &[u8]) -> Sha256 {
        use sha2::Digest;
        Sha256(sha2::Sha256::digest(bytes).into())
    }
}

/// Where parsed values sit in the manifest, for errors found after parsing.
#[derive(Debug, Clone, Default)]
pub(crate) struct EntryLines {
    pub file: usize,
    pub sha256: usize,
    pub onset: usize,
}

// ---------------------------------------------------------------------------------
// Parsing.

/// A finite number, as TOML float or integer.
struct Finite(f64);

impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f64::deserialize(d)?;
        if v.is_finite() {
            Ok(Finite(v))
        } else {
            Err(de::Error::custom(format!("{v} is not finite")))
        }
    }
}

/// A finite number > 0.
struct Positive(f64);

impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Finite(v) = Finite::deserialize(d)?;
        if v > 0.0 {
            Ok(Positive(v))
        } else {
            Err(de::Error::custom(format!("must be > 0, found {v}")))
        }
    }
}

/// A finite number ≥ 0.
struct NonNegative(f64);

impl<'de> Deserialize<'de> for NonNegative {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Finite(v) = Finite::deserialize(d)?;
        if v >= 0.0 {
            Ok(NonNegative(v))
        } else {
            Err(de::Error::custom(format!("must be ≥ 0, found {v}")))
        }
    }
}

/// Exactly two elements (`[f64; 2]` alone would accept `[1.0, 2.0, 3.0]`).
struct Pair<T>([T; 2]);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Pair<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = Pair<T>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an array of two numbers [x, y]")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Pair<T>, A::Error> {
                let a = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let b = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(1, &self))?;
                let mut n = 2;
                while seq.next_element::<de::IgnoredAny>()?.is_some() {
                    n += 1;
                }
                if n == 2 {
                    Ok(Pair([a, b]))
                } else {
                    Err(de::Error::invalid_length(n, &self))
                }
            }
        }
        d.deserialize_seq(V(std::marker::PhantomData))
    }
}

fn finite2(p: Pair<Finite>) -> [f64; 2] {
    let [Finite(a), Finite(b)] = p.0;
    [a, b]
}

fn positive2(p: Pair<Positive>) -> [f64; 2] {
    let [Positive(a), Positive(b)] = p.0;
    [a, b]
}

fn non_negative2(p: Pair<NonNegative>) -> [f64; 2] {
    let [NonNegative(a), NonNegative(b)] = p.0;
    [a, b]
}

/// First pass: only what must be right before anything else is read.
#[derive(Deserialize)]
struct RawHead {
    format: Option<Spanned<toml::Value>>,
    format_version: Option<Spanned<toml::Value>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    #[serde(rename = "format")]
    _format: de::IgnoredAny,
    #[serde(rename = "format_version")]
    _format_version: de::IgnoredAny,
    source: Spanned<String>,
    rate_hz: Positive,
    created: Spanned<toml::Value>,
    device: RawDevice,
    subject: Subject,
    sim: Option<SimInfo>,
    timing: Option<Timing>,
    #[serde(default)]
    trial: Vec<RawTrial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDevice {
    kind: String,
    mass_kg: Pair<Positive>,
    damping_n_s_per_m: Pair<NonNegative>,
    handle_mass_kg: Option<NonNegative>,
    workspace_half_width_m: Option<Positive>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTrial {
    id: Spanned<u32>,
    file: Spanned<String>,
    sha256: Option<Spanned<String>>,
    kind: String,
    start_m: Option<Pair<Finite>>,
    goal_m: Option<Pair<Finite>>,
    perturbation: Option<Spanned<RawPerturbation>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPerturbation {
    kind: String,
    onset_s: Spanned<Finite>,
    duration_s: Positive,
    amplitude_n: Option<Finite>,
    amplitude_m: Option<Finite>,
    angle_deg: Finite,
}

/// Deserializes `[subject]`, keeping keys version 1 does not define.
impl<'de> Deserialize<'de> for Subject {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Subject;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("the [subject] table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Subject, A::Error> {
                let (mut id, mut shoulder) = (None, None);
                let mut s = Subject {
                    id: String::new(),
                    shoulder_m: [0.0; 2],
                    upper_arm_m: None,
                    forearm_m: None,
                    body_mass_kg: None,
                    extra: BTreeMap::new(),
                };
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "id" => id = Some(map.next_value::<String>()?),
                        "shoulder_m" => shoulder = Some(finite2(map.next_value()?)),
                        "upper_arm_m" => s.upper_arm_m = Some(map.next_value::<Positive>()?.0),
                        "forearm_m" => s.forearm_m = Some(map.next_value::<Positive>()?.0),
                        "body_mass_kg" => s.body_mass_kg = Some(map.next_value::<Positive>()?.0),
                        _ => {
                            let v = map.next_value::<toml::Value>()?;
                            s.extra.insert(key, v);
                        }
                    }
                }
                s.id = id.ok_or_else(|| de::Error::missing_field("id"))?;
                s.shoulder_m = shoulder.ok_or_else(|| de::Error::missing_field("shoulder_m"))?;
                Ok(s)
            }
        }
        d.deserialize_map(V)
    }
}

/// Deserializes `[sim]`, keeping further keys.
impl<'de> Deserialize<'de> for SimInfo {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = SimInfo;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("the [sim] table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<SimInfo, A::Error> {
                let mut s = SimInfo::default();
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "seed" => s.seed = Some(map.next_value::<u64>()?),
                        "protocol" => s.protocol = Some(map.next_value::<String>()?),
                        "model" => s.model = Some(map.next_value::<String>()?),
                        _ => {
                            let v = map.next_value::<toml::Value>()?;
                            s.extra.insert(key, v);
                        }
                    }
                }
                Ok(s)
            }
        }
        d.deserialize_map(V)
    }
}

/// Maps byte offsets of a TOML text to lines and key paths.
pub(crate) struct Locator<'a> {
    text: &'a str,
    file: &'a Path,
}

impl<'a> Locator<'a> {
    pub(crate) fn new(text: &'a str, file: &'a Path) -> Self {
        Locator { text, file }
    }

    /// 1-based line of byte offset `at`.
    pub(crate) fn line(&self, at: usize) -> usize {
        let at = at.min(self.text.len());
        1 + self.text.as_bytes()[..at]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    fn line_text(&self, line: usize) -> &'a str {
        self.text.lines().nth(line.saturating_sub(1)).unwrap_or("")
    }

    /// The table header in force at `line` (`trial.perturbation`), empty at top level.
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

    /// The key path of whatever sits at `line`: the key of a `key = value` line, or the
    /// table of a header line, prefixed by its table.
    pub(crate) fn field_at(&self, line: usize, key: Option<&str>) -> String {
        let table = self.table_at(line);
        let text = self.line_text(line).trim();
        let key = match key {
            Some(k) => Some(k.to_string()),
            None if !text.starts_with('[') => text
                .split_once('=')
                .map(|(k, _)| k.trim().trim_matches('"').trim_matches('\'').to_string()),
            None => None,
        };
        match (table.is_empty(), key) {
            (_, None) => table,
            (true, Some(k)) => k,
            (false, Some(k)) => format!("{table}.{k}"),
        }
    }

    fn span_line(&self, span: &Range<usize>) -> usize {
        self.line(span.start)
    }

    /// Turns a toml error into the session error that names line and key.
    fn toml_error(&self, e: &toml::de::Error, syntax: bool) -> SessionError {
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
        let file = self.file.to_path_buf();
        if !syntax && message.starts_with("missing field") {
            return SessionError::MissingKey {
                file,
                line,
                field: self.field_at(line, quoted),
            };
        }
        if !syntax && message.starts_with("unknown field") {
            return SessionError::UnknownKey {
                file,
                line,
                field: self.field_at(line, quoted),
                message: message
                    .split_once(", ")
                    .map_or("", |(_, rest)| rest)
                    .to_string(),
            };
        }
        let field = self.field_at(line, None);
        if syntax {
            SessionError::Toml {
                file,
                line,
                column,
                field,
                message,
            }
        } else {
            SessionError::InvalidValue {
                file,
                line,
                field,
                message,
            }
        }
    }

    fn invalid(&self, span: &Range<usize>, message: impl Into<String>) -> SessionError {
        let line = self.span_line(span);
        SessionError::InvalidValue {
            file: self.file.to_path_buf(),
            line,
            field: self.field_at(line, None),
            message: message.into(),
        }
    }
}

/// Parses a manifest's text. `file` is only used in errors.
pub(crate) fn parse(text: &str, file: &Path) -> Result<(Manifest, Vec<EntryLines>), SessionError> {
    let loc = Locator::new(text, file);
    let head: RawHead = toml::from_str(text).map_err(|e| loc.toml_error(&e, true))?;
    let missing = |field: &str| SessionError::MissingKey {
        file: file.to_path_buf(),
        line: 1,
        field: field.into(),
    };
    let format = head.format.ok_or_else(|| missing("format"))?;
    if format.get_ref().as_str() != Some(FORMAT) {
        let found = match format.get_ref() {
            toml::Value::String(s) => s.clone(),
            other => other.to_string(),
        };
        let line = loc.span_line(&format.span());
        return Err(SessionError::WrongFormat {
            file: file.to_path_buf(),
            line,
            field: "format".into(),
            found,
        });
    }
    let version = head
        .format_version
        .ok_or_else(|| missing("format_version"))?;
    match version.get_ref() {
        toml::Value::Integer(FORMAT_VERSION) => {}
        toml::Value::Integer(v) => {
            let line = loc.span_line(&version.span());
            return Err(SessionError::UnsupportedVersion {
                file: file.to_path_buf(),
                line,
                field: "format_version".into(),
                found: *v,
            });
        }
        other => {
            return Err(loc.invalid(
                &version.span(),
                format!("expected the integer 1, found {other}"),
            ));
        }
    }

    let raw: RawManifest = toml::from_str(text).map_err(|e| loc.toml_error(&e, false))?;
    let source = match raw.source.get_ref().as_str() {
        "rig" => Source::Rig,
        "sim" => Source::Sim,
        other => {
            return Err(loc.invalid(
                &raw.source.span(),
                format!("expected \"rig\" or \"sim\", found {other:?}"),
            ));
        }
    };
    let created = match raw.created.get_ref() {
        toml::Value::String(s) => s.clone(),
        toml::Value::Datetime(d) => d.to_string(),
        other => {
            return Err(loc.invalid(
                &raw.created.span(),
                format!("expected a date-time string, found {other}"),
            ));
        }
    };
    let device = Device {
        kind: raw.device.kind,
        mass_kg: positive2(raw.device.mass_kg),
        damping_n_s_per_m: non_negative2(raw.device.damping_n_s_per_m),
        handle_mass_kg: raw.device.handle_mass_kg.map(|v| v.0),
        workspace_half_width_m: raw.device.workspace_half_width_m.map(|v| v.0),
    };
    let mut trials = Vec::with_capacity(raw.trial.len());
    let mut lines = Vec::with_capacity(raw.trial.len());
    let mut ids: BTreeMap<u32, usize> = BTreeMap::new();
    let mut files: BTreeMap<String, usize> = BTreeMap::new();
    for t in raw.trial {
        let id_line = loc.span_line(&t.id.span());
        if let Some(&first_line) = ids.get(t.id.get_ref()) {
            return Err(SessionError::DuplicateTrialId {
                file: file.to_path_buf(),
                line: id_line,
                field: "trial.id".into(),
                id: *t.id.get_ref(),
                first_line,
            });
        }
        ids.insert(*t.id.get_ref(), id_line);
        let (entry, entry_lines) = convert_trial(t, &loc)?;
        if files.insert(entry.file.clone(), entry_lines.file).is_some() {
            return Err(SessionError::DuplicateTrialFile {
                file: file.to_path_buf(),
                line: entry_lines.file,
                field: "trial.file".into(),
                path: entry.file,
            });
        }
        trials.push(entry);
        lines.push(entry_lines);
    }
    let manifest = Manifest {
        source,
        rate_hz: raw.rate_hz.0,
        created,
        device,
        subject: raw.subject,
        sim: raw.sim,
        timing: raw.timing,
        trials,
    };
    Ok((manifest, lines))
}

/// Parses one `[[trial]]` entry written on its own (the writer's in-progress sidecar).
pub(crate) fn parse_trial_entry(
    text: &str,
    file: &Path,
) -> Result<(TrialEntry, EntryLines), SessionError> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct One {
        trial: Vec<RawTrial>,
    }
    let loc = Locator::new(text, file);
    let one: One = toml::from_str(text).map_err(|e| loc.toml_error(&e, false))?;
    match <[RawTrial; 1]>::try_from(one.trial) {
        Ok([t]) => convert_trial(t, &loc),
        Err(v) => Err(SessionError::InvalidValue {
            file: file.to_path_buf(),
            line: 1,
            field: "trial".into(),
            message: format!("expected one [[trial]] entry, found {}", v.len()),
        }),
    }
}

fn convert_trial(t: RawTrial, loc: &Locator<'_>) -> Result<(TrialEntry, EntryLines), SessionError> {
    let file_line = loc.span_line(&t.file.span());
    let rel = t.file.get_ref();
    let escapes = Path::new(rel)
        .components()
        .any(|c| !matches!(c, Component::Normal(_)));
    if rel.is_empty() || escapes || rel.contains('\\') {
        return Err(loc.invalid(
            &t.file.span(),
            format!("{rel:?} must be a relative path inside the session, `/`-separated, without `.` or `..`"),
        ));
    }
    let (sha256, sha_line) = match &t.sha256 {
        None => (None, file_line),
        Some(s) => {
            let digest = s
                .get_ref()
                .parse::<Sha256>()
                .map_err(|m| loc.invalid(&s.span(), m))?;
            (Some(digest), loc.span_line(&s.span()))
        }
    };
    let (perturbation, onset_line) = match t.perturbation {
        None => (None, 0),
        Some(p) => {
            let span = p.span();
            let p = p.into_inner();
            let amplitude = match (p.amplitude_n, p.amplitude_m) {
                (Some(n), None) => Amplitude::ForceN(n.0),
                (None, Some(m)) => Amplitude::PositionM(m.0),
                (Some(_), Some(_)) => {
                    return Err(loc.invalid(
                        &span,
                        "give amplitude_n (force) or amplitude_m (position), not both",
                    ));
                }
                (None, None) => {
                    let line = loc.span_line(&span);
                    return Err(SessionError::MissingKey {
                        file: loc.file.to_path_buf(),
                        line,
                        field: "trial.perturbation.amplitude_n".into(),
                    });
                }
            };
            let onset_line = loc.span_line(&p.onset_s.span());
            let perturbation = Perturbation {
                kind: PerturbationKind::from(p.kind),
                onset_s: p.onset_s.into_inner().0,
                duration_s: p.duration_s.0,
                amplitude,
                angle_deg: p.angle_deg.0,
            };
            (Some(perturbation), onset_line)
        }
    };
    let entry = TrialEntry {
        id: t.id.into_inner(),
        file: t.file.into_inner(),
        sha256,
        kind: TrialKind::from(t.kind),
        start_m: t.start_m.map(finite2),
        goal_m: t.goal_m.map(finite2),
        perturbation,
    };
    Ok((
        entry,
        EntryLines {
            file: file_line,
            sha256: sha_line,
            onset: onset_line,
        },
    ))
}

// ---------------------------------------------------------------------------------
// Writing: a fixed layout, so the same manifest always gives the same bytes.

fn float(v: f64) -> String {
    // `{:?}` is the shortest text that reads back to the same f64 and is valid TOML
    // (`5.0`, `0.15`, `1e-7`); values are finite by construction.
    format!("{v:?}")
}

fn string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn pair(v: [f64; 2]) -> String {
    format!("[{}, {}]", float(v[0]), float(v[1]))
}

fn key(k: &str) -> String {
    let bare = !k.is_empty()
        && k.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-');
    if bare { k.to_string() } else { string(k) }
}

fn extra(out: &mut String, map: &BTreeMap<String, toml::Value>) {
    for (k, v) in map {
        let _ = writeln!(out, "{} = {}", key(k), v);
    }
}

/// Writes one `[[trial]]` entry.
pub(crate) fn write_trial_entry(out: &mut String, t: &TrialEntry) {
    let _ = writeln!(out, "[[trial]]");
    let _ = writeln!(out, "id = {}", t.id);
    let _ = writeln!(out, "file = {}", string(&t.file));
    if let Some(sha) = t.sha256 {
        let _ = writeln!(out, "sha256 = \"{sha}\"");
    }
    let _ = writeln!(out, "kind = {}", string(t.kind.as_str()));
    if let Some(v) = t.start_m {
        let _ = writeln!(out, "start_m = {}", pair(v));
    }
    if let Some(v) = t.goal_m {
        let _ = writeln!(out, "goal_m = {}", pair(v));
    }
    if let Some(p) = &t.perturbation {
        let _ = writeln!(out, "\n[trial.perturbation]");
        let _ = writeln!(out, "kind = {}", string(p.kind.as_str()));
        let _ = writeln!(out, "onset_s = {}", float(p.onset_s));
        let _ = writeln!(out, "duration_s = {}", float(p.duration_s));
        match p.amplitude {
            Amplitude::ForceN(a) => {
                let _ = writeln!(out, "amplitude_n = {}", float(a));
            }
            Amplitude::PositionM(a) => {
                let _ = writeln!(out, "amplitude_m = {}", float(a));
            }
        }
        let _ = writeln!(out, "angle_deg = {}", float(p.angle_deg));
    }
}

impl Manifest {
    /// The manifest as TOML text, in the spec's layout. Deterministic: the same
    /// manifest always gives the same bytes.
    #[must_use]
    pub fn to_toml(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "format = \"{FORMAT}\"");
        let _ = writeln!(out, "format_version = {FORMAT_VERSION}");
        let _ = writeln!(out, "source = \"{}\"", self.source.as_str());
        let _ = writeln!(out, "rate_hz = {}", float(self.rate_hz));
        let _ = writeln!(out, "created = {}", string(&self.created));
        let d = &self.device;
        let _ = writeln!(out, "\n[device]");
        let _ = writeln!(out, "kind = {}", string(&d.kind));
        let _ = writeln!(out, "mass_kg = {}", pair(d.mass_kg));
        let _ = writeln!(out, "damping_n_s_per_m = {}", pair(d.damping_n_s_per_m));
        if let Some(v) = d.handle_mass_kg {
            let _ = writeln!(out, "handle_mass_kg = {}", float(v));
        }
        if let Some(v) = d.workspace_half_width_m {
            let _ = writeln!(out, "workspace_half_width_m = {}", float(v));
        }
        let s = &self.subject;
        let _ = writeln!(out, "\n[subject]");
        let _ = writeln!(out, "id = {}", string(&s.id));
        let _ = writeln!(out, "shoulder_m = {}", pair(s.shoulder_m));
        for (k, v) in [
            ("upper_arm_m", s.upper_arm_m),
            ("forearm_m", s.forearm_m),
            ("body_mass_kg", s.body_mass_kg),
        ] {
            if let Some(v) = v {
                let _ = writeln!(out, "{k} = {}", float(v));
            }
        }
        extra(&mut out, &s.extra);
        if let Some(sim) = &self.sim {
            let _ = writeln!(out, "\n[sim]");
            if let Some(seed) = sim.seed {
                let _ = writeln!(out, "seed = {seed}");
            }
            if let Some(p) = &sim.protocol {
                let _ = writeln!(out, "protocol = {}", string(p));
            }
            if let Some(m) = &sim.model {
                let _ = writeln!(out, "model = {}", string(m));
            }
            extra(&mut out, &sim.extra);
        }
        if let Some(t) = &self.timing {
            let _ = writeln!(out, "\n[timing]");
            let _ = writeln!(out, "period_us = {}", float(t.period_us));
            let _ = writeln!(out, "ticks = {}", t.ticks);
            let _ = writeln!(out, "missed_deadlines = {}", t.missed_deadlines);
            let _ = writeln!(out, "max_consecutive_misses = {}", t.max_consecutive_misses);
            for (name, p) in [("wake_latency", t.wake_latency), ("loop_time", t.loop_time)] {
                let _ = writeln!(
                    out,
                    "{name} = {{ p50_us = {}, p99_us = {}, p999_us = {}, max_us = {} }}",
                    float(p.p50_us),
                    float(p.p99_us),
                    float(p.p999_us),
                    float(p.max_us)
                );
            }
        }
        for t in &self.trials {
            out.push('\n');
            write_trial_entry(&mut out, t);
        }
        out
    }

    /// Parses manifest text; `file` names it in errors.
    ///
    /// # Errors
    /// Any [`SessionError`] naming `file`, the line and the key.
    pub fn from_toml(text: &str, file: &Path) -> Result<Manifest, SessionError> {
        parse(text, file).map(|(m, _)| m)
    }

    /// The entry with trial id `id`.
    #[must_use]
    pub fn trial(&self, id: u32) -> Option<&TrialEntry> {
        self.trials.iter().find(|t| t.id == id)
    }
}
