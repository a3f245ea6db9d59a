//! rigtwin-import — a lab's measured log in, a rigtwin session out.
//!
//! A lab records its rig as one continuous log: a MATLAB `.mat` file (often a struct of
//! arrays, as Simulink writes) or a CSV/TSV text file, in the lab's own units and names.
//! This crate turns such logs into a session of the recording format
//! (`shared/specs/recording-format.md`, read and written by `rigtwin-session`) by
//! following a *map file*: which variable is which session column and with what scale
//! into SI units, how the log's clock is known, how the log is cut into trials, what
//! the device is, and how a trial's perturbation is known.
//!
//! - [`inspect`] lists what a file holds ([`Inventory`]: each variable or column with
//!   its shape, element type and, for a uniform time vector, its rate), so that a
//!   person can write the map.
//! - [`Map::read`] reads and checks a map.
//! - [`import`] reads the logs, checks everything, cuts the trials and writes the session
//!   ([`Imported`] says what was written).
//!
//! Every error ([`ImportError`]) names the file, the line (text files and the map) or
//! the variable (`.mat` files), and the map key concerned; no input makes it panic.
//!
//! # Inputs
//!
//! **MATLAB level-5 MAT-files**, as MATLAB's `save` writes by default (`-v7`,
//! compressed) or with `-v6` (uncompressed), little- or big-endian: arrays of class
//! double, single, every integer class and logical, and structs of them, nested to any
//! depth. A struct's fields are named `s.field` (`log.signals.values`); the elements of
//! a struct array are `s(k).field` (1-based). Char arrays, cells, sparse and complex
//! arrays and objects are listed by [`inspect`] but cannot be channels. A file is read
//! as a MAT-file when its name ends in `.mat` or it starts with `MATLAB`.
//!
//! **MATLAB v7.3 MAT-files** (`save(..., '-v7.3')`, needed for variables over 2 GB):
//! an HDF5 file behind MATLAB's 512-byte header, told by that header's text
//! (`MATLAB 7.3 MAT-file`) or by the HDF5 signature at byte 512 (or at byte 0, an HDF5
//! file without the header), and read with a pure-Rust HDF5 reader (`hdf5-pure`; no C
//! library). The same variables as level 5, under the same names: each top-level
//! variable with the class of its `MATLAB_class` attribute and its MATLAB shape (HDF5
//! stores the dimensions reversed, an N×1 vector as 1×N; they are turned back), chunked
//! and gzip-compressed or not; structs nested to any depth as `s.field`; struct arrays
//! (fields stored as object references) as `s(k).field`; empty arrays (`MATLAB_empty`)
//! with their shape and no samples. Top-level variables are listed sorted by name (HDF5
//! keeps no file order), a struct's fields in the order of its `MATLAB_fields`. Char
//! arrays, cells, complex arrays and objects (`string`, `datetime`, classes) are listed
//! but cannot be channels. A truncated or corrupt file is
//! [`ImportError::MatV73Corrupt`], naming the file and the variable.
//!
//! **Text logs** (any other file): one sample per row; the delimiter is comma, tab or
//! semicolon, sniffed from the first line (or set by `[csv] delimiter`); the first row is
//! a header unless every field of it is a number (or as `[csv] header` says); without a
//! header the columns are `col1`, `col2`, …. Lines starting with `#` and blank lines are
//! skipped; CRLF line ends are fine, and errors give the file's own line numbers. Fields
//! are trimmed and may be double-quoted (a header `"x, mm"`); a field that is not a
//! number is an error only when the map uses its column.
//!
//! **Variables and columns.** A map names a source by `var` (a MATLAB variable, or a
//! CSV column name). A vector (1×N, N×1, or 1×1×N as Simulink writes) is one channel. A
//! matrix holds one channel per column when it is taller than wide (N×k, and when
//! square) and one per row when it is wider than tall (k×N); `column = j` (1-based, as
//! in MATLAB) picks one, and is required for a matrix. Every channel of one log must
//! have the same number of samples; `NaN` and infinite samples are errors.
//!
//! **Not supported:** sparse arrays, complex arrays, and the contents of cells and
//! objects (`string`, `datetime`, classes), in level-5 and v7.3 files alike: they are
//! listed by [`inspect`], not channels.
//!
//! # The map file
//!
//! TOML. Every key is listed here; a key that is not is an error
//! ([`ImportError::MapUnknownKey`]), so a misspelt optional key is never silently
//! ignored. Absent optional keys take the defaults stated.
//!
//! ```toml
//! # How a lab's log becomes a rigtwin session.
//! created = "2026-11-21T10:00:00Z"  # optional; default "1970-01-01T00:00:00Z"
//! axes = ["x"]                      # optional; ["x"], ["y"] or ["x", "y"] (default)
//!
//! [time]                            # the log's clock: exactly one of
//! rate_hz = 1000.0                  # ... a rate, Hz (the first sample is at 0 s)
//! # var = "t"                       # ... or a time variable (s after `scale`), which
//! # scale = 1e-3                    #     must be uniform; `column` as for channels
//!
//! [csv]                             # optional; text logs only
//! delimiter = ","                   # ",", "\t" (or "tab"), ";", " ", "|"; default sniffed
//! header = true                     # default: a header unless the first row is numbers
//!
//! [channels]                        # session column = source
//! x_m      = { var = "pos", scale = 1e-3, unit = "mm" }
//! ref_x_m  = { var = "ref", scale = 1e-3, unit = "mm" }
//! cmd_fx_n = { var = "data.u", column = 2, scale = 12.5, offset = 0.0, unit = "V" }
//!
//! [device]                          # what the file does not hold
//! kind = "position-servo"           # required, free text, into session.toml
//! mass_kg = [2.0, 2.0]              # required: admittance (moving) mass per axis, > 0
//! damping_n_s_per_m = [0.0, 0.0]    # required: admittance damping per axis, ≥ 0
//! handle_mass_kg = 0.35             # optional
//! workspace_half_width_m = 0.15     # optional
//! force_sensor = false              # optional, default true
//!
//! [subject]                         # optional
//! id = "axis-1"                     # default: the first log's file stem
//! shoulder_m = [0.0, -0.425]        # default [0, 0]
//! upper_arm_m = 0.31                # optional, as are forearm_m and body_mass_kg
//!
//! [trials]
//! cut = "marker"                    # "whole", "marker", "onsets" or "threshold"
//! marker = { var = "trig", above = 0.5 }
//! kind = "reach"                    # default "reach"
//!
//! [perturbation]                    # optional
//! from = "channel"
//! above_n = 0.5
//! ```
//!
//! **Top level.** `created`: the session's `created`, a string or TOML date-time,
//! copied as written (default `1970-01-01T00:00:00Z`, so output never depends on the
//! clock). `axes`: which axes the rig has (see *One-axis rigs*).
//!
//! **`[time]`** (required). `rate_hz`: the log's sampling rate, Hz, > 0. Or `var`: a
//! time variable or column, in seconds after multiplying by `scale` (optional, > 0,
//! default 1), with `column` for a matrix; it must be uniform: every sample within 10⁻⁶
//! of a period of the line through the first and last (for text logs, plus half the
//! last decimal written, at most a quarter period), else
//! [`ImportError::NonUniformTime`] names the sample. The rate is then
//! `(N − 1) / (t_last − t_first)`, rounded to the millihertz when that changes it by
//! less than 10⁻⁹. Several logs must agree on the rate within 10⁻⁶.
//!
//! **`[csv]`** (optional): `delimiter` and `header`, as above.
//!
//! **`[channels]`** (required). Each key is a session column: `x_m`, `y_m`, `fx_n`,
//! `fy_n`, `pert_fx_n`, `pert_fy_n` (required by the format), `vx_m_per_s`,
//! `vy_m_per_s`, `ref_x_m`, `ref_y_m`, `cmd_fx_n`, `cmd_fy_n` (optional). Each value is
//! an inline table: `var` (required), `column` (1-based, for a matrix), `scale`
//! (default 1, not 0) and `offset` (SI, default 0) giving `value = raw * scale +
//! offset`, and `unit` (the raw unit, documentation only, echoed in [`Imported`]'s
//! summary). Optional columns not mapped are not written. A required column not mapped
//! is written as zeros only when
//! - its axis is absent (`axes`),
//! - it is `fx_n`/`fy_n` and `[device] force_sensor = false`, or
//! - it is `pert_fx_n`/`pert_fy_n` and the map does not read perturbations from
//!   them (`[perturbation]` absent or `from = "table"`);
//!
//! otherwise it is [`ImportError::MissingChannel`] naming the key `channels.<column>`.
//!
//! **`[device]`** (required): `kind`, `mass_kg`, `damping_n_s_per_m`,
//! `handle_mass_kg`, `workspace_half_width_m` go into the session's `[device]` as the
//! format defines them; `force_sensor` (default true) says whether the rig measures the
//! hand force.
//!
//! **`[subject]`** (optional): `id` (default: the first log's file stem),
//! `shoulder_m` (default `[0, 0]`), `upper_arm_m`, `forearm_m`, `body_mass_kg`.
//!
//! **`[trials]`** (required): `cut` (below), `kind` (the trial kind in the manifest,
//! default `reach`), and the keys of the cut; a key of another cut is an error.
//!
//! # Cut modes
//!
//! Each log is cut on its own; trials are numbered 1, 2, … across the logs in the order
//! given. Each trial's `t_s` starts at 0 and is uniform at the rate.
//! - `cut = "whole"`: the whole log is one trial.
//! - `cut = "marker"`, `marker = { var, column, above }` (`above` default 0.5): a
//!   trial starts at each rising edge (a sample above `above` after one at or below it,
//!   or the log's first sample if it is above: a logger armed by the trigger starts on
//!   it) and ends before the next edge, or at the log's end. With `length_s`, each trial is that long instead (an
//!   error if it runs past the log's end). A marker that never rises is
//!   [`ImportError::MarkerNeverRises`].
//! - `cut = "onsets"`: `onsets_s = [0.0, 2.5, 5.0]` (increasing, s), or `onsets = { var,
//!   column, scale }` (a variable of onsets, s after `scale`). Onsets are on the log's
//!   clock: the time variable's own values when `[time] var` is given, else 0 at the
//!   first sample; each is rounded to the nearest sample. A trial runs to the next onset
//!   or the log's end, or `length_s` when given. An onset past the log's end is
//!   [`ImportError::TrialOutsideLog`].
//! - `cut = "threshold"`, `threshold = { channel, speed_above, before_s, length_s }`:
//!   movement starts in a mapped session column (`channel`, e.g. `x_m`): the first
//!   sample whose speed `|x[i] − x[i−1]| · rate` exceeds `speed_above` (in the column's
//!   SI unit per second). A trial starts `before_s` (default 0) before it and lasts
//!   `length_s`; the next movement is looked for after that trial, once the speed has
//!   fallen back to the threshold. A trial that would start before the log or end after
//!   it is [`ImportError::TrialOutsideLog`]; no movement at all is
//!   [`ImportError::NoMovement`].
//!
//! # Perturbations
//!
//! **`[perturbation]`** (optional; without it no trial is perturbed). `kind`: the
//! perturbation kind in the manifest (default `force-pulse`). `from`:
//! - `"channel"`: from the trial's `pert_fx_n`/`pert_fy_n`: the onset is the first
//!   sample where `|F|` exceeds `above_n` (N, default 0.5), the duration runs until it
//!   falls back to `above_n` (or the trial's end), the amplitude is the peak `|F|` and
//!   the angle is the direction of the force at the peak (degrees, from +x toward +y).
//!   A trial whose `|F|` never exceeds `above_n` is unperturbed.
//! - `"table"`: `onset_s`, `duration_s`, `amplitude_n`, `angle_deg`, lists with one
//!   value per trial (of all logs, in order); a trial with amplitude 0 is unperturbed.
//!
//! # One-axis rigs
//!
//! A linear stage has one axis: `axes = ["x"]` (or `["y"]`). The manifest then says
//! `axes = ["x"]` and the absent axis's required columns (`y_m`, `fy_n`, `pert_fy_n`)
//! are written as zeros, as is the absent member of an optional pair whose present
//! member is mapped (`ref_y_m` when `ref_x_m` is); mapping a column of the absent axis
//! is an error.
//!
//! # Output
//!
//! The session is written with `rigtwin_session::SessionWriter` into `out`, which must
//! not exist or be an empty directory ([`ImportError::OutputNotEmpty`]). `source =
//! "rig"`. Everything is read and checked before anything is written, and the same
//! inputs give the same bytes.

// An error is built once per import, on its way out; its fields (file, line, variable,
// map key) are what the caller shows, so they stay inline rather than boxed.
#![allow(clippy::result_large_err)]

mod csvlog;
mod error;
mod import;
mod inventory;
mod log;
mod map;
mod mat;
mod mat73;
mod read;

pub use error::{ImportError, MapAt, SampleAt};
pub use import::{Imported, MappedChannel, ZeroedChannel, import};
pub use inventory::{Entry, Inventory, inspect};
pub use map::{DEFAULT_CREATED, Map};
