//! A log in memory, whatever file it came from: named variables with a shape, an
//! element class and (when numeric) their values as `f64`, column-major.

use std::path::PathBuf;

use crate::error::{ImportError, MapAt, SampleAt};
use crate::map::SourceRef;

/// One variable of a log: a MATLAB array (struct fields flattened to `a.b.c`) or a
/// CSV column.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Var {
    /// `a.b.c` for struct fields, the header name (or `colK`) for CSV columns.
    pub name: String,
    /// MATLAB dimensions; `[rows, 1]` for a CSV column.
    pub shape: Vec<usize>,
    /// Element class: `double`, `single`, `int16`, `logical`, `char`, `cell`, `text`…
    pub class: String,
    /// Values, column-major, when the class is numeric.
    pub values: Option<Vec<f64>>,
    /// For a CSV column: the first field that is not a number (0-based row, text).
    pub bad: Option<(usize, String)>,
    /// For a CSV column: the fewest decimals any field was written with.
    pub decimals: Option<i32>,
}

/// What a file holds, read.
#[derive(Debug, Clone)]
pub(crate) struct Log {
    /// The file.
    pub path: PathBuf,
    /// `MATLAB level 5`, `MATLAB v7.3 (HDF5)`, `CSV (comma)`…
    pub format: String,
    /// Variables in file order.
    pub vars: Vec<Var>,
    /// For text logs: the 1-based line of each data row.
    pub row_lines: Option<Vec<usize>>,
}

impl Log {
    /// The variable names, for errors.
    pub(crate) fn names(&self) -> Vec<String> {
        self.vars.iter().map(|v| v.name.clone()).collect()
    }

    fn var(&self, name: &str, at: &MapAt) -> Result<&Var, ImportError> {
        self.vars
            .iter()
            .find(|v| v.name == name)
            .ok_or_else(|| ImportError::MissingVariable {
                file: self.path.clone(),
                var: name.to_string(),
                at: at.clone(),
                available: self.names(),
            })
    }

    /// Where sample `i` (0-based) sits, for errors.
    pub(crate) fn sample_at(&self, i: usize) -> SampleAt {
        SampleAt {
            sample: i + 1,
            line: self.row_lines.as_ref().and_then(|l| l.get(i).copied()),
        }
    }

    /// The raw values of one channel of a variable (before scale and offset), checked
    /// to be numbers and finite.
    pub(crate) fn channel(&self, src: &SourceRef) -> Result<Vec<f64>, ImportError> {
        let var = self.var(&src.var, &src.at)?;
        let wrong = |message: String| ImportError::WrongShape {
            file: self.path.clone(),
            var: var.name.clone(),
            shape: shape_text(&var.shape),
            message,
            at: src.at.clone(),
        };
        if let Some((row, text)) = &var.bad {
            let line = self
                .row_lines
                .as_ref()
                .and_then(|l| l.get(*row).copied())
                .unwrap_or(0);
            return Err(ImportError::BadNumber {
                file: self.path.clone(),
                line,
                column: var.name.clone(),
                text: text.clone(),
                at: src.at.clone(),
            });
        }
        let Some(values) = &var.values else {
            return Err(wrong(format!(
                "a {} array holds no numeric samples",
                var.class
            )));
        };
        // Singleton dimensions do not count: Simulink writes 1×1×N.
        let dims: Vec<usize> = var.shape.iter().copied().filter(|&d| d != 1).collect();
        let out: Vec<f64> = match dims.as_slice() {
            [] | [_] => {
                if let Some(c) = src.column
                    && c != 1
                {
                    return Err(wrong(format!(
                        "a vector has one column, `column = {c}` asks for another"
                    )));
                }
                values.clone()
            }
            &[rows, cols] => {
                let Some(c) = src.column else {
                    return Err(wrong(format!(
                        "a matrix holds {} channels; say which with `column = 1..{}`",
                        rows.min(cols),
                        rows.min(cols)
                    )));
                };
                // Samples run along the longer dimension (N×k: one channel per column;
                // k×N: one per row); a square matrix is read as N×k.
                if rows >= cols {
                    if c == 0 || c > cols {
                        return Err(wrong(format!("`column = {c}` is not in 1..{cols}")));
                    }
                    values
                        .get((c - 1) * rows..c * rows)
                        .map(<[f64]>::to_vec)
                        .unwrap_or_default()
                } else {
                    if c == 0 || c > rows {
                        return Err(wrong(format!("`column = {c}` is not in 1..{rows}")));
                    }
                    values.iter().skip(c - 1).step_by(rows).copied().collect()
                }
            }
            _ => {
                return Err(wrong(
                    "an array of more than two non-singleton dimensions is not a channel".into(),
                ));
            }
        };
        if out.is_empty() {
            return Err(wrong("the variable is empty".into()));
        }
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(ImportError::NonFinite {
                file: self.path.clone(),
                var: var.name.clone(),
                sample: self.sample_at(i),
                value: out[i],
                at: src.at.clone(),
            });
        }
        Ok(out)
    }

    /// The fewest decimals a CSV variable's fields were written with.
    pub(crate) fn decimals(&self, name: &str) -> Option<i32> {
        self.vars
            .iter()
            .find(|v| v.name == name)
            .and_then(|v| v.decimals)
    }
}

/// `3×1000`.
pub(crate) fn shape_text(shape: &[usize]) -> String {
    shape
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("×")
}

/// Decimal places of a number's text: `0.001` → 3, `1.5e-4` → 5, `12` → 0.
pub(crate) fn decimals(text: &str) -> i32 {
    // One pass over the bytes (this runs for every field of a text log).
    let b = text.as_bytes();
    let (mantissa, exp) = match b.iter().position(|&c| c == b'e' || c == b'E') {
        Some(i) => (&b[..i], text[i + 1..].parse::<i32>().unwrap_or(0)),
        None => (b, 0),
    };
    let frac = mantissa
        .iter()
        .position(|&c| c == b'.')
        .map_or(0, |p| mantissa.len() - p - 1);
    i32::try_from(frac)
        .unwrap_or(i32::MAX / 2)
        .saturating_sub(exp.clamp(-1000, 1000))
}

/// A uniform clock fitted to `t`: its rate, or the first sample (0-based) off it with
/// the expected and found times. `tolerance_s` is the largest allowed deviation.
pub(crate) fn uniform_rate(t: &[f64], tolerance_s: impl Fn(f64) -> f64) -> UniformFit {
    let n = t.len();
    if n < 2 {
        return UniformFit::TooShort;
    }
    let (first, last) = (t[0], t[n - 1]);
    let span = last - first;
    if !(span.is_finite() && span > 0.0) {
        return UniformFit::Off {
            index: n - 1,
            expected_s: f64::NAN,
            found_s: last,
        };
    }
    let period = span / (n - 1) as f64;
    let tol = tolerance_s(period);
    for (i, &ti) in t.iter().enumerate() {
        let expected = first + i as f64 * period;
        if (ti - expected).abs() > tol || !ti.is_finite() {
            return UniformFit::Off {
                index: i,
                expected_s: expected,
                found_s: ti,
            };
        }
    }
    let rate = 1.0 / period;
    // Snap to the millihertz when that is within the clock's tolerance, so that a
    // 1000 Hz log does not become 999.9999999997 Hz.
    let snapped = (rate * 1e3).round() / 1e3;
    let rate = if ((snapped - rate) / rate).abs() < 1e-9 {
        snapped
    } else {
        rate
    };
    UniformFit::Rate(rate)
}

/// The outcome of [`uniform_rate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum UniformFit {
    /// Uniform at this rate, Hz.
    Rate(f64),
    /// Fewer than two samples.
    TooShort,
    /// Sample `index` is off the clock.
    Off {
        index: usize,
        expected_s: f64,
        found_s: f64,
    },
}

/// The allowed deviation from a uniform clock: 1e-6 of the period, plus, for text, half
/// the last decimal written (times the `scale` into seconds), capped at a quarter
/// period so that a missing sample is always caught.
pub(crate) fn time_tolerance(decimals: Option<i32>, scale: f64) -> impl Fn(f64) -> f64 {
    move |period: f64| {
        let rounding = decimals.map_or(0.0, |d| 0.5 * 10_f64.powi(-d.clamp(-300, 300)));
        (rounding * scale.abs()).min(0.25 * period) + 1e-6 * period
    }
}

#[cfg(test)]
mod tests {
    use super::decimals;

    #[test]
    fn decimals_count_the_fraction_less_the_exponent() {
        for (text, d) in [
            ("0.001", 3),
            ("1.5e-4", 5),
            ("1.5E-4", 5),
            ("12", 0),
            ("-3.250000", 6),
            ("2e3", -3),
            ("1.25e+1", 1),
            (".5", 1),
            ("7.", 0),
        ] {
            assert_eq!(decimals(text), d, "{text}");
        }
    }
}
