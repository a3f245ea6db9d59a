//! Parsing `session.toml`: a first pass for the format and version, the raw tables,
//! and their conversion to the typed [`Manifest`], with every error naming the file,
//! the line and the key (the [`Locator`] maps byte offsets to lines and key paths).

#[allow(clippy::wildcard_imports)]
use super::*;

use super::values::*;

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
    rate_hz: SampleRate,
    axes: Option<Spanned<Vec<String>>>,
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
    /// Byte offset of the start of each line: line `n` (1-based) starts at
    /// `starts[n - 1]`. Built once, so locating a key costs a binary search and a manifest
    /// of N trials is read in time linear in N.
    starts: Vec<usize>,
}

impl<'a> Locator<'a> {
    pub(crate) fn new(text: &'a str, file: &'a Path) -> Self {
        let starts = std::iter::once(0)
            .chain(
                text.bytes()
                    .enumerate()
                    .filter(|&(_, b)| b == b'\n')
                    .map(|(i, _)| i + 1),
            )
            .collect();
        Locator { text, file, starts }
    }

    /// 1-based line of byte offset `at`.
    pub(crate) fn line(&self, at: usize) -> usize {
        let at = at.min(self.text.len());
        // The number of line starts at or before `at`.
        self.starts.partition_point(|&s| s <= at)
    }

    fn line_text(&self, line: usize) -> &'a str {
        let Some(&start) = line.checked_sub(1).and_then(|i| self.starts.get(i)) else {
            return "";
        };
        let end = self.starts.get(line).map_or(self.text.len(), |&e| e);
        self.text[start..end].trim_end_matches(['\n', '\r'])
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
                        &a.span(),
                        format!("expected [\"x\"], [\"y\"] or [\"x\", \"y\"], found {other:?}"),
                    ));
                }
            }
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
        axes,
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
