//! Continuous text logs: CSV, TSV or semicolon-separated, one sample per row.
//!
//! The delimiter is the map's `csv.delimiter` or sniffed from the first line that is
//! not a comment (a tab makes TSV; more semicolons than commas, semicolons; else
//! commas). The first row is a header unless `csv.header = false`, or, when the map
//! does not say, unless every field of it is a number; without a header the columns are
//! `col1`, `col2`, …. Lines starting with `#` and blank lines are skipped; CRLF line
//! ends and a UTF-8 byte-order mark are accepted, and errors give the file's own line
//! numbers. A field that is not a number is an error only if the map uses its column.

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

fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    if t.is_empty() {
        return None;
    }
    t.parse::<f64>().ok()
}

/// Reads a text log.
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
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .has_headers(false)
        .comment(Some(b'#'))
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    let mut names: Vec<String> = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut bad: Vec<Option<(usize, String)>> = Vec::new();
    let mut dec: Vec<Option<i32>> = Vec::new();
    let mut lines: Vec<usize> = Vec::new();
    let mut header_line = 0;
    let mut record = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e
                    .position()
                    .map_or(0, |p| usize::try_from(p.line()).unwrap_or(usize::MAX));
                return Err(csv_error(line, e.to_string()));
            }
        }
        let line = record
            .position()
            .map_or(0, |p| usize::try_from(p.line()).unwrap_or(usize::MAX));
        // A line holding only blanks and delimiters.
        if record.iter().all(str::is_empty) {
            continue;
        }
        if names.is_empty() {
            let numeric = record.iter().all(|f| parse_number(f).is_some());
            let header = opts.header.unwrap_or(!numeric);
            let n = record.len();
            columns = vec![Vec::new(); n];
            bad = vec![None; n];
            dec = vec![None; n];
            if header {
                header_line = line;
                for (k, f) in record.iter().enumerate() {
                    let name = if f.is_empty() {
                        format!("col{}", k + 1)
                    } else {
                        f.to_string()
                    };
                    if names.contains(&name) {
                        return Err(csv_error(line, format!("column `{name}` appears twice")));
                    }
                    names.push(name);
                }
                continue;
            }
            names = (1..=n).map(|k| format!("col{k}")).collect();
        }
        if record.len() != names.len() {
            return Err(csv_error(
                line,
                format!(
                    "{} fields, the {} has {}",
                    record.len(),
                    if header_line > 0 {
                        format!("header (line {header_line})")
                    } else {
                        "first row".to_string()
                    },
                    names.len()
                ),
            ));
        }
        let row = lines.len();
        for (k, f) in record.iter().enumerate() {
            match parse_number(f) {
                Some(v) => {
                    columns[k].push(v);
                    if v.is_finite() {
                        let d = decimals(f);
                        dec[k] = Some(dec[k].map_or(d, |m: i32| m.min(d)));
                    }
                }
                None => {
                    columns[k].push(f64::NAN);
                    if bad[k].is_none() {
                        bad[k] = Some((row, f.to_string()));
                    }
                }
            }
        }
        lines.push(line);
    }
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
