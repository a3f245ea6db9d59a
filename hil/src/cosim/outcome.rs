//! What one trial's co-simulation leaves: the recorded rows, the extremes of every tick
//! (for the safety and workspace report), and the ground truth at perturbation onsets.

use rigtwin_device::TickReport;

use super::record::Block;

/// Ground truth at the onset of a force pulse.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OnsetTruth {
    /// Onset tick.
    pub tick: u64,
    /// Arm endpoint inertia `J⁻ᵀ M_q J⁻¹`, kg (the a-priori `M_BSP`).
    pub mass_kg: [[f64; 2]; 2],
    /// Intrinsic endpoint damping of the muscles, N s/m.
    pub damping_n_s_per_m: [[f64; 2]; 2],
    /// Intrinsic endpoint stiffness of the muscles, N/m.
    pub stiffness_n_per_m: [[f64; 2]; 2],
    /// Hand position, rig frame, m.
    pub hand_m: [f64; 2],
}

/// Per-tick extremes of a trial, for the safety and workspace parts of the report.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Extremes {
    /// Largest |hand force| as the controller measured it, N.
    pub peak_force_n: f64,
    /// Largest handle speed from the drive's velocity, m/s.
    pub peak_speed_m_per_s: f64,
    /// Largest |motor command| per axis, N.
    pub peak_command_n: [f64; 2],
    /// Largest |position| per axis, m.
    pub peak_position_m: [f64; 2],
    /// Ticks with a saturated motor command.
    pub saturated_ticks: u64,
    /// Ticks with a soft-wall force acting.
    pub wall_ticks: u64,
    /// First safety trip: tick and reason.
    pub trip: Option<(u64, String)>,
}

/// The raw result of simulating one trial.
#[derive(Debug, Clone)]
pub struct Simulated {
    /// Block-mean rows at the recording rate.
    pub rows: Vec<Block>,
    /// Whether a simulated arm held the handle, so that the rows' activation channels
    /// (`record::ch::ACTIVATION`) hold its muscles' (false for the spring-mass rig).
    pub muscles: bool,
    /// Extremes over all ticks.
    pub extremes: Extremes,
    /// Onset tick of the force pulse, if one fired.
    pub pulse_onset: Option<u64>,
    /// Ground truth at the pulse onset.
    pub onset_truth: Option<OnsetTruth>,
    /// Onset tick and direction (degrees) of each position perturbation.
    pub push_onsets: Vec<(u64, f64)>,
}

/// Folds one tick's report into the trial's extremes.
pub fn track(e: &mut Extremes, r: &TickReport) {
    e.peak_force_n = e.peak_force_n.max(r.force_n[0].hypot(r.force_n[1]));
    e.peak_speed_m_per_s = e
        .peak_speed_m_per_s
        .max(r.velocity_m_per_s[0].hypot(r.velocity_m_per_s[1]));
    for i in 0..2 {
        e.peak_command_n[i] = e.peak_command_n[i].max(r.command_n[i].abs());
        e.peak_position_m[i] = e.peak_position_m[i].max(r.position_m[i].abs());
    }
    if r.saturated[0] || r.saturated[1] {
        e.saturated_ticks += 1;
    }
    if r.wall_force_n[0] != 0.0 || r.wall_force_n[1] != 0.0 {
        e.wall_ticks += 1;
    }
    if e.trip.is_none()
        && let Some(t) = r.trip
    {
        e.trip = Some((r.tick.0, format!("{t:?}")));
    }
}
