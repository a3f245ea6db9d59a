//! Trial tables: one CSV file per trial, stored in memory as column vectors.
//!
//! Reading accepts columns in any order, `#` comment lines, CRLF line ends, a UTF-8
//! byte-order mark and blanks around fields. Every field of every column, known or
//! not, must be a finite number (the spec's tables are tables of numbers); unknown
//! columns are kept as [`Column`]s in file order. Time must be `i / rate_hz` on row
//! `i`, within the tolerance of [`time_tolerance_s`].

use std::fmt::Write as _;
use std::path::Path;

use super::error::SessionError;

/// The required columns, in the order the writer puts them.
pub const REQUIRED_COLUMNS: [&str; 7] = [
    "t_s",
    "x_m",
    "y_m",
    "fx_n",
    "fy_n",
    "pert_fx_n",
    "pert_fy_n",
];
/// The optional columns the spec names, in the order the writer puts them.
pub const OPTIONAL_COLUMNS: [&str; 6] = [
    "vx_m_per_s",
    "vy_m_per_s",
    "ref_x_m",
    "ref_y_m",
    "cmd_fx_n",
    "cmd_fy_n",
];

/// A column the spec does not name, kept as read.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Header name.
    pub name: String,
    /// One value per sample.
    pub values: Vec<f64>,
}

/// One trial's samples as columns of equal length. Units are in the names; the frame is
/// the rig frame of the recording spec.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trial {
    /// Time since the first sample, s: `i / rate_hz`.
    pub t_s: Vec<f64>,
    /// Handle position x, m.
    pub x_m: Vec<f64>,
    /// Handle position y, m.
    pub y_m: Vec<f64>,
    /// Force of the hand on the handle, x, N.
    pub fx_n: Vec<f64>,
    /// Force of the hand on the handle, y, N.
    pub fy_n: Vec<f64>,
    /// Perturbation force added to the admittance input, x, N.
    pub pert_fx_n: Vec<f64>,
    /// Perturbation force added to the admittance input, y, N.
    pub pert_fy_n: Vec<f64>,
    /// Drive velocity x, m/s.
    pub vx_m_per_s: Option<Vec<f64>>,
    /// Drive velocity y, m/s.
    pub vy_m_per_s: Option<Vec<f64>>,
    /// Admittance position reference x, m.
    pub ref_x_m: Option<Vec<f64>>,
    /// Admittance position reference y, m.
    pub ref_y_m: Option<Vec<f64>>,
    /// Motor force command x, N.
    pub cmd_fx_n: Option<Vec<f64>>,
    /// Motor force command y, N.
    pub cmd_fy_n: Option<Vec<f64>>,
    /// Columns the spec does not name, in file order.
    pub extra: Vec<Column>,
}

/// The largest difference between a row's `t_s` and `i / rate_hz` that is still a
/// uniform clock, s. `decimals` is how many decimals the value was written with (a
/// file written to 1 µs may be off by half of that); the rounding allowance is capped
/// at a quarter period so that a missing sample (one period) is always caught.
#[must_use]
pub fn time_tolerance_s(rate_hz: f64, decimals: i32) -> f64 {
    let period = 1.0 / rate_hz;
    let rounding = 0.5 * 10_f64.powi(-decimals.clamp(-300, 300));
    rounding.min(0.25 * period) + 1e-6 * period + 1e-9
}

/// Decimal places of a number's text: `0.001` → 3, `1.5e-4` → 5, `12` → 0.
fn decimals(text: &str) -> i32 {
    let (mantissa, exp) = match text.find(['e', 'E']) {
        Some(i) => (&text[..i], text[i + 1..].parse::<i32>().unwrap_or(0)),
        None => (text, 0),
    };
    let frac = mantissa.split_once('.').map_or(0, |(_, f)| f.len());
    i32::try_from(frac).unwrap_or(i32::MAX / 2) - exp
}

impl Trial {
    /// Number of samples.
    #[must_use]
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// `true` when there is no sample.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Time of the last sample, s (0 for an empty trial).
    #[must_use]
    pub fn end_s(&self) -> f64 {
        self.t_s.last().copied().unwrap_or(0.0)
    }

    /// Peak magnitude of the hand force `|(fx, fy)|`, N.
    #[must_use]
    pub fn peak_force_n(&self) -> f64 {
        self.fx_n
            .iter()
            .zip(&self.fy_n)
            .map(|(x, y)| x.hypot(*y))
            .fold(0.0, f64::max)
    }

    /// Length of the handle's path, m.
    #[must_use]
    pub fn path_length_m(&self) -> f64 {
        let steps = self.x_m.windows(2).zip(self.y_m.windows(2));
        steps.map(|(x, y)| (x[1] - x[0]).hypot(y[1] - y[0])).sum()
    }

    /// A column by header name, known or extra.
    #[must_use]
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns()
            .into_iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v)
    }

    /// Every present column as (name, values), in the writer's order: required, then
    /// the present optional ones, then the extra ones.
    #[must_use]
    pub fn columns(&self) -> Vec<(&str, &[f64])> {
        let required = [
            &self.t_s,
            &self.x_m,
            &self.y_m,
            &self.fx_n,
            &self.fy_n,
            &self.pert_fx_n,
            &self.pert_fy_n,
        ];
        let optional = [
            &self.vx_m_per_s,
            &self.vy_m_per_s,
            &self.ref_x_m,
            &self.ref_y_m,
            &self.cmd_fx_n,
            &self.cmd_fy_n,
        ];
        let mut out: Vec<(&str, &[f64])> = REQUIRED_COLUMNS
            .iter()
            .zip(required)
            .map(|(n, v)| (*n, v.as_slice()))
            .collect();
        for (n, v) in OPTIONAL_COLUMNS.iter().zip(optional) {
            if let Some(v) = v {
                out.push((*n, v.as_slice()));
            }
        }
        out.extend(
            self.extra
                .iter()
                .map(|c| (c.name.as_str(), c.values.as_slice())),
        );
        out
    }

    fn slot(&mut self, name: &str) -> Option<&mut Vec<f64>> {
        Some(match name {
            "t_s" => &mut self.t_s,
            "x_m" => &mut self.x_m,
            "y_m" => &mut self.y_m,
            "fx_n" => &mut self.fx_n,
            "fy_n" => &mut self.fy_n,
            "pert_fx_n" => &mut self.pert_fx_n,
            "pert_fy_n" => &mut self.pert_fy_n,
            "vx_m_per_s" => self.vx_m_per_s.get_or_insert_with(Vec::new),
            "vy_m_per_s" => self.vy_m_per_s.get_or_insert_with(Vec::new),
            "ref_x_m" => self.ref_x_m.get_or_insert_with(Vec::new),
            "ref_y_m" => self.ref_y_m.get_or_insert_with(Vec::new),
            "cmd_fx_n" => self.cmd_fx_n.get_or_insert_with(Vec::new),
            "cmd_fy_n" => self.cmd_fy_n.get_or_insert_with(Vec::new),
            _ => return None,
        })
    }

    /// The header line the writer puts at the top of this trial's file.
    pub(crate) fn header_line(&self) -> String {
        let names: Vec<&str> = self.columns().into_iter().map(|(n, _)| n).collect();
        let mut s = names.join(",");
        s.push('\n');
        s
    }

    /// Checks that the trial can be written as a valid table: equal column lengths,
    /// at least one sample, finite values. `file` names the target in errors.
    pub(crate) fn check_writable(&self, file: &Path) -> Result<(), SessionError> {
        let invalid = |message: String| SessionError::InvalidWrite {
            file: file.to_path_buf(),
            message,
        };
        if self.is_empty() {
            return Err(invalid("a trial needs at least one sample".into()));
        }
        for (name, values) in self.columns() {
            if values.len() != self.len() {
                return Err(invalid(format!(
                    "column `{name}` has {} values, `t_s` has {}",
                    values.len(),
                    self.len()
                )));
            }
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(invalid(format!(
                    "column `{name}` row {i}: {} is not finite",
                    values[i]
                )));
            }
            if !is_column_name(name) {
                return Err(invalid(format!(
                    "column name {name:?} is not a plain CSV header name"
                )));
            }
        }
        Ok(())
    }

    /// The whole table as CSV bytes, as the writer produces them.
    #[must_use]
    pub fn to_csv(&self) -> String {
        let columns = self.columns();
        let mut out = self.header_line();
        for i in 0..self.len() {
            for (k, (_, v)) in columns.iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                let _ = write!(out, "{}", v.get(i).copied().unwrap_or(f64::NAN));
            }
            out.push('\n');
        }
        out
    }
}

/// The 1-based line of a byte offset, for offsets that only grow: each call counts the
/// newlines since the previous one, so a whole file costs one pass.
struct LineOf<'a> {
    bytes: &'a [u8],
    byte: usize,
    line: usize,
}

impl<'a> LineOf<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        LineOf {
            bytes,
            byte: 0,
            line: 1,
        }
    }

    /// The line of the record the csv reader placed at `byte` (at or after the previous
    /// call's offset). After a CRLF line the reader's offset is the `\n` of the previous
    /// line's end, so line-end bytes at the offset are skipped first: no record starts
    /// with one.
    fn at(&mut self, byte: usize) -> usize {
        let mut end = byte.min(self.bytes.len());
        while end < self.bytes.len() && matches!(self.bytes[end], b'\r' | b'\n') {
            end += 1;
        }
        if end > self.byte {
            self.line += self.bytes[self.byte..end]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            self.byte = end;
        }
        self.line
    }
}

/// A header name the writer can put in a CSV file without quoting.
pub(crate) fn is_column_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('#')
        && name
            .bytes()
            .all(|b| b.is_ascii_graphic() && !matches!(b, b',' | b'"'))
}

/// Parses a trial table. `rate_hz` is the manifest's; `file` names the file in errors.
pub(crate) fn parse_csv(bytes: &[u8], rate_hz: f64, file: &Path) -> Result<Trial, SessionError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(bytes);
    // Lines are counted from the record's byte offset: the csv crate's own line count
    // is one short after every CRLF-ended line (what Windows, MATLAB and Excel write).
    let mut lines = LineOf::new(bytes);
    let csv_error = |e: csv::Error| SessionError::Csv {
        file: file.to_path_buf(),
        line: e
            .position()
            .map_or(0, |p| LineOf::new(bytes).at(p.byte() as usize)),
        message: e.to_string(),
    };
    let mut record = csv::StringRecord::new();
    let header_found = reader.read_record(&mut record).map_err(csv_error)?;
    let header_line = record.position().map_or(1, |p| lines.at(p.byte() as usize));
    if !header_found {
        return Err(SessionError::MissingHeader {
            file: file.to_path_buf(),
            line: header_line,
        });
    }
    let names: Vec<String> = record.iter().map(str::to_string).collect();
    for (i, name) in names.iter().enumerate() {
        let bad = |message: &str| SessionError::BadColumnName {
            file: file.to_path_buf(),
            line: header_line,
            column: name.clone(),
            message: message.into(),
        };
        if name.is_empty() {
            return Err(bad("is empty"));
        }
        if names[..i].contains(name) {
            return Err(bad("appears twice"));
        }
    }
    for required in REQUIRED_COLUMNS {
        if !names.iter().any(|n| n == required) {
            return Err(SessionError::MissingColumn {
                file: file.to_path_buf(),
                line: header_line,
                column: required.into(),
            });
        }
    }
    // A row is a little over 8 bytes per field; reserve so the columns rarely regrow.
    let rows_estimate = bytes.len() / (8 * names.len()).max(1);
    let mut columns: Vec<Vec<f64>> = names
        .iter()
        .map(|_| Vec::with_capacity(rows_estimate))
        .collect();
    let t_index = names.iter().position(|n| n == "t_s").unwrap_or(0);
    let mut row_values = vec![0.0_f64; names.len()];
    let mut previous_t = f64::NEG_INFINITY;
    let mut rows = 0_usize;
    while reader.read_record(&mut record).map_err(csv_error)? {
        let line = record.position().map_or(0, |p| lines.at(p.byte() as usize));
        if record.len() != names.len() {
            return Err(SessionError::FieldCount {
                file: file.to_path_buf(),
                line,
                expected: names.len(),
                found: record.len(),
            });
        }
        for ((value, text), name) in row_values.iter_mut().zip(record.iter()).zip(&names) {
            *value = parse_field(text, file, line, name)?;
        }
        let t = row_values[t_index];
        if t <= previous_t {
            return Err(SessionError::NonMonotonicTime {
                file: file.to_path_buf(),
                line,
                column: "t_s".into(),
                previous_s: previous_t,
                found_s: t,
            });
        }
        let expected = rows as f64 / rate_hz;
        let written_decimals = decimals(record.get(t_index).unwrap_or(""));
        if (t - expected).abs() > time_tolerance_s(rate_hz, written_decimals) {
            return Err(SessionError::NonUniformTime {
                file: file.to_path_buf(),
                line,
                column: "t_s".into(),
                expected_s: expected,
                found_s: t,
            });
        }
        previous_t = t;
        for (column, value) in columns.iter_mut().zip(&row_values) {
            column.push(*value);
        }
        rows += 1;
    }
    if rows == 0 {
        return Err(SessionError::NoSamples {
            file: file.to_path_buf(),
            line: header_line,
        });
    }
    let mut trial = Trial::default();
    for (name, values) in names.into_iter().zip(columns) {
        match trial.slot(&name) {
            Some(slot) => *slot = values,
            None => trial.extra.push(Column { name, values }),
        }
    }
    Ok(trial)
}

fn parse_field(text: &str, file: &Path, line: usize, column: &str) -> Result<f64, SessionError> {
    if text.is_empty() {
        return Err(SessionError::EmptyField {
            file: file.to_path_buf(),
            line,
            column: column.into(),
        });
    }
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(SessionError::NonFinite {
            file: file.to_path_buf(),
            line,
            column: column.into(),
            text: text.into(),
        }),
        Err(_) => Err(SessionError::BadNumber {
            file: file.to_path_buf(),
            line,
            column: column.into(),
            text: text.into(),
        }),
    }
}
