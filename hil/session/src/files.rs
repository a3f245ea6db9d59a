//! Reading the files a session names, with bounds: only regular files (a FIFO named
//! `session.toml` would block a reader forever, `/dev/zero` would never end), never more
//! than a stated number of bytes (a sparse 20 GiB file must not be read into memory to be
//! refused), and trial files only inside the session directory.

use std::io::Read as _;
use std::path::{Path, PathBuf};

use crate::SessionError;

/// The most bytes a manifest may have: 64 MiB, a quarter of a million `[[trial]]` entries
/// of the writer's size (about 250 bytes each).
pub const MAX_MANIFEST_BYTES: u64 = 64 << 20;

/// The longest trial a reader reads, s: an hour.
pub const MAX_TRIAL_S: f64 = 3600.0;

/// The widest row a reader expects, bytes: 32 columns of 16 characters.
pub const MAX_ROW_BYTES: f64 = 512.0;

/// The most bytes a configuration file (a protocol, a model, a map) may have: 1 MiB,
/// a hundred times the largest shipped one.
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// The most bytes any trial file may have, whatever its rate: 8 GiB.
pub const MAX_TRIAL_BYTES: u64 = 8 << 30;

/// The most bytes a trial table at `rate_hz` may have: [`MAX_TRIAL_S`] of rows of
/// [`MAX_ROW_BYTES`], at most [`MAX_TRIAL_BYTES`] (1.8 GB at 1 kHz).
#[must_use]
pub fn max_trial_bytes(rate_hz: f64) -> u64 {
    let bytes = rate_hz * MAX_TRIAL_S * MAX_ROW_BYTES;
    if bytes.is_finite() && bytes < MAX_TRIAL_BYTES as f64 {
        // Finite, non-negative and below 2^33: the conversion is exact enough.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let b = bytes.ceil() as u64;
        b
    } else {
        MAX_TRIAL_BYTES
    }
}

/// What a path is, for an error, when it is not a regular file.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if t.is_fifo() {
            return "FIFO";
        }
        if t.is_socket() {
            return "socket";
        }
        if t.is_block_device() || t.is_char_device() {
            return "device";
        }
    }
    "special file"
}

/// Checks that `path` (followed through links) is a regular file of at most `limit`
/// bytes, and returns its size. `why` says where the limit comes from.
///
/// # Errors
/// [`SessionError::Io`] (including a missing file), [`SessionError::NotARegularFile`],
/// [`SessionError::TooLarge`].
pub fn check_regular(path: &Path, limit: u64, why: &str) -> Result<u64, SessionError> {
    let meta = std::fs::metadata(path).map_err(|e| SessionError::io(path, e))?;
    if !meta.is_file() {
        return Err(SessionError::NotARegularFile {
            file: path.to_path_buf(),
            kind: kind_of(&meta),
        });
    }
    if meta.len() > limit {
        return Err(SessionError::TooLarge {
            file: path.to_path_buf(),
            bytes: meta.len(),
            limit,
            why: why.to_owned(),
        });
    }
    Ok(meta.len())
}

/// Reads a regular file of at most `limit` bytes. A file that grows while it is read is
/// cut at `limit + 1` bytes and refused.
///
/// # Errors
/// As [`check_regular`].
pub fn read_bounded(path: &Path, limit: u64, why: &str) -> Result<Vec<u8>, SessionError> {
    let size = check_regular(path, limit, why)?;
    let file = std::fs::File::open(path).map_err(|e| SessionError::io(path, e))?;
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| SessionError::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(SessionError::TooLarge {
            file: path.to_path_buf(),
            bytes: bytes.len() as u64,
            limit,
            why: why.to_owned(),
        });
    }
    Ok(bytes)
}

/// Where `path` leads if that is outside `resolved_dir` (a directory already resolved
/// through links), or `None` when it stays inside or cannot be resolved (a missing file
/// is reported elsewhere).
#[must_use]
pub fn escapes(resolved_dir: &Path, path: &Path) -> Option<PathBuf> {
    let resolved = std::fs::canonicalize(path).ok()?;
    (!resolved.starts_with(resolved_dir)).then_some(resolved)
}

/// [`read_bounded`] for readers with errors of their own (protocols, model files, map
/// files, lab logs): the refusal is an [`std::io::Error`] whose message says what the
/// file is or how large, for the caller to wrap with the file's name.
///
/// # Errors
/// The operating system's error; `InvalidInput` for a path that is not a regular file;
/// `FileTooLarge` past `limit`.
pub fn read_regular(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    read_bounded(path, limit, "this reader reads").map_err(|e| match e {
        SessionError::Io { source, .. } => source,
        SessionError::NotARegularFile { kind, .. } => std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("is a {kind}, not a regular file"),
        ),
        SessionError::TooLarge { bytes, limit, .. } => std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("{bytes} bytes is more than the {limit} bytes this reader reads"),
        ),
        other => std::io::Error::other(other.to_string()),
    })
}

/// [`read_regular`] as UTF-8 text.
///
/// # Errors
/// As [`read_regular`]; `InvalidData` for text that is not UTF-8.
pub fn read_regular_text(path: &Path, limit: u64) -> std::io::Result<String> {
    utf8(read_regular(path, limit)?)
}

/// `bytes` as text; invalid UTF-8 is an `InvalidData` error that names the line and
/// column of the first bad byte.
///
/// # Errors
/// `InvalidData`, located.
pub fn utf8(bytes: Vec<u8>) -> std::io::Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let (line, column) = line_column(bytes, at);
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "line {line}, column {column}: not UTF-8 text (byte 0x{:02x})",
                bytes[at]
            ),
        )
    })
}

/// The 1-based line and column (in characters) of byte offset `at` in `text`: lines end
/// at `\n`, so CRLF text counts as LF text does. For errors that point into a file.
#[must_use]
pub fn line_column(text: &[u8], at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    let column = 1 + String::from_utf8_lossy(&before[line_start..])
        .chars()
        .count();
    (line, column)
}
