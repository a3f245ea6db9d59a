//! `session.toml`: the typed manifest, its parser (every error names file, line, key)
//! and its deterministic writer.
//!
//! Which tables accept keys that version 1 does not define:
//! - top level, `[device]`, `[[trial]]`, `[trial.perturbation]`: **no**. These keys
//!   drive models and analyses; a misspelt optional key (`handle_mass = 0.35`) would
//!   otherwise be dropped without a word. An unknown key is [`SessionError::UnknownKey`].
//!   The project's own additions are declared here: `axes` for rigs of one axis,
//!   `[sim]`, `[timing]`, `amplitude_m` for position perturbations, trial kinds and
//!   perturbation kinds beyond the spec's (all listed in `hil/session/FORMAT.md`).
//! - `[subject]` and `[sim]`: **yes**. Labs record subject metadata (age, handedness)
//!   and the simulator records whatever reproduces a run; unknown keys are kept in
//!   `extra`, in name order, and written back.

use std::collections::BTreeMap;
use std::fmt::{self, Write as _};
use std::ops::Range;
use std::path::{Component, Path, PathBuf};
use std::str::FromStr;

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::SessionError;

mod parse;
mod values;
mod write;

pub(crate) use parse::{parse, parse_trial_entry};
pub(crate) use write::write_trial_entry;

/// The value of `format`.
pub const FORMAT: &str = "rig-session";
/// The only `format_version` this module reads and writes.
pub const FORMAT_VERSION: i64 = 1;
/// The lowest `rate_hz` a reader accepts, Hz: below it a sample period's tolerance no
/// longer checks a time column.
pub const MIN_RATE_HZ: f64 = 1.0;
/// The highest `rate_hz` a reader accepts, Hz (a haptic rig's loop runs at 1–10 kHz).
pub const MAX_RATE_HZ: f64 = 1.0e6;

/// Which of the rig frame's axes a session's rig has: the optional top-level
/// `axes = ["x"]` (an extension of version 1; both when absent, and readers of the spec
/// ignore it). The columns of an axis the rig lacks are present and zero, so every
/// reader of the spec still reads the tables; analyses judge only the axes listed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Axes {
    /// A planar rig: `x` and `y`.
    #[default]
    Both,
    /// One axis, along the rig frame's `x`.
    X,
    /// One axis, along the rig frame's `y`.
    Y,
}

impl Axes {
    /// Whether axis `i` (0 = x, 1 = y) is present.
    #[must_use]
    pub fn has(self, i: usize) -> bool {
        match self {
            Axes::Both => i < 2,
            Axes::X => i == 0,
            Axes::Y => i == 1,
        }
    }

    /// The axes' names, as `axes` lists them.
    #[must_use]
    pub fn names(self) -> &'static [&'static str] {
        match self {
            Axes::Both => &["x", "y"],
            Axes::X => &["x"],
            Axes::Y => &["y"],
        }
    }
}

/// A parsed `session.toml`.
#[derive(Debug, Clone, PartialEq)]
pub struct Manifest {
    /// Measured (`rig`) or simulated (`sim`).
    pub source: Source,
    /// Sampling rate of every trial table, Hz ([`MIN_RATE_HZ`] to [`MAX_RATE_HZ`]).
    pub rate_hz: f64,
    /// `axes`: which axes the rig has (optional; both when absent). A one-axis rig (a
    /// linear servo stage) writes its other axis's columns as zeros.
    pub axes: Axes,
    /// When the session was recorded, as written (RFC 3339 in practice). Passed in by
    /// the writer, never read from the clock, so output is deterministic.
    pub created: String,
    /// `[device]`.
    pub device: Device,
    /// `[subject]`.
    pub subject: Subject,
    /// `[sim]`: present on simulator output.
    pub sim: Option<SimInfo>,
    /// `[timing]`: present on sessions recorded in real time (an extension of version 1
    /// that readers of the spec skip as an unknown table).
    pub timing: Option<Timing>,
    /// `[[trial]]`, in file order.
    pub trials: Vec<TrialEntry>,
}

/// A distribution of durations, µs.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Percentiles {
    /// Median, µs.
    pub p50_us: f64,
    /// 99th percentile, µs.
    pub p99_us: f64,
    /// 99.9th percentile, µs.
    pub p999_us: f64,
    /// Largest, µs.
    pub max_us: f64,
}

/// `[timing]`: how the real-time loop that recorded the session kept its clock.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Timing {
    /// Period of the control clock, µs (250 at 4 kHz).
    pub period_us: f64,
    /// Ticks the loop ran.
    pub ticks: u64,
    /// Deadlines missed: ticks the loop skipped (the plant moved on under the held
    /// command; every recorded sample is still there).
    pub missed_deadlines: u64,
    /// Longest run of consecutive missed deadlines.
    pub max_consecutive_misses: u64,
    /// Wake-up latency: how late after its deadline each tick started.
    pub wake_latency: Percentiles,
    /// Loop time: from one wake-up to the next request for a tick.
    pub loop_time: Percentiles,
}

impl Timing {
    /// Missed deadlines per 10⁵ deadlines.
    #[must_use]
    pub fn misses_per_1e5(&self) -> f64 {
        let due = self.ticks + self.missed_deadlines;
        if due == 0 {
            0.0
        } else {
            self.missed_deadlines as f64 * 1e5 / due as f64
        }
    }
}

/// Where the data came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// Measured on the rig.
    Rig,
    /// Simulator output.
    Sim,
}

impl Source {
    /// The manifest spelling.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Source::Rig => "rig",
            Source::Sim => "sim",
        }
    }
}

/// `[device]`: the admittance `M a + D v = F_hand + F_pert`.
#[derive(Debug, Clone, PartialEq)]
pub struct Device {
    /// Controller kind, e.g. `admittance`.
    pub kind: String,
    /// Admittance inertia per axis (x, y), kg (> 0).
    pub mass_kg: [f64; 2],
    /// Admittance damping per axis (x, y), N s/m (≥ 0).
    pub damping_n_s_per_m: [f64; 2],
    /// Mass between the force sensor and the hand, kg (≥ 0).
    pub handle_mass_kg: Option<f64>,
    /// Half the side of the square workspace, m (> 0).
    pub workspace_half_width_m: Option<f64>,
}

/// `[subject]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Subject {
    /// Subject code.
    pub id: String,
    /// Shoulder joint centre in the rig frame, m.
    pub shoulder_m: [f64; 2],
    /// Upper arm length, m (> 0).
    pub upper_arm_m: Option<f64>,
    /// Forearm length (elbow to handle), m (> 0).
    pub forearm_m: Option<f64>,
    /// Body mass, kg (> 0).
    pub body_mass_kg: Option<f64>,
    /// Keys version 1 does not define, kept and written back in name order.
    pub extra: BTreeMap<String, toml::Value>,
}

/// `[sim]`: how a simulated session was produced (a project addition).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SimInfo {
    /// Seed of every random draw.
    pub seed: Option<u64>,
    /// Protocol file or name that was run.
    pub protocol: Option<String>,
    /// Model name or description.
    pub model: Option<String>,
    /// Further keys, kept and written back in name order.
    pub extra: BTreeMap<String, toml::Value>,
}

/// One `[[trial]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialEntry {
    /// Trial id, unique in the session.
    pub id: u32,
    /// Path of the trial table relative to the session directory, `/`-separated.
    pub file: String,
    /// Digest of the trial file; optional on input, always written on output.
    pub sha256: Option<Sha256>,
    /// What the subject did.
    pub kind: TrialKind,
    /// Movement start, rig frame, m.
    pub start_m: Option<[f64; 2]>,
    /// Movement goal, rig frame, m.
    pub goal_m: Option<[f64; 2]>,
    /// The perturbation, if the trial was perturbed.
    pub perturbation: Option<Perturbation>,
}

impl TrialEntry {
    /// The trial file's path under the session directory `dir`.
    #[must_use]
    pub fn path_in(&self, dir: &Path) -> PathBuf {
        self.file
            .split('/')
            .fold(dir.to_path_buf(), |p, part| p.join(part))
    }
}

/// The trial's task.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TrialKind {
    /// A point-to-point reach.
    Reach,
    /// Holding a posture.
    Hold,
    /// Anything else (free text in the spec).
    Other(String),
}

impl TrialKind {
    /// The manifest spelling.
    #[must_use]
    pub fn as_str(&self) -> &str {
        match self {
            TrialKind::Reach => "reach",
            TrialKind::Hold => "hold",
            TrialKind::Other(s) => s,
        }
    }
}

impl From<String> for TrialKind {
    fn from(s: String) -> Self {
        match s.as_str() {
            "reach" => TrialKind::Reach,
            "hold" => TrialKind::Hold,
            _ => TrialKind::Other(s),
        }
    }
}

/// `[trial.perturbation]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Perturbation {
    /// Its shape.
    pub kind: PerturbationKind,
    /// Onset within the trial, on the `t_s` clock, s.
    pub onset_s: f64,
    /// Duration, s (> 0).
    pub duration_s: f64,
    /// Peak size: `amplitude_n` (force) or `amplitude_m` (position, a project addition).
    pub amplitude: Amplitude,
    /// Direction in the rig frame, from +x toward +y, degrees.
    pub angle_deg: f64,
}

/// The perturbation's shape.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PerturbationKind {
    /// `force-pulse`: the three-section smooth-jerk force pulse (Börner eqs. 22-23).
    ForcePulse,
    /// `position-min-snap`: a minimum-snap position displacement (Piovesan).
    PositionMinSnap,
    /// Any other name.
    Other(String),
}

impl PerturbationKind {
    /// The manifest spelling.
    #[must_use]
    pub fn as_str(&self) -> &str {
        match self {
            PerturbationKind::ForcePulse => "force-pulse",
            PerturbationKind::PositionMinSnap => "position-min-snap",
            PerturbationKind::Other(s) => s,
        }
    }
}

impl From<String> for PerturbationKind {
    fn from(s: String) -> Self {
        match s.as_str() {
            "force-pulse" => PerturbationKind::ForcePulse,
            "position-min-snap" => PerturbationKind::PositionMinSnap,
            _ => PerturbationKind::Other(s),
        }
    }
}

/// A perturbation's peak size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Amplitude {
    /// `amplitude_n`: peak force, N.
    ForceN(f64),
    /// `amplitude_m`: peak displacement, m.
    PositionM(f64),
}

/// A SHA-256 digest, written as 64 lower-case hex digits.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Sha256(pub [u8; 32]);

impl fmt::Debug for Sha256 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Sha256({self})")
    }
}

impl fmt::Display for Sha256 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.iter().try_for_each(|b| write!(f, "{b:02x}"))
    }
}

impl FromStr for Sha256 {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bytes = s.as_bytes();
        if bytes.len() != 64 {
            return Err(format!(
                "a SHA-256 digest has 64 hex digits, found {}",
                bytes.len()
            ));
        }
        let mut out = [0_u8; 32];
        for (o, pair) in out.iter_mut().zip(bytes.chunks_exact(2)) {
            let hex = |c: u8| char::from(c).to_digit(16);
            match (hex(pair[0]), hex(pair[1])) {
                (Some(h), Some(l)) => *o = (h * 16 + l) as u8,
                _ => return Err(format!("{s:?} is not hexadecimal")),
            }
        }
        Ok(Sha256(out))
    }
}

impl Sha256 {
    /// The digest of `bytes`.
    #[must_use]
    pub fn of(bytes: &[u8]) -> Sha256 {
        use sha2::Digest;
        Sha256(sha2::Sha256::digest(bytes).into())
    }
}

/// Where parsed values sit in the manifest, for errors found after parsing.
#[derive(Debug, Clone, Default)]
pub(crate) struct EntryLines {
    pub file: usize,
    pub sha256: usize,
    pub onset: usize,
}
