//! MATLAB level-5 MAT-files.
//!
//! The file is walked element by element here: the 128-byte header, then top-level
//! elements, each a miMATRIX or a miCOMPRESSED (zlib) wrapping one. Of each miMATRIX the
//! walker reads only the array flags (class), dimensions and name. A numeric array
//! (every integer class, single, double, logical) is handed to `matfile` as a one-array
//! file of its own, so the numeric decoding is matfile's; a struct (mxSTRUCT_CLASS) is
//! walked here: field-name length, field names, then one miMATRIX per field and element,
//! named `s.field` (or `s(k).field` for a struct array), recursively. Other classes
//! (char, cell, sparse, objects) are listed with their class and no values.
//!
//! Every length is checked against the bytes that remain before it is used, so a
//! truncated or corrupt file is a [`ImportError::MatCorrupt`] naming the byte offset and
//! the variable, never a panic.

use std::io::Read;
use std::path::Path;

use crate::error::ImportError;
use crate::log::{Log, Var};

const MI_INT8: u32 = 1;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const HEADER: usize = 128;
/// The largest inflated element accepted (a guard against a corrupt length).
const MAX_INFLATED: u64 = 1 << 34;
/// Deepest struct nesting followed.
const MAX_DEPTH: usize = 32;

/// A fault found while walking, with the byte offset in its buffer.
struct Fault {
    offset: usize,
    message: String,
}

fn fault(offset: usize, message: impl Into<String>) -> Fault {
    Fault {
        offset,
        message: message.into(),
    }
}

/// One data element: its type, its data and where the next element starts.
struct Element<'a> {
    ty: u32,
    data: &'a [u8],
    /// Offset of the data within the walked buffer.
    start: usize,
    next: usize,
}

#[derive(Clone, Copy)]
struct Endian {
    big: bool,
}

impl Endian {
    fn u32(self, b: &[u8], at: usize) -> Result<u32, Fault> {
        let bytes: [u8; 4] = b
            .get(at..at + 4)
            .and_then(|s| s.try_into().ok())
            .ok_or_else(|| fault(at, "truncated: 4 bytes expected"))?;
        Ok(if self.big {
            u32::from_be_bytes(bytes)
        } else {
            u32::from_le_bytes(bytes)
        })
    }

    fn bytes(self, v: u32) -> [u8; 4] {
        if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    }

    /// The element starting at `at` in `b`: normal (8-byte tag, padded to 8) or small
    /// (type and size in one word, up to 4 bytes of data in the next).
    fn element<'a>(self, b: &'a [u8], at: usize) -> Result<Element<'a>, Fault> {
        let first = self.u32(b, at)?;
        if first >> 16 != 0 {
            let size = (first >> 16) as usize;
            if size > 4 {
                return Err(fault(at, format!("small element of {size} bytes (max 4)")));
            }
            let data = b
                .get(at + 4..at + 4 + size)
                .ok_or_else(|| fault(at, "truncated small element"))?;
            return Ok(Element {
                ty: first & 0xffff,
                data,
                start: at + 4,
                next: at + 8,
            });
        }
        let size = self.u32(b, at + 4)? as usize;
        let start = at + 8;
        let data = b.get(start..start.saturating_add(size)).ok_or_else(|| {
            fault(
                at,
                format!(
                    "truncated: the element declares {size} bytes, {} remain",
                    b.len().saturating_sub(start)
                ),
            )
        })?;
        let padded = if first == MI_COMPRESSED {
            size
        } else {
            size.div_ceil(8) * 8
        };
        Ok(Element {
            ty: first,
            data,
            start,
            next: start.saturating_add(padded).min(b.len()),
        })
    }
}

fn class_name(class: u32, logical: bool) -> &'static str {
    match class {
        1 => "cell",
        2 => "struct",
        3 => "object",
        4 => "char",
        5 => "sparse",
        6 => "double",
        7 => "single",
        8 => "int8",
        9 if logical => "logical",
        9 => "uint8",
        10 => "int16",
        11 => "uint16",
        12 => "int32",
        13 => "uint32",
        14 => "int64",
        15 => "uint64",
        16 => "function",
        17 => "opaque",
        _ => "unknown",
    }
}

/// Reads a level-5 MAT-file's variables (a v7.3 file, told by `mat73::is_v73`, is
/// read by `mat73::read` instead).
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<Log, ImportError> {
    let corrupt = |offset: usize, what: &str, message: String| ImportError::MatCorrupt {
        file: path.to_path_buf(),
        offset,
        what: what.to_string(),
        message,
    };
    if bytes.len() < HEADER {
        return Err(corrupt(
            0,
            "header",
            format!(
                "{} bytes, shorter than the 128-byte header of a MAT-file",
                bytes.len()
            ),
        ));
    }
    let endian = match &bytes[126..128] {
        b"IM" => Endian { big: false },
        b"MI" => Endian { big: true },
        _ => {
            return Err(corrupt(
                126,
                "header",
                "no endian indicator: not a MATLAB level-5 MAT-file".into(),
            ));
        }
    };
    let version = if endian.big {
        u16::from_be_bytes([bytes[124], bytes[125]])
    } else {
        u16::from_le_bytes([bytes[124], bytes[125]])
    };
    if version != 0x0100 {
        return Err(corrupt(
            124,
            "header",
            format!("version {version:#06x}, a level-5 MAT-file has 0x0100"),
        ));
    }
    let walker = Walker {
        header: &bytes[..HEADER],
        endian,
    };
    let mut vars = Vec::new();
    let mut at = HEADER;
    while at < bytes.len() {
        // Some writers pad the end of the file with zeros.
        if bytes[at..].iter().all(|&b| b == 0) {
            break;
        }
        let el = endian
            .element(bytes, at)
            .map_err(|f| corrupt(f.offset, "top-level element", f.message))?;
        match el.ty {
            MI_MATRIX => walker
                .matrix(el.data, "", &mut vars, 0)
                .map_err(|(what, f)| corrupt(el.start + f.offset, &what, f.message))?,
            MI_COMPRESSED => {
                let mut inflated = Vec::new();
                flate2::read::ZlibDecoder::new(el.data)
                    .take(MAX_INFLATED)
                    .read_to_end(&mut inflated)
                    .map_err(|e| {
                        corrupt(at, "compressed element", format!("cannot inflate: {e}"))
                    })?;
                // Offsets inside are those of the inflated bytes; name the element.
                let inner = |what: String, f: Fault| {
                    corrupt(
                        at,
                        &what,
                        format!(
                            "{} (at byte {} of the inflated element)",
                            f.message, f.offset
                        ),
                    )
                };
                let mut i = 0;
                while i < inflated.len() {
                    let inner_el = endian
                        .element(&inflated, i)
                        .map_err(|f| inner("compressed element".into(), f))?;
                    if inner_el.ty == MI_MATRIX {
                        walker
                            .matrix(inner_el.data, "", &mut vars, 0)
                            .map_err(|(what, f)| {
                                inner(
                                    what,
                                    Fault {
                                        offset: f.offset + inner_el.start,
                                        message: f.message,
                                    },
                                )
                            })?;
                    }
                    i = inner_el.next;
                }
            }
            // Other top-level elements (subsystem data) hold no variable.
            _ => {}
        }
        at = el.next;
    }
    Ok(Log {
        path: path.to_path_buf(),
        format: "MATLAB level 5".into(),
        vars,
        row_lines: None,
    })
}

struct Walker<'h> {
    header: &'h [u8],
    endian: Endian,
}

type WalkError = (String, Fault);

impl Walker<'_> {
    /// Walks one miMATRIX's data (`m`), naming it `prefix` when its own name is empty
    /// (a struct field) and pushing what it holds onto `out`.
    fn matrix(
        &self,
        m: &[u8],
        prefix: &str,
        out: &mut Vec<Var>,
        depth: usize,
    ) -> Result<(), WalkError> {
        let e = self.endian;
        let ctx = |f: Fault| {
            (
                if prefix.is_empty() {
                    "variable".to_string()
                } else {
                    format!("variable `{prefix}`")
                },
                f,
            )
        };
        if m.is_empty() {
            // An empty miMATRIX: MATLAB's `[]` in a struct field.
            out.push(Var {
                name: prefix.to_string(),
                shape: vec![0, 0],
                class: "double".into(),
                values: Some(Vec::new()),
                bad: None,
                decimals: None,
            });
            return Ok(());
        }
        let flags = e.element(m, 0).map_err(ctx)?;
        if flags.ty != MI_UINT32 || flags.data.len() != 8 {
            return Err(ctx(fault(0, "array flags subelement expected")));
        }
        let word = e.u32(flags.data, 0).map_err(ctx)?;
        let class = word & 0xff;
        let logical = word & 0x0200 != 0;
        let complex = word & 0x0800 != 0;
        let dims_el = e.element(m, flags.next).map_err(ctx)?;
        if dims_el.ty != MI_INT32 || dims_el.data.len() < 8 || dims_el.data.len() % 4 != 0 {
            return Err(ctx(fault(flags.next, "dimensions subelement expected")));
        }
        let mut shape = Vec::with_capacity(dims_el.data.len() / 4);
        for k in 0..dims_el.data.len() / 4 {
            let d = e.u32(dims_el.data, 4 * k).map_err(ctx)?;
            let d = i32::from_ne_bytes(d.to_ne_bytes());
            let d = usize::try_from(d)
                .map_err(|_| ctx(fault(dims_el.start, format!("negative dimension {d}"))))?;
            shape.push(d);
        }
        let count = shape
            .iter()
            .try_fold(1_usize, |a, &d| a.checked_mul(d))
            .filter(|&c| c <= m.len().saturating_mul(8).max(1 << 20))
            .ok_or_else(|| ctx(fault(dims_el.start, "dimensions too large for the data")))?;
        let name_el = e.element(m, dims_el.next).map_err(ctx)?;
        if name_el.ty != MI_INT8 {
            return Err(ctx(fault(dims_el.next, "array name subelement expected")));
        }
        let own = String::from_utf8_lossy(name_el.data).into_owned();
        let name = if own.is_empty() {
            prefix.to_string()
        } else if prefix.is_empty() {
            own
        } else {
            format!("{prefix}.{own}")
        };
        let ctx = |f: Fault| (format!("variable `{name}`"), f);
        let class_text = class_name(class, logical);
        let mut var = Var {
            name: name.clone(),
            shape: shape.clone(),
            class: class_text.into(),
            values: None,
            bad: None,
            decimals: None,
        };
        match class {
            2 => {
                if depth >= MAX_DEPTH {
                    return Err(ctx(fault(0, "structs nested too deep")));
                }
                let len_el = e.element(m, name_el.next).map_err(ctx)?;
                if len_el.ty != MI_INT32 || len_el.data.len() != 4 {
                    return Err(ctx(fault(name_el.next, "field name length expected")));
                }
                let width = e.u32(len_el.data, 0).map_err(ctx)? as usize;
                let names_el = e.element(m, len_el.next).map_err(ctx)?;
                if names_el.ty != MI_INT8 || (width == 0 && !names_el.data.is_empty()) {
                    return Err(ctx(fault(len_el.next, "field names expected")));
                }
                let fields: Vec<String> = if width == 0 {
                    Vec::new()
                } else {
                    if names_el.data.len() % width != 0 {
                        return Err(ctx(fault(
                            len_el.next,
                            "field names do not fill the field width",
                        )));
                    }
                    names_el
                        .data
                        .chunks(width)
                        .map(|c| {
                            let end = c.iter().position(|&b| b == 0).unwrap_or(c.len());
                            String::from_utf8_lossy(&c[..end]).into_owned()
                        })
                        .collect()
                };
                var.class = format!("struct ({} fields)", fields.len());
                out.push(var);
                let mut at = names_el.next;
                for k in 0..count {
                    for field in &fields {
                        let el = e.element(m, at).map_err(ctx)?;
                        if el.ty != MI_MATRIX {
                            return Err(ctx(fault(
                                at,
                                format!("field `{field}`: miMATRIX expected"),
                            )));
                        }
                        let child = if count == 1 {
                            format!("{name}.{field}")
                        } else {
                            format!("{name}({}).{field}", k + 1)
                        };
                        self.matrix(el.data, &child, out, depth + 1)
                            .map_err(|(w, f)| {
                                (
                                    w,
                                    Fault {
                                        offset: f.offset + el.start,
                                        message: f.message,
                                    },
                                )
                            })?;
                        at = el.next;
                    }
                }
            }
            6..=15 if !complex => {
                var.values = Some(self.numeric(m, &dims_el, &name_el, count).map_err(ctx)?);
                out.push(var);
            }
            6..=15 => {
                var.class = format!("complex {class_text}");
                out.push(var);
            }
            1 | 3..=5 | 16 | 17 => out.push(var),
            _ => return Err(ctx(fault(0, format!("unknown array class {class}")))),
        }
        Ok(())
    }

    /// Decodes a numeric array through matfile: the array is copied into a one-array
    /// file of its own (this file's header, the array with the name `v`).
    fn numeric(
        &self,
        m: &[u8],
        dims: &Element<'_>,
        name: &Element<'_>,
        count: usize,
    ) -> Result<Vec<f64>, Fault> {
        let e = self.endian;
        let mut body = Vec::with_capacity(m.len() + 8);
        body.extend_from_slice(&m[..dims.next.min(m.len())]);
        body.extend_from_slice(&e.bytes(MI_INT8 | (1 << 16)));
        body.extend_from_slice(b"v\0\0\0");
        body.extend_from_slice(m.get(name.next..).unwrap_or(&[]));
        let mut file = Vec::with_capacity(body.len() + HEADER + 8);
        file.extend_from_slice(self.header);
        file.extend_from_slice(&e.bytes(MI_MATRIX));
        let len = u32::try_from(body.len()).map_err(|_| fault(0, "array too large"))?;
        file.extend_from_slice(&e.bytes(len));
        file.extend_from_slice(&body);
        let parsed = std::panic::catch_unwind(|| {
            matfile::MatFile::parse(file.as_slice()).map_err(|e| e.to_string())
        });
        let mat = match parsed {
            Ok(Ok(mat)) => mat,
            Ok(Err(msg)) => return Err(fault(dims.start, format!("numeric data: {msg}"))),
            Err(_) => return Err(fault(dims.start, "numeric data cannot be decoded")),
        };
        let Some(array) = mat.arrays().first() else {
            return Err(fault(
                dims.start,
                "numeric data do not match the array's class and dimensions",
            ));
        };
        use matfile::NumericData as N;
        let values: Vec<f64> = match array.data() {
            N::Int8 { real, .. } => real.iter().map(|&v| f64::from(v)).collect(),
            N::UInt8 { real, .. } => real.iter().map(|&v| f64::from(v)).collect(),
            N::Int16 { real, .. } => real.iter().map(|&v| f64::from(v)).collect(),
            N::UInt16 { real, .. } => real.iter().map(|&v| f64::from(v)).collect(),
            N::Int32 { real, .. } => real.iter().map(|&v| f64::from(v)).collect(),
            N::UInt32 { real, .. } => real.iter().map(|&v| f64::from(v)).collect(),
            #[allow(clippy::cast_precision_loss)]
            N::Int64 { real, .. } => real.iter().map(|&v| v as f64).collect(),
            #[allow(clippy::cast_precision_loss)]
            N::UInt64 { real, .. } => real.iter().map(|&v| v as f64).collect(),
            N::Single { real, .. } => real.iter().map(|&v| f64::from(v)).collect(),
            N::Double { real, .. } => real.clone(),
        };
        if values.len() != count {
            return Err(fault(
                dims.start,
                format!("{} values for {count} elements", values.len()),
            ));
        }
        Ok(values)
    }
}
