//! MATLAB v7.3 MAT-files: an HDF5 file behind a 512-byte user block (MATLAB's text
//! header), read with the pure-Rust `hdf5-pure`.
//!
//! The HDF5 side (superblock, object headers, B-trees, chunks, deflate) is hdf5-pure's;
//! the MATLAB conventions are walked here, into the same [`Var`]s the level-5 reader
//! gives:
//! - every top-level variable is a dataset, or a group for a struct, at the root
//!   (`#refs#` and `#subsystem#`, MATLAB's hidden stores, are not variables); names
//!   are listed sorted, as HDF5 keeps them;
//! - the attribute `MATLAB_class` gives the class (`double`, `int16`, `logical`,
//!   `struct`, `char`, `cell`…); without it the class follows the HDF5 element type;
//! - data are column-major, so the HDF5 dimensions are the MATLAB dimensions reversed
//!   (an N×1 vector is stored as (1, N)); the values, read in storage order, are
//!   MATLAB's column-major order, as [`Var::values`] wants;
//! - `MATLAB_empty` marks an empty array, whose dataset holds its dimensions;
//! - a struct's fields are the group's members (in the order of `MATLAB_fields` when
//!   present), named `s.field`; a struct array (a group whose members are datasets of
//!   object references, one per element) is followed through the references, its
//!   elements named `s(k).field` (1-based, column-major), as for level 5;
//! - char, cell, sparse (`MATLAB_sparse`), complex arrays and objects
//!   (`MATLAB_object_decode`, e.g. `string`) are listed with their class and no values,
//!   so they are not channels.
//!
//! hdf5-pure returns errors for the faults it finds; every call into it is also made
//! under `catch_unwind`, so that a corrupt file it does not expect is still an
//! [`ImportError::MatV73Corrupt`] naming the file and the variable, never a panic.

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use hdf5_pure::{AttrValue, DType, Dataset, File, Group, Object};

use crate::error::ImportError;
use crate::log::{Log, Var};

/// The HDF5 format signature.
const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";
/// Deepest struct nesting (and chain of references) followed.
const MAX_DEPTH: usize = 32;
/// Deflate expands at most ~1032:1; a dataset that declares more elements than this
/// allows for the whole file is corrupt (a guard before anything is allocated).
const MAX_EXPANSION: u64 = 1100;

/// Whether `bytes` is a MATLAB v7.3 MAT-file: MATLAB's header text says so, or the
/// HDF5 signature sits where MATLAB puts it (byte 512) or at the start (an HDF5 file
/// written without MATLAB's user block).
pub(crate) fn is_v73(bytes: &[u8]) -> bool {
    let text = String::from_utf8_lossy(bytes.get(..116).unwrap_or(bytes));
    text.contains("MATLAB 7.3 MAT-file")
        || bytes.get(512..520) == Some(HDF5_SIGNATURE)
        || bytes.starts_with(HDF5_SIGNATURE)
}

/// A fault: what was being read (`HDF5 file`, ``variable `x` ``) and what is wrong.
type Fault = (String, String);

fn in_var(name: &str) -> impl Fn(hdf5_pure::Error) -> Fault + '_ {
    move |e| (format!("variable `{name}`"), e.to_string())
}

/// Reads a v7.3 MAT-file's variables.
pub(crate) fn read(path: &Path, bytes: Vec<u8>) -> Result<Log, ImportError> {
    let corrupt = |(what, message): Fault| ImportError::MatV73Corrupt {
        file: path.to_path_buf(),
        what,
        message,
    };
    let limit = (bytes.len() as u64)
        .saturating_mul(MAX_EXPANSION)
        .max(1 << 24);
    let walked = catch_unwind(AssertUnwindSafe(move || -> Result<Vec<Var>, Fault> {
        let file = File::from_bytes(bytes).map_err(|e| {
            (
                "HDF5 file".to_string(),
                format!("cannot be opened, truncated or corrupt ({e})"),
            )
        })?;
        let walker = Walker { limit };
        let mut vars = Vec::new();
        walker.members(&file.root(), "", &mut vars, 0)?;
        Ok(vars)
    }));
    let vars = match walked {
        Ok(r) => r.map_err(corrupt)?,
        Err(_) => {
            return Err(corrupt((
                "HDF5 file".into(),
                "the HDF5 reader failed on a corrupt structure".into(),
            )));
        }
    };
    Ok(Log {
        path: path.to_path_buf(),
        format: "MATLAB v7.3 (HDF5)".into(),
        vars,
        row_lines: None,
    })
}

struct Walker {
    /// The most bytes of values a dataset may declare.
    limit: u64,
}

/// A member of a group: a dataset or a group.
enum Member {
    Dataset(Dataset),
    Group(Group),
}

fn class_attr(attrs: &HashMap<String, AttrValue>) -> Option<String> {
    attrs
        .get("MATLAB_class")
        .and_then(AttrValue::as_str)
        .map(|s| s.trim_end_matches('\0').to_string())
}

/// The class a dataset without `MATLAB_class` has, from its element type.
fn class_of(dtype: &DType) -> &'static str {
    match dtype {
        DType::F64 => "double",
        DType::F32 => "single",
        DType::I8 => "int8",
        DType::I16 => "int16",
        DType::I32 => "int32",
        DType::I64 => "int64",
        DType::U8 => "uint8",
        DType::U16 => "uint16",
        DType::U32 => "uint32",
        DType::U64 => "uint64",
        DType::String | DType::VariableLengthString => "char",
        DType::ObjectReference => "cell",
        _ => "unknown",
    }
}

fn is_numeric_class(class: &str) -> bool {
    matches!(
        class,
        "double"
            | "single"
            | "int8"
            | "uint8"
            | "int16"
            | "uint16"
            | "int32"
            | "uint32"
            | "int64"
            | "uint64"
            | "logical"
    )
}

/// MATLAB's dimensions from HDF5's: reversed, at least two.
fn matlab_shape(hdf5: &[u64]) -> Result<Vec<usize>, String> {
    let mut shape = hdf5
        .iter()
        .rev()
        .map(|&d| usize::try_from(d).map_err(|_| format!("dimension {d} too large")))
        .collect::<Result<Vec<_>, _>>()?;
    while shape.len() < 2 {
        shape.push(1);
    }
    Ok(shape)
}

fn child_name(prefix: &str, name: &str) -> String {
    if prefix.is_empty() {
        name.to_string()
    } else {
        format!("{prefix}.{name}")
    }
}

impl Walker {
    /// The members of `group` (hidden `#…` stores skipped): the names of
    /// `MATLAB_fields` first, in its order, then the others sorted.
    fn list(&self, group: &Group, what: &str) -> Result<Vec<(String, Member)>, Fault> {
        let err = |e: hdf5_pure::Error| (what.to_string(), e.to_string());
        let mut names: Vec<(String, bool)> = group
            .datasets()
            .map_err(err)?
            .into_iter()
            .map(|n| (n, true))
            .chain(group.groups().map_err(err)?.into_iter().map(|n| (n, false)))
            .filter(|(n, _)| !n.starts_with('#'))
            .collect();
        names.sort();
        let order: Vec<String> = group
            .attrs()
            .map_err(err)?
            .get("MATLAB_fields")
            .and_then(AttrValue::as_strings)
            .map(<[String]>::to_vec)
            .unwrap_or_default();
        let rank = |n: &str| order.iter().position(|f| f == n).unwrap_or(usize::MAX);
        names.sort_by_key(|(n, _)| rank(n));
        names
            .into_iter()
            .map(|(n, is_dataset)| {
                let m = if is_dataset {
                    Member::Dataset(group.dataset(&n).map_err(err)?)
                } else {
                    Member::Group(group.group(&n).map_err(err)?)
                };
                Ok((n, m))
            })
            .collect()
    }

    /// Pushes the variables of every member of `group`, named under `prefix`.
    fn members(
        &self,
        group: &Group,
        prefix: &str,
        out: &mut Vec<Var>,
        depth: usize,
    ) -> Result<(), Fault> {
        let what = if prefix.is_empty() {
            "HDF5 file".to_string()
        } else {
            format!("variable `{prefix}`")
        };
        for (name, member) in self.list(group, &what)? {
            let full = child_name(prefix, &name);
            self.object(member, &full, out, depth)?;
        }
        Ok(())
    }

    fn object(&self, m: Member, name: &str, out: &mut Vec<Var>, depth: usize) -> Result<(), Fault> {
        match m {
            Member::Dataset(ds) => {
                out.push(self.dataset(&ds, name)?);
                Ok(())
            }
            Member::Group(g) => self.group(&g, name, out, depth + 1),
        }
    }

    /// A struct (or object) stored as a group.
    fn group(&self, g: &Group, name: &str, out: &mut Vec<Var>, depth: usize) -> Result<(), Fault> {
        let ctx = in_var(name);
        if depth > MAX_DEPTH {
            return Err((
                format!("variable `{name}`"),
                "structs nested too deep".into(),
            ));
        }
        let attrs = g.attrs().map_err(&ctx)?;
        let mut class = class_attr(&attrs).unwrap_or_else(|| "struct".into());
        if attrs.contains_key("MATLAB_sparse") {
            // A sparse matrix: a group of data, ir and jc.
            class = "sparse".into();
        }
        if class != "struct" || attrs.contains_key("MATLAB_object_decode") {
            // A sparse matrix or an object of a user class: listed, not walked.
            out.push(Var {
                name: name.to_string(),
                shape: vec![1, 1],
                class,
                values: None,
                bad: None,
                decimals: None,
            });
            return Ok(());
        }
        let members = self.list(g, &format!("variable `{name}`"))?;
        // A struct array: no subgroups, and every field a dataset of object references
        // without a class of its own (a cell field has `MATLAB_class = cell`).
        let mut array = !members.is_empty();
        for (_, m) in &members {
            array &= match m {
                Member::Group(_) => false,
                Member::Dataset(ds) => {
                    ds.dtype().map_err(&ctx)? == DType::ObjectReference
                        && !ds.attrs().map_err(&ctx)?.contains_key("MATLAB_class")
                }
            };
        }
        if !array {
            out.push(Var {
                name: name.to_string(),
                shape: vec![1, 1],
                class: format!("struct ({} fields)", members.len()),
                values: None,
                bad: None,
                decimals: None,
            });
            for (field, m) in members {
                self.object(m, &child_name(name, &field), out, depth)?;
            }
            return Ok(());
        }
        let mut shape = None;
        let mut fields = Vec::with_capacity(members.len());
        for (field, m) in members {
            let Member::Dataset(ds) = m else {
                continue;
            };
            let s = matlab_shape(&ds.shape().map_err(&ctx)?).map_err(|e| (ctx_text(name), e))?;
            if shape.as_ref().is_some_and(|first| *first != s) {
                return Err((
                    ctx_text(name),
                    format!("struct array field `{field}` has another shape than the first"),
                ));
            }
            let targets = ds.dereference().map_err(&ctx)?;
            shape = Some(s);
            fields.push((field, targets));
        }
        let shape = shape.unwrap_or_else(|| vec![0, 0]);
        let count: usize = shape.iter().product();
        out.push(Var {
            name: name.to_string(),
            shape,
            class: format!("struct ({} fields)", fields.len()),
            values: None,
            bad: None,
            decimals: None,
        });
        let mut columns: Vec<(String, std::vec::IntoIter<Object>)> = fields
            .into_iter()
            .map(|(f, t)| {
                if t.len() == count {
                    Ok((f, t.into_iter()))
                } else {
                    Err((
                        ctx_text(name),
                        format!(
                            "struct array field `{f}` has {} references for {count} elements",
                            t.len()
                        ),
                    ))
                }
            })
            .collect::<Result<_, _>>()?;
        for k in 0..count {
            for (field, targets) in &mut columns {
                let child = if count == 1 {
                    format!("{name}.{field}")
                } else {
                    format!("{name}({}).{field}", k + 1)
                };
                let member = match targets.next() {
                    Some(Object::Dataset(ds)) => Member::Dataset(*ds),
                    Some(Object::Group(g)) => Member::Group(g),
                    // Another kind of object (a named datatype): nothing to list.
                    _ => continue,
                };
                self.object(member, &child, out, depth)?;
            }
        }
        Ok(())
    }

    /// One array stored as a dataset.
    fn dataset(&self, ds: &Dataset, name: &str) -> Result<Var, Fault> {
        let ctx = in_var(name);
        let attrs = ds.attrs().map_err(&ctx)?;
        let dtype = ds.dtype().map_err(&ctx)?;
        let hdf5_shape = ds.shape().map_err(&ctx)?;
        let class = class_attr(&attrs).unwrap_or_else(|| class_of(&dtype).into());
        let mut var = Var {
            name: name.to_string(),
            shape: matlab_shape(&hdf5_shape).map_err(|e| (ctx_text(name), e))?,
            class,
            values: None,
            bad: None,
            decimals: None,
        };
        let empty = attrs
            .get("MATLAB_empty")
            .and_then(AttrValue::as_i64)
            .is_some_and(|v| v != 0);
        if empty {
            // The dataset holds the dimensions (HDF5 order), not values.
            let dims = ds.read_u64().map_err(&ctx)?;
            var.shape = if dims.len() >= 2 && dims.contains(&0) {
                matlab_shape(&dims).map_err(|e| (ctx_text(name), e))?
            } else {
                vec![0, 0]
            };
            if is_numeric_class(&var.class) {
                var.values = Some(Vec::new());
            }
            return Ok(var);
        }
        if attrs.contains_key("MATLAB_object_decode") || !is_numeric_class(&var.class) {
            return Ok(var);
        }
        let element = match dtype {
            DType::F64 | DType::I64 | DType::U64 => 8,
            DType::F32 | DType::I32 | DType::U32 => 4,
            DType::I16 | DType::U16 => 2,
            DType::I8 | DType::U8 => 1,
            // Complex arrays are compounds {real, imag}.
            DType::Compound(_) => {
                var.class = format!("complex {}", var.class);
                return Ok(var);
            }
            other => {
                return Err((
                    ctx_text(name),
                    format!(
                        "MATLAB_class `{}` over HDF5 elements of type {other}",
                        var.class
                    ),
                ));
            }
        };
        let count = hdf5_shape
            .iter()
            .try_fold(1_u64, |a, &d| a.checked_mul(d))
            .filter(|&c| c.saturating_mul(element) <= self.limit)
            .ok_or_else(|| (ctx_text(name), "dimensions too large for the file".into()))?;
        let values = ds.read_f64().map_err(&ctx)?;
        if values.len() as u64 != count {
            return Err((
                ctx_text(name),
                format!("{} values for {count} elements", values.len()),
            ));
        }
        var.values = Some(values);
        Ok(var)
    }
}

fn ctx_text(name: &str) -> String {
    format!("variable `{name}`")
}
