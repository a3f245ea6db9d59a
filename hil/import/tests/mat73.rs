//! Round trips through MATLAB v7.3 MAT-files written by an independent writer: h5py
//! (the HDF5 C library) laying the file out as MATLAB's `save -v7.3` does — a 512-byte
//! user block holding MATLAB's text header (version 0x0200, `IM`), every variable a
//! dataset or a struct group at the root with a `MATLAB_class` attribute, data stored
//! transposed (column-major: an N×1 vector is HDF5 (1, N)), gzip-compressed and
//! chunked (and, in one case, not), struct field order in `MATLAB_fields`, cells and
//! struct arrays as object references into `#refs#`, an empty array with `MATLAB_empty`.
//!
//! Tolerances as in `mat.rs`: doubles and integer counts are exact; singles are compared
//! with the f32 value widened to f64, which is exact too.

#![allow(clippy::unwrap_used, clippy::expect_used)] // a panic in a test is its failure message

mod common;

use std::path::Path;

use common::known::{N, check_samples, map_text, pos_mm, single, trig};
use common::{DEVICE, python_h5py, write};
use rigtwin_import::{ImportError, import, inspect};
use rigtwin_session::{Axes, Session};

/// A writer of MATLAB-layout v7.3 files over h5py: `put` stores an array as MATLAB
/// does (transposed, `MATLAB_class`), `struct` makes a struct group with
/// `MATLAB_fields`, `header` writes MATLAB's text header into the user block.
const PRELUDE: &str = r#"
import h5py, numpy as np
def put(g, name, a, cls, compress=True, **attrs):
    a = np.asarray(a)
    ds = g.create_dataset(name, data=a.T, compression='gzip' if compress else None,
                          chunks=True if compress else None)
    ds.attrs['MATLAB_class'] = np.bytes_(cls)
    for k, v in attrs.items():
        ds.attrs[k] = v
    return ds
def struct(g, name, fields):
    s = g.create_group(name)
    s.attrs['MATLAB_class'] = np.bytes_('struct')
    names = np.empty(len(fields), dtype=object)
    for k, f in enumerate(fields):
        names[k] = np.array(list(f), dtype='S1')
    s.attrs.create('MATLAB_fields', names, dtype=h5py.vlen_dtype(np.dtype('S1')))
    return s
def header(path):
    text = b'MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Tue Dec  1 09:00:00 2026 HDF5 schema 1.00 .'
    block = text.ljust(116, b' ') + b'\x00' * 8 + (0x0200).to_bytes(2, 'little') + b'IM'
    with open(path, 'r+b') as fh:
        fh.write(block)
"#;

fn write_v73(path: &Path, compress: bool) {
    let script = format!(
        r#"{PRELUDE}
N = {N}
i = np.arange(N)
c = {compress}
pos = (i % 97).astype(float) * 0.25 - 10.0 + (i // 97).astype(float) * 0.5
ref = (i % 50).astype(float) * 0.125
sig = np.stack([i * 0.5 + k * 1000.0 for k in range(3)], axis=1)   # N x 3
counts = (((i * 37) % 4001) - 2000).astype(np.int16)
single = (i * 0.001 + 0.1).astype(np.float32)
trig = ((i >= 100) & (((i - 100) % 1000) < 50)).astype(np.uint8)
path = r"{path}"
with h5py.File(path, 'w', userblock_size=512) as f:
    put(f, 't', (i / 1000.0).reshape(1, N), 'double', c)            # 1 x N
    d = struct(f, 'data', ['pos', 'ref', 'note'])
    put(d, 'pos', pos.reshape(N, 1), 'double', c)
    put(d, 'ref', ref.reshape(N, 1), 'double', c)
    put(d, 'note', np.array([[ord(ch) for ch in 'rig A']], dtype=np.uint16), 'char', c,
        MATLAB_int_decode=np.int32(2))
    log = struct(f, 'log', ['signals', 'label'])
    s = struct(log, 'signals', ['values', 'wide'])
    put(s, 'values', sig, 'double', c)                               # N x 3
    put(s, 'wide', sig.T.copy(), 'double', c)                        # 3 x N
    put(log, 'label', np.array([[ord(ch) for ch in 'run 1']], dtype=np.uint16), 'char', c)
    put(f, 'counts', counts.reshape(N, 1), 'int16', c)
    put(f, 'u', single.reshape(N, 1), 'single', c)
    put(f, 'trig', trig.reshape(N, 1), 'logical', c, MATLAB_int_decode=np.int32(1))
    put(f, 'nothing', np.array([0, 0], dtype=np.uint64), 'double', False,
        MATLAB_empty=np.uint8(1))
    refs = f.create_group('#refs#')
    def hidden(name, a):
        return put(refs, name, a, 'double', c)
    a = hidden('a', np.array([[1.0, 2.0]]))
    b = hidden('b', np.array([[3.0]]))
    cell = f.create_dataset('names', data=np.array([[a.ref, b.ref]], dtype=h5py.ref_dtype).T)
    cell.attrs['MATLAB_class'] = np.bytes_('cell')
    # A 1 x 2 struct array: each field a dataset of references, one per element.
    sa = struct(f, 'trials', ['pos', 'id'])
    p1 = hidden('c', (pos * 2.0).reshape(N, 1))
    p2 = hidden('d', (pos * 3.0).reshape(N, 1))
    i1 = hidden('e', np.array([[1.0]]))
    i2 = hidden('f', np.array([[2.0]]))
    sa.create_dataset('pos', data=np.array([[p1.ref, p2.ref]], dtype=h5py.ref_dtype).T)
    sa.create_dataset('id', data=np.array([[i1.ref, i2.ref]], dtype=h5py.ref_dtype).T)
header(path)
"#,
        path = path.display(),
        compress = if compress { "True" } else { "False" },
    );
    python_h5py(&script);
}

/// The struct array's channel, mapped on top of the level-5 files' channels.
const CMD: &str = r#"cmd_fx_n = { var = "trials(2).pos", scale = 1e-3 }"#;

/// `trials(2).pos` holds three times the position (the writer's second element).
fn cmd_is_pos_times_3(trial: &rigtwin_session::Trial, i: usize, j: usize) {
    assert_eq!(trial.cmd_fx_n.as_ref().unwrap()[j], pos_mm(i) * 3.0 * 1e-3);
}

#[test]
fn v73_structs_matrices_ints_singles_and_struct_arrays_round_trip() {
    for compress in [true, false] {
        let dir = tempfile::tempdir().unwrap();
        let mat = dir.path().join("block1.mat");
        write_v73(&mat, compress);
        let bytes = std::fs::read(&mat).unwrap();
        assert!(bytes.starts_with(b"MATLAB 7.3 MAT-file"));
        assert_eq!(&bytes[124..128], b"\x00\x02IM");
        assert_eq!(&bytes[512..520], b"\x89HDF\r\n\x1a\n");
        let map = write(dir.path(), "map.toml", &map_text(r#"cut = "whole""#, CMD));
        let out = dir.path().join("session");
        let imported = import(std::slice::from_ref(&mat), &map, &out).unwrap();
        assert_eq!(imported.rate_hz, 1000.0);
        assert_eq!(imported.samples, vec![N]);
        let s = Session::read(&out).unwrap();
        assert_eq!(s.manifest.rate_hz, 1000.0);
        assert_eq!(s.manifest.subject.id, "S07");
        assert_eq!(s.manifest.axes, Axes::Both);
        assert_eq!(s.trials[0].len(), N);
        check_samples(&s, &[0], cmd_is_pos_times_3);
        let text = imported.to_string();
        assert!(text.contains("1 trial at 1000 Hz"), "{text}");
    }
}

#[test]
fn v73_logical_marker_cuts_trials() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("log.mat");
    write_v73(&mat, true);
    let map = write(
        dir.path(),
        "map.toml",
        &map_text(
            r#"cut = "marker"
marker = { var = "trig", above = 0.5 }"#,
            CMD,
        ),
    );
    let out = dir.path().join("s");
    let imported = import(&[mat], &map, &out).unwrap();
    let starts: Vec<usize> = (1..N).filter(|&i| trig(i) && !trig(i - 1)).collect();
    assert_eq!(starts, [100, 1100, 2100]);
    assert_eq!(imported.samples, vec![1000, 1000, N - 2100]);
    check_samples(&Session::read(&out).unwrap(), &starts, cmd_is_pos_times_3);
}

#[test]
fn v73_inspect_lists_matlab_shapes_classes_and_the_time_rate() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("log.mat");
    write_v73(&mat, true);
    let inv = inspect(&mat).unwrap();
    assert_eq!(inv.format, "MATLAB v7.3 (HDF5)");
    let get = |n: &str| {
        inv.entries
            .iter()
            .find(|e| e.name == n)
            .unwrap_or_else(|| panic!("{n} missing from {inv}"))
    };
    // MATLAB shapes (HDF5's reversed), not HDF5's.
    assert_eq!(get("t").shape, vec![1, N]);
    assert_eq!(get("t").rate_hz, Some(1000.0));
    assert_eq!(get("data.pos").shape, vec![N, 1]);
    assert_eq!(get("data.pos").class, "double");
    assert_eq!(get("log.signals.values").shape, vec![N, 3]);
    assert_eq!(get("log.signals.wide").shape, vec![3, N]);
    assert_eq!(get("counts").class, "int16");
    assert_eq!(get("u").class, "single");
    assert_eq!(get("trig").class, "logical");
    assert!(get("trig").numeric);
    assert_eq!(get("data.note").class, "char");
    assert_eq!(get("data.note").shape, vec![1, 5]);
    assert!(!get("data.note").numeric);
    assert_eq!(get("data").class, "struct (3 fields)");
    assert_eq!(get("log").class, "struct (2 fields)");
    assert_eq!(get("names").class, "cell");
    assert_eq!(get("names").shape, vec![1, 2]);
    assert!(!get("names").numeric);
    assert_eq!(get("nothing").shape, vec![0, 0]);
    assert_eq!(get("trials").shape, vec![1, 2]);
    assert_eq!(get("trials(2).pos").shape, vec![N, 1]);
    assert_eq!(get("trials(1).id").shape, vec![1, 1]);
    let names: Vec<&str> = inv.entries.iter().map(|e| e.name.as_str()).collect();
    // MATLAB's hidden stores are not variables.
    assert!(names.iter().all(|n| !n.contains('#')), "{names:?}");
    // Top level sorted; a struct's fields in `MATLAB_fields` order; a struct array's
    // elements in order, each with its fields.
    assert_eq!(
        names,
        [
            "counts",
            "data",
            "data.pos",
            "data.ref",
            "data.note",
            "log",
            "log.signals",
            "log.signals.values",
            "log.signals.wide",
            "log.label",
            "names",
            "nothing",
            "t",
            "trials",
            "trials(1).pos",
            "trials(1).id",
            "trials(2).pos",
            "trials(2).id",
            "trig",
            "u",
        ]
    );
    let text = inv.to_string();
    assert!(text.contains("MATLAB v7.3 (HDF5)"), "{text}");
    assert!(text.contains("3000×3"), "{text}");
    assert!(text.contains("uniform time: 1000 Hz"), "{text}");
}

#[test]
fn v73_missing_variable_names_the_file_and_the_variable() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("rig7.mat");
    write_v73(&mat, true);
    let map = map_text(r#"cut = "whole""#, CMD).replace("\"data.ref\"", "\"data.vel\"");
    let map = write(dir.path(), "map.toml", &map);
    let e = import(&[mat], &map, &dir.path().join("s")).unwrap_err();
    assert!(
        matches!(&e, ImportError::MissingVariable { var, .. } if var == "data.vel"),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(msg.contains("rig7.mat"), "{msg}");
    assert!(msg.contains("`data.vel`"), "{msg}");
    assert!(msg.contains("channels.ref_x_m"), "{msg}");
    assert!(msg.contains("data.ref"), "the names the file has: {msg}");
}

#[test]
fn truncated_v73_files_are_errors_naming_the_file_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("whole.mat");
    write_v73(&mat, true);
    let good = std::fs::read(&mat).unwrap();
    let cut = dir.path().join("cut.mat");
    let mut errors = 0;
    for len in (0..good.len())
        .step_by(997)
        .chain([512, 600, good.len() / 2, good.len() - 1])
    {
        std::fs::write(&cut, &good[..len]).unwrap();
        match inspect(&cut) {
            Ok(_) => {}
            Err(e) => {
                errors += 1;
                assert!(e.to_string().contains("cut.mat"), "{len}: {e}");
                if len > 128 {
                    assert!(
                        matches!(e, ImportError::MatV73Corrupt { .. }),
                        "{len}: {e:?}"
                    );
                }
            }
        }
    }
    assert!(errors > 0);
    std::fs::write(&cut, &good[..good.len() / 2]).unwrap();
    let e = inspect(&cut).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ImportError::MatV73Corrupt { .. }), "{e:?}");
    assert!(msg.contains("cut.mat") && msg.contains("v7.3"), "{msg}");
}

#[test]
fn a_corrupt_chunk_is_an_error_naming_the_variable() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("chunk.mat");
    // One compressed variable among others; its chunk's offset, from h5py.
    python_h5py(&format!(
        r#"{PRELUDE}
path = r"{}"
with h5py.File(path, 'w', userblock_size=512) as f:
    put(f, 'a', np.arange(1000.0).reshape(1000, 1), 'double', False)
    ds = put(f, 'pos', np.sin(np.arange(5000.0)).reshape(5000, 1), 'double', True)
    info = ds.id.get_chunk_info(0)
    open(path + '.chunk', 'w').write(f'{{info.byte_offset}} {{info.size}}')
header(path)
"#,
        mat.display()
    ));
    let (offset, size) = {
        let text = std::fs::read_to_string(dir.path().join("chunk.mat.chunk")).unwrap();
        let mut it = text.split(' ').map(|v| v.trim().parse::<usize>().unwrap());
        (it.next().unwrap(), it.next().unwrap())
    };
    let mut bytes = std::fs::read(&mat).unwrap();
    assert!(inspect(&mat).is_ok());
    // h5py reports addresses from the start of the file, user block included.
    let at = if offset >= 512 { offset } else { offset + 512 };
    for b in &mut bytes[at + size / 4..at + size / 2] {
        *b = 0x55;
    }
    std::fs::write(&mat, &bytes).unwrap();
    let e = inspect(&mat).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ImportError::MatV73Corrupt { .. }), "{e:?}");
    assert!(msg.contains("chunk.mat"), "{msg}");
    assert!(msg.contains("variable `pos`"), "{msg}");
}

#[test]
fn flipped_bytes_in_a_v73_file_are_errors_or_reads_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("small.mat");
    python_h5py(&format!(
        r#"{PRELUDE}
path = r"{}"
with h5py.File(path, 'w', userblock_size=512) as f:
    put(f, 't', (np.arange(200) / 100.0).reshape(200, 1), 'double', True)
    s = struct(f, 's', ['a', 'b'])
    put(s, 'a', np.arange(200, dtype=np.int16).reshape(200, 1), 'int16', True)
    put(s, 'b', np.ones((200, 2), dtype=np.float32), 'single', False)
header(path)
"#,
        mat.display()
    ));
    let good = std::fs::read(&mat).unwrap();
    assert!(inspect(&mat).is_ok());
    let flip = dir.path().join("flip.mat");
    let mut errors = 0;
    for k in (512..good.len()).step_by(3) {
        let mut bad = good.clone();
        bad[k] ^= 0xff;
        std::fs::write(&flip, &bad).unwrap();
        errors += usize::from(inspect(&flip).is_err());
    }
    assert!(errors > 0);
}

#[test]
fn v73_one_axis_rig_from_a_scalar_struct() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("stage.mat");
    write_v73(&mat, true);
    let map = write(
        dir.path(),
        "map.toml",
        &format!(
            r#"
axes = ["x"]
[time]
rate_hz = 1000.0
[channels]
x_m = {{ var = "data.pos", scale = 1e-3, unit = "mm" }}
cmd_fx_n = {{ var = "u", scale = 12.5, unit = "V" }}
{DEVICE}
[trials]
cut = "whole"
"#
        ),
    );
    let out = dir.path().join("s");
    import(&[mat], &map, &out).unwrap();
    let s = Session::read(&out).unwrap();
    assert_eq!(s.manifest.axes, Axes::X);
    assert_eq!(s.manifest.subject.id, "stage");
    let t = &s.trials[0];
    for i in 0..N {
        assert_eq!(t.x_m[i], pos_mm(i) * 1e-3);
        assert_eq!(t.cmd_fx_n.as_ref().unwrap()[i], f64::from(single(i)) * 12.5);
    }
}
