//! Everything that can be wrong with a session on disk, each naming the file, the line
//! (1-based) and the field (manifest key path such as `trial.perturbation.onset_s`, or a
//! CSV column name) so that a person can go straight to the fault.

use std::path::PathBuf;

/// An error reading or writing a session. Every variant about file content names the
/// `file`, the 1-based `line` and the `field` (a manifest key path or a CSV column).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// The operating system refused a read or write.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file or directory concerned.
        file: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },

    /// The manifest is not valid TOML, or a value has the wrong type.
    #[error("{}:{line}:{column}: field `{field}`: {message}", file.display())]
    Toml {
        /// The manifest.
        file: PathBuf,
        /// 1-based line of the fault.
        line: usize,
        /// 1-based column (in characters) of the fault.
        column: usize,
        /// The key path at the fault (`device.mass_kg`), empty when the fault is syntax
        /// outside any key.
        field: String,
        /// What the TOML parser said.
        message: String,
    },

    /// A required manifest key is absent.
    #[error("{}:{line}: missing key `{field}`", file.display())]
    MissingKey {
        /// The manifest (or in-progress trial sidecar).
        file: PathBuf,
        /// Line of the table that should hold the key.
        line: usize,
        /// The key path that is missing.
        field: String,
    },

    /// A manifest key that version 1 does not define in a table that does not accept
    /// additions (a typo would otherwise silently drop a value).
    #[error("{}:{line}: unknown key `{field}` ({message})", file.display())]
    UnknownKey {
        /// The manifest.
        file: PathBuf,
        /// Line of the key.
        line: usize,
        /// The key path.
        field: String,
        /// The keys that are allowed there.
        message: String,
    },

    /// `format` is not `"rig-session"`.
    #[error("{}:{line}: field `{field}`: expected \"rig-session\", found {found:?}", file.display())]
    WrongFormat {
        /// The manifest.
        file: PathBuf,
        /// Line of the key.
        line: usize,
        /// Always `format`.
        field: String,
        /// The value found.
        found: String,
    },

    /// `format_version` is not a version this reader knows (1).
    #[error("{}:{line}: field `{field}`: unsupported format version {found} (this reader knows 1)", file.display())]
    UnsupportedVersion {
        /// The manifest.
        file: PathBuf,
        /// Line of the key.
        line: usize,
        /// Always `format_version`.
        field: String,
        /// The version found.
        found: i64,
    },

    /// A manifest value has the right type but a value the format forbids.
    #[error("{}:{line}: field `{field}`: {message}", file.display())]
    InvalidValue {
        /// The manifest.
        file: PathBuf,
        /// Line of the key.
        line: usize,
        /// The key path.
        field: String,
        /// What is wrong.
        message: String,
    },

    /// Two `[[trial]]` entries share an `id`.
    #[error("{}:{line}: field `{field}`: duplicate trial id {id} (first at line {first_line})", file.display())]
    DuplicateTrialId {
        /// The manifest.
        file: PathBuf,
        /// Line of the second `id`.
        line: usize,
        /// Always `trial.id`.
        field: String,
        /// The repeated id.
        id: u32,
        /// Line of the first `id`.
        first_line: usize,
    },

    /// Two `[[trial]]` entries name the same `file`.
    #[error("{}:{line}: field `{field}`: trial file {path:?} listed twice", file.display())]
    DuplicateTrialFile {
        /// The manifest.
        file: PathBuf,
        /// Line of the second `file`.
        line: usize,
        /// Always `trial.file`.
        field: String,
        /// The repeated path.
        path: String,
    },

    /// A trial's `file` does not exist.
    #[error("{}:{line}: field `{field}`: trial file {} does not exist", file.display(), missing.display())]
    TrialFileMissing {
        /// The manifest.
        file: PathBuf,
        /// Line of the `file` key.
        line: usize,
        /// Always `trial.file`.
        field: String,
        /// The path that is missing.
        missing: PathBuf,
    },

    /// A trial file's SHA-256 differs from the manifest's `sha256`.
    #[error("{}: content does not match field `trial.sha256` at {}:{line}: expected {expected}, found {actual}", file.display(), manifest.display())]
    ShaMismatch {
        /// The trial file.
        file: PathBuf,
        /// The manifest.
        manifest: PathBuf,
        /// Line of the `trial.sha256` key in the manifest.
        line: usize,
        /// Digest in the manifest.
        expected: crate::Sha256,
        /// Digest of the file.
        actual: crate::Sha256,
    },

    /// A perturbation's onset is not within the trial's time span.
    #[error("{}:{line}: field `{field}`: onset {onset_s} s is outside the trial (0 to {end_s} s)", file.display())]
    PerturbationOutsideTrial {
        /// The manifest.
        file: PathBuf,
        /// Line of the `onset_s` key.
        line: usize,
        /// Always `trial.perturbation.onset_s`.
        field: String,
        /// The onset, s.
        onset_s: f64,
        /// Time of the trial's last sample, s.
        end_s: f64,
    },

    /// The CSV layer could not split the file (bad UTF-8, unbalanced quotes).
    #[error("{}:{line}: {message}", file.display())]
    Csv {
        /// The trial file.
        file: PathBuf,
        /// Line of the fault.
        line: usize,
        /// What the CSV reader said.
        message: String,
    },

    /// A trial file has no header line.
    #[error("{}:{line}: no header line", file.display())]
    MissingHeader {
        /// The trial file.
        file: PathBuf,
        /// Line where the header should be.
        line: usize,
    },

    /// A trial file has a header but no sample.
    #[error("{}:{line}: the table has no samples", file.display())]
    NoSamples {
        /// The trial file.
        file: PathBuf,
        /// Line of the header.
        line: usize,
    },

    /// A required column is absent from the header.
    #[error("{}:{line}: missing required column `{column}`", file.display())]
    MissingColumn {
        /// The trial file.
        file: PathBuf,
        /// Line of the header.
        line: usize,
        /// The column.
        column: String,
    },

    /// A column name appears twice in the header (or is empty).
    #[error("{}:{line}: column `{column}` {message}", file.display())]
    BadColumnName {
        /// The trial file.
        file: PathBuf,
        /// Line of the header.
        line: usize,
        /// The column.
        column: String,
        /// What is wrong with it.
        message: String,
    },

    /// A row has more or fewer fields than the header.
    #[error("{}:{line}: {found} fields, the header has {expected}", file.display())]
    FieldCount {
        /// The trial file.
        file: PathBuf,
        /// Line of the row.
        line: usize,
        /// Number of header columns.
        expected: usize,
        /// Number of fields in the row.
        found: usize,
    },

    /// A field is empty.
    #[error("{}:{line}: column `{column}`: empty field", file.display())]
    EmptyField {
        /// The trial file.
        file: PathBuf,
        /// Line of the row.
        line: usize,
        /// The column.
        column: String,
    },

    /// A field is not a number.
    #[error("{}:{line}: column `{column}`: {text:?} is not a number", file.display())]
    BadNumber {
        /// The trial file.
        file: PathBuf,
        /// Line of the row.
        line: usize,
        /// The column.
        column: String,
        /// The field's text.
        text: String,
    },

    /// A field is `NaN` or infinite.
    #[error("{}:{line}: column `{column}`: {text:?} is not finite", file.display())]
    NonFinite {
        /// The trial file.
        file: PathBuf,
        /// Line of the row.
        line: usize,
        /// The column.
        column: String,
        /// The field's text.
        text: String,
    },

    /// `t_s` does not increase.
    #[error("{}:{line}: column `{column}`: time {found_s} s does not follow {previous_s} s", file.display())]
    NonMonotonicTime {
        /// The trial file.
        file: PathBuf,
        /// Line of the row.
        line: usize,
        /// Always `t_s`.
        column: String,
        /// Time on the previous row, s.
        previous_s: f64,
        /// Time on this row, s.
        found_s: f64,
    },

    /// `t_s` is not `row_index / rate_hz` (a gap, a jitter, or not starting at 0).
    #[error("{}:{line}: column `{column}`: time {found_s} s, expected {expected_s} s at the manifest's rate (a missing or shifted sample)", file.display())]
    NonUniformTime {
        /// The trial file.
        file: PathBuf,
        /// Line of the row.
        line: usize,
        /// Always `t_s`.
        column: String,
        /// `row_index / rate_hz`, s.
        expected_s: f64,
        /// The time on the row, s.
        found_s: f64,
    },

    /// A file the session names is not a regular file: a FIFO, a device or a socket
    /// would block a reader or never end.
    #[error("{}: is a {kind}, not a regular file", file.display())]
    NotARegularFile {
        /// The path.
        file: PathBuf,
        /// What it is (`FIFO`, `directory`, `device`, `socket`).
        kind: &'static str,
    },

    /// A file is larger than a reader reads: the bound is stated so that no file (a
    /// sparse image, a mistaken path) can make a reader allocate without limit.
    #[error("{}: {bytes} bytes is more than the {limit} bytes {why}", file.display())]
    TooLarge {
        /// The file.
        file: PathBuf,
        /// Its size, bytes.
        bytes: u64,
        /// The bound, bytes.
        limit: u64,
        /// Where the bound comes from.
        why: String,
    },

    /// A trial's `file` resolves (through a symbolic link) to a place outside the
    /// session directory.
    #[error("{}:{line}: field `{field}`: trial file {} resolves to {}, outside the session directory", file.display(), path.display(), resolved.display())]
    OutsideSession {
        /// The manifest.
        file: PathBuf,
        /// Line of the `file` key.
        line: usize,
        /// Always `trial.file`.
        field: String,
        /// The trial file as listed.
        path: PathBuf,
        /// Where it leads.
        resolved: PathBuf,
    },

    /// The writer was asked to do something that would produce a file that breaks the
    /// format (non-finite sample, columns of different lengths, a trial id used twice).
    #[error("{}: {message}", file.display())]
    InvalidWrite {
        /// The file the writer was producing.
        file: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl SessionError {
    /// The file the error is about.
    #[must_use]
    pub fn file(&self) -> &std::path::Path {
        match self {
            SessionError::Io { file, .. }
            | SessionError::Toml { file, .. }
            | SessionError::MissingKey { file, .. }
            | SessionError::UnknownKey { file, .. }
            | SessionError::WrongFormat { file, .. }
            | SessionError::UnsupportedVersion { file, .. }
            | SessionError::InvalidValue { file, .. }
            | SessionError::DuplicateTrialId { file, .. }
            | SessionError::DuplicateTrialFile { file, .. }
            | SessionError::TrialFileMissing { file, .. }
            | SessionError::ShaMismatch { file, .. }
            | SessionError::PerturbationOutsideTrial { file, .. }
            | SessionError::Csv { file, .. }
            | SessionError::MissingHeader { file, .. }
            | SessionError::NoSamples { file, .. }
            | SessionError::MissingColumn { file, .. }
            | SessionError::BadColumnName { file, .. }
            | SessionError::FieldCount { file, .. }
            | SessionError::EmptyField { file, .. }
            | SessionError::BadNumber { file, .. }
            | SessionError::NonFinite { file, .. }
            | SessionError::NonMonotonicTime { file, .. }
            | SessionError::NonUniformTime { file, .. }
            | SessionError::NotARegularFile { file, .. }
            | SessionError::TooLarge { file, .. }
            | SessionError::OutsideSession { file, .. }
            | SessionError::InvalidWrite { file, .. } => file,
        }
    }

    /// The 1-based line the error is about, where there is one.
    #[must_use]
    pub fn line(&self) -> Option<usize> {
        match self {
            SessionError::Io { .. }
            | SessionError::InvalidWrite { .. }
            | SessionError::NotARegularFile { .. }
            | SessionError::TooLarge { .. } => None,
            SessionError::Toml { line, .. }
            | SessionError::MissingKey { line, .. }
            | SessionError::UnknownKey { line, .. }
            | SessionError::WrongFormat { line, .. }
            | SessionError::UnsupportedVersion { line, .. }
            | SessionError::InvalidValue { line, .. }
            | SessionError::DuplicateTrialId { line, .. }
            | SessionError::DuplicateTrialFile { line, .. }
            | SessionError::TrialFileMissing { line, .. }
            | SessionError::OutsideSession { line, .. }
            | SessionError::ShaMismatch { line, .. }
            | SessionError::PerturbationOutsideTrial { line, .. }
            | SessionError::Csv { line, .. }
            | SessionError::MissingHeader { line, .. }
            | SessionError::NoSamples { line, .. }
            | SessionError::MissingColumn { line, .. }
            | SessionError::BadColumnName { line, .. }
            | SessionError::FieldCount { line, .. }
            | SessionError::EmptyField { line, .. }
            | SessionError::BadNumber { line, .. }
            | SessionError::NonFinite { line, .. }
            | SessionError::NonMonotonicTime { line, .. }
            | SessionError::NonUniformTime { line, .. } => Some(*line),
        }
    }

    pub(crate) fn io(file: impl Into<PathBuf>, source: std::io::Error) -> SessionError {
        SessionError::Io {
            file: file.into(),
            source,
        }
    }
}
