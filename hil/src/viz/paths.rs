//! Entity paths, in one place so that the blueprint, the tests and anyone reading an `.rrd`
//! agree on them.
//!
//! ```text
//! rig/workspace            static  square workspace limit
//! rig/rails/x              static  rail of the lower cart (along x)
//! rig/rails/y              per sample  rail of the upper cart, carried by the lower cart
//! rig/carts/lower          per sample  lower cart (box)
//! rig/carts/upper          per sample  upper cart (box)
//! rig/handle               per sample  handle = hand position
//! arm/shoulder             static  shoulder joint
//! arm/links                per sample  shoulder–elbow–hand polyline
//! arm/elbow                per sample  elbow joint
//! trial/path               per trial   the trial's hand path
//! trial/targets            per trial   start and goal
//! trial/onset              per trial   hand at perturbation onset (cleared when unperturbed)
//! trial/perturbation       per trial   arrow: direction and size of the pulse
//! plots/position/{x,y}     per sample  m
//! plots/velocity/{x,y}     per sample  m/s (when recorded)
//! plots/force/sensor_{x,y} per sample  N
//! plots/force/pert_{x,y}   per sample  N
//! plots/reference/{x,y}    per sample  m (when recorded)
//! plots/command/{x,y}      per sample  N (when recorded)
//! plots/arm/{shoulder,elbow}_deg  per sample  degrees
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

/// Root of the 2D scene.
pub const SCENE: &str = "/";
/// Workspace limit.
pub const WORKSPACE: &str = "rig/workspace";
/// Fixed rail of the lower cart.
pub const RAIL_X: &str = "rig/rails/x";
/// Moving rail of the upper cart.
pub const RAIL_Y: &str = "rig/rails/y";
/// Lower cart.
pub const CART_LOWER: &str = "rig/carts/lower";
/// Upper cart.
pub const CART_UPPER: &str = "rig/carts/upper";
/// Handle.
pub const HANDLE: &str = "rig/handle";
/// Shoulder.
pub const SHOULDER: &str = "arm/shoulder";
/// Upper arm and forearm.
pub const ARM_LINKS: &str = "arm/links";
/// Elbow.
pub const ELBOW: &str = "arm/elbow";
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
/// Shoulder angle.
pub const ARM_SHOULDER_DEG: &str = "plots/arm/shoulder_deg";
/// Elbow angle.
pub const ARM_ELBOW_DEG: &str = "plots/arm/elbow_deg";

/// Prefix of the measured channels in an overlay.
pub const MEASURED: &str = "measured";
/// Prefix of the simulated channels in an overlay.
pub const SIMULATED: &str = "simulated";
/// Root of the motor command predicted by a force-balance model.
pub const PREDICTED_COMMAND: &str = "predicted/plots/command";

/// The overlay entity of a trial column under `prefix` (`simulated`, `x_m` →
/// `simulated/plots/position/x`), `None` for `t_s` and unknown names.
pub fn overlay_series(prefix: &str, column: &str) -> Option<String> {
    series(column).map(|s| format!("{prefix}/{s}"))
}

/// The entity of the motor command on `axis` (0 = x, 1 = y) predicted by `model`
/// (`baseline`, a candidate's name, or `measured` for the command itself).
pub fn predicted_command(axis: usize, model: &str) -> String {
    let a = if axis == 0 { "x" } else { "y" };
    format!("{PREDICTED_COMMAND}/{a}/{model}")
}

/// The time-series entity of a trial column (`x_m` → `plots/position/x`), `None` for `t_s`
/// and unknown names.
pub fn series(column: &str) -> Option<&'static str> {
    Some(match column {
        "x_m" => "plots/position/x",
        "y_m" => "plots/position/y",
        "vx_m_per_s" => "plots/velocity/x",
        "vy_m_per_s" => "plots/velocity/y",
        "fx_n" => "plots/force/sensor_x",
        "fy_n" => "plots/force/sensor_y",
        "pert_fx_n" => "plots/force/pert_x",
        "pert_fy_n" => "plots/force/pert_y",
        "ref_x_m" => "plots/reference/x",
        "ref_y_m" => "plots/reference/y",
        "cmd_fx_n" => "plots/command/x",
        "cmd_fy_n" => "plots/command/y",
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
