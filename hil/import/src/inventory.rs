//! What a log file holds: [`inspect`] and its [`Inventory`].

use std::fmt;
use std::path::{Path, PathBuf};

use crate::error::ImportError;
use crate::log::{Log, UniformFit, shape_text, time_tolerance, uniform_rate};
use crate::map::CsvOptions;

/// One variable (MATLAB; struct fields as `a.b.c`) or column (CSV) of a log.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Name as a map's `var` gives it.
    pub name: String,
    /// Dimensions (`[rows, 1]` for a CSV column).
    pub shape: Vec<usize>,
    /// Element class: `double`, `single`, `int16`, `logical`, `struct (2 fields)`,
    /// `char`, `cell`, `text` (a CSV column with a field that is not a number)…
    pub class: String,
    /// The sampling rate, Hz, when this looks like a uniform time vector (named `t`,
    /// `time`, `t_s`, `tout`, or ending in `.time` and so on, or a CSV's first column).
    pub rate_hz: Option<f64>,
    /// Whether a map can use it as a channel (numeric).
    pub numeric: bool,
}

/// What a log file holds, as [`inspect`] finds it.
#[derive(Debug, Clone, PartialEq)]
pub struct Inventory {
    /// The file.
    pub file: PathBuf,
    /// `MATLAB level 5`, `MATLAB v7.3 (HDF5)`, `CSV (comma-separated)`, `TSV (tab-separated)`…
    pub format: String,
    /// Every variable or column, in file order.
    pub entries: Vec<Entry>,
}

fn looks_like_time(name: &str) -> bool {
    let last = name.rsplit('.').next().unwrap_or(name).to_ascii_lowercase();
    matches!(last.as_str(), "t" | "time" | "t_s" | "tout")
}

/// Lists what a log holds: each variable or column with its shape, element class and,
/// for a uniform time vector, the rate. A text log is read with the delimiter and
/// header sniffed.
///
/// # Errors
/// [`ImportError::Io`], [`ImportError::MatCorrupt`], [`ImportError::MatV73Corrupt`],
/// [`ImportError::Csv`].
pub fn inspect(path: &Path) -> Result<Inventory, ImportError> {
    let log = crate::read::read_log(path, &CsvOptions::default())?;
    Ok(inventory(&log))
}

pub(crate) fn inventory(log: &Log) -> Inventory {
    let text = log.row_lines.is_some();
    let entries = log
        .vars
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let vector = v.shape.iter().filter(|&&d| d != 1).count() <= 1;
            let candidate =
                v.bad.is_none() && vector && (looks_like_time(&v.name) || (text && k == 0));
            let rate_hz = match (&v.values, candidate) {
                (Some(values), true) => match uniform_rate(values, time_tolerance(v.decimals, 1.0))
                {
                    UniformFit::Rate(r) => Some(r),
                    _ => None,
                },
                _ => None,
            };
            Entry {
                name: v.name.clone(),
                shape: v.shape.clone(),
                class: v.class.clone(),
                rate_hz,
                numeric: v.values.is_some() && v.bad.is_none(),
            }
        })
        .collect();
    Inventory {
        file: log.path.clone(),
        format: log.format.clone(),
        entries,
    }
}

impl fmt::Display for Inventory {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{} ({})", self.file.display(), self.format)?;
        let shapes: Vec<String> = self.entries.iter().map(|e| shape_text(&e.shape)).collect();
        let wn = self
            .entries
            .iter()
            .map(|e| e.name.chars().count())
            .chain([4])
            .max()
            .unwrap_or(4);
        let ws = shapes
            .iter()
            .map(|s| s.chars().count())
            .chain([5])
            .max()
            .unwrap_or(5);
        let wc = self
            .entries
            .iter()
            .map(|e| e.class.chars().count())
            .chain([4])
            .max()
            .unwrap_or(4);
        writeln!(f, "  {:wn$}  {:ws$}  {:wc$}  note", "name", "shape", "type")?;
        // Widths count characters (`×` is one), as `format!` pads.
        for (e, shape) in self.entries.iter().zip(&shapes) {
            let note = match (e.rate_hz, e.numeric) {
                (Some(r), _) => format!("uniform time: {r} Hz"),
                (None, true) => String::new(),
                (None, false) if e.class.starts_with("struct") => "fields below".into(),
                (None, false) => "not a channel".into(),
            };
            let line = format!("  {:wn$}  {shape:ws$}  {:wc$}  {note}", e.name, e.class);
            writeln!(f, "{}", line.trim_end())?;
        }
        if self.entries.is_empty() {
            writeln!(f, "  (no variables)")?;
        }
        Ok(())
    }
}
