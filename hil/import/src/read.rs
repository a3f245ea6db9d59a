//! Reading a log file whole and handing it to the reader of its format: a `.mat`
//! (level 5 or v7.3) by extension or content, a CSV/TSV otherwise.

use std::path::Path;

use crate::error::ImportError;
use crate::log::Log;
use crate::map::CsvOptions;

/// Whether `path` is read as a MAT-file: its extension, or its first bytes.
fn is_mat(path: &Path, head: &[u8]) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    ext.as_deref() == Some("mat") || head.starts_with(b"MATLAB")
}

/// The largest log `import` reads, bytes: 16 GiB.
pub const MAX_LOG_BYTES: u64 = 16 << 30;

/// Reads a `.mat` (by extension or content) or a CSV/TSV file.
pub(crate) fn read_log(path: &Path, csv: &CsvOptions) -> Result<Log, ImportError> {
    // A log is read whole; 16 GiB is four hours of a 4 kHz 12-channel CSV.
    let bytes =
        rigtwin_session::files::read_regular(path, MAX_LOG_BYTES).map_err(|e| ImportError::Io {
            file: path.to_path_buf(),
            source: e,
        })?;
    if is_mat(path, &bytes) {
        if crate::mat73::is_v73(&bytes) {
            crate::mat73::read(path, bytes)
        } else {
            crate::mat::read(path, &bytes)
        }
    } else {
        crate::csvlog::read(path, &bytes, csv)
    }
}
