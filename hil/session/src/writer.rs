//! Crash-safe streaming writer.
//!
//! What a run killed at any instant leaves behind, and why it always reads back:
//! - `session.toml` lists **finished trials only**. It is replaced atomically (temp file
//!   in the same directory, fsync, rename, fsync of the directory) after every trial, so
//!   it is always either the old or the new complete manifest.
//! - The trial being recorded is `trials/NNNN.csv.partial`, with its manifest entry in
//!   `trials/NNNN.partial.toml`. Readers only open files the manifest lists, so they
//!   never see it. Its rows are flushed to the operating system at least every 10 ms of
//!   samples (`rate_hz / 100` rows), so a killed process loses at most that much.
//! - A trial is finished in this order: flush + fsync the CSV, rename it to
//!   `NNNN.csv`, rewrite the manifest with its entry and digest, delete the sidecar.
//! - [`recover`] turns a leftover partial trial into a finished one (cut at its last
//!   complete row), or cleans up after a kill that came after the manifest was written.
//!
//! Output is deterministic: the same calls give the same bytes. Times are `i / rate_hz`
//! for row `i`, computed from the row count (never accumulated); `created` is passed in.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use sha2::Digest;

use super::MANIFEST_FILE;
use super::error::SessionError;
use super::manifest::{self, Manifest, Perturbation, Sha256, TrialEntry, TrialKind};
use super::table::{self, Trial};

/// What the writer needs to know about a trial before its first sample.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialMeta {
    /// Trial id, unique in the session; the file is `trials/{id:04}.csv`.
    pub id: u32,
    /// What the subject did.
    pub kind: TrialKind,
    /// Movement start, rig frame, m.
    pub start_m: Option<[f64; 2]>,
    /// Movement goal, rig frame, m.
    pub goal_m: Option<[f64; 2]>,
    /// The perturbation, if any.
    pub perturbation: Option<Perturbation>,
}

/// Which optional columns a streamed trial has.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Channels {
    /// `vx_m_per_s, vy_m_per_s`.
    pub velocity: bool,
    /// `ref_x_m, ref_y_m`.
    pub reference: bool,
    /// `cmd_fx_n, cmd_fy_n`.
    pub command: bool,
    /// Further columns, in this order, after the spec's.
    pub extra: Vec<String>,
}

impl Channels {
    /// All of the spec's optional columns, no extra ones.
    #[must_use]
    pub fn all() -> Channels {
        Channels {
            velocity: true,
            reference: true,
            command: true,
            extra: Vec::new(),
        }
    }
}

/// One row of a streamed trial. Its time is the writer's: `row / rate_hz`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// Handle position, rig frame, m.
    pub pos_m: [f64; 2],
    /// Hand force on the handle, rig frame, N.
    pub force_n: [f64; 2],
    /// Perturbation force added to the admittance input, N.
    pub pert_force_n: [f64; 2],
    /// Drive velocity, m/s; `Some` exactly when [`Channels::velocity`].
    pub vel_m_per_s: Option<[f64; 2]>,
    /// Admittance position reference, m; `Some` exactly when [`Channels::reference`].
    pub ref_m: Option<[f64; 2]>,
    /// Motor force command, N; `Some` exactly when [`Channels::command`].
    pub cmd_n: Option<[f64; 2]>,
}

struct Active {
    meta: TrialMeta,
    channels: Channels,
    rel: String,
    partial: PathBuf,
    sidecar: PathBuf,
    out: BufWriter<File>,
    hasher: sha2::Sha256,
    rows: u64,
    flush_every: u64,
    line: String,
}

impl Active {
    fn emit(&mut self, text: &str) -> Result<(), SessionError> {
        self.hasher.update(text.as_bytes());
        self.out
            .write_all(text.as_bytes())
            .map_err(|e| SessionError::io(&self.partial, e))
    }
}

/// Writes a session trial by trial; see the module documentation for what survives a
/// crash.
#[derive(Debug)]
pub struct SessionWriter {
    dir: PathBuf,
    manifest: Manifest,
    active: Option<Active>,
    /// Held while the writer lives, so that a second writer into the same directory is
    /// refused instead of interleaving trials.
    _lock: DirLock,
}

/// The name of the lock file a [`SessionWriter`] holds in its directory.
pub const LOCK_FILE: &str = ".session.lock";

/// An exclusive advisory lock on a session directory (`flock` on [`LOCK_FILE`]); the
/// file is removed when the lock is dropped. The kernel releases the lock of a killed
/// process, so a stale file never blocks the next writer.
#[derive(Debug)]
struct DirLock {
    path: PathBuf,
    _file: File,
}

impl DirLock {
    fn take(dir: &Path) -> Result<DirLock, SessionError> {
        let path = dir.join(LOCK_FILE);
        let file = File::options()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| SessionError::io(&path, e))?;
        match file.try_lock() {
            Ok(()) => Ok(DirLock { path, _file: file }),
            Err(std::fs::TryLockError::WouldBlock) => Err(invalid(
                dir,
                "another writer is recording into this directory (its lock is held)",
            )),
            Err(std::fs::TryLockError::Error(e)) => Err(SessionError::io(&path, e)),
        }
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Best effort: a lock file left behind is harmless (the lock died with its file
        // handle), and there is no one to tell in a drop.
        let _ = fs::remove_file(&self.path);
    }
}

impl std::fmt::Debug for Active {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Active")
            .field("id", &self.meta.id)
            .field("rows", &self.rows)
            .finish_non_exhaustive()
    }
}

fn invalid(file: &Path, message: impl Into<String>) -> SessionError {
    SessionError::InvalidWrite {
        file: file.to_path_buf(),
        message: message.into(),
    }
}

/// Writes `bytes` to `path` so that `path` holds either its old content or all of
/// `bytes`, whatever happens: temp file in the same directory, fsync, rename, fsync of
/// the directory.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SessionError> {
    let dir = path.parent().unwrap_or_else(|| Path::new("."));
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".tmp");
    let tmp = dir.join(name);
    let mut f = File::create(&tmp).map_err(|e| SessionError::io(&tmp, e))?;
    f.write_all(bytes).map_err(|e| SessionError::io(&tmp, e))?;
    f.sync_all().map_err(|e| SessionError::io(&tmp, e))?;
    drop(f);
    fs::rename(&tmp, path).map_err(|e| SessionError::io(path, e))?;
    sync_dir(dir)
}

fn sync_dir(dir: &Path) -> Result<(), SessionError> {
    File::open(dir)
        .and_then(|d| d.sync_all())
        .map_err(|e| SessionError::io(dir, e))
}

fn remove_if_present(path: &Path) -> Result<(), SessionError> {
    match fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(SessionError::io(path, e)),
        _ => Ok(()),
    }
}

fn trial_paths(dir: &Path, id: u32) -> (String, PathBuf, PathBuf, PathBuf) {
    let rel = format!("trials/{id:04}.csv");
    let trials = dir.join("trials");
    (
        rel,
        trials.join(format!("{id:04}.csv")),
        trials.join(format!("{id:04}.csv.partial")),
        trials.join(format!("{id:04}.partial.toml")),
    )
}

fn entry(meta: &TrialMeta, rel: String, sha256: Option<Sha256>) -> TrialEntry {
    TrialEntry {
        id: meta.id,
        file: rel,
        sha256,
        kind: meta.kind.clone(),
        start_m: meta.start_m,
        goal_m: meta.goal_m,
        perturbation: meta.perturbation.clone(),
    }
}

fn push_number(line: &mut String, v: f64) {
    use std::fmt::Write as _;
    line.push(',');
    // `{}` is the shortest decimal text that reads back to the same f64.
    let _ = write!(line, "{v}");
}

impl SessionWriter {
    /// Starts a new session in `dir` (created if needed) and writes its manifest with no
    /// trial. `manifest.trials` must be empty; `manifest.created` is written as given.
    ///
    /// # Errors
    /// [`SessionError::InvalidWrite`] if `dir` already holds a session or the manifest
    /// lists trials or has a non-finite or non-positive `rate_hz`; I/O errors.
    pub fn create(
        dir: impl AsRef<Path>,
        manifest: Manifest,
    ) -> Result<SessionWriter, SessionError> {
        let dir = dir.as_ref().to_path_buf();
        let path = dir.join(MANIFEST_FILE);
        if path.exists() {
            return Err(invalid(
                &path,
                "already holds a session (use SessionWriter::resume)",
            ));
        }
        let trials = dir.join("trials");
        fs::create_dir_all(&trials).map_err(|e| SessionError::io(&trials, e))?;
        let lock = DirLock::take(&dir)?;
        // Checked again under the lock: another writer may have started in between.
        if path.exists() {
            return Err(invalid(
                &path,
                "already holds a session (use SessionWriter::resume)",
            ));
        }
        if !manifest.trials.is_empty() {
            return Err(invalid(&path, "a new session starts with no trial"));
        }
        if let Some(seed) = manifest.sim.as_ref().and_then(|s| s.seed)
            && i64::try_from(seed).is_err()
        {
            return Err(invalid(
                &path,
                format!(
                    "sim.seed {seed} is past 2^63 - 1, the largest integer a TOML reader must accept"
                ),
            ));
        }
        if !(manifest.rate_hz.is_finite() && manifest.rate_hz > 0.0) {
            return Err(invalid(
                &path,
                format!("rate_hz must be finite and > 0, found {}", manifest.rate_hz),
            ));
        }
        let writer = SessionWriter {
            dir,
            manifest,
            active: None,
            _lock: lock,
        };
        writer.write_manifest()?;
        Ok(writer)
    }

    /// Continues a session already on disk, adding trials after the ones it lists.
    ///
    /// # Errors
    /// Any error of [`super::Session::open`]; [`SessionError::InvalidWrite`] if an
    /// unfinished trial is left (run [`recover`] first).
    pub fn resume(dir: impl AsRef<Path>) -> Result<SessionWriter, SessionError> {
        let reader = super::Session::open(&dir)?;
        let lock = DirLock::take(dir.as_ref())?;
        let dir = dir.as_ref().to_path_buf();
        if let Some(sidecar) = sidecars(&dir)?.into_iter().next() {
            return Err(invalid(
                &sidecar,
                "an unfinished trial is left; run session::recover first",
            ));
        }
        Ok(SessionWriter {
            dir,
            manifest: reader.into_manifest(),
            active: None,
            _lock: lock,
        })
    }

    /// The manifest as it stands: finished trials only.
    #[must_use]
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The session directory.
    #[must_use]
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Sets the manifest's `[timing]` (a real-time recording's clock) and writes the
    /// manifest again.
    ///
    /// # Errors
    /// [`SessionError`] if the manifest cannot be written.
    pub fn set_timing(&mut self, timing: crate::Timing) -> Result<(), SessionError> {
        self.manifest.timing = Some(timing);
        self.write_manifest()
    }

    fn write_manifest(&self) -> Result<(), SessionError> {
        write_atomic(
            &self.dir.join(MANIFEST_FILE),
            self.manifest.to_toml().as_bytes(),
        )
    }

    /// The paths of trial `id` (relative file, final file, partial file, sidecar), once
    /// it is sure that no trial is in progress and that the id and file are free.
    fn free_trial_paths(
        &self,
        id: u32,
    ) -> Result<(String, PathBuf, PathBuf, PathBuf), SessionError> {
        let paths = trial_paths(&self.dir, id);
        if let Some(a) = &self.active {
            return Err(invalid(
                &a.partial,
                format!("trial {} is still in progress", a.meta.id),
            ));
        }
        if self
            .manifest
            .trials
            .iter()
            .any(|t| t.id == id || t.file == paths.0)
        {
            return Err(invalid(
                &paths.2,
                format!("trial id {id} is already in the session"),
            ));
        }
        Ok(paths)
    }

    /// Starts streaming trial `meta.id` with the given optional columns.
    ///
    /// # Errors
    /// [`SessionError::InvalidWrite`] if a trial is in progress, the id is taken or a
    /// column name cannot be written; I/O errors.
    pub fn begin_trial(&mut self, meta: TrialMeta, channels: Channels) -> Result<(), SessionError> {
        let (rel, _, partial, sidecar) = self.free_trial_paths(meta.id)?;
        let mut header: Vec<&str> = table::REQUIRED_COLUMNS.to_vec();
        let optional = table::OPTIONAL_COLUMNS;
        for (on, names) in [
            (channels.velocity, &optional[0..2]),
            (channels.reference, &optional[2..4]),
        ]
        .into_iter()
        .chain([(channels.command, &optional[4..6])])
        {
            if on {
                header.extend_from_slice(names);
            }
        }
        for name in &channels.extra {
            if !table::is_column_name(name) || header.contains(&name.as_str()) {
                return Err(invalid(
                    &partial,
                    format!("extra column {name:?} is not a new plain header name"),
                ));
            }
            header.push(name);
        }
        let mut text = header.join(",");
        text.push('\n');
        let mut side = String::new();
        manifest::write_trial_entry(&mut side, &entry(&meta, rel.clone(), None));
        write_atomic(&sidecar, side.as_bytes())?;
        let file = File::create(&partial).map_err(|e| SessionError::io(&partial, e))?;
        // At least every 10 ms of samples (rounded down to whole rows, at least one).
        let flush_every = ((self.manifest.rate_hz / 100.0).floor() as u64).max(1);
        let mut active = Active {
            meta,
            channels,
            rel,
            partial,
            sidecar,
            out: BufWriter::new(file),
            hasher: sha2::Sha256::new(),
            rows: 0,
            flush_every,
            line: String::with_capacity(256),
        };
        active.emit(&text)?;
        active
            .out
            .flush()
            .map_err(|e| SessionError::io(&active.partial, e))?;
        self.active = Some(active);
        Ok(())
    }

    /// Appends one row to the trial in progress.
    ///
    /// # Errors
    /// [`SessionError::InvalidWrite`] if no trial is in progress, a value is not finite
    /// or the sample's optional parts do not match the trial's [`Channels`]; I/O errors.
    pub fn push(&mut self, sample: &Sample) -> Result<(), SessionError> {
        self.push_with_extra(sample, &[])
    }

    /// Appends one row with values for the [`Channels::extra`] columns, in their order.
    ///
    /// # Errors
    /// As [`SessionWriter::push`], and if `extra` has the wrong length.
    pub fn push_with_extra(&mut self, sample: &Sample, extra: &[f64]) -> Result<(), SessionError> {
        let rate_hz = self.manifest.rate_hz;
        let Some(a) = self.active.as_mut() else {
            return Err(invalid(
                &self.dir,
                "push without a trial in progress (call begin_trial)",
            ));
        };
        let layout = [
            (a.channels.velocity, sample.vel_m_per_s, "vel_m_per_s"),
            (a.channels.reference, sample.ref_m, "ref_m"),
            (a.channels.command, sample.cmd_n, "cmd_n"),
        ];
        if let Some((_, _, name)) = layout.iter().find(|(on, v, _)| *on != v.is_some()) {
            return Err(invalid(
                &a.partial,
                format!("sample.{name} does not match the trial's channels"),
            ));
        }
        if extra.len() != a.channels.extra.len() {
            let n = a.channels.extra.len();
            return Err(invalid(
                &a.partial,
                format!("{} extra values for {n} extra columns", extra.len()),
            ));
        }
        let t = a.rows as f64 / rate_hz;
        let values = [sample.pos_m, sample.force_n, sample.pert_force_n]
            .into_iter()
            .chain(layout.iter().filter_map(|(_, v, _)| *v))
            .flatten()
            .chain(extra.iter().copied());
        let mut line = std::mem::take(&mut a.line);
        line.clear();
        use std::fmt::Write as _;
        let _ = write!(line, "{t}");
        for v in values {
            if !v.is_finite() {
                a.line = line;
                return Err(invalid(
                    &a.partial,
                    format!("row {}: {v} is not finite", a.rows),
                ));
            }
            push_number(&mut line, v);
        }
        line.push('\n');
        let result = a.emit(&line);
        a.line = line;
        result?;
        a.rows += 1;
        if a.rows % a.flush_every == 0 {
            a.out.flush().map_err(|e| SessionError::io(&a.partial, e))?;
        }
        Ok(())
    }

    /// Rows pushed to the trial in progress (0 without one).
    #[must_use]
    pub fn rows_in_progress(&self) -> u64 {
        self.active.as_ref().map_or(0, |a| a.rows)
    }

    /// Finishes the trial in progress: its file gets its final name and the manifest
    /// lists it with its digest.
    ///
    /// # Errors
    /// [`SessionError::InvalidWrite`] without a trial in progress or with no row; I/O.
    pub fn finish_trial(&mut self) -> Result<&TrialEntry, SessionError> {
        let Some(a) = self.active.take() else {
            return Err(invalid(
                &self.dir,
                "finish_trial without a trial in progress",
            ));
        };
        if a.rows == 0 {
            let file = a.partial.clone();
            self.active = Some(a);
            return Err(invalid(&file, "a trial needs at least one sample"));
        }
        let Active {
            meta,
            rel,
            partial,
            sidecar,
            out,
            hasher,
            ..
        } = a;
        let file = out
            .into_inner()
            .map_err(|e| SessionError::io(&partial, e.into_error()))?;
        file.sync_all().map_err(|e| SessionError::io(&partial, e))?;
        drop(file);
        let sha = Sha256(hasher.finalize().into());
        self.commit(&meta, rel, &partial, &sidecar, sha)
    }

    fn commit(
        &mut self,
        meta: &TrialMeta,
        rel: String,
        partial: &Path,
        sidecar: &Path,
        sha: Sha256,
    ) -> Result<&TrialEntry, SessionError> {
        let done = entry(meta, rel, Some(sha));
        let final_path = done.path_in(&self.dir);
        fs::rename(partial, &final_path).map_err(|e| SessionError::io(&final_path, e))?;
        sync_dir(&self.dir.join("trials"))?;
        self.manifest.trials.push(done);
        self.write_manifest()?;
        remove_if_present(sidecar)?;
        self.manifest
            .trials
            .last()
            .ok_or_else(|| invalid(&self.dir, "manifest lost its last trial"))
    }

    /// Writes a whole in-memory trial (its own `t_s` included) through the same
    /// crash-safe path.
    ///
    /// # Errors
    /// [`SessionError::InvalidWrite`] if a trial is in progress, the id is taken, or the
    /// trial is empty, ragged or not finite; I/O errors.
    pub fn write_trial(
        &mut self,
        meta: TrialMeta,
        trial: &Trial,
    ) -> Result<&TrialEntry, SessionError> {
        let (rel, _, partial, sidecar) = self.free_trial_paths(meta.id)?;
        trial.check_writable(&partial)?;
        let mut side = String::new();
        manifest::write_trial_entry(&mut side, &entry(&meta, rel.clone(), None));
        write_atomic(&sidecar, side.as_bytes())?;
        let csv = trial.to_csv();
        let mut f = File::create(&partial).map_err(|e| SessionError::io(&partial, e))?;
        f.write_all(csv.as_bytes())
            .map_err(|e| SessionError::io(&partial, e))?;
        f.sync_all().map_err(|e| SessionError::io(&partial, e))?;
        drop(f);
        self.commit(&meta, rel, &partial, &sidecar, Sha256::of(csv.as_bytes()))
    }

    /// Ends the session and returns its manifest.
    ///
    /// # Errors
    /// [`SessionError::InvalidWrite`] if a trial is still in progress.
    pub fn finish(self) -> Result<Manifest, SessionError> {
        match &self.active {
            Some(a) => Err(invalid(
                &a.partial,
                format!("trial {} is still in progress", a.meta.id),
            )),
            None => Ok(self.manifest),
        }
    }
}

fn sidecars(dir: &Path) -> Result<Vec<PathBuf>, SessionError> {
    let trials = dir.join("trials");
    let entries = match fs::read_dir(&trials) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(SessionError::io(&trials, e)),
    };
    let mut out = Vec::new();
    for e in entries {
        let path = e.map_err(|e| SessionError::io(&trials, e))?.path();
        if path.to_string_lossy().ends_with(".partial.toml") {
            out.push(path);
        }
    }
    out.sort();
    Ok(out)
}

/// A trial that [`recover`] added to a session.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Recovered {
    /// The trial's id.
    pub id: u32,
    /// Samples kept (complete rows that had reached the disk).
    pub samples: usize,
}

/// Finishes what a killed [`SessionWriter`] left in `dir`: a partial trial with at
/// least one complete row becomes a listed trial cut at its last complete row; an empty
/// one is removed; leftovers of a kill after the manifest was written are cleaned up.
///
/// # Errors
/// Errors reading the manifest; a partial trial whose complete rows do not parse (left
/// untouched for a person to look at); I/O errors.
pub fn recover(dir: impl AsRef<Path>) -> Result<Vec<Recovered>, SessionError> {
    let dir = dir.as_ref();
    let mut manifest = super::Session::open(dir)?.into_manifest();
    let _lock = DirLock::take(dir)?;
    remove_if_present(&dir.join(format!("{MANIFEST_FILE}.tmp")))?;
    let mut recovered = Vec::new();
    for (sidecar, mut entry) in sidecar_entries(dir)? {
        let final_path = entry.path_in(dir);
        let partial = partial_of(&final_path);
        if manifest.trials.iter().any(|t| t.id == entry.id) {
            remove_if_present(&partial)?;
            remove_if_present(&sidecar)?;
            continue;
        }
        let source = if partial.exists() {
            partial.clone()
        } else {
            final_path.clone()
        };
        let bytes = match fs::read(&source) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(SessionError::io(&source, e)),
        };
        let complete = bytes
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(&bytes[..0], |i| &bytes[..=i]);
        let samples = match table::parse_csv(complete, manifest.rate_hz, &source) {
            Ok(trial) => trial.len(),
            Err(SessionError::NoSamples { .. } | SessionError::MissingHeader { .. }) => 0,
            Err(e) => return Err(e),
        };
        if samples == 0 {
            remove_if_present(&partial)?;
            remove_if_present(&final_path)?;
            remove_if_present(&sidecar)?;
            continue;
        }
        write_atomic(&final_path, complete)?;
        if source != final_path {
            remove_if_present(&source)?;
        }
        entry.sha256 = Some(Sha256::of(complete));
        recovered.push(Recovered {
            id: entry.id,
            samples,
        });
        manifest.trials.push(entry);
        write_atomic(&dir.join(MANIFEST_FILE), manifest.to_toml().as_bytes())?;
        remove_if_present(&sidecar)?;
    }
    Ok(recovered)
}

/// Each sidecar a killed writer left, with the trial entry it holds.
fn sidecar_entries(dir: &Path) -> Result<Vec<(PathBuf, TrialEntry)>, SessionError> {
    sidecars(dir)?
        .into_iter()
        .map(|sidecar| {
            let text = fs::read_to_string(&sidecar).map_err(|e| SessionError::io(&sidecar, e))?;
            let (entry, _) = manifest::parse_trial_entry(&text, &sidecar)?;
            Ok((sidecar, entry))
        })
        .collect()
}

/// `trials/NNNN.csv.partial` for `trials/NNNN.csv`: where the writer records a trial.
fn partial_of(final_path: &Path) -> PathBuf {
    let mut name = final_path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".partial");
    final_path.with_file_name(name)
}

/// What [`repair`] did to a killed session.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Repaired {
    /// Trials that were complete on disk (renamed into place after their last row was
    /// synced) but not yet in the manifest, now listed with their digest.
    pub listed: Vec<u32>,
    /// Files of the trial being recorded when the run was killed, moved unchanged into
    /// [`SET_ASIDE_DIR`]: a cut trial is not a trial the protocol asked for, and its
    /// rows are kept for a person to look at.
    pub set_aside: Vec<PathBuf>,
    /// Leftovers that hold nothing the manifest does not (a sidecar of a listed trial,
    /// a manifest temp file), removed.
    pub removed: Vec<PathBuf>,
}

/// Where [`repair`] puts an incomplete trial's files, inside the session directory.
pub const SET_ASIDE_DIR: &str = "set-aside";

/// The files a killed [`SessionWriter`] can leave beside a session: a manifest temp file,
/// trial sidecars and partial trial tables, and anything already set aside. Readers ignore
/// them; `rigtwin inspect` names them.
///
/// # Errors
/// I/O errors listing the directories.
pub fn leftovers(dir: impl AsRef<Path>) -> Result<Vec<PathBuf>, SessionError> {
    let dir = dir.as_ref();
    let mut out = Vec::new();
    let tmp = dir.join(format!("{MANIFEST_FILE}.tmp"));
    if tmp.exists() {
        out.push(tmp);
    }
    for sub in ["trials", SET_ASIDE_DIR] {
        let d = dir.join(sub);
        let entries = match fs::read_dir(&d) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(SessionError::io(&d, e)),
        };
        for e in entries {
            let path = e.map_err(|e| SessionError::io(&d, e))?.path();
            let name = path.to_string_lossy();
            if sub == SET_ASIDE_DIR || name.ends_with(".partial") || name.ends_with(".partial.toml")
            {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Finishes the manifest of a killed session: every complete trial is listed, the trial
/// that was being recorded is set aside (moved, never deleted), and leftovers that hold
/// nothing new are removed. A repaired session's trials are byte for byte those of an
/// uninterrupted run, because a trial file only takes its final name after its last row
/// is synced. Unlike [`recover`], no trial is cut. Repairing twice changes nothing.
///
/// # Errors
/// The manifest does not read (a run killed before its first manifest has nothing to
/// repair); a sidecar does not parse; I/O errors.
pub fn repair(dir: impl AsRef<Path>) -> Result<Repaired, SessionError> {
    let dir = dir.as_ref();
    let mut manifest = super::Session::open(dir)?.into_manifest();
    let _lock = DirLock::take(dir)?;
    let mut done = Repaired::default();
    let tmp = dir.join(format!("{MANIFEST_FILE}.tmp"));
    if tmp.exists() {
        remove_if_present(&tmp)?;
        done.removed.push(tmp);
    }
    for (sidecar, mut entry) in sidecar_entries(dir)? {
        let final_path = entry.path_in(dir);
        let partial = partial_of(&final_path);
        if manifest.trials.iter().any(|t| t.id == entry.id) {
            // Killed after the manifest listed it: the sidecar is a copy.
            remove_if_present(&sidecar)?;
            done.removed.push(sidecar);
            continue;
        }
        if partial.exists() || !final_path.exists() {
            for f in [&partial, &sidecar] {
                if f.exists() {
                    done.set_aside.push(set_aside(dir, f)?);
                }
            }
            continue;
        }
        let bytes = fs::read(&final_path).map_err(|e| SessionError::io(&final_path, e))?;
        // The file is complete; check it parses before listing it.
        table::parse_csv(&bytes, manifest.rate_hz, &final_path)?;
        entry.sha256 = Some(Sha256::of(&bytes));
        done.listed.push(entry.id);
        manifest.trials.push(entry);
        manifest.trials.sort_by_key(|t| t.id);
        write_atomic(&dir.join(MANIFEST_FILE), manifest.to_toml().as_bytes())?;
        remove_if_present(&sidecar)?;
        done.removed.push(sidecar);
    }
    Ok(done)
}

/// Moves `file` into the session's [`SET_ASIDE_DIR`] under its own name (with `.1`,
/// `.2`, ... if that is taken) and returns where it went.
fn set_aside(dir: &Path, file: &Path) -> Result<PathBuf, SessionError> {
    let aside = dir.join(SET_ASIDE_DIR);
    fs::create_dir_all(&aside).map_err(|e| SessionError::io(&aside, e))?;
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut to = aside.join(&name);
    let mut k = 0;
    while to.exists() {
        k += 1;
        to = aside.join(format!("{name}.{k}"));
    }
    fs::rename(file, &to).map_err(|e| SessionError::io(file, e))?;
    sync_dir(&aside)?;
    Ok(to)
}
