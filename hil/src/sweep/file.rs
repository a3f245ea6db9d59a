//! The sweep file: a base protocol, a grid of its keys, a population of virtual subjects,
//! an optional hidden effect and its sizes, and what to measure.
//!
//! ```toml
//! name = "pulses"
//! protocol = "reach-perturb"   # a shipped protocol, or a file relative to this one
//! seed = 1                     # draws the population and every session's noise
//! replicates = 1               # sessions per subject and grid point
//! max_trials = 40              # optional: the first 40 trials of each session
//! realistic = true             # a lab's rig and subject: the protocol's [nuisance], or
//!                              # its realistic defaults (sensor offset and drift, motor
//!                              # gain and noise, reaches varying); default false
//!
//! [set]                        # protocol keys held at these values in every run
//! "recording.truth_columns" = false
//!
//! [grid]                       # any protocol key, dotted; the runs are its product
//! "reach.repetitions" = [1, 2, 3]
//!
//! [population]                 # the protocol's [subjects], drawn with `seed`
//! subjects = 8
//! spread = { muscle_stiffness = 0.25, reflex_gain = 0.3 }
//! reflex = { delay_ms = 25.0, gain_n_s_per_m = 150.0 }
//!
//! [effect]                     # optional: hide an effect and ask the diagnosis for it
//! name = "handle-mass"
//! key = "plant.effects.handle_mass.extra_mass_kg"
//! sizes = [0.0, 0.1, 0.2, 0.4]
//! parameter = "extra_mass_kg"
//!
//! [measure]
//! estimate = true              # D and K against the simulated truth (reach protocols)
//! diagnose = true              # default: on when [effect] is given
//!
//! [report]
//! targets = { K22 = 20.0 }     # the ± a lab wants, in the element's unit
//! ```
//!
//! Every grid point and effect size is turned into a protocol and checked before any run
//! starts, so a bad key or value is an error naming the sweep file, its line and the key,
//! not a failure an hour into a cluster job.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rigtwin_arm::params::StretchReflex;
use rigtwin_diagnose::EffectKind;
use serde::Deserialize;

use crate::protocol::subjects::SubjectSpread;
use crate::protocol::{InvalidKey, Protocol, ProtocolError};

/// The elements of D and K a sweep reports, in the order of its columns.
pub const ELEMENTS: [&str; 8] = ["D11", "D12", "D21", "D22", "K11", "K12", "K21", "K22"];

/// The unit of element `name` of [`ELEMENTS`].
#[must_use]
pub fn element_unit(name: &str) -> &'static str {
    if name.starts_with('D') {
        "N s/m"
    } else {
        "N/m"
    }
}

/// Sweeps larger than this are refused: a typo in a grid would otherwise plan a year.
pub const MAX_RUNS: usize = 1_000_000;

/// Why a sweep file cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SweepFileError {
    /// The file could not be read.
    #[error("cannot read sweep file {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not TOML, or an unknown key or a wrong type (the message names line and key).
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message with line, column and key.
        message: String,
    },
    /// A value out of range, or a grid point the protocol refuses.
    #[error("{path}: {}", crate::protocol::error::located(.errors, .lines, ""))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Every invalid key.
        errors: Vec<InvalidKey>,
        /// Its line in the file.
        lines: Vec<Option<usize>>,
    },
    /// The base protocol could not be read.
    #[error("{path}: `protocol`: {source}")]
    Protocol {
        /// The sweep file.
        path: PathBuf,
        /// The protocol's error.
        source: ProtocolError,
    },
}

impl SweepFileError {
    /// True if the error names `key` (a dotted key of the sweep file).
    #[must_use]
    pub fn names(&self, key: &str) -> bool {
        match self {
            SweepFileError::Invalid { errors, .. } => errors.iter().any(|e| e.key == key),
            SweepFileError::Parse { message, .. } => message.contains(key),
            SweepFileError::Protocol { .. } => key == "protocol",
            SweepFileError::Read { .. } => false,
        }
    }
}

/// The population of virtual subjects a sweep draws (the base protocol's `[subjects]`
/// with these keys replaced).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Population {
    /// Subjects drawn; the same subjects at every grid point (common random numbers, so
    /// that a difference between grid points is the protocol's, not the draw's).
    pub subjects: u32,
    /// Subject 1 is the nominal arm, undrawn.
    pub first_is_nominal: bool,
    /// Log-normal σ of each factor; `None` keeps the protocol's.
    pub spread: Option<SubjectSpread>,
    /// Every subject has this stretch reflex (its gain spread by `spread.reflex_gain`);
    /// `None` keeps the protocol's arm.
    pub reflex: Option<StretchReflex>,
}

impl Default for Population {
    fn default() -> Self {
        Population {
            subjects: 8,
            first_is_nominal: false,
            spread: None,
            reflex: None,
        }
    }
}

/// A hidden effect swept over its sizes: the diagnosis is asked to name it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectSweep {
    /// The catalog effect the diagnosis should name.
    pub name: EffectKind,
    /// The protocol key that sets its size (a number).
    pub key: String,
    /// The sizes, in the key's unit; 0 (if the key allows it) measures false alarms.
    pub sizes: Vec<f64>,
    /// The diagnosis parameter compared with the size.
    pub parameter: String,
    /// Other keys of the effect, held at these values (dotted protocol keys).
    #[serde(default)]
    pub fixed: BTreeMap<String, toml::Value>,
}

/// What each run measures.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Measure {
    /// D and K against the simulated truth (reach protocols); default on for them.
    pub estimate: Option<bool>,
    /// The diagnosis of each session; default on when an effect is hidden.
    pub diagnose: Option<bool>,
    /// The diagnosis's cross-validation folds.
    pub folds: usize,
}

impl Default for Measure {
    fn default() -> Self {
        Measure {
            estimate: None,
            diagnose: None,
            folds: 8,
        }
    }
}

/// What the report's sentences aim at.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReportConfig {
    /// The ± a lab wants per element (`K22 = 20.0`, in N/m), for "±Y needs Z pulses";
    /// an element without one aims at half of what the largest grid point gives.
    pub targets: BTreeMap<String, f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    name: String,
    protocol: String,
    #[serde(default = "one_u64")]
    seed: u64,
    #[serde(default = "one_u32")]
    replicates: u32,
    max_trials: Option<usize>,
    #[serde(default)]
    realistic: bool,
    #[serde(default)]
    set: BTreeMap<String, toml::Value>,
    #[serde(default)]
    grid: BTreeMap<String, Vec<toml::Value>>,
    #[serde(default)]
    population: Population,
    effect: Option<EffectSweep>,
    #[serde(default)]
    measure: Measure,
    #[serde(default)]
    report: ReportConfig,
}

fn one_u64() -> u64 {
    1
}

fn one_u32() -> u32 {
    1
}

/// A sweep, read and checked: every grid point's protocol is built.
#[derive(Debug, Clone)]
pub struct SweepFile {
    /// The file it was read from.
    pub path: PathBuf,
    /// Its text, as read (copied next to the results, hashed into the shards' id).
    pub text: String,
    /// The base protocol's text.
    pub protocol_text: String,
    /// Folder-safe name.
    pub name: String,
    /// Seed of the population and of every session.
    pub seed: u64,
    /// Sessions per subject and grid point.
    pub replicates: u32,
    /// The first trials of each session only.
    pub max_trials: Option<usize>,
    /// A lab's rig and subject (the nuisances).
    pub realistic: bool,
    /// The grid: keys in file order of their names (sorted), each with its values.
    pub grid: Vec<(String, Vec<toml::Value>)>,
    /// The population.
    pub population: Population,
    /// The hidden effect.
    pub effect: Option<EffectSweep>,
    /// Whether runs estimate D and K.
    pub estimate: bool,
    /// Whether runs diagnose their session.
    pub diagnose: bool,
    /// The diagnosis's folds.
    pub folds: usize,
    /// Report settings.
    pub report: ReportConfig,
    /// One protocol per grid point and effect size, in run order.
    pub protocols: Vec<Protocol>,
}

impl SweepFile {
    /// Reads and checks a sweep file.
    ///
    /// # Errors
    /// [`SweepFileError`], naming the file, the line and the key.
    pub fn load(path: &Path) -> Result<SweepFile, SweepFileError> {
        let text = rigtwin_session::files::read_regular_text(
            path,
            rigtwin_session::files::MAX_CONFIG_BYTES,
        )
        .map_err(|source| SweepFileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        SweepFile::from_toml(&text, path)
    }

    /// Parses and checks a sweep from its text; `path` names it in errors and anchors a
    /// relative `protocol` path.
    ///
    /// # Errors
    /// [`SweepFileError`], naming the file, the line and the key.
    pub fn from_toml(text: &str, path: &Path) -> Result<SweepFile, SweepFileError> {
        SweepFile::parse(text, path, None)
    }

    /// [`SweepFile::from_toml`] with the base protocol's text given instead of the one
    /// `protocol` names (a merge reads the copy kept next to the results).
    ///
    /// # Errors
    /// As [`SweepFile::from_toml`].
    pub fn with_protocol_text(
        text: &str,
        path: &Path,
        protocol_text: &str,
    ) -> Result<SweepFile, SweepFileError> {
        SweepFile::parse(text, path, Some(protocol_text))
    }

    fn parse(
        text: &str,
        path: &Path,
        protocol_text: Option<&str>,
    ) -> Result<SweepFile, SweepFileError> {
        let raw: Raw = toml::from_str(text).map_err(|e| SweepFileError::Parse {
            path: path.to_path_buf(),
            message: crate::protocol::parse_message(text, &e),
        })?;
        let invalid = |errors: Vec<InvalidKey>| {
            let root = toml::de::DeTable::parse(text).ok();
            let mut lines = crate::protocol::locate::lines_of(text, root.as_ref(), &errors);
            // A grid key is one quoted name with dots in it: find its own line.
            for (e, line) in errors.iter().zip(&mut lines) {
                let quoted = ["grid.", "effect.fixed.", "set."]
                    .iter()
                    .find_map(|p| e.key.strip_prefix(p))
                    .map(|k| format!("\"{k}\""));
                if let Some(q) = quoted
                    && let Some(i) = text.lines().position(|l| l.trim_start().starts_with(&q))
                {
                    *line = Some(i + 1);
                }
            }
            SweepFileError::Invalid {
                path: path.to_path_buf(),
                lines,
                errors,
            }
        };
        let mut c = crate::protocol::Checker::default();
        check_raw(&raw, &mut c);
        if !c.errors().is_empty() {
            return Err(invalid(c.into_errors()));
        }
        let protocol_text = match protocol_text {
            Some(t) => t.to_owned(),
            None => protocol_source(&raw.protocol, path)?,
        };
        let mut base: toml::Table =
            toml::from_str(&protocol_text).map_err(|e| SweepFileError::Protocol {
                path: path.to_path_buf(),
                source: ProtocolError::Parse {
                    path: PathBuf::from(&raw.protocol),
                    message: e.to_string(),
                },
            })?;
        if raw.realistic && !base.contains_key("nuisance") {
            // An empty table takes the realistic ranges (`NuisanceConfig::default`).
            base.insert(
                "nuisance".to_owned(),
                toml::Value::Table(toml::Table::new()),
            );
        }
        let grid: Vec<(String, Vec<toml::Value>)> = raw.grid.into_iter().collect();
        let sizes: Vec<Option<f64>> = match &raw.effect {
            Some(e) => e.sizes.iter().copied().map(Some).collect(),
            None => vec![None],
        };
        let points = grid.iter().map(|(_, v)| v.len()).product::<usize>();
        let runs = points
            .saturating_mul(sizes.len())
            .saturating_mul(raw.population.subjects as usize)
            .saturating_mul(raw.replicates as usize);
        if runs > MAX_RUNS {
            let mut c = crate::protocol::Checker::default();
            c.fail(
                "grid",
                format!("plans {runs} runs, more than the {MAX_RUNS} a sweep may have"),
            );
            return Err(invalid(c.into_errors()));
        }
        // Every grid point and size as a protocol, checked now.
        let mut protocols = Vec::with_capacity(points * sizes.len());
        let mut errors = Vec::new();
        for point in 0..points {
            let values = point_values(&grid, point);
            for size in &sizes {
                match build_protocol(
                    &base,
                    &raw.set,
                    &values,
                    raw.effect.as_ref(),
                    *size,
                    &raw.population,
                ) {
                    Ok(p) => protocols.push(p),
                    Err((key, problem)) => {
                        if !errors.iter().any(|e: &InvalidKey| e.key == key) {
                            errors.push(InvalidKey { key, problem });
                        }
                    }
                }
            }
        }
        if !errors.is_empty() {
            return Err(invalid(errors));
        }
        let reach = protocols
            .first()
            .is_some_and(|p| p.kind == crate::protocol::ProtocolKind::ReachPerturb);
        Ok(SweepFile {
            path: path.to_path_buf(),
            text: text.to_owned(),
            protocol_text,
            name: raw.name,
            seed: raw.seed,
            replicates: raw.replicates,
            max_trials: raw.max_trials,
            realistic: raw.realistic || protocols.first().is_some_and(|p| p.nuisance.is_some()),
            grid,
            population: raw.population,
            estimate: raw.measure.estimate.unwrap_or(reach),
            diagnose: raw.measure.diagnose.unwrap_or(raw.effect.is_some()),
            effect: raw.effect,
            folds: raw.measure.folds,
            report: raw.report,
            protocols,
        })
    }

    /// Grid points (the product of the grid's value lists; 1 without a grid).
    #[must_use]
    pub fn points(&self) -> usize {
        self.grid.iter().map(|(_, v)| v.len()).product()
    }

    /// Effect sizes per grid point (1 without an effect).
    #[must_use]
    pub fn sizes(&self) -> usize {
        self.effect.as_ref().map_or(1, |e| e.sizes.len())
    }

    /// Runs in the sweep.
    #[must_use]
    pub fn runs(&self) -> usize {
        self.points() * self.sizes() * self.population.subjects as usize * self.replicates as usize
    }

    /// The protocol of grid point `point` at effect size `size` (0 without an effect),
    /// before a subject is drawn into it.
    #[must_use]
    pub fn protocol_at(&self, point: usize, size: usize) -> &Protocol {
        &self.protocols[point * self.sizes() + size]
    }

    /// The grid values of point `point`.
    #[must_use]
    pub fn point_values(&self, point: usize) -> Vec<(String, toml::Value)> {
        point_values(&self.grid, point)
    }
}

/// The text of the base protocol `name`: a file relative to the sweep file, or a
/// shipped protocol's name.
fn protocol_source(name: &str, sweep: &Path) -> Result<String, SweepFileError> {
    let relative = sweep.parent().unwrap_or(Path::new(".")).join(name);
    let err = |source| SweepFileError::Protocol {
        path: sweep.to_path_buf(),
        source,
    };
    if relative.exists() {
        return rigtwin_session::files::read_regular_text(
            &relative,
            rigtwin_session::files::MAX_CONFIG_BYTES,
        )
        .map_err(|source| {
            err(ProtocolError::Read {
                path: relative.clone(),
                source,
            })
        });
    }
    Protocol::builtin_text(name)
        .map(str::to_owned)
        .ok_or_else(|| {
            err(ProtocolError::Read {
                path: relative.clone(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "neither a file next to the sweep file nor a shipped protocol \
                 (reach-perturb, hold-sinusoid, calibration-rig)",
                ),
            })
        })
}

fn check_raw(raw: &Raw, c: &mut crate::protocol::Checker) {
    if raw.name.is_empty()
        || raw.name.len() > 64
        || !raw
            .name
            .chars()
            .all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_')
    {
        c.fail(
            "name",
            format!(
                "must be a folder-safe name of 1 to 64 letters, digits, - and _, got {:?}",
                raw.name
            ),
        );
    }
    if raw.replicates == 0 {
        c.fail("replicates", "must be > 0, got 0");
    }
    if raw.max_trials == Some(0) {
        c.fail("max_trials", "must be > 0, got 0");
    }
    if raw.population.subjects == 0 {
        c.fail("population.subjects", "must be > 0, got 0");
    }
    if raw.population.subjects > crate::protocol::MAX_SUBJECTS {
        c.fail(
            "population.subjects",
            format!(
                "must be <= {}, got {}",
                crate::protocol::MAX_SUBJECTS,
                raw.population.subjects
            ),
        );
    }
    if raw.measure.folds < 2 {
        c.fail(
            "measure.folds",
            format!("must be >= 2, got {}", raw.measure.folds),
        );
    }
    for key in raw.set.keys() {
        if !is_dotted_key(key) {
            c.fail(
                format!("set.{key}"),
                "is not a dotted protocol key of names",
            );
        }
        if raw.grid.contains_key(key) {
            c.fail(
                format!("set.{key}"),
                "is also in [grid]; sweep it or set it, not both",
            );
        }
    }
    for (key, values) in &raw.grid {
        let k = format!("grid.{key}");
        if values.is_empty() {
            c.fail(k.clone(), "has no values; give at least one");
        }
        if !is_dotted_key(key) {
            c.fail(
                k.clone(),
                "is not a dotted protocol key of names (`reach.repetitions`); indices are not swept",
            );
        }
        if key == "seed" || key.starts_with("subjects.") && key != "subjects.co_contraction_level" {
            c.fail(
                k.clone(),
                "is drawn by the sweep: set the population in [population] and the seed at the top",
            );
        }
        let mut seen: Vec<&toml::Value> = Vec::new();
        for v in values {
            if seen.contains(&v) {
                c.fail(k.clone(), format!("lists {v} twice"));
            }
            seen.push(v);
        }
    }
    if let Some(e) = &raw.effect {
        if e.sizes.is_empty() {
            c.fail("effect.sizes", "has no values; give at least one");
        }
        for s in &e.sizes {
            if !s.is_finite() {
                c.fail("effect.sizes", format!("must be finite, got {s}"));
            }
        }
        if !is_dotted_key(&e.key) {
            c.fail("effect.key", "is not a dotted protocol key of names");
        }
        if raw.grid.contains_key(&e.key) {
            c.fail("effect.key", "is also in [grid]; sweep it in one place");
        }
        if !e.name.parameter_names().contains(&e.parameter.as_str()) {
            c.fail(
                "effect.parameter",
                format!(
                    "{:?} is not a parameter of {}; it has {}",
                    e.parameter,
                    e.name.name(),
                    e.name.parameter_names().join(", ")
                ),
            );
        }
        for key in e.fixed.keys() {
            if !is_dotted_key(key) {
                c.fail(
                    format!("effect.fixed.{key}"),
                    "is not a dotted protocol key",
                );
            }
        }
    }
    for (element, target) in &raw.report.targets {
        let k = format!("report.targets.{element}");
        if !ELEMENTS.contains(&element.as_str()) {
            c.fail(k, format!("is not one of {}", ELEMENTS.join(", ")));
        } else if !(target.is_finite() && *target > 0.0) {
            c.fail(k, format!("must be > 0, got {target}"));
        }
    }
}

fn is_dotted_key(key: &str) -> bool {
    !key.is_empty()
        && key
            .split('.')
            .all(|s| !s.is_empty() && s.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_'))
}

/// The values of grid point `point`: the last key varies fastest.
fn point_values(grid: &[(String, Vec<toml::Value>)], point: usize) -> Vec<(String, toml::Value)> {
    let mut rest = point;
    let mut out = vec![(String::new(), toml::Value::Boolean(false)); grid.len()];
    for (i, (key, values)) in grid.iter().enumerate().rev() {
        out[i] = (key.clone(), values[rest % values.len()].clone());
        rest /= values.len();
    }
    out
}

/// Sets dotted `key` in `table` to `value`, making the tables on its way.
fn set_key(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts.pop().unwrap_or(key);
    let mut t = table;
    let mut path = String::new();
    for p in parts {
        if !path.is_empty() {
            path.push('.');
        }
        path.push_str(p);
        let entry = t
            .entry(p.to_owned())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = match entry {
            toml::Value::Table(inner) => inner,
            other => {
                return Err(format!(
                    "`{path}` is a {} in the protocol, not a table",
                    other.type_str()
                ));
            }
        };
    }
    t.insert(last.to_owned(), value);
    Ok(())
}

/// The protocol of one grid point and effect size: `(key, problem)` on a refusal,
/// `key` being the sweep file's key that caused it.
fn build_protocol(
    base: &toml::Table,
    set: &BTreeMap<String, toml::Value>,
    values: &[(String, toml::Value)],
    effect: Option<&EffectSweep>,
    size: Option<f64>,
    population: &Population,
) -> Result<Protocol, (String, String)> {
    let mut t = base.clone();
    let mut sources: Vec<(String, String)> = Vec::new();
    for (key, value) in set {
        set_key(&mut t, key, value.clone()).map_err(|e| (format!("set.{key}"), e))?;
        sources.push((key.clone(), format!("set.{key}")));
    }
    for (key, value) in values {
        set_key(&mut t, key, value.clone()).map_err(|e| (format!("grid.{key}"), e))?;
        sources.push((key.clone(), format!("grid.{key}")));
    }
    if let (Some(e), Some(size)) = (effect, size) {
        for (key, value) in &e.fixed {
            set_key(&mut t, key, value.clone()).map_err(|m| (format!("effect.fixed.{key}"), m))?;
            sources.push((key.clone(), format!("effect.fixed.{key}")));
        }
        set_key(&mut t, &e.key, toml::Value::Float(size))
            .map_err(|m| ("effect.key".to_owned(), m))?;
        sources.push((e.key.clone(), "effect.key".to_owned()));
    }
    let subjects = |k: &str| format!("subjects.{k}");
    let mut set_pop = |key: &str, v: toml::Value, from: &str| {
        set_key(&mut t, key, v).map_err(|m| (from.to_owned(), m))?;
        sources.push((key.to_owned(), from.to_owned()));
        Ok::<(), (String, String)>(())
    };
    set_pop(
        &subjects("first_is_nominal"),
        toml::Value::Boolean(population.first_is_nominal),
        "population.first_is_nominal",
    )?;
    if let Some(s) = &population.spread {
        let v =
            toml::Value::try_from(s).map_err(|e| ("population.spread".into(), e.to_string()))?;
        set_pop(&subjects("spread"), v, "population.spread")?;
    }
    if let Some(r) = &population.reflex {
        let v =
            toml::Value::try_from(r).map_err(|e| ("population.reflex".into(), e.to_string()))?;
        set_pop(&subjects("arm.stretch_reflex"), v, "population.reflex")?;
    }
    let text = toml::to_string(&t).map_err(|e| ("protocol".to_owned(), e.to_string()))?;
    Protocol::from_toml(&text, Path::new("<sweep point>")).map_err(|e| {
        // Name the sweep's key that set what the protocol refuses.
        let from = sources
            .iter()
            .rev()
            .find(|(key, _)| e.names(key) || protocol_error_mentions(&e, key))
            .map_or_else(|| "protocol".to_owned(), |(_, from)| from.clone());
        let value = values
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .chain(size.map(|s| format!("effect size {s}")))
            .collect::<Vec<_>>()
            .join(", ");
        let at = if value.is_empty() {
            String::new()
        } else {
            format!(" (at {value})")
        };
        (
            from,
            format!("the protocol refuses it{at}: {}", refusal(&e)),
        )
    })
}

/// The protocol's complaint without its `<sweep point>:` prefix.
fn refusal(e: &ProtocolError) -> String {
    let text = e.to_string();
    let text = text.strip_prefix("<sweep point>: ").unwrap_or(&text);
    // A parse error's line and column are of the generated protocol, not of any file.
    match text.split_once(": ") {
        Some((at, rest)) if at.starts_with("line ") && at.contains(", column ") => rest.to_owned(),
        _ => text.to_owned(),
    }
}

/// True if `e` names a key under `key` or the last segment of `key` (serde names an
/// unknown field by its own name only).
fn protocol_error_mentions(e: &ProtocolError, key: &str) -> bool {
    match e {
        ProtocolError::Invalid { errors, .. } => errors
            .iter()
            .any(|x| x.key.starts_with(key) || key.starts_with(&x.key)),
        ProtocolError::Parse { message, .. } => key
            .rsplit('.')
            .next()
            .is_some_and(|last| message.contains(&format!("`{last}`"))),
        ProtocolError::Read { .. } => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "t"
protocol = "reach-perturb"
seed = 3
replicates = 2

[grid]
"reach.repetitions" = [1, 2]
"controller.force_pulse.amplitude_n" = [10.0, 15.0, 20.0]

[population]
subjects = 2
"#;

    fn err(text: &str) -> SweepFileError {
        match SweepFile::from_toml(text, Path::new("s.toml")) {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => e,
        }
    }

    /// The runs are the grid's product × subjects × replicates, the last grid key
    /// (sorted by name) varying fastest, and every point's protocol carries its values.
    #[test]
    fn the_grid_is_a_product_and_every_point_is_its_protocol() {
        let s = SweepFile::from_toml(GOOD, Path::new("s.toml")).unwrap();
        assert_eq!((s.points(), s.sizes(), s.runs()), (6, 1, 24));
        assert_eq!(s.grid[0].0, "controller.force_pulse.amplitude_n");
        let v = s.point_values(4);
        assert_eq!(v[0].1, toml::Value::Float(20.0));
        assert_eq!(v[1].1, toml::Value::Integer(1));
        assert_eq!(s.protocols[4].controller.force_pulse.amplitude_n, 20.0);
        assert_eq!(s.protocols[4].reach().repetitions, 1);
        assert!(s.estimate && !s.diagnose);
    }

    /// Every shipped sweep file (`hil/sweeps/*.toml`) reads and builds all its points.
    #[test]
    fn the_shipped_sweeps_load() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("sweeps");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let s = SweepFile::load(&path).unwrap_or_else(|e| panic!("{e}"));
                assert!(s.runs() > 0 && s.protocols.len() == s.points() * s.sizes());
                n += 1;
            }
        }
        assert!(n >= 2, "{n} sweep files in {}", dir.display());
    }

    /// `realistic` gives every point the protocol's realistic nuisances; `[set]` holds a
    /// key in every run; a key both set and swept is refused.
    #[test]
    fn realistic_and_set_reach_every_point() {
        let text = GOOD.replace(
            "replicates = 2",
            "replicates = 2\nrealistic = true\n\n[set]\n\"recording.rate_hz\" = 500",
        );
        let s = SweepFile::from_toml(&text, Path::new("s.toml")).unwrap();
        assert!(s.realistic);
        for p in &s.protocols {
            assert_eq!(
                p.nuisance,
                Some(crate::protocol::nuisance::NuisanceConfig::REALISTIC)
            );
            assert_eq!(p.recording.rate_hz, 500);
        }
        let both = text.replace("\"recording.rate_hz\" = 500", "\"reach.repetitions\" = 2");
        assert!(err(&both).names("set.reach.repetitions"));
    }

    /// Each bad file is refused naming its key (and, where the file has it, the line).
    #[test]
    fn bad_sweep_files_name_the_key_and_the_line() {
        let cases: [(&str, &str, &str); 8] = [
            (
                &GOOD.replace("replicates = 2", "replicates = 0"),
                "replicates",
                "line 5",
            ),
            (
                &GOOD.replace("\"reach.repetitions\"", "\"reach.repetitons\""),
                "grid.reach.repetitons",
                "line 8",
            ),
            (
                &GOOD.replace("15.0, 20.0", "-15.0, 20.0"),
                "grid.controller.force_pulse.amplitude_n",
                "line 9",
            ),
            (&GOOD.replace("seed = 3", "sede = 3"), "sede", "line 4"),
            (
                &GOOD.replace("subjects = 2", "subjects = 0"),
                "population.subjects",
                "line 12",
            ),
            (
                &format!(
                    "{GOOD}\n[effect]\nname = \"handle-mass\"\nkey = \"plant.effects.handle_mass.extra_mass_kg\"\nsizes = [0.2]\nparameter = \"mass_kg\"\n"
                ),
                "effect.parameter",
                "extra_mass_kg",
            ),
            (
                &format!(
                    "{GOOD}\n[effect]\nname = \"cogging\"\nkey = \"a.b\"\nsizes = [0.2]\nparameter = \"x\"\n"
                ),
                "name",
                "cogging",
            ),
            (
                &GOOD.replace("reach-perturb", "no-such-protocol"),
                "protocol",
                "no-such-protocol",
            ),
        ];
        for (text, key, also) in cases {
            let e = err(text);
            let msg = e.to_string();
            assert!(e.names(key), "{key}: {msg}");
            assert!(msg.contains(also), "{also}: {msg}");
            assert!(msg.starts_with("s.toml"), "{msg}");
        }
    }
}
