//! A recorded session (measured or simulated) in the viewer: the glue between
//! [`crate::session::Session`] and the column API of [`Viewer`].

use std::path::Path;

use sha2::{Digest as _, Sha256};

use super::columns::{
    PerturbationMeta, PerturbationSize, RigGeometry, TrialColumns, TrialMeta, TrialSpan,
};
use super::geometry::{Elbow, two_link_inverse};
use super::{ArmColumns, EventLevel, Viewer, VizError};
use crate::session::{Amplitude, MANIFEST_FILE, Manifest, Session, Trial, TrialEntry};

/// Extra trial columns with the arm's joint angles, rad (shoulder from +x toward +y, elbow
/// relative to the upper arm). A simulated session that records them is drawn from them;
/// otherwise the arm is solved from the handle path by inverse kinematics.
pub const ARM_ANGLE_COLUMNS: [&str; 2] = ["shoulder_rad", "elbow_rad"];

/// The workspace drawn when the manifest does not give one, m.
const DEFAULT_WORKSPACE_HALF_WIDTH_M: f64 = 0.15;

/// What was sent.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Logged {
    /// Trials logged.
    pub trials: usize,
    /// Samples logged, all trials.
    pub samples: usize,
    /// Perturbed trials.
    pub perturbed: usize,
    /// Whether the arm was drawn (segment lengths or joint angles known).
    pub arm: bool,
    /// Samples whose hand position the arm cannot reach (drawn stretched).
    pub out_of_reach: usize,
    /// Where each trial landed on the timelines, in manifest order.
    pub spans: Vec<TrialSpan>,
}

/// A recording id that is a function of the session: the subject and the first 16 hex
/// digits of the SHA-256 of `session.toml` (which holds every trial file's digest). The same
/// session replaces itself in a running viewer, and saved files are reproducible.
pub fn recording_id(session: &Session) -> Result<String, VizError> {
    session_recording_id(&session.dir, &session.manifest.subject.id)
}

/// [`recording_id`] of the session in `dir` whose subject is `subject`.
pub(crate) fn session_recording_id(dir: &Path, subject: &str) -> Result<String, VizError> {
    let path = dir.join(MANIFEST_FILE);
    let bytes =
        rigtwin_session::files::read_regular(&path, rigtwin_session::files::MAX_MANIFEST_BYTES)
            .map_err(|source| VizError::Io { path, source })?;
    let digest = Sha256::digest(&bytes);
    let hex: String = digest[..8].iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("{subject}-{hex}"))
}

/// Logs a whole session: rig geometry, every trial in manifest order with its arm, and a
/// summary event.
pub fn log_session(viewer: &mut Viewer, session: &Session) -> Result<Logged, VizError> {
    log_session_at(viewer, session, 0)
}

/// [`log_session`] with the session's first trial at `first_trial` on the `trial` timeline,
/// for several sessions back to back in one recording; the `tick` and `time` timelines
/// continue from where the viewer is.
pub fn log_session_at(
    viewer: &mut Viewer,
    session: &Session,
    first_trial: u32,
) -> Result<Logged, VizError> {
    let manifest = &session.manifest;
    log_session_start(viewer, manifest)?;
    let mut logged = Logged::default();
    for (index, (entry, trial)) in session.iter().enumerate() {
        let trial_index = u32::try_from(index)
            .unwrap_or(u32::MAX)
            .saturating_add(first_trial);
        log_session_trial(viewer, manifest, trial_index, entry, trial, &mut logged)?;
    }
    log_session_end(viewer, manifest, &logged)?;
    Ok(logged)
}

/// The start of a session: the rig (workspace from the manifest) and the subject's
/// shoulder.
pub(crate) fn log_session_start(viewer: &mut Viewer, manifest: &Manifest) -> Result<(), VizError> {
    let workspace = manifest
        .device
        .workspace_half_width_m
        .unwrap_or(DEFAULT_WORKSPACE_HALF_WIDTH_M);
    viewer.log_rig_geometry(
        &RigGeometry::with_workspace(workspace).with_shoulder(manifest.subject.shoulder_m),
    )
}

/// One trial of a session, read from its files or handed over by a rehearsal as it was
/// written (the same logging either way): its series and overlays ([`Viewer::log_trial`])
/// at `trial_index` on the `trial` timeline, and the arm, from the recorded joint angles
/// ([`ARM_ANGLE_COLUMNS`]) or solved from the handle path when the manifest gives the
/// segment lengths. Adds to `logged` and returns where the trial landed.
pub(crate) fn log_session_trial(
    viewer: &mut Viewer,
    manifest: &Manifest,
    trial_index: u32,
    entry: &TrialEntry,
    trial: &Trial,
    logged: &mut Logged,
) -> Result<TrialSpan, VizError> {
    let subject = &manifest.subject;
    let segments = subject.upper_arm_m.zip(subject.forearm_m);
    let meta = TrialMeta {
        trial_index,
        id: entry.id,
        kind: entry.kind.as_str().to_owned(),
        rate_hz: manifest.rate_hz,
        start_m: entry.start_m,
        goal_m: entry.goal_m,
        perturbation: entry.perturbation.as_ref().map(|p| PerturbationMeta {
            onset_s: p.onset_s,
            duration_s: p.duration_s,
            size: match p.amplitude {
                Amplitude::ForceN(n) => PerturbationSize::ForceN(n),
                Amplitude::PositionM(m) => PerturbationSize::PositionM(m),
            },
            angle_deg: p.angle_deg,
        }),
    };
    let columns = columns_of(trial);
    let span = viewer.log_trial(&meta, &columns)?;
    logged.spans.push(span);
    logged.trials += 1;
    logged.samples += trial.len();
    logged.perturbed += usize::from(meta.perturbation.is_some());

    let angles = trial
        .column(ARM_ANGLE_COLUMNS[0])
        .zip(trial.column(ARM_ANGLE_COLUMNS[1]));
    match (angles, segments) {
        (Some((q1, q2)), Some((l1, l2))) => {
            let s = subject.shoulder_m;
            let elbow_x: Vec<f64> = q1.iter().map(|q| s[0] + l1 * q.cos()).collect();
            let elbow_y: Vec<f64> = q1.iter().map(|q| s[1] + l1 * q.sin()).collect();
            let reach = |e: &[f64], f: fn(f64) -> f64| -> Vec<f64> {
                e.iter()
                    .zip(q1.iter().zip(q2))
                    .map(|(e, (a, b))| e + l2 * f(a + b))
                    .collect()
            };
            let hand_x = reach(&elbow_x, f64::cos);
            let hand_y = reach(&elbow_y, f64::sin);
            let arm = ArmColumns {
                shoulder_m: s,
                elbow_x_m: &elbow_x,
                elbow_y_m: &elbow_y,
                hand_x_m: &hand_x,
                hand_y_m: &hand_y,
                shoulder_rad: q1,
                elbow_rad: q2,
            };
            viewer.log_arm(&span, &trial.t_s, &arm)?;
            logged.arm = true;
        }
        (None, Some((l1, l2))) => {
            let arm = two_link_inverse(
                subject.shoulder_m,
                l1,
                l2,
                &trial.x_m,
                &trial.y_m,
                Elbow::Down,
            );
            logged.out_of_reach += arm.out_of_reach;
            viewer.log_arm(&span, &trial.t_s, &arm.columns())?;
            logged.arm = true;
        }
        (_, None) => {}
    }
    Ok(span)
}

/// The end of a session: a summary event after its last trial.
pub(crate) fn log_session_end(
    viewer: &mut Viewer,
    manifest: &Manifest,
    logged: &Logged,
) -> Result<(), VizError> {
    let end = viewer.stamp_at(viewer.next_trial_offset_s());
    let mut text = format!(
        "session {} ({}, {} trials, {} perturbed, {:.0} Hz)",
        manifest.subject.id,
        manifest.source.as_str(),
        logged.trials,
        logged.perturbed,
        manifest.rate_hz
    );
    if !logged.arm {
        text.push_str("; arm not drawn: the manifest gives no segment lengths");
    }
    let level = if logged.out_of_reach > 0 {
        text.push_str(&format!(
            "; {} samples out of the arm's reach (drawn stretched)",
            logged.out_of_reach
        ));
        EventLevel::Warn
    } else {
        EventLevel::Info
    };
    viewer.log_event(end, level, &text)
}

/// The columns of a session table, as [`TrialColumns`] (the optional ones when recorded).
pub(crate) fn columns_of(trial: &Trial) -> TrialColumns<'_> {
    TrialColumns {
        vx_m_per_s: trial.vx_m_per_s.as_deref(),
        vy_m_per_s: trial.vy_m_per_s.as_deref(),
        ref_x_m: trial.ref_x_m.as_deref(),
        ref_y_m: trial.ref_y_m.as_deref(),
        cmd_fx_n: trial.cmd_fx_n.as_deref(),
        cmd_fy_n: trial.cmd_fy_n.as_deref(),
        ..TrialColumns::required(
            &trial.t_s,
            &trial.x_m,
            &trial.y_m,
            &trial.fx_n,
            &trial.fy_n,
            &trial.pert_fx_n,
            &trial.pert_fy_n,
        )
    }
}
