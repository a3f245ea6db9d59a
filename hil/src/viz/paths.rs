//! Entity paths, in one place so that the blueprint, the tests and anyone reading an `.rrd`
//! agree on them.
//!
//! ```text
//! rig/workspace            static  square workspace limit
//! rig/rails/x              static  rail of the lower cart (along x)
//! rig/carriage             per sample  both carts (two boxes: lower, upper), the upper
//!                                      cart's rail carried by the lower cart (strip) and
//!                                      the handle = hand position (point)
//! arm/shoulder             static  shoulder joint
//! arm/links                per sample  shoulder–elbow–hand polyline (strip) and the
//!                                      elbow joint (point)
//! trial/path               per trial   the trial's hand path
//! trial/targets            per trial   start and goal
//! trial/onset              per trial   hand at perturbation onset (cleared when unperturbed)
//! trial/perturbation       per trial   arrow: direction and size of the pulse
//! plots/position          per sample  m, lines x and y
//! plots/velocity          per sample  m/s, lines x and y (when recorded)
//! plots/force/sensor      per sample  N, lines x and y
//! plots/force/pert        per sample  N, lines x and y
//! plots/reference         per sample  m, lines x and y (when recorded)
//! plots/command           per sample  N, lines x and y (when recorded)
//! plots/arm/angles_deg    per sample  degrees, lines shoulder and elbow
//! plots/muscles/activations_n  per sample  N, six lines SF SE EF EE BF BE (rehearsals only:
//!                                      the simulated arm's, not in the session files)
//! plots/timing/wake_latency_us  per sample  µs, the real-time loop's wake-up latency (mean
//!                                      of the sample's ticks; `rehearse --realtime` only)
//! plots/timing/held        per sample  share of the sample's ticks held (missed deadlines)
//! plots/response/{x,y}_mm  per perturbed trial, 150 ms after onset, mm
//! ellipses/<name>/outline  the image of the unit circle under the matrix (scaled)
//! ellipses/<name>/axes     its principal semi-axes, labelled with the matrix
//! events                   text log
//!
//! overlays (`rigtwin compare --rerun`, `rigtwin diagnose --rerun`):
//! measured/plots/<series>         per sample  a measured channel, as under plots/
//! simulated/plots/<series>        per sample  the same channel of the simulated replay
//! predicted/plots/command/{x,y}/<model>  per evaluated row  motor command the cart force
//!                                 balance of <model> predicts (`measured`: the command there)
//! ```
//!
//! Each pair of per-sample series is one entity with two scalars per row (rerun's `Scalars`
//! with `SeriesLines` names), so the pair shares one set of timeline columns and row ids:
//! a rehearsal's file is then about a third smaller than with one entity per line. For the
//! same reason the moving parts of the scene are two entities, each holding several
//! archetypes (boxes, strips, points) on one set of timeline columns; their sizes and colours
//! are static rows.

/// Root of the 2D scene.
pub const SCENE: &str = "/";
/// Workspace limit.
pub const WORKSPACE: &str = "rig/workspace";
/// Fixed rail of the lower cart.
pub const RAIL_X: &str = "rig/rails/x";
/// The moving parts of the rig: the lower and the upper cart (`Boxes2D`, two boxes in that
/// order), the upper cart's rail (`LineStrips2D`) and the handle (`Points2D`).
pub const CARRIAGE: &str = "rig/carriage";
/// Shoulder.
pub const SHOULDER: &str = "arm/shoulder";
/// Upper arm and forearm (`LineStrips2D`) and the elbow (`Points2D`).
pub const ARM_LINKS: &str = "arm/links";
/// Hand path of the current trial.
pub const TRIAL_PATH: &str = "trial/path";
/// Start and goal of the current trial.
pub const TRIAL_TARGETS: &str = "trial/targets";
/// Hand position at the perturbation onset.
pub const TRIAL_ONSET: &str = "trial/onset";
/// Direction and size of the perturbation.
pub const TRIAL_PERTURBATION: &str = "trial/perturbation";
/// Root of all time series.
pub const PLOTS: &str = "plots";
/// Root of the ellipses.
pub const ELLIPSES: &str = "ellipses";
/// Safety and protocol events.
pub const EVENTS: &str = "events";
/// Variational response, x.
pub const RESPONSE_X: &str = "plots/response/x_mm";
/// Variational response, y.
pub const RESPONSE_Y: &str = "plots/response/y_mm";
/// Names of the two lines of an x/y series, in the order of the scalars in each row.
pub const XY: [&str; 2] = ["x", "y"];
/// Handle position, m (x, y).
pub const POSITION: &str = "plots/position";
/// Handle velocity from the drive, m/s (x, y).
pub const VELOCITY: &str = "plots/velocity";
/// Force of the hand on the handle, N (x, y).
pub const FORCE_SENSOR: &str = "plots/force/sensor";
/// Perturbation force, N (x, y).
pub const FORCE_PERT: &str = "plots/force/pert";
/// Admittance position reference, m (x, y).
pub const REFERENCE: &str = "plots/reference";
/// Motor force command, N (x, y).
pub const COMMAND: &str = "plots/command";
/// Joint angles of the arm, degrees (shoulder, elbow).
pub const ARM_ANGLES_DEG: &str = "plots/arm/angles_deg";
/// Names of the two lines of [`ARM_ANGLES_DEG`], in the order of the scalars in each row.
pub const ARM_ANGLE_NAMES: [&str; 2] = ["shoulder", "elbow"];
/// Number of muscles of the simulated arm.
pub const MUSCLES: usize = rigtwin_arm::muscles::MUSCLES;
/// Muscle activations of a rehearsal's simulated arm, N (six lines, [`MUSCLE_NAMES`]).
pub const MUSCLE_ACTIVATIONS_N: &str = "plots/muscles/activations_n";
/// Names of the six lines of [`MUSCLE_ACTIVATIONS_N`], in the order of the scalars in each
/// row: shoulder, elbow and biarticular flexor and extensor.
pub const MUSCLE_NAMES: [&str; MUSCLES] = rigtwin_arm::muscles::MUSCLE_NAMES;

/// The real-time loop's wake-up latency per sample, µs (one line).
pub const TIMING_WAKE_US: &str = "plots/timing/wake_latency_us";
/// The share of a sample's ticks the real-time loop held (missed deadlines), 0-1.
pub const TIMING_HELD: &str = "plots/timing/held";

/// Prefix of the measured channels in an overlay.
pub const MEASURED: &str = "measured";
/// Prefix of the simulated channels in an overlay.
pub const SIMULATED: &str = "simulated";
/// Root of the motor command predicted by a force-balance model.
pub const PREDICTED_COMMAND: &str = "predicted/plots/command";

/// The overlay entity of a trial column under `prefix` (`simulated`, `x_m` →
/// `simulated/plots/position/x`): one entity per line, so measured and simulated
/// copies of a column sit side by side; `None` for `t_s` and unknown names.
pub fn overlay_series(prefix: &str, column: &str) -> Option<String> {
    series(column).map(|(entity, line)| format!("{prefix}/{entity}/{}", ["x", "y"][line]))
}

/// The entity of the motor command on `axis` (0 = x, 1 = y) predicted by `model`
/// (`baseline`, a candidate's name, or `measured` for the command itself).
pub fn predicted_command(axis: usize, model: &str) -> String {
    let a = if axis == 0 { "x" } else { "y" };
    format!("{PREDICTED_COMMAND}/{a}/{model}")
}

/// The time-series entity of a trial column and its place in each row (`y_m` →
/// `("plots/position", 1)`), `None` for `t_s` and unknown names.
pub fn series(column: &str) -> Option<(&'static str, usize)> {
    Some(match column {
        "x_m" => (POSITION, 0),
        "y_m" => (POSITION, 1),
        "vx_m_per_s" => (VELOCITY, 0),
        "vy_m_per_s" => (VELOCITY, 1),
        "fx_n" => (FORCE_SENSOR, 0),
        "fy_n" => (FORCE_SENSOR, 1),
        "pert_fx_n" => (FORCE_PERT, 0),
        "pert_fy_n" => (FORCE_PERT, 1),
        "ref_x_m" => (REFERENCE, 0),
        "ref_y_m" => (REFERENCE, 1),
        "cmd_fx_n" => (COMMAND, 0),
        "cmd_fy_n" => (COMMAND, 1),
        _ => return None,
    })
}

/// The outline entity of a named ellipse.
pub fn ellipse_outline(name: &str) -> String {
    format!("{ELLIPSES}/{name}/outline")
}

/// The axes entity of a named ellipse.
pub fn ellipse_axes(name: &str) -> String {
    format!("{ELLIPSES}/{name}/axes")
}
