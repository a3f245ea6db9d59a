//! rigtwin-session — sessions: the recording format, version 1
//! (`shared/specs/recording-format.md`), and [`replay::ReplayRig`], a recorded session as
//! a rig.
//!
//! This crate is the contract between whatever records a session and whatever reads
//! one: a rig-side logger, the diagnosis and the `rigtwin` application all depend on it
//! without depending on each other, and it knows nothing of the simulator, protocols or
//! the viewer (it depends on `rigtwin-device` for the `RigIo` boundary only).
//!
//! A session is a directory with `session.toml` (the [`Manifest`]) and one CSV table
//! per trial (a [`Trial`], stored as column vectors). [`Session::read`] reads all of it;
//! [`Session::open`] reads the manifest and gives a [`SessionReader`] that reads trials
//! one at a time, for sessions too big to hold. Every file that breaks the format is
//! rejected with a [`SessionError`] that names the file, the line and the field.
//! [`SessionWriter`] records a session so that a crash at any instant leaves a session
//! that reads back.

mod error;
pub mod files;
mod manifest;
pub mod replay;
mod table;
mod writer;

use std::path::{Path, PathBuf};

pub use error::SessionError;
pub use manifest::{
    Amplitude, Axes, Device, FORMAT, FORMAT_VERSION, MAX_RATE_HZ, MIN_RATE_HZ, Manifest,
    Percentiles, Perturbation, PerturbationKind, Sha256, SimInfo, Source, Subject, Timing,
    TrialEntry, TrialKind,
};
pub use table::{Column, OPTIONAL_COLUMNS, REQUIRED_COLUMNS, Trial, time_tolerance_s};
pub use writer::{
    Channels, LOCK_FILE, Recovered, Repaired, SET_ASIDE_DIR, Sample, SessionWriter, TrialMeta,
    leftovers, recover, repair,
};

/// The manifest's file name inside a session directory.
pub const MANIFEST_FILE: &str = "session.toml";

/// Where the trial files' size bound comes from, for its error.
const TRIAL_BOUND: &str = "a trial table at the manifest's rate_hz may have (an hour of 512-byte rows, files::max_trial_bytes)";

/// A whole session in memory: the manifest and every trial, in manifest order.
#[derive(Debug, Clone, PartialEq)]
pub struct Session {
    /// The session directory it was read from.
    pub dir: PathBuf,
    /// The manifest.
    pub manifest: Manifest,
    /// `trials[i]` is the table of `manifest.trials[i]`.
    pub trials: Vec<Trial>,
}

impl Session {
    /// Reads and checks the whole session in `dir`: the manifest, every listed trial
    /// file, its digest when the manifest gives one, and each perturbation's onset.
    /// Files the manifest does not list (such as a trial still being recorded) are
    /// ignored.
    ///
    /// # Errors
    /// The first fault found, in manifest order, as a [`SessionError`] naming file,
    /// line and field.
    pub fn read(dir: impl AsRef<Path>) -> Result<Session, SessionError> {
        let reader = Session::open(dir)?;
        let trials = reader
            .trials()
            .map(|r| r.map(|(_, t)| t))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Session {
            dir: reader.dir,
            manifest: reader.manifest,
            trials,
        })
    }

    /// Reads and checks the manifest in `dir` and that every listed trial file exists;
    /// trial tables are read on demand.
    ///
    /// # Errors
    /// A [`SessionError`] naming `session.toml`, the line and the key.
    pub fn open(dir: impl AsRef<Path>) -> Result<SessionReader, SessionError> {
        let dir = dir.as_ref().to_path_buf();
        let manifest_path = dir.join(MANIFEST_FILE);
        let bytes = files::read_bounded(
            &manifest_path,
            files::MAX_MANIFEST_BYTES,
            "a manifest may have (files::MAX_MANIFEST_BYTES)",
        )?;
        let text = files::utf8(bytes).map_err(|e| SessionError::io(&manifest_path, e))?;
        let (manifest, lines) = manifest::parse(&text, &manifest_path)?;
        let reader = SessionReader {
            // Resolved once: every trial file is checked against it.
            resolved_dir: std::fs::canonicalize(&dir).ok(),
            dir,
            manifest_path,
            manifest,
            lines,
        };
        for (entry, at) in reader.manifest.trials.iter().zip(&reader.lines) {
            let path = reader.trial_path(entry, at)?;
            files::check_regular(&path, reader.max_trial_bytes(), TRIAL_BOUND)?;
        }
        Ok(reader)
    }

    /// Each trial's entry with its table, in manifest order.
    pub fn iter(&self) -> impl Iterator<Item = (&TrialEntry, &Trial)> {
        self.manifest.trials.iter().zip(&self.trials)
    }

    /// The trial with id `id`.
    #[must_use]
    pub fn trial(&self, id: u32) -> Option<(&TrialEntry, &Trial)> {
        self.iter().find(|(e, _)| e.id == id)
    }
}

/// A session whose manifest is read and checked, with trials read on demand.
#[derive(Debug, Clone)]
pub struct SessionReader {
    dir: PathBuf,
    /// `dir` resolved through links (`None` if it cannot be).
    resolved_dir: Option<PathBuf>,
    manifest_path: PathBuf,
    manifest: Manifest,
    lines: Vec<manifest::EntryLines>,
}

impl SessionReader {
    /// The manifest.
    #[must_use]
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The session directory.
    #[must_use]
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The manifest, giving up the reader.
    #[must_use]
    pub fn into_manifest(self) -> Manifest {
        self.manifest
    }

    /// Reads and checks the table of `manifest().trials[index]`; `None` past the end.
    #[must_use]
    pub fn read_trial(&self, index: usize) -> Option<Result<Trial, SessionError>> {
        let entry = self.manifest.trials.get(index)?;
        let at = self.lines.get(index).cloned().unwrap_or_default();
        Some(self.read_entry(entry, &at))
    }

    /// Each trial's entry with its table, read one at a time, in manifest order.
    pub fn trials(&self) -> impl Iterator<Item = Result<(&TrialEntry, Trial), SessionError>> {
        self.manifest
            .trials
            .iter()
            .zip(&self.lines)
            .map(|(e, at)| self.read_entry(e, at).map(|t| (e, t)))
    }

    /// The trial file of `entry`, which must exist and, resolved through links, lie
    /// inside the session directory: a session is read as one folder, and its readers
    /// must not be pointed at other files.
    fn trial_path(
        &self,
        entry: &TrialEntry,
        at: &manifest::EntryLines,
    ) -> Result<PathBuf, SessionError> {
        let path = entry.path_in(&self.dir);
        if !path.exists() {
            return Err(SessionError::TrialFileMissing {
                file: self.manifest_path.clone(),
                line: at.file,
                field: "trial.file".into(),
                missing: path,
            });
        }
        if let Some(resolved) = self
            .resolved_dir
            .as_deref()
            .and_then(|dir| files::escapes(dir, &path))
        {
            return Err(SessionError::OutsideSession {
                file: self.manifest_path.clone(),
                line: at.file,
                field: "trial.file".into(),
                path,
                resolved,
            });
        }
        Ok(path)
    }

    /// The size bound of a trial table at this session's rate.
    fn max_trial_bytes(&self) -> u64 {
        files::max_trial_bytes(self.manifest.rate_hz)
    }

    fn read_entry(
        &self,
        entry: &TrialEntry,
        at: &manifest::EntryLines,
    ) -> Result<Trial, SessionError> {
        let path = self.trial_path(entry, at)?;
        let bytes = files::read_bounded(&path, self.max_trial_bytes(), TRIAL_BOUND)?;
        if let Some(expected) = entry.sha256 {
            let actual = Sha256::of(&bytes);
            if actual != expected {
                return Err(SessionError::ShaMismatch {
                    file: path,
                    manifest: self.manifest_path.clone(),
                    line: at.sha256,
                    expected,
                    actual,
                });
            }
        }
        let trial = table::parse_csv(&bytes, self.manifest.rate_hz, &path)?;
        if let Some(p) = &entry.perturbation {
            // The onset has the control clock's resolution, so it may fall after the
            // last row but within its sample period.
            let end_s = trial.end_s();
            if !(0.0..end_s + 1.0 / self.manifest.rate_hz).contains(&p.onset_s) {
                return Err(SessionError::PerturbationOutsideTrial {
                    file: self.manifest_path.clone(),
                    line: at.onset,
                    field: "trial.perturbation.onset_s".into(),
                    onset_s: p.onset_s,
                    end_s,
                });
            }
        }
        Ok(trial)
    }
}
