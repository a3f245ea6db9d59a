//! Continuous text logs: CSV, TSV or semicolon-separated, one sample per row.
//!
//! The delimiter is the map's `csv.delimiter` or sniffed from the first line that is
//! not a comment (a tab makes TSV; more semicolons than commas, semicolons; else
//! commas). The first row is a header unless `csv.header = false`, or, when the map
//! does not say, unless every field of it is a number; without a header the columns are
//! `col1`, `col2`, …. Lines starting with `#` and blank lines are skipped; CRLF line
//! ends and a UTF-8 byte-order mark are accepted, and errors give the file's own line
//! numbers (every line counts, comments included). Fields are trimmed; a field may be
//! double-quoted (a header `"x, mm"`), but a quoted field may not span lines. A field that is not a number is an error only if the map uses its column.

use std::path::Path;

use crate::error::ImportError;
use crate::log::{Log, Var, decimals};
use crate::map::CsvOptions;

fn sniff(text: &str) -> u8 {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap_or("");
    let count = |c: char| first.matches(c).count();
    if count('\t') > 0 {
        b'\t'
    } else if count(';') > count(',') {
        b';'
    } else {
        b','
    }
}

/// Splits one line at `delim` into trimmed fields; a field may be double-quoted (`""`
/// inside is a quote), so that a header such as `"x, mm"` is one field.
fn split(line: &str, delim: char, out: &mut Vec<String>) -> Result<(), String> {
    out.clear();
    let mut field = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    let mut was_quoted = false;
    while let Some(c) = chars.next() {
        if quoted {
            if c == '"' {
                if chars.peek() == Some(&'"') {
                    field.push('"');
                    chars.next();
                } else {
                    quoted = false;
                }
            } else {
                field.push(c);
            }
        } else if c == delim {
            out.push(if was_quoted {
                std::mem::take(&mut field)
            } else {
                std::mem::take(&mut field).trim().to_string()
            });
            was_quoted = false;
        } else if c == '"' && field.trim().is_empty() {
            field.clear();
            quoted = true;
            was_quoted = true;
        } else {
            field.push(c);
        }
    }
    if quoted {
        return Err("a quoted field is not closed on its line".into());
    }
    out.push(if was_quoted {
        field
    } else {
        field.trim().to_string()
    });
    Ok(())
}

/// A field as a number (a quoted field may still hold blanks).
fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    if t.is_empty() {
        return None;
    }
    t.parse::<f64>().ok()
}

/// The columns being read.
struct Columns {
    names: Vec<String>,
    values: Vec<Vec<f64>>,
    bad: Vec<Option<(usize, String)>>,
    dec: Vec<Option<i32>>,
    /// The 1-based line of each data row.
    lines: Vec<usize>,
    header_line: usize,
    /// Data rows expected (for reserving), an upper bound.
    capacity: usize,
}

/// A text log at least this large is parsed on two threads.
const PARALLEL_BYTES: usize = 4 << 20;

impl Columns {
    /// Reads the lines of `text`, the first of which is line `first` of the file. With
    /// `until_named`, stops after the line that names the columns (the header, or the
    /// first row) and returns the byte offset after it; else returns `text.len()`. A
    /// fault is its line and message.
    fn read_lines(
        &mut self,
        text: &str,
        first: usize,
        delim: char,
        header: Option<bool>,
        until_named: bool,
    ) -> Result<usize, (usize, String)> {
        let mut fields: Vec<&str> = Vec::new();
        let mut quoted: Vec<String> = Vec::new();
        let mut offset = 0;
        for (k, full) in text.split('\n').enumerate() {
            let line = first + k;
            offset += full.len() + 1;
            let raw = full.strip_suffix('\r').unwrap_or(full);
            if raw.trim_start().starts_with('#') {
                continue;
            }
            let result = if raw.contains('"') {
                split(raw, delim, &mut quoted).map_err(|m| (line, m))?;
                // A line holding only blanks and delimiters.
                if quoted.iter().all(String::is_empty) {
                    continue;
                }
                let record: Vec<&str> = quoted.iter().map(String::as_str).collect();
                self.row(line, &record, header)
            } else {
                fields.clear();
                fields.extend(raw.split(delim).map(str::trim));
                if fields.iter().all(|f| f.is_empty()) {
                    continue;
                }
                self.row(line, &fields, header)
            };
            result.map_err(|m| (line, m))?;
            if until_named && !self.names.is_empty() {
                return Ok(offset.min(text.len()));
            }
        }
        Ok(text.len())
    }

    /// Appends the rows of `later`, read from the lines after this one's.
    fn append(&mut self, later: Columns) {
        let rows = self.lines.len();
        for (k, values) in later.values.into_iter().enumerate() {
            self.values[k].extend(values);
        }
        for (mine, theirs) in self.bad.iter_mut().zip(later.bad) {
            if mine.is_none() {
                *mine = theirs.map(|(row, text)| (row + rows, text));
            }
        }
        for (mine, theirs) in self.dec.iter_mut().zip(later.dec) {
            *mine = match (*mine, theirs) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
        }
        self.lines.extend(later.lines);
    }

    /// Takes one line's fields (not all empty): the header, or a data row.
    fn row(&mut self, line: usize, record: &[&str], header: Option<bool>) -> Result<(), String> {
        if self.names.is_empty() {
            let numeric = record.iter().all(|f| parse_number(f).is_some());
            let header = header.unwrap_or(!numeric);
            let n = record.len();
            self.values = (0..n).map(|_| Vec::with_capacity(self.capacity)).collect();
            self.bad = vec![None; n];
            self.dec = vec![None; n];
            if header {
                self.header_line = line;
                for (k, f) in record.iter().enumerate() {
                    let name = if f.is_empty() {
                        format!("col{}", k + 1)
                    } else {
                        (*f).to_string()
                    };
                    if self.names.contains(&name) {
                        return Err(format!("column `{name}` appears twice"));
                    }
                    self.names.push(name);
                }
                return Ok(());
            }
            self.names = (1..=n).map(|k| format!("col{k}")).collect();
        }
        if record.len() != self.names.len() {
            return Err(format!(
                "{} fields, the {} has {}",
                record.len(),
                if self.header_line > 0 {
                    format!("header (line {})", self.header_line)
                } else {
                    "first row".to_string()
                },
                self.names.len()
            ));
        }
        let row = self.lines.len();
        for (k, f) in record.iter().enumerate() {
            match parse_number(f) {
                Some(v) => {
                    self.values[k].push(v);
                    if v.is_finite() {
                        let d = decimals(f);
                        self.dec[k] = Some(self.dec[k].map_or(d, |m: i32| m.min(d)));
                    }
                }
                None => {
                    self.values[k].push(f64::NAN);
                    if self.bad[k].is_none() {
                        self.bad[k] = Some((row, (*f).to_string()));
                    }
                }
            }
        }
        self.lines.push(line);
        Ok(())
    }
}

/// Reads a text log.
///
/// A line without a double quote (every data row of a log) is split in place, its
/// fields borrowed from the text; only a line with quotes goes through [`split`]. A log
/// of [`PARALLEL_BYTES`] or more is parsed in two halves on two threads (when the
/// machine has two cores), which give the same columns, line numbers and first fault
/// as one pass.
pub(crate) fn read(path: &Path, bytes: &[u8], opts: &CsvOptions) -> Result<Log, ImportError> {
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    let csv_error = |line: usize, message: String| ImportError::Csv {
        file: path.to_path_buf(),
        line,
        message,
    };
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        csv_error(line, "not UTF-8 text".into())
    })?;
    let delimiter = opts.delimiter.unwrap_or_else(|| sniff(text));
    let delim = char::from(delimiter);
    let mut cols = Columns {
        names: Vec::new(),
        values: Vec::new(),
        bad: Vec::new(),
        dec: Vec::new(),
        lines: Vec::new(),
        header_line: 0,
        capacity: 0,
    };
    cols.capacity = 1 + bytes.iter().filter(|&&b| b == b'\n').count();
    cols.lines.reserve(cols.capacity);
    let csv_fault = |(line, message): (usize, String)| csv_error(line, message);
    // The header (or first row) names the columns; the rest is only data rows.
    let named = cols
        .read_lines(text, 1, delim, opts.header, true)
        .map_err(csv_fault)?;
    let rest = &text[named..];
    let rest_line = 1 + bytes[..named].iter().filter(|&&b| b == b'\n').count();
    // A large log is parsed in two halves at a line boundary, on two threads.
    let cut = (rest.len() >= PARALLEL_BYTES
        && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1))
    .then(|| {
        // Just after a newline, so on a character boundary whatever the text holds.
        let mid = rest.len() / 2;
        rest.as_bytes()[mid..]
            .iter()
            .position(|&c| c == b'\n')
            .map(|i| mid + i + 1)
    })
    .flatten();
    match cut {
        Some(cut) if !cols.names.is_empty() => {
            let (a, b) = rest.split_at(cut);
            let b_line = rest_line + a.bytes().filter(|&c| c == b'\n').count();
            let mut second = Columns {
                names: cols.names.clone(),
                values: Vec::new(),
                bad: vec![None; cols.names.len()],
                dec: vec![None; cols.names.len()],
                lines: Vec::new(),
                header_line: cols.header_line,
                capacity: 1 + b.bytes().filter(|&c| c == b'\n').count(),
            };
            second.values = (0..cols.names.len())
                .map(|_| Vec::with_capacity(second.capacity))
                .collect();
            let (first_result, second_result) = std::thread::scope(|scope| {
                let other = scope.spawn(|| second.read_lines(b, b_line, delim, opts.header, false));
                let mine = cols.read_lines(a, rest_line, delim, opts.header, false);
                let theirs = other
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
                (mine, theirs)
            });
            // The first fault in the file is the one reported.
            first_result.map_err(csv_fault)?;
            second_result.map_err(csv_fault)?;
            cols.append(second);
        }
        _ => {
            cols.read_lines(rest, rest_line, delim, opts.header, false)
                .map_err(csv_fault)?;
        }
    }
    let Columns {
        names,
        values: columns,
        bad,
        dec,
        lines,
        header_line,
        ..
    } = cols;
    if lines.is_empty() {
        return Err(csv_error(
            header_line.max(1),
            "the log has no data rows".into(),
        ));
    }
    let n = lines.len();
    let vars = names
        .into_iter()
        .zip(columns)
        .zip(bad.into_iter().zip(dec))
        .map(|((name, values), (bad, decimals))| Var {
            name,
            shape: vec![n, 1],
            class: if bad.is_some() { "text" } else { "double" }.into(),
            values: Some(values),
            bad,
            decimals,
        })
        .collect();
    let format = match delimiter {
        b'\t' => "TSV (tab-separated)".to_string(),
        b',' => "CSV (comma-separated)".to_string(),
        b';' => "CSV (semicolon-separated)".to_string(),
        d => format!("text, separated by {:?}", char::from(d)),
    };
    Ok(Log {
        path: path.to_path_buf(),
        format,
        vars,
        row_lines: Some(lines),
    })
}
