//! A seeded corpus of hostile inputs, run on the `rigtwin` binary in CI: sessions,
//! protocols, map files with their log, and wire datagrams, corrupted in every way a
//! review of acquisition software tries (truncations, bit flips, swapped or missing
//! columns, NaN/inf, BOMs, CRLF, duplicate ids, paths out of the folder, symlinks,
//! FIFOs, directories, sparse giants, absurd numbers, long fields, unknown keys).
//!
//! Every case must end within its time with exit 0, 1 or 2: 0 aborts, 0 hangs, 0 panics.
//! A case built to be invalid that is accepted is a wrong acceptance and fails. Every
//! refusal must name the file; a refusal of a file's content must name a line; the counts
//! of refusals that name a field (a key or column) are printed (`--nocapture`).
//! The corpus is the same for the same seed: `HOSTILE_SEED` (default 20) picks another.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod hostile;

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use hostile::{Ended, mkfifo, run_in, small_session};

/// What a case must give.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Expect {
    /// The input is invalid: exit 0 is a wrong acceptance.
    Refuse,
    /// Either answer is right (a bit flip in a comment, a cut after a whole entry).
    Either,
}

/// Where a refusal's message must point.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Locate {
    /// The file's content is at fault: file and line.
    Content,
    /// The file itself (its type, size, place): the file.
    File,
}

/// One file a case writes before it runs.
enum Make {
    Bytes(Vec<u8>),
    Fifo,
    Dir,
    Symlink(PathBuf),
    Sparse(u64),
}

struct Case {
    class: &'static str,
    /// Written into the case's folder, relative paths, in order.
    files: Vec<(String, Make)>,
    /// `rigtwin` arguments (relative to the case's folder).
    args: Vec<String>,
    expect: Expect,
    locate: Locate,
}

/// Per-case time, s: every accepted case is a small job (a two-trial inspect, a dry run,
/// a one-minute import) measured at well under 2 s; the rest is margin for a loaded
/// machine. A case that takes longer is a hang.
const CASE_S: f64 = 60.0;

fn flip(bytes: &mut [u8], rng: &mut ChaCha8Rng) {
    let i = rng.random_range(0..bytes.len());
    bytes[i] ^= 1 << rng.random_range(0..8);
}

fn cut(bytes: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    bytes[..rng.random_range(0..bytes.len())].to_vec()
}

/// Values a number in a config may be replaced by.
const HOSTILE_NUMBERS: [&str; 17] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "4294967295",
    "18446744073709551615",
    "1e6",
    "nan",
    "inf",
    "-inf",
    "5e-324",
    "\"x\"",
    "true",
    "[]",
    "[1, 2, 3]",
    "{}",
    "0.000001",
];

/// The line numbers (0-based) of `key = number` lines of `text`.
fn number_lines(text: &str) -> Vec<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| {
            let l = l.trim_start();
            !l.starts_with('#')
                && l.split_once('=').is_some_and(|(_, v)| {
                    let v = v.trim_start();
                    v.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '[')
                })
        })
        .map(|(i, _)| i)
        .collect()
}

fn replace_value(text: &str, line: usize, value: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let (key, _) = lines[line].split_once('=').unwrap();
    lines[line] = format!("{key}= {value}");
    lines.join("\n") + "\n"
}

fn with_line(text: &str, after: usize, new: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    lines.insert(after + 1, new);
    lines.join("\n") + "\n"
}

fn without_line(text: &str, line: usize) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    lines.remove(line);
    lines.join("\n") + "\n"
}

fn bom_crlf(text: &str) -> Vec<u8> {
    let mut b = b"\xEF\xBB\xBF".to_vec();
    b.extend(text.replace('\n', "\r\n").bytes());
    b
}

/// Cases on sessions: `inspect` of a two-trial copy of `example-none`.
fn session_cases(rng: &mut ChaCha8Rng, base: &Path, n: usize) -> Vec<Case> {
    let manifest = std::fs::read_to_string(base.join("session.toml")).unwrap();
    let trial = std::fs::read_to_string(base.join("trials/0001.csv")).unwrap();
    let no_sha: String = manifest
        .lines()
        .filter(|l| !l.starts_with("sha256"))
        .map(|l| format!("{l}\n"))
        .collect();
    let inspect = |json: bool| {
        let mut a = vec!["inspect".to_owned(), "s".to_owned()];
        if json {
            a.push("--json".into());
        }
        a
    };
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let m = |t: String| ("s/session.toml".to_owned(), Make::Bytes(t.into_bytes()));
        let t1 = |t: Vec<u8>| ("s/trials/0001.csv".to_owned(), Make::Bytes(t));
        let (class, files, expect, locate) = match k % 24 {
            0 => (
                "session: manifest cut",
                vec![m(
                    String::from_utf8_lossy(&cut(manifest.as_bytes(), rng)).into()
                )],
                Expect::Either,
                Locate::Content,
            ),
            1 => {
                let mut b = manifest.clone().into_bytes();
                flip(&mut b, rng);
                (
                    "session: manifest bit flip",
                    vec![("s/session.toml".into(), Make::Bytes(b))],
                    Expect::Either,
                    Locate::Content,
                )
            }
            2 => (
                "session: trial cut (digest listed)",
                vec![t1(cut(trial.as_bytes(), rng))],
                Expect::Refuse,
                Locate::Content,
            ),
            3 => {
                let mut b = trial.clone().into_bytes();
                flip(&mut b, rng);
                (
                    "session: trial bit flip (digest listed)",
                    vec![t1(b)],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            4 | 5 => {
                // A bad field in a random data row and column, without the digest.
                let mut lines: Vec<String> = trial.lines().map(str::to_owned).collect();
                let row = rng.random_range(1..lines.len());
                let mut f: Vec<String> = lines[row].split(',').map(str::to_owned).collect();
                let col = rng.random_range(0..f.len());
                f[col] = ["nan", "inf", "-inf", "", "x", "1e999", "0x10", "1,2"]
                    [rng.random_range(0..8)]
                .into();
                lines[row] = f.join(",");
                (
                    "session: bad field",
                    vec![
                        m(no_sha.clone()),
                        t1((lines.join("\n") + "\n").into_bytes()),
                    ],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            6 => {
                let mut lines: Vec<String> = trial.lines().map(str::to_owned).collect();
                let mut h: Vec<String> = lines[0].split(',').map(str::to_owned).collect();
                let col = rng.random_range(0..5);
                h.remove(col);
                lines[0] = h.join(",");
                (
                    "session: required column missing from the header",
                    vec![
                        m(no_sha.clone()),
                        t1((lines.join("\n") + "\n").into_bytes()),
                    ],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            7 => {
                let mut lines: Vec<String> = trial.lines().map(str::to_owned).collect();
                let mut h: Vec<String> = lines[0].split(',').map(str::to_owned).collect();
                let (a, b) = (rng.random_range(0..h.len()), rng.random_range(0..h.len()));
                h.swap(a, b);
                lines[0] = h.join(",");
                (
                    "session: two header names swapped",
                    vec![
                        m(no_sha.clone()),
                        t1((lines.join("\n") + "\n").into_bytes()),
                    ],
                    Expect::Either,
                    Locate::Content,
                )
            }
            8 => (
                "session: trial with BOM and CRLF",
                vec![m(no_sha.clone()), t1(bom_crlf(&trial))],
                Expect::Either,
                Locate::Content,
            ),
            9 => (
                "session: manifest with BOM and CRLF",
                vec![("s/session.toml".into(), Make::Bytes(bom_crlf(&manifest)))],
                Expect::Either,
                Locate::Content,
            ),
            10 => {
                let row = rng.random_range(2..trial.lines().count());
                let mut lines: Vec<String> = trial.lines().map(str::to_owned).collect();
                lines[row].push_str(",0");
                (
                    "session: a row with one field too many",
                    vec![
                        m(no_sha.clone()),
                        t1((lines.join("\n") + "\n").into_bytes()),
                    ],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            11 => (
                "session: duplicate trial id",
                vec![m(manifest.replacen("id = 2", "id = 1", 1))],
                Expect::Refuse,
                Locate::Content,
            ),
            12 => {
                let to = [
                    "../x.csv",
                    "/etc/passwd",
                    "trials/../../x.csv",
                    "trials\\\\0001.csv",
                    "",
                ][rng.random_range(0..5)];
                (
                    "session: trial path out of the folder",
                    vec![m(manifest.replacen("trials/0002.csv", to, 1))],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            13 => {
                let v = HOSTILE_NUMBERS[rng.random_range(0..HOSTILE_NUMBERS.len())];
                (
                    "session: hostile rate_hz",
                    vec![m(manifest.replacen(
                        "rate_hz = 1000.0",
                        &format!("rate_hz = {v}"),
                        1,
                    ))],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            14 => {
                let lines = number_lines(&manifest);
                let line = lines[rng.random_range(0..lines.len())];
                let v = HOSTILE_NUMBERS[rng.random_range(0..HOSTILE_NUMBERS.len())];
                (
                    "session: hostile number",
                    vec![m(replace_value(&manifest, line, v))],
                    Expect::Either,
                    Locate::Content,
                )
            }
            15 => {
                let line = rng.random_range(0..manifest.lines().count());
                (
                    "session: a manifest line deleted",
                    vec![m(without_line(&manifest, line))],
                    Expect::Either,
                    Locate::Content,
                )
            }
            16 => {
                let at = manifest
                    .lines()
                    .position(|l| l.starts_with("[device]"))
                    .unwrap();
                (
                    "session: unknown key in [device]",
                    vec![m(with_line(&manifest, at, "spare_kg = 1.0"))],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            17 => {
                let long = "p".repeat(rng.random_range(1_000..200_000));
                (
                    "session: long subject id",
                    vec![m(manifest.replacen(
                        "id = \"P75\"",
                        &format!("id = \"{long}\""),
                        1,
                    ))],
                    Expect::Either,
                    Locate::Content,
                )
            }
            18 => (
                "session: format_version 2",
                vec![m(manifest.replacen(
                    "format_version = 1",
                    "format_version = 2",
                    1,
                ))],
                Expect::Refuse,
                Locate::Content,
            ),
            19 => {
                let which = ["s/session.toml", "s/trials/0001.csv", "s/trials/0002.csv"]
                    [rng.random_range(0..3)];
                let remove = vec![(which.to_owned(), Make::Fifo)];
                (
                    "session: a FIFO for a file",
                    remove,
                    Expect::Refuse,
                    Locate::File,
                )
            }
            20 => (
                "session: a directory for a trial",
                vec![("s/trials/0002.csv".into(), Make::Dir)],
                Expect::Refuse,
                Locate::File,
            ),
            21 => (
                "session: a sparse 20 GiB trial",
                vec![("s/trials/0002.csv".into(), Make::Sparse(20 << 30))],
                Expect::Refuse,
                Locate::File,
            ),
            22 => (
                "session: a trial linked out of the folder",
                vec![(
                    "s/trials/0002.csv".into(),
                    Make::Symlink(base.join("trials/0002.csv")),
                )],
                Expect::Refuse,
                Locate::Content,
            ),
            _ => (
                "session: an empty trial file",
                vec![m(no_sha.clone()), t1(Vec::new())],
                Expect::Refuse,
                Locate::Content,
            ),
        };
        out.push(Case {
            class,
            files,
            args: inspect(k % 5 == 0),
            expect,
            locate,
        });
    }
    out
}

/// Cases on protocols: `rehearse <file> --dry-run` on the three shipped ones, mutated.
fn protocol_cases(rng: &mut ChaCha8Rng, n: usize) -> Vec<Case> {
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (_, base) = rigtwin::protocol::BUILTIN[k % 3];
        let p = |t: Vec<u8>| vec![("p.toml".to_owned(), Make::Bytes(t))];
        let (class, files, expect, locate) = match (k / 3) % 12 {
            0..=2 => {
                let lines = number_lines(base);
                let line = lines[rng.random_range(0..lines.len())];
                let v = HOSTILE_NUMBERS[rng.random_range(0..HOSTILE_NUMBERS.len())];
                (
                    "protocol: hostile number",
                    p(replace_value(base, line, v).into_bytes()),
                    Expect::Either,
                    Locate::Content,
                )
            }
            3 => {
                // A pair gets a third element.
                let pairs: Vec<usize> = base
                    .lines()
                    .enumerate()
                    .filter(|(_, l)| {
                        !l.trim_start().starts_with('#')
                            && l.contains("= [")
                            && !l.contains("[[")
                            && l.matches(',').count() == 1
                            && l.trim_end().ends_with(']')
                    })
                    .map(|(i, _)| i)
                    .collect();
                let line = pairs[rng.random_range(0..pairs.len())];
                let l = base.lines().nth(line).unwrap();
                let longer = l.replacen(']', ", 5.0]", 1);
                let text = base
                    .lines()
                    .map(|x| if x == l { longer.clone() } else { x.to_owned() })
                    .collect::<Vec<_>>()
                    .join("\n");
                (
                    "protocol: a pair with a third element",
                    p(text.into_bytes()),
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            4 => (
                "protocol: cut",
                p(cut(base.as_bytes(), rng)),
                Expect::Either,
                Locate::Content,
            ),
            5 => {
                let mut b = base.as_bytes().to_vec();
                flip(&mut b, rng);
                ("protocol: bit flip", p(b), Expect::Either, Locate::Content)
            }
            6 => {
                let line = rng.random_range(0..base.lines().count());
                (
                    "protocol: a line deleted",
                    p(without_line(base, line).into_bytes()),
                    Expect::Either,
                    Locate::Content,
                )
            }
            7 => {
                // Lines that start with a bare key (a line of an inline array of tables,
                // `{ force_deg = 0.0, ... },`, written twice is one more valid element).
                let keys: Vec<usize> = number_lines(base)
                    .into_iter()
                    .filter(|&i| {
                        base.lines().nth(i).is_some_and(|l| {
                            l.trim_start()
                                .starts_with(|c: char| c.is_ascii_alphabetic())
                        })
                    })
                    .collect();
                let line = keys[rng.random_range(0..keys.len())];
                let l = base.lines().nth(line).unwrap().to_owned();
                (
                    "protocol: a key twice",
                    p(with_line(base, line, &l).into_bytes()),
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            8 => {
                let tables: Vec<usize> = base
                    .lines()
                    .enumerate()
                    .filter(|(_, l)| l.starts_with('['))
                    .map(|(i, _)| i)
                    .collect();
                let at = tables[rng.random_range(0..tables.len())];
                (
                    "protocol: an unknown key",
                    p(with_line(base, at, "spare_setting = 1.0").into_bytes()),
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            9 => (
                "protocol: BOM and CRLF",
                p(bom_crlf(base)),
                Expect::Either,
                Locate::Content,
            ),
            10 => {
                let long = "n".repeat(rng.random_range(1_000..300_000));
                (
                    "protocol: a long name",
                    p(base
                        .replacen("name = \"", &format!("name = \"{long}"), 1)
                        .into_bytes()),
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            _ => {
                let (class, make) = [
                    ("protocol: a FIFO", Make::Fifo),
                    ("protocol: a directory", Make::Dir),
                    ("protocol: a sparse 2 GiB file", Make::Sparse(2 << 30)),
                    ("protocol: an empty file", Make::Bytes(Vec::new())),
                ]
                .into_iter()
                .nth(rng.random_range(0..4))
                .unwrap();
                let locate = if matches!(make, Make::Bytes(_)) {
                    Locate::Content
                } else {
                    Locate::File
                };
                (
                    class,
                    vec![("p.toml".to_owned(), make)],
                    Expect::Refuse,
                    locate,
                )
            }
        };
        out.push(Case {
            class,
            files,
            args: ["rehearse", "p.toml", "--dry-run"]
                .map(str::to_owned)
                .to_vec(),
            expect,
            locate,
        });
    }
    out
}

/// Cases on imports: the servo example's map file and `.mat` log, mutated.
fn import_cases(rng: &mut ChaCha8Rng, root: &Path, n: usize) -> Vec<Case> {
    let map = std::fs::read_to_string(root.join("recordings/example-servo-axis.map.toml")).unwrap();
    let mat = std::fs::read(root.join("recordings/example-servo-axis.mat")).unwrap();
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let good_mat = ("log.mat".to_owned(), Make::Bytes(mat.clone()));
        let mp = |t: String| ("map.toml".to_owned(), Make::Bytes(t.into_bytes()));
        let (class, files, expect, locate) = match k % 10 {
            0 | 1 => {
                let lines = number_lines(&map);
                let line = lines[rng.random_range(0..lines.len())];
                let v = HOSTILE_NUMBERS[rng.random_range(0..HOSTILE_NUMBERS.len())];
                (
                    "import: hostile number in the map",
                    vec![good_mat, mp(replace_value(&map, line, v))],
                    Expect::Either,
                    Locate::Content,
                )
            }
            2 => {
                let var =
                    ["bench.t", "bench.pos", "bench.ref", "bench.drive"][rng.random_range(0..4)];
                (
                    "import: a variable the log lacks",
                    vec![good_mat, mp(map.replacen(var, "bench.nothing", 1))],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            3 => {
                let line = rng.random_range(0..map.lines().count());
                (
                    "import: a map line deleted",
                    vec![good_mat, mp(without_line(&map, line))],
                    Expect::Either,
                    Locate::Content,
                )
            }
            4 => {
                let at = map.lines().position(|l| l.starts_with("[device]")).unwrap();
                (
                    "import: an unknown map key",
                    vec![good_mat, mp(with_line(&map, at, "spare = 1"))],
                    Expect::Refuse,
                    Locate::Content,
                )
            }
            5 => (
                "import: the log cut",
                vec![
                    ("log.mat".to_owned(), Make::Bytes(cut(&mat, rng))),
                    mp(map.clone()),
                ],
                Expect::Refuse,
                Locate::File,
            ),
            6 => {
                let mut b = mat.clone();
                flip(&mut b, rng);
                (
                    "import: a bit flip in the log",
                    vec![("log.mat".to_owned(), Make::Bytes(b)), mp(map.clone())],
                    Expect::Either,
                    Locate::File,
                )
            }
            7 => (
                "import: the map with BOM and CRLF",
                vec![
                    good_mat,
                    ("map.toml".to_owned(), Make::Bytes(bom_crlf(&map))),
                ],
                Expect::Either,
                Locate::Content,
            ),
            8 => {
                let mut b = map.clone().into_bytes();
                flip(&mut b, rng);
                (
                    "import: a bit flip in the map",
                    vec![good_mat, ("map.toml".to_owned(), Make::Bytes(b))],
                    Expect::Either,
                    Locate::Content,
                )
            }
            _ => {
                let which = ["log.mat", "map.toml"][rng.random_range(0..2)];
                let mut files = vec![good_mat, mp(map.clone())];
                files.retain(|(f, _)| f != which);
                files.push((which.to_owned(), Make::Fifo));
                (
                    "import: a FIFO for a file",
                    files,
                    Expect::Refuse,
                    Locate::File,
                )
            }
        };
        out.push(Case {
            class,
            files,
            args: ["import", "log.mat", "--map", "map.toml", "--out", "out"]
                .map(str::to_owned)
                .to_vec(),
            expect,
            locate,
        });
    }
    out
}

/// Writes a case's files into `dir` (a copy of `base` session at `dir/s` first, for
/// session cases).
fn materialise(case: &Case, dir: &Path) {
    if case.files.iter().any(|(f, _)| f.starts_with("s/")) {
        let s = small_session(dir, 2);
        std::fs::rename(&s, dir.join("s")).unwrap();
    }
    for (rel, make) in &case.files {
        let path = dir.join(rel);
        if path.exists() || path.is_symlink() {
            if path.is_dir() {
                std::fs::remove_dir_all(&path).unwrap();
            } else {
                std::fs::remove_file(&path).unwrap();
            }
        }
        match make {
            Make::Bytes(b) => std::fs::write(&path, b).unwrap(),
            Make::Fifo => mkfifo(&path),
            Make::Dir => std::fs::create_dir(&path).unwrap(),
            Make::Symlink(to) => std::os::unix::fs::symlink(to, &path).unwrap(),
            Make::Sparse(len) => {
                std::fs::write(&path, b"t_s,x_m\n").unwrap();
                std::fs::OpenOptions::new()
                    .write(true)
                    .open(&path)
                    .unwrap()
                    .set_len(*len)
                    .unwrap();
            }
        }
    }
}

/// The message names a line: `file:12`, `line 12`.
fn names_line(text: &str) -> bool {
    let b = text.as_bytes();
    (0..b.len().saturating_sub(1)).any(|i| b[i] == b':' && b[i + 1].is_ascii_digit())
        || text.contains("line ")
        || text.contains("not in the file")
}

/// The message names a field: a key or a column in backquotes, or a dotted key.
fn names_field(text: &str) -> bool {
    text.contains('`')
        || text
            .split(|c: char| c.is_whitespace() || c == ':')
            .any(|w| {
                let w =
                    w.trim_matches(|c: char| !c.is_ascii_alphanumeric() && c != '_' && c != '.');
                w.contains('.')
                    && w.chars().all(|c| {
                        c.is_ascii_lowercase() || c == '_' || c == '.' || c.is_ascii_digit()
                    })
                    && !w.ends_with(".toml")
                    && !w.ends_with(".csv")
                    && !w.ends_with(".mat")
            })
}

/// Wire datagrams, decoded in-process (the codec is the whole of the wire's reading);
/// returns (cases, wrong acceptances). A panic fails the test by itself.
fn datagram_cases(rng: &mut ChaCha8Rng, n: usize) -> (usize, Vec<String>) {
    use rigtwin_device::{Mode, MotorCommand, SensorFrame, Tick};
    use rigtwin_wire::{CommandDatagram, SensorDatagram, decode};
    let mut wrong = Vec::new();
    for k in 0..n {
        let sensor = SensorDatagram {
            sequence: rng.random(),
            tick: Tick(rng.random_range(0..u64::MAX)),
            trial: rng.random(),
            frame: SensorFrame {
                encoder_counts: [rng.random(), rng.random()],
                force_raw_n: [
                    rng.random_range(-100.0..100.0),
                    rng.random_range(-100.0..100.0),
                ],
                estop: rng.random(),
            },
            watchdog_zeroed: rng.random(),
            echo_tick: None,
        }
        .encode()
        .to_vec();
        let command = CommandDatagram {
            sequence: rng.random(),
            tick: Tick(rng.random_range(0..u64::MAX)),
            trial: rng.random(),
            command: MotorCommand {
                force_n: [
                    rng.random_range(-200.0..200.0),
                    rng.random_range(-200.0..200.0),
                ],
            },
            mode: Mode::Active,
            answers_tick: None,
        }
        .encode()
        .unwrap()
        .to_vec();
        let mut b = if k % 2 == 0 { sensor } else { command.clone() };
        let (what, must_fail) = match (k / 2) % 7 {
            0 => {
                b.truncate(rng.random_range(0..b.len()));
                ("truncated", true)
            }
            1 => {
                b.extend((0..rng.random_range(1..64)).map(|_| rng.random::<u8>()));
                ("extended", true)
            }
            2 => {
                b[rng.random_range(0..4)] ^= 0x20;
                ("bad magic", true)
            }
            3 => {
                b[4] = 2;
                ("version 2", true)
            }
            4 => {
                b[6] = 3;
                ("unknown kind", true)
            }
            5 => {
                let mut c = command;
                let at = 20 + 8 * rng.random_range(0..2);
                c[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
                b = c;
                ("NaN command", true)
            }
            _ => {
                flip(&mut b, rng);
                ("bit flip", false)
            }
        };
        if must_fail && decode(&b).is_ok() {
            wrong.push(format!("datagram {k}: {what} decoded"));
        }
    }
    (n, wrong)
}

#[test]
fn a_thousand_hostile_inputs_end_in_a_clear_answer() {
    let seed: u64 = std::env::var("HOSTILE_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let base_dir = tempfile::tempdir().unwrap();
    let base = small_session(base_dir.path(), 2);
    let mut cases = session_cases(&mut rng, &base, 480);
    cases.extend(protocol_cases(&mut rng, 360));
    cases.extend(import_cases(&mut rng, &root, 120));
    let (datagrams, mut wrong) = datagram_cases(&mut rng, 280);

    let failures = Mutex::new(Vec::<String>::new());
    let wrong_acc = Mutex::new(Vec::<String>::new());
    // Per class: (cases, refused, refusals naming file, line where due, field).
    let tally = Mutex::new(std::collections::BTreeMap::<&str, [usize; 5]>::new());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let work = tempfile::tempdir().unwrap();
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(case) = cases.get(i) else { break };
                    let dir = work.path().join(format!("case{i:04}"));
                    std::fs::create_dir(&dir).unwrap();
                    materialise(case, &dir);
                    let args: Vec<&str> = case.args.iter().map(String::as_str).collect();
                    let e: Ended = run_in(&dir, &args, CASE_S, None);
                    let label =
                        format!("case {i} ({}): rigtwin {}", case.class, case.args.join(" "));
                    if let Some(f) = e.failed() {
                        failures
                            .lock()
                            .unwrap()
                            .push(format!("{label}: {f}\n{}", e.stderr));
                    }
                    if e.code == Some(0) && case.expect == Expect::Refuse {
                        wrong_acc.lock().unwrap().push(label.clone());
                    }
                    let mut t = tally.lock().unwrap();
                    let row = t.entry(case.class).or_default();
                    row[0] += 1;
                    if e.refused() {
                        row[1] += 1;
                        let named = case.files.iter().any(|(f, _)| {
                            let name = Path::new(f)
                                .file_name()
                                .unwrap()
                                .to_string_lossy()
                                .into_owned();
                            e.stderr.contains(&name)
                        }) || e.stderr.contains(" s:")
                            || e.stderr.contains("session s");
                        if named {
                            row[2] += 1;
                        } else {
                            failures.lock().unwrap().push(format!(
                                "{label}: the refusal does not name the file: {}",
                                e.stderr
                            ));
                        }
                        if case.locate == Locate::File || names_line(&e.stderr) {
                            row[3] += 1;
                        } else if e.code == Some(1) {
                            failures.lock().unwrap().push(format!(
                                "{label}: the refusal does not name a line: {}",
                                e.stderr
                            ));
                        }
                        if names_field(&e.stderr) {
                            row[4] += 1;
                        }
                    }
                    drop(t);
                    let _ = std::fs::remove_dir_all(&dir);
                }
            });
        }
    });
    wrong.extend(wrong_acc.into_inner().unwrap());
    let tally = tally.into_inner().unwrap();
    let total: usize = tally.values().map(|r| r[0]).sum::<usize>() + datagrams;
    eprintln!(
        "{:<52} {:>5} {:>7} {:>5} {:>5} {:>5}",
        "class", "cases", "refused", "file", "line", "field"
    );
    for (class, r) in &tally {
        eprintln!(
            "{class:<52} {:>5} {:>7} {:>5} {:>5} {:>5}",
            r[0], r[1], r[2], r[3], r[4]
        );
    }
    eprintln!(
        "{:<52} {datagrams:>5}",
        "wire: datagrams decoded (in process)"
    );
    let failures = failures.into_inner().unwrap();
    eprintln!(
        "{total} cases; {} aborts, hangs, panics or unnamed refusals; {} wrong acceptances",
        failures.len(),
        wrong.len()
    );
    for w in &wrong {
        eprintln!("wrong acceptance: {w}");
    }
    assert!(
        total >= 1000,
        "the corpus must hold at least 1000 cases, has {total}"
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n---\n")
    );
    assert!(
        wrong.is_empty(),
        "{} wrong acceptances:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}
