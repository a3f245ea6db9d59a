//! Output that may fail. `println!` panics when standard output cannot be written — a
//! full disk behind `> report.txt`, a device such as `/dev/full` — and a panic is exit
//! 101 with a backtrace where the user needs a sentence. The macros here write through
//! the locked stream and turn a failed write into an [`OutputError`] that the command
//! returns with `?`, so it ends with `error: writing to standard output: …` and exit 1.
//! Whatever the command recorded before is already on disk (sessions are written trial
//! by trial and renamed into place), so nothing is lost.
//!
//! A reader that went away (`rigtwin diagnose … | head`) is the one failure that is not
//! an error: [`OutputError::is_broken_pipe`] lets `main` exit quietly, as a filter killed
//! by SIGPIPE would.

use std::io;

/// A write to standard output or standard error failed.
#[derive(Debug, thiserror::Error)]
#[error("writing to standard {stream}")]
pub struct OutputError {
    /// `output` or `error`.
    pub stream: &'static str,
    /// What the operating system said.
    #[source]
    pub source: io::Error,
}

impl OutputError {
    /// The reader of a pipe closed its end: nobody is left to tell.
    #[must_use]
    pub fn is_broken_pipe(&self) -> bool {
        self.source.kind() == io::ErrorKind::BrokenPipe
    }
}

/// Wraps the result of a write to the stream named `stream`.
///
/// # Errors
/// The write's own error, named.
pub fn checked(stream: &'static str, written: io::Result<()>) -> Result<(), OutputError> {
    written.map_err(|source| OutputError { stream, source })
}

/// Flushes standard output, so that text held in its buffer meets the device (and its
/// error) before the command reports success.
///
/// # Errors
/// The flush's error, named.
pub fn flush() -> Result<(), OutputError> {
    use io::Write as _;
    checked("output", io::stdout().lock().flush())
}

/// `println!` that returns a failed write as an error (`?` inside).
macro_rules! outln {
    ($($t:tt)*) => {
        $crate::cli::out::checked("output", {
            use std::io::Write as _;
            writeln!(std::io::stdout().lock(), $($t)*)
        })?
    };
}

/// `print!` that returns a failed write as an error (`?` inside).
macro_rules! out {
    ($($t:tt)*) => {
        $crate::cli::out::checked("output", {
            use std::io::Write as _;
            write!(std::io::stdout().lock(), $($t)*)
        })?
    };
}

/// `eprintln!` that returns a failed write as an error (`?` inside).
macro_rules! errln {
    ($($t:tt)*) => {
        $crate::cli::out::checked("error", {
            use std::io::Write as _;
            writeln!(std::io::stderr().lock(), $($t)*)
        })?
    };
}
