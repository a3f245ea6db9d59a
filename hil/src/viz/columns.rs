//! The plain inputs of the viewer API: slices of samples and small metadata structs, so that
//! callers need none of rerun's types and the viewer none of theirs.

use super::{TICK_HZ, VizError};

/// The fixed parts of the rig drawn in the 2D scene. Rig frame, metres.
#[derive(Debug, Clone, PartialEq)]
pub struct RigGeometry {
    /// Half the side of the square workspace the handle may reach, m.
    pub workspace_half_width_m: f64,
    /// `y` of the fixed rail the lower cart runs on (along `x`), m.
    pub lower_rail_y_m: f64,
    /// Half extent of the lower cart (`x`, `y`), m.
    pub lower_cart_half_size_m: [f64; 2],
    /// Half extent of the upper cart (`x`, `y`), m.
    pub upper_cart_half_size_m: [f64; 2],
    /// Shoulder joint centre in the rig frame, m, when a subject is known.
    pub shoulder_m: Option<[f64; 2]>,
}

impl RigGeometry {
    /// The geometry of a workspace of this half width, carts sized to match, no subject.
    pub fn with_workspace(workspace_half_width_m: f64) -> Self {
        let w = workspace_half_width_m;
        Self {
            workspace_half_width_m: w,
            lower_rail_y_m: -w - 0.04,
            lower_cart_half_size_m: [0.04, 0.025],
            upper_cart_half_size_m: [0.03, 0.03],
            shoulder_m: None,
        }
    }

    /// The same geometry with the subject's shoulder drawn.
    pub fn with_shoulder(mut self, shoulder_m: [f64; 2]) -> Self {
        self.shoulder_m = Some(shoulder_m);
        self
    }
}

/// The perturbation of one trial, as the recording manifest gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerturbationMeta {
    /// Onset within the trial, s (same clock as `t_s`).
    pub onset_s: f64,
    /// Duration of the pulse, s.
    pub duration_s: f64,
    /// Peak size.
    pub size: PerturbationSize,
    /// Direction in the rig frame, degrees from +x toward +y.
    pub angle_deg: f64,
}

/// The peak of a perturbation: a force pulse or a position displacement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PerturbationSize {
    /// Peak force, N.
    ForceN(f64),
    /// Peak displacement, m.
    PositionM(f64),
}

impl PerturbationSize {
    /// The length of the arrow that shows it in the scene, m: 2 mm per N, or the
    /// displacement itself.
    pub fn arrow_m(self) -> f64 {
        match self {
            Self::ForceN(n) => 0.002 * n,
            Self::PositionM(m) => m,
        }
    }

    /// `15.0 N` or `10.0 mm`.
    pub fn label(self) -> String {
        match self {
            Self::ForceN(n) => format!("{n:.1} N"),
            Self::PositionM(m) => format!("{:.1} mm", m * 1e3),
        }
    }
}

/// What the viewer needs to know about one trial besides its samples.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialMeta {
    /// 0-based position of the trial in the session: the `trial` timeline.
    pub trial_index: u32,
    /// The trial's id in the manifest (shown in labels).
    pub id: u32,
    /// `reach`, `hold` or free text.
    pub kind: String,
    /// Sampling rate of the columns, Hz.
    pub rate_hz: f64,
    /// Movement start, rig frame, m.
    pub start_m: Option<[f64; 2]>,
    /// Movement goal, rig frame, m.
    pub goal_m: Option<[f64; 2]>,
    /// The perturbation, if the trial is perturbed.
    pub perturbation: Option<PerturbationMeta>,
}

impl TrialMeta {
    /// A trial with only an index and a rate (id = index + 1, kind `reach`).
    pub fn new(trial_index: u32, rate_hz: f64) -> Self {
        Self {
            trial_index,
            id: trial_index + 1,
            kind: "reach".to_owned(),
            rate_hz,
            start_m: None,
            goal_m: None,
            perturbation: None,
        }
    }
}

/// One trial's samples, column by column, in the units of the recording format.
///
/// The seven required columns must be present; the others are drawn when given.
#[derive(Debug, Clone, Copy)]
pub struct TrialColumns<'a> {
    /// Time since the start of the trial, s.
    pub t_s: &'a [f64],
    /// Handle position, m.
    pub x_m: &'a [f64],
    /// Handle position, m.
    pub y_m: &'a [f64],
    /// Force of the hand on the handle, N.
    pub fx_n: &'a [f64],
    /// Force of the hand on the handle, N.
    pub fy_n: &'a [f64],
    /// Perturbation force, N.
    pub pert_fx_n: &'a [f64],
    /// Perturbation force, N.
    pub pert_fy_n: &'a [f64],
    /// Velocity from the drive, m/s.
    pub vx_m_per_s: Option<&'a [f64]>,
    /// Velocity from the drive, m/s.
    pub vy_m_per_s: Option<&'a [f64]>,
    /// Admittance position reference, m.
    pub ref_x_m: Option<&'a [f64]>,
    /// Admittance position reference, m.
    pub ref_y_m: Option<&'a [f64]>,
    /// Motor force command, N.
    pub cmd_fx_n: Option<&'a [f64]>,
    /// Motor force command, N.
    pub cmd_fy_n: Option<&'a [f64]>,
}

impl<'a> TrialColumns<'a> {
    /// The required columns only.
    pub fn required(
        t_s: &'a [f64],
        x_m: &'a [f64],
        y_m: &'a [f64],
        fx_n: &'a [f64],
        fy_n: &'a [f64],
        pert_fx_n: &'a [f64],
        pert_fy_n: &'a [f64],
    ) -> Self {
        Self {
            t_s,
            x_m,
            y_m,
            fx_n,
            fy_n,
            pert_fx_n,
            pert_fy_n,
            vx_m_per_s: None,
            vy_m_per_s: None,
            ref_x_m: None,
            ref_y_m: None,
            cmd_fx_n: None,
            cmd_fy_n: None,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// Whether the trial has no samples.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Every column with its name, optional ones only when present.
    pub(crate) fn named(&self) -> Vec<(&'static str, &'a [f64])> {
        let mut out = vec![
            ("x_m", self.x_m),
            ("y_m", self.y_m),
            ("fx_n", self.fx_n),
            ("fy_n", self.fy_n),
            ("pert_fx_n", self.pert_fx_n),
            ("pert_fy_n", self.pert_fy_n),
        ];
        let optional = [
            ("vx_m_per_s", self.vx_m_per_s),
            ("vy_m_per_s", self.vy_m_per_s),
            ("ref_x_m", self.ref_x_m),
            ("ref_y_m", self.ref_y_m),
            ("cmd_fx_n", self.cmd_fx_n),
            ("cmd_fy_n", self.cmd_fy_n),
        ];
        out.extend(
            optional
                .into_iter()
                .filter_map(|(name, c)| c.map(|c| (name, c))),
        );
        out
    }

    /// Checks that every column has as many samples as `t_s`.
    pub(crate) fn check(&self) -> Result<(), VizError> {
        check_lengths(self.t_s.len(), &self.named())
    }
}

pub(crate) fn check_lengths(
    expected: usize,
    columns: &[(&'static str, &[f64])],
) -> Result<(), VizError> {
    for (column, c) in columns {
        if c.len() != expected {
            return Err(VizError::ColumnLength {
                column,
                len: c.len(),
                expected,
            });
        }
    }
    Ok(())
}

/// The arm over one trial, column by column: joint positions in the rig frame (m) and joint
/// angles (rad; shoulder from +x toward +y, elbow relative to the upper arm, flexion
/// positive).
#[derive(Debug, Clone, Copy)]
pub struct ArmColumns<'a> {
    /// Shoulder joint centre, m (fixed).
    pub shoulder_m: [f64; 2],
    /// Elbow position, m.
    pub elbow_x_m: &'a [f64],
    /// Elbow position, m.
    pub elbow_y_m: &'a [f64],
    /// Hand position, m.
    pub hand_x_m: &'a [f64],
    /// Hand position, m.
    pub hand_y_m: &'a [f64],
    /// Shoulder angle, rad.
    pub shoulder_rad: &'a [f64],
    /// Elbow angle, rad.
    pub elbow_rad: &'a [f64],
}

impl ArmColumns<'_> {
    pub(crate) fn check(&self, expected: usize) -> Result<(), VizError> {
        check_lengths(
            expected,
            &[
                ("elbow_x_m", self.elbow_x_m),
                ("elbow_y_m", self.elbow_y_m),
                ("hand_x_m", self.hand_x_m),
                ("hand_y_m", self.hand_y_m),
                ("shoulder_rad", self.shoulder_rad),
                ("elbow_rad", self.elbow_rad),
            ],
        )
    }
}

/// An owned arm trajectory, e.g. computed by [`super::two_link_inverse`] from a measured hand
/// path.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ArmTrajectory {
    /// Shoulder joint centre, m.
    pub shoulder_m: [f64; 2],
    /// Elbow position, m.
    pub elbow_x_m: Vec<f64>,
    /// Elbow position, m.
    pub elbow_y_m: Vec<f64>,
    /// Hand position, m.
    pub hand_x_m: Vec<f64>,
    /// Hand position, m.
    pub hand_y_m: Vec<f64>,
    /// Shoulder angle, rad.
    pub shoulder_rad: Vec<f64>,
    /// Elbow angle, rad.
    pub elbow_rad: Vec<f64>,
    /// Samples where the hand was out of the arm's reach (drawn with the arm stretched).
    pub out_of_reach: usize,
}

impl ArmTrajectory {
    /// Borrowed columns for [`super::Viewer::log_arm`].
    pub fn columns(&self) -> ArmColumns<'_> {
        ArmColumns {
            shoulder_m: self.shoulder_m,
            elbow_x_m: &self.elbow_x_m,
            elbow_y_m: &self.elbow_y_m,
            hand_x_m: &self.hand_x_m,
            hand_y_m: &self.hand_y_m,
            shoulder_rad: &self.shoulder_rad,
            elbow_rad: &self.elbow_rad,
        }
    }
}

/// Where a trial sits on the session's time axis, returned by
/// [`super::Viewer::log_trial`]; pass it back to log more about the same trial.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialSpan {
    /// The trial's index (the `trial` timeline).
    pub trial_index: u32,
    /// Session time of the trial's `t_s = 0`, s.
    pub offset_s: f64,
    /// Trial duration as logged (samples × period), s.
    pub duration_s: f64,
}

impl TrialSpan {
    /// The stamp of trial time `t_s`.
    pub fn stamp(&self, t_s: f64) -> Stamp {
        let time_s = self.offset_s + t_s;
        Stamp {
            tick: tick_of(time_s),
            time_s,
            trial: Some(self.trial_index),
        }
    }
}

/// A point on the viewer's timelines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stamp {
    /// 4 kHz ticks since the start of the session.
    pub tick: i64,
    /// Seconds since the start of the session.
    pub time_s: f64,
    /// The trial, when known.
    pub trial: Option<u32>,
}

impl Stamp {
    /// The stamp of a control tick (trial unknown): `time = tick / 4000 s`.
    pub fn from_tick(tick: u64) -> Self {
        let tick = i64::try_from(tick).unwrap_or(i64::MAX);
        Self {
            tick,
            time_s: tick as f64 / TICK_HZ,
            trial: None,
        }
    }
}

/// The tick of a session time.
pub(crate) fn tick_of(time_s: f64) -> i64 {
    (time_s * TICK_HZ).round() as i64
}

/// Severity of a logged event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventLevel {
    /// Informational (trial start, protocol step).
    Info,
    /// A safety margin approached or a limit reached.
    Warn,
    /// A fault (the controller latched off).
    Error,
}
