//! Where a dotted key (`reach.trials`, `controller.safety.force_limit_n[1]`,
//! `hold.conditions[2].force_deg`) sits in a protocol's text, so that a validation
//! error names its line; and arrays longer than the key takes, which serde would
//! silently cut (`force_limit_n = [900, 900, 5]` read as `[900, 900]`).

use std::ops::Range;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use super::InvalidKey;

/// One segment of a dotted key: a name and the indices after it (`mass_kg[0]`).
fn segments(dotted: &str) -> Vec<(&str, Vec<usize>)> {
    dotted
        .split('.')
        .map(|seg| {
            let mut parts = seg.split('[');
            let name = parts.next().unwrap_or("");
            let indices = parts
                .filter_map(|p| p.trim_end_matches(']').parse().ok())
                .collect();
            (name, indices)
        })
        .collect()
}

/// The span of the key `dotted` in `root`, or of the deepest table on its path that is
/// there (a key left at its default has no line of its own; its table has).
fn span_of(root: &Spanned<DeTable<'_>>, dotted: &str) -> Option<Range<usize>> {
    let mut table = root.get_ref();
    let mut found: Option<Range<usize>> = None;
    for (name, indices) in segments(dotted) {
        let Some((key, value)) = table.get_key_value(name) else {
            return found;
        };
        found = Some(key.span());
        let mut value = value;
        for i in indices {
            match value.get_ref() {
                DeValue::Array(items) if i < items.len() => {
                    value = &items[i];
                    found = Some(value.span());
                }
                _ => return found,
            }
        }
        match value.get_ref() {
            DeValue::Table(t) => table = t,
            _ => return found,
        }
    }
    found
}

/// The line of each key of `errors` in `text`, parsed as `root` (`None` where the text
/// does not have it, or did not parse).
#[must_use]
pub(crate) fn lines_of(
    text: &str,
    root: Option<&Spanned<DeTable<'_>>>,
    errors: &[InvalidKey],
) -> Vec<Option<usize>> {
    let Some(root) = root else {
        return vec![None; errors.len()];
    };
    errors
        .iter()
        .map(|e| {
            span_of(root, &e.key)
                .map(|s| rigtwin_session::files::line_column(text.as_bytes(), s.start).0)
        })
        .collect()
}

/// Every array of the document `root` with more elements than the same key has in
/// `parsed` (the protocol as serde kept it, written back): serde fills `[f64; 2]` from
/// the first two elements of a longer array without a word.
#[must_use]
pub(crate) fn cut_arrays(root: &Spanned<DeTable<'_>>, parsed: &toml::Value) -> Vec<InvalidKey> {
    let mut out = Vec::new();
    if let toml::Value::Table(kept) = parsed {
        walk_table(root.get_ref(), kept, "", &mut out);
    }
    out
}

fn walk_table(input: &DeTable<'_>, kept: &toml::Table, path: &str, out: &mut Vec<InvalidKey>) {
    for (key, value) in input {
        let name = key.get_ref();
        let Some(k) = kept.get(name.as_ref()) else {
            continue;
        };
        let here = if path.is_empty() {
            name.to_string()
        } else {
            format!("{path}.{name}")
        };
        walk_value(value.get_ref(), k, &here, out);
    }
}

fn walk_value(input: &DeValue<'_>, kept: &toml::Value, path: &str, out: &mut Vec<InvalidKey>) {
    match (input, kept) {
        (DeValue::Table(t), toml::Value::Table(k)) => walk_table(t, k, path, out),
        (DeValue::Array(items), toml::Value::Array(k)) => {
            if items.len() > k.len() {
                out.push(InvalidKey {
                    key: path.to_owned(),
                    problem: format!(
                        "has {} elements; it takes {} (the rest would be ignored)",
                        items.len(),
                        k.len()
                    ),
                });
            }
            for (i, (a, b)) in items.iter().zip(k).enumerate() {
                walk_value(a.get_ref(), b, &format!("{path}[{i}]"), out);
            }
        }
        _ => {}
    }
}
