//! The sweep's results as a CSV table, its shards, and their merge.
//!
//! CSV, not Parquet: the table is a few columns by at most a million rows (a 1000-run
//! sweep is ~300 kB); pandas (`read_csv`), polars and MATLAB (`readtable`) open it with
//! no extra package; its bytes are a function of the values alone (Rust's shortest
//! round-trip decimal for every float, so a reader gets back the exact double), which is
//! what makes "the merged table is byte-identical for any number of shards" a `cmp`;
//! and it needs no new dependency (the `parquet` crate is not in this build; the
//! rerun stack builds `arrow` but not its Parquet writer, whose files also carry a
//! writer-version string).
//!
//! A shard file is the table's header and its runs, after one line that says which
//! sweep and which shard it is:
//!
//! ```text
//! # rigtwin-sweep 1 id=<sha256 of the sweep> shard=3/16 runs=96
//! run,point,reach.repetitions,subject,...
//! 3,0,1,4,...
//! ```
//!
//! Shard K of N holds runs K, K+N, K+2N, … (round robin, so each shard gets its share
//! of every grid point however their costs differ). It is written to a temporary file
//! and renamed into place, so a task killed or requeued midway never leaves half a
//! shard. [`merge`] checks that every shard of one sweep is there once with all its runs
//! and writes the runs in order: the same bytes as a run on one machine.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::file::{ELEMENTS, SweepFile};
use super::run::Row;

/// The shard header's first word and version.
pub const SHARD_MAGIC: &str = "# rigtwin-sweep 1";

/// Why shards cannot be merged (or written).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ShardError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A shard file is not one.
    #[error("{path}: line {line}: {problem}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        problem: String,
    },
    /// Shards of different sweeps, or of different splits of one sweep.
    #[error("mismatched shards: {0}")]
    Mismatched(String),
    /// Shards missing.
    #[error(
        "missing shards: {missing} of {of} (their tasks have not finished or failed; see their logs, then run them again with --shard K/{of})"
    )]
    Missing {
        /// The missing shard numbers, listed.
        missing: String,
        /// N.
        of: usize,
    },
    /// One shard twice.
    #[error("shard {shard}/{of} twice: {first} and {second}")]
    Duplicate {
        /// K.
        shard: usize,
        /// N.
        of: usize,
        /// One file.
        first: PathBuf,
        /// The other.
        second: PathBuf,
    },
    /// No shards at all.
    #[error("no shard files (shard-*-of-*.csv) in {0}")]
    None(PathBuf),
}

/// The table's columns for `sweep`.
#[must_use]
pub fn header(sweep: &SweepFile) -> Vec<String> {
    let mut h: Vec<String> = ["run", "point"].map(str::to_owned).into();
    h.extend(sweep.grid.iter().map(|(k, _)| k.clone()));
    if let Some(e) = &sweep.effect {
        h.push(e.key.clone());
    }
    h.extend(
        [
            "subject",
            "replicate",
            "session_seed",
            "error",
            "trials",
            "perturbed",
            "session_length_s",
            "peak_command_n",
            "peak_speed_m_per_s",
            "wall_margin_m",
            "trips",
        ]
        .map(str::to_owned),
    );
    if sweep.estimate {
        for what in ["est", "true", "se"] {
            for e in ELEMENTS {
                h.push(element_column(e, what));
            }
        }
        h.push("estimate_error".to_owned());
    }
    if sweep.diagnose {
        h.extend(["cause", "causes", "named"].map(str::to_owned));
        if let Some(e) = &sweep.effect {
            h.push(format!("found_{}", e.parameter));
        }
        h.extend(["gain", "unexplained", "diagnose_error"].map(str::to_owned));
    }
    h
}

/// `K22_est_n_per_m`, `D11_true_n_s_per_m`.
#[must_use]
pub fn element_column(element: &str, what: &str) -> String {
    let unit = if element.starts_with('D') {
        "n_s_per_m"
    } else {
        "n_per_m"
    };
    format!("{element}_{what}_{unit}")
}

/// A float as the table writes it: Rust's shortest round-trip decimal.
#[must_use]
pub fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

fn opt(v: Option<f64>) -> String {
    v.map(num).unwrap_or_default()
}

/// A grid value as a table cell (strings unquoted, numbers as [`num`]).
#[must_use]
pub fn cell(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(f) => num(*f),
        toml::Value::Boolean(b) => b.to_string(),
        other => other.to_string(),
    }
}

/// The cells of `row`, in [`header`]'s order.
#[must_use]
pub fn cells(sweep: &SweepFile, row: &Row) -> Vec<String> {
    let mut c = vec![row.run.index.to_string(), row.run.point.to_string()];
    c.extend(
        sweep
            .point_values(row.run.point)
            .iter()
            .map(|(_, v)| cell(v)),
    );
    if sweep.effect.is_some() {
        c.push(opt(row.effect_size));
    }
    c.extend([
        row.run.subject.to_string(),
        row.run.replicate.to_string(),
        row.session_seed.to_string(),
        row.error.clone().unwrap_or_default(),
        row.trials.to_string(),
        row.perturbed.to_string(),
        num(row.session_length_s),
        num(row.peak_command_n),
        num(row.peak_speed_m_per_s),
        num(row.wall_margin_m),
        row.trips.to_string(),
    ]);
    if sweep.estimate {
        for v in [row.estimate, row.truth, row.std_err] {
            for i in 0..ELEMENTS.len() {
                c.push(opt(v.map(|a| a[i])));
            }
        }
        c.push(row.estimate_error.clone().unwrap_or_default());
    }
    if sweep.diagnose {
        let d = row.diagnosis.as_ref();
        c.push(d.map(|d| d.cause.clone()).unwrap_or_default());
        c.push(d.map(|d| d.causes.clone()).unwrap_or_default());
        c.push(d.map(|d| d.named.to_string()).unwrap_or_default());
        if sweep.effect.is_some() {
            c.push(opt(d.and_then(|d| d.parameter)));
        }
        c.push(opt(d.and_then(|d| d.gain)));
        c.push(d.map(|d| d.unexplained.to_string()).unwrap_or_default());
        c.push(d.and_then(|d| d.error.clone()).unwrap_or_default());
    }
    c
}

/// CSV text of `records` (a header then rows), `\n` line ends.
///
/// # Errors
/// The CSV writer's error (it writes to memory, so only on a malformed record).
pub fn csv_text(records: &[Vec<String>]) -> Result<String, csv::Error> {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    for r in records {
        w.write_record(r)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| csv::Error::from(std::io::Error::other(e.to_string())))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// The file name of shard `k` of `n`.
#[must_use]
pub fn shard_name(k: usize, n: usize) -> String {
    format!("shard-{k:04}-of-{n:04}.csv")
}

/// The runs of shard `k` of `n` of a sweep of `runs` runs.
pub fn shard_runs(k: usize, n: usize, runs: usize) -> impl Iterator<Item = usize> {
    (k..runs).step_by(n.max(1))
}

/// The first line of shard `k` of `n`.
#[must_use]
pub fn shard_header(id: &str, k: usize, n: usize, runs: usize) -> String {
    format!("{SHARD_MAGIC} id={id} shard={k}/{n} runs={runs}")
}

/// Writes `text` to `path` atomically: a temporary file in the same folder, synced,
/// then renamed over `path`.
///
/// # Errors
/// [`ShardError::Io`].
pub fn write_atomic(path: &Path, text: &str) -> Result<(), ShardError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let io = |p: &Path, source| ShardError::Io {
        path: p.to_path_buf(),
        source,
    };
    let mut f = std::fs::File::create(&tmp).map_err(|e| io(&tmp, e))?;
    f.write_all(text.as_bytes()).map_err(|e| io(&tmp, e))?;
    f.sync_all().map_err(|e| io(&tmp, e))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(|e| io(path, e))
}

/// A shard file read back.
#[derive(Debug, Clone)]
struct Shard {
    path: PathBuf,
    id: String,
    k: usize,
    n: usize,
    runs: usize,
    header: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

fn read_shard(path: &Path) -> Result<Shard, ShardError> {
    let text = std::fs::read_to_string(path).map_err(|source| ShardError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |line: usize, problem: String| ShardError::Malformed {
        path: path.to_path_buf(),
        line,
        problem,
    };
    let (first, body) = text.split_once('\n').unwrap_or((&text, ""));
    let fields = first.strip_prefix(SHARD_MAGIC).ok_or_else(|| {
        bad(
            1,
            format!("not a rigtwin sweep shard (want `{SHARD_MAGIC} id=… shard=K/N runs=…`)"),
        )
    })?;
    let mut kv: BTreeMap<&str, &str> = BTreeMap::new();
    for f in fields.split_whitespace() {
        let (k, v) = f
            .split_once('=')
            .ok_or_else(|| bad(1, format!("`{f}` is not key=value")))?;
        kv.insert(k, v);
    }
    let get = |k: &str| {
        kv.get(k)
            .copied()
            .ok_or_else(|| bad(1, format!("the header has no `{k}=`")))
    };
    let id = get("id")?.to_owned();
    let (k, n) = get("shard")?
        .split_once('/')
        .and_then(|(k, n)| Some((k.parse::<usize>().ok()?, n.parse::<usize>().ok()?)))
        .filter(|(k, n)| k < n)
        .ok_or_else(|| bad(1, "`shard=` is not K/N with K < N".to_owned()))?;
    let runs: usize = get("runs")?
        .parse()
        .map_err(|e| bad(1, format!("`runs=`: {e}")))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(body.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| bad(2, e.to_string()))?
        .iter()
        .map(str::to_owned)
        .collect();
    let mut rows = Vec::new();
    for (i, rec) in reader.records().enumerate() {
        let line = i + 3;
        let rec = rec.map_err(|e| bad(line, e.to_string()))?;
        let cells: Vec<String> = rec.iter().map(str::to_owned).collect();
        let run: usize = cells
            .first()
            .and_then(|c| c.parse().ok())
            .ok_or_else(|| bad(line, "`run` is not a run number".to_owned()))?;
        rows.push((run, cells));
    }
    Ok(Shard {
        path: path.to_path_buf(),
        id,
        k,
        n,
        runs,
        header,
        rows,
    })
}

/// The shard files in `dir` (`shard-*-of-*.csv`), sorted by name.
///
/// # Errors
/// [`ShardError::Io`] when `dir` cannot be listed.
pub fn shard_files(dir: &Path) -> Result<Vec<PathBuf>, ShardError> {
    let entries = std::fs::read_dir(dir).map_err(|source| ShardError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                n.starts_with("shard-") && n.ends_with(".csv") && n.contains("-of-")
            })
        })
        .collect();
    files.sort();
    Ok(files)
}

/// True if `path` is a complete shard `k`/`n` of sweep `id` (a task run again skips it).
#[must_use]
pub fn shard_is_complete(path: &Path, id: &str, k: usize, n: usize) -> bool {
    read_shard(path).is_ok_and(|s| {
        s.id == id && s.k == k && s.n == n && s.rows.len() == shard_runs(k, n, s.runs).count()
    })
}

/// Merges the shards in `dir` of sweep `id` (of `runs` runs) into the table's records
/// (header first), in run order.
///
/// # Errors
/// [`ShardError`]: no shards, a malformed one, shards of another sweep or another split,
/// a shard twice, a shard missing, or a shard without all its runs.
pub fn merge(dir: &Path, id: &str, runs: usize) -> Result<Vec<Vec<String>>, ShardError> {
    let files = shard_files(dir)?;
    if files.is_empty() {
        return Err(ShardError::None(dir.to_path_buf()));
    }
    let shards = files
        .iter()
        .map(|f| read_shard(f))
        .collect::<Result<Vec<_>, _>>()?;
    for s in &shards {
        if s.id != id {
            return Err(ShardError::Mismatched(format!(
                "{} is of sweep {}…, this folder's sweep.toml is {}…",
                s.path.display(),
                &s.id[..s.id.len().min(12)],
                &id[..id.len().min(12)]
            )));
        }
        if s.runs != runs {
            return Err(ShardError::Mismatched(format!(
                "{} counts {} runs, the sweep has {runs}",
                s.path.display(),
                s.runs
            )));
        }
    }
    let n = shards[0].n;
    if let Some(other) = shards.iter().find(|s| s.n != n) {
        return Err(ShardError::Mismatched(format!(
            "{} is a shard of {} tasks and {} of {}; remove the shards of the earlier submission",
            shards[0].path.display(),
            n,
            other.path.display(),
            other.n
        )));
    }
    if let Some(other) = shards.iter().find(|s| s.header != shards[0].header) {
        return Err(ShardError::Mismatched(format!(
            "{} and {} have different columns",
            shards[0].path.display(),
            other.path.display()
        )));
    }
    let mut by_k: BTreeMap<usize, &Shard> = BTreeMap::new();
    for s in &shards {
        if let Some(first) = by_k.insert(s.k, s) {
            return Err(ShardError::Duplicate {
                shard: s.k,
                of: n,
                first: first.path.clone(),
                second: s.path.clone(),
            });
        }
    }
    let missing: Vec<String> = (0..n)
        .filter(|k| !by_k.contains_key(k))
        .map(|k| k.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(ShardError::Missing {
            missing: missing.join(", "),
            of: n,
        });
    }
    let mut rows: Vec<Option<Vec<String>>> = vec![None; runs];
    for s in by_k.values() {
        let want: Vec<usize> = shard_runs(s.k, n, runs).collect();
        let got: Vec<usize> = s.rows.iter().map(|r| r.0).collect();
        if got != want {
            return Err(ShardError::Malformed {
                path: s.path.clone(),
                line: 3,
                problem: format!(
                    "holds {} runs where shard {}/{n} has {} ({}…)",
                    got.len(),
                    s.k,
                    want.len(),
                    want.iter()
                        .take(4)
                        .map(ToString::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
        for (run, cells) in &s.rows {
            rows[*run] = Some(cells.clone());
        }
    }
    let mut out = vec![shards[0].header.clone()];
    out.extend(rows.into_iter().flatten());
    Ok(out)
}

/// The records of the table for `rows` (header first), rows in run order.
#[must_use]
pub fn records(sweep: &SweepFile, rows: &[Row]) -> Vec<Vec<String>> {
    let mut sorted: Vec<&Row> = rows.iter().collect();
    sorted.sort_by_key(|r| r.run.index);
    let mut out = vec![header(sweep)];
    out.extend(sorted.into_iter().map(|r| cells(sweep, r)));
    out
}
