//! Everything that can go wrong turning a log into a session. Every variant about the
//! map names the map file, its 1-based line and the key path (`channels.x_m.var`);
//! every variant about a log names the log file and the variable or column (and, for
//! text logs, the line), so that a person can go straight to the fault.

use std::fmt;
use std::path::PathBuf;

/// Where in the map file a fault was found: file, 1-based line, key path.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MapAt {
    /// The map file.
    pub map: PathBuf,
    /// 1-based line of the key.
    pub line: usize,
    /// The key path, such as `channels.x_m` or `trials.marker.var`.
    pub key: String,
}

impl fmt::Display for MapAt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "map {}:{}, key `{}`",
            self.map.display(),
            self.line,
            self.key
        )
    }
}

/// Where in a log a sample sits: its 1-based sample number and, for text logs, the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleAt {
    /// 1-based sample (row) number within the variable.
    pub sample: usize,
    /// 1-based line of the text file, for CSV/TSV logs.
    pub line: Option<usize>,
}

impl fmt::Display for SampleAt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "line {l} (sample {})", self.sample),
            None => write!(f, "sample {}", self.sample),
        }
    }
}

/// An error reading a log or a map, or writing the session.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImportError {
    /// The operating system refused a read or write.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file or directory concerned.
        file: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },

    /// The map is not valid TOML, or a value has the wrong type.
    #[error("{}:{line}:{column}: key `{key}`: {message}", map.display())]
    MapSyntax {
        /// The map file.
        map: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The key path at the fault (empty for syntax outside any key).
        key: String,
        /// What the TOML parser said.
        message: String,
    },

    /// A required map key is absent.
    #[error("{}:{line}: missing key `{key}`", map.display())]
    MapMissingKey {
        /// The map file.
        map: PathBuf,
        /// Line of the table that should hold the key.
        line: usize,
        /// The missing key path.
        key: String,
    },

    /// A map key this crate does not define (a misspelt key must not be ignored).
    #[error("{}:{line}: unknown key `{key}` ({allowed})", map.display())]
    MapUnknownKey {
        /// The map file.
        map: PathBuf,
        /// Line of the key.
        line: usize,
        /// The key path.
        key: String,
        /// The keys allowed there.
        allowed: String,
    },

    /// A map value has the right type but a value that cannot be used.
    #[error("{}:{line}: key `{key}`: {message}", map.display())]
    MapValue {
        /// The map file.
        map: PathBuf,
        /// Line of the key.
        line: usize,
        /// The key path.
        key: String,
        /// What is wrong.
        message: String,
    },

    /// A MATLAB v7.3 MAT-file (HDF5 inside) whose HDF5 part cannot be read: truncated
    /// or corrupt (the HDF5 reader's own message follows), or an array whose HDF5
    /// element type does not fit its `MATLAB_class`.
    #[error("{}: MATLAB v7.3 (HDF5) MAT-file: {what}: {message}", file.display())]
    MatV73Corrupt {
        /// The log file.
        file: PathBuf,
        /// The variable being read (``variable `s.pos` ``), or `HDF5 file` for a fault
        /// outside any variable (the superblock, the root group).
        what: String,
        /// What is wrong.
        message: String,
    },

    /// A `.mat` file that is neither a level-5 nor a v7.3 MAT-file, or a level-5 one
    /// that is truncated or corrupt.
    #[error("{}: byte {offset}: {what}: {message}", file.display())]
    MatCorrupt {
        /// The log file.
        file: PathBuf,
        /// Byte offset of the fault in the file (of the enclosing compressed element for
        /// faults inside one).
        offset: usize,
        /// The variable being read, or `header`.
        what: String,
        /// What is wrong.
        message: String,
    },

    /// The CSV layer could not split a text log (bad UTF-8, unbalanced quotes, a row
    /// with more or fewer fields than the first).
    #[error("{}:{line}: {message}", file.display())]
    Csv {
        /// The log file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },

    /// A field of a text log column that the map uses is not a number.
    #[error("{}:{line}: column `{column}`: {text:?} is not a number ({at})", file.display())]
    BadNumber {
        /// The log file.
        file: PathBuf,
        /// 1-based line of the field.
        line: usize,
        /// The column.
        column: String,
        /// The field's text.
        text: String,
        /// The map key that uses the column.
        at: MapAt,
    },

    /// The map names a variable or column the file does not have.
    #[error("{}: no variable `{var}` ({at}); the file has: {}", file.display(), available.join(", "))]
    MissingVariable {
        /// The log file.
        file: PathBuf,
        /// The name the map gives.
        var: String,
        /// The map key.
        at: MapAt,
        /// The names the file has.
        available: Vec<String>,
    },

    /// A variable's shape or class cannot give one channel (a 3×N matrix without
    /// `column`, a column out of range, a char array, a struct).
    #[error("{}: variable `{var}` ({shape}): {message} ({at})", file.display())]
    WrongShape {
        /// The log file.
        file: PathBuf,
        /// The variable.
        var: String,
        /// Its shape, `3×1000`.
        shape: String,
        /// What is wrong.
        message: String,
        /// The map key.
        at: MapAt,
    },

    /// Two channels of one file have different numbers of samples.
    #[error("{}: variable `{var}` has {len} samples but `{other_var}` ({other_key}) has {other_len} ({at})", file.display())]
    LengthMismatch {
        /// The log file.
        file: PathBuf,
        /// The variable.
        var: String,
        /// Its length.
        len: usize,
        /// The map key of `var`.
        at: MapAt,
        /// The variable it disagrees with (the first one read).
        other_var: String,
        /// Its map key path.
        other_key: String,
        /// Its length.
        other_len: usize,
    },

    /// A sample is `NaN` or infinite.
    #[error("{}: variable `{var}`: {sample}: {value} is not finite ({at})", file.display())]
    NonFinite {
        /// The log file.
        file: PathBuf,
        /// The variable.
        var: String,
        /// Where the sample sits.
        sample: SampleAt,
        /// The value.
        value: f64,
        /// The map key.
        at: MapAt,
    },

    /// The time variable is not uniformly sampled (or does not increase).
    #[error("{}: variable `{var}`: {sample}: time {found_s} s, expected {expected_s} s on a uniform clock ({at})", file.display())]
    NonUniformTime {
        /// The log file.
        file: PathBuf,
        /// The time variable.
        var: String,
        /// Where the first bad sample sits.
        sample: SampleAt,
        /// The time on a uniform clock from the first to the last sample, s.
        expected_s: f64,
        /// The time in the file, s.
        found_s: f64,
        /// The map key (`time.var`).
        at: MapAt,
    },

    /// Two input files imply different sampling rates.
    #[error("{}: sampled at {rate_hz} Hz, but {} at {first_rate_hz} Hz ({at})", file.display(), first.display())]
    RateMismatch {
        /// The later file.
        file: PathBuf,
        /// Its rate, Hz.
        rate_hz: f64,
        /// The first file.
        first: PathBuf,
        /// Its rate, Hz.
        first_rate_hz: f64,
        /// The map key (`time.var`).
        at: MapAt,
    },

    /// The marker never rises above its threshold, so no trial starts.
    #[error("{}: marker `{var}` never rises above {above} ({at})", file.display())]
    MarkerNeverRises {
        /// The log file.
        file: PathBuf,
        /// The marker variable.
        var: String,
        /// The threshold.
        above: f64,
        /// The map key (`trials.marker`).
        at: MapAt,
    },

    /// The threshold cut found no movement start.
    #[error("{}: channel `{channel}` never moves faster than {speed_above} /s ({at})", file.display())]
    NoMovement {
        /// The log file.
        file: PathBuf,
        /// The session channel.
        channel: String,
        /// The speed threshold, in the channel's unit per second.
        speed_above: f64,
        /// The map key (`trials.threshold`).
        at: MapAt,
    },

    /// A trial would start before the log or run past its end.
    #[error("{}: trial {trial} spans {start_s} s to {end_s} s, outside the log (0 to {log_end_s} s) ({at})", file.display())]
    TrialOutsideLog {
        /// The log file.
        file: PathBuf,
        /// 1-based trial number within the file.
        trial: usize,
        /// Start of the trial on the log's clock, s.
        start_s: f64,
        /// End of the trial on the log's clock, s.
        end_s: f64,
        /// Time of the log's last sample, s.
        log_end_s: f64,
        /// The map key.
        at: MapAt,
    },

    /// A session column the format requires has no source and may not be zero.
    #[error("{}:{}: key `{}`: session column `{column}` is required and not mapped: {reason}", at.map.display(), at.line, at.key)]
    MissingChannel {
        /// The session column.
        column: String,
        /// Why it cannot be written as zero.
        reason: String,
        /// The map key that should give it (`channels.x_m`).
        at: MapAt,
    },

    /// `import` was given no file.
    #[error("no input file given")]
    NoInput,

    /// The output directory exists and is not empty.
    #[error("{}: the output directory exists and is not empty; choose a new one", dir.display())]
    OutputNotEmpty {
        /// The output directory.
        dir: PathBuf,
    },

    /// Writing or reading back the session failed.
    #[error(transparent)]
    Session(#[from] rigtwin_session::SessionError),
}
