//! The checks a candidate must pass besides its held-out gain before it is named: its
//! parameters are material in physical units, they are not at the edge of their search
//! range, and its own evidence agrees with its law.
//!
//! **Material.** Every rule compares the largest force the fitted effect makes over the
//! session with [`FORCE_RESOLUTION_N`], or states the physical floor the effect has:
//!
//! | effect | material when |
//! |---|---|
//! | `rail-friction` | `|Fc| + |b| v_max ≥ 0.25 N` at the session's largest cart speed, with `Fc, b ≥ 0` |
//! | `force-ripple` | the larger of the two axes' amplitudes `≥ 0.25 N` |
//! | `sensor-rotation` | `|sin θ| F_max ≥ 0.25 N` at the session's largest sensor force, and `|θ| ≥ 0.5°` |
//! | `actuation-delay` | at least one 4 kHz tick (0.25 ms) beyond the nominal latency |
//! | `handle-mass` | `m a_max ≥ 0.25 N` at the session's largest cart acceleration |
//! | `grip-compliance` | the grip stretches `≥ 0.25 mm` under the session's largest sensor force |
//! | `stretch-reflex` | gain `≥ 25 N s/m` (a tenth of the muscles' own damping, 100–300 N s/m), and its force `g S Δv(t − δ)` `≥ 0.25 N` somewhere in one pulse's response (`HandCandidate::peak_force_n`) |
//!
//! **Inside its range.** A parameter found at the first or last point of its grid (a
//! ripple pitch at 5 or 100 mm, an angle at ±45°, a reflex delay at 10 or 50 ms, a grip
//! at 0.5 or 50 kN/m, a friction knee at its softest 10 mm/s) says the law was pushed to
//! fit something else; it is not named. A friction knee at the sharpest setting is the
//! sign-function limit of the law, not an edge; nor is any knee of a friction whose
//! Coulomb force is below the rig's 0.25 N (a viscous friction: the knee shapes
//! nothing, and the folds put it anywhere; a named friction lists such a knee as
//! [`undetermined`]). A grip whose range (the stiffnesses the
//! folds cannot tell from the found one) reaches 50 kN/m is not told from a rigid grip
//! ([`unbounded_grip`]).
//!
//! **Not leaning on the motor gains' bound.** The nominal balance holds each motor's
//! force gain within a force constant's ±10 % ([`MOTOR_GAIN_TOLERANCE`]). A candidate
//! whose fit sits at that bound is judged again with the gains at their nominal values
//! in its fit and its base's alike, and must pass the t-test and the gain floor there
//! too ([`at_gain_bound`]): on reaches without pulses a viscous friction and the gains
//! trade through the admittance, and what such a fit gains is the command's scale.
//!
//! **Its own evidence.** For the effects that are a function of the carts' state
//! (friction of the velocity, ripple of the position), the *partial residual* (the
//! candidate's held-out-fitted residual plus the effect's own fitted force) is averaged
//! in bins of the effect's coordinate and compared with the fitted law averaged in the
//! same bins: the law must explain at least [`MIN_EVIDENCE_R2`] of the binned partial
//! residual's variance across bins. A 0.18 N "ripple" of 75 mm pitch fitted to a slow
//! trend fails it (the bins are flat where the sine swings).

use super::candidate::{Candidate, MOTOR_GAIN_TOLERANCE, NUISANCE_COLUMNS};
use super::effect::EffectKind;
use super::error::DiscrepancyError;
use super::hand::GRIP_STIFFNESS_N_PER_M;
use super::signals::BalanceSignals;
use rigtwin_session::Session;
use std::collections::BTreeMap;

/// The force a lab's rig resolves over a session, N: the realistic force-sensor noise
/// is 0.05–0.15 N RMS per sample and the tare error up to 0.3 N
/// (`protocol::nuisance::NuisanceConfig::REALISTIC`, the shared realistic sessions);
/// an effect whose force stays below a quarter newton everywhere changes no command or
/// trajectory a lab would act on.
pub const FORCE_RESOLUTION_N: f64 = 0.25;

/// Share of the binned partial residual's variance the law must explain.
pub const MIN_EVIDENCE_R2: f64 = 0.5;

/// Bins of the evidence check.
const BINS: usize = 16;

/// What bounds the session's forces and motions, for the materiality rules.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionScale {
    /// Largest cart speed, m/s.
    pub v_max: f64,
    /// Largest cart acceleration, m/s².
    pub a_max: f64,
    /// Largest sensor force, N.
    pub f_max: f64,
}

impl SessionScale {
    /// The largest magnitudes over the evaluated rows of every trial and axis (of the
    /// smoothed signals the balance uses, so no single sample's noise sets them).
    #[must_use]
    pub fn of(signals: &[BalanceSignals]) -> SessionScale {
        let max = |pick: &dyn Fn(&BalanceSignals, usize) -> &Vec<f64>| {
            signals
                .iter()
                .flat_map(|s| (0..2).flat_map(move |a| s.at_rows(pick(s, a))))
                .map(f64::abs)
                .fold(0.0, f64::max)
        };
        SessionScale {
            v_max: max(&|s, a| &s.v[a]),
            a_max: max(&|s, a| &s.a[a]),
            f_max: max(&|s, a| &s.f[a]),
        }
    }

    /// The scale of the whole session: [`Self::of`] the `signals` the cart balance
    /// uses, and of the trials it skips for want of the motor command (the hand balance
    /// judges them too), whose positions and forces are smoothed here as the balance
    /// smooths them, with a zero command standing in (the scale reads no command).
    ///
    /// # Errors
    /// A trial that cannot be smoothed.
    pub fn of_session(
        session: &Session,
        signals: &[BalanceSignals],
    ) -> Result<SessionScale, DiscrepancyError> {
        let rate = session.manifest.rate_hz;
        let mut skipped = Vec::new();
        for (entry, trial) in session.iter() {
            if trial.cmd_fx_n.is_none() || trial.cmd_fy_n.is_none() {
                let mut t = trial.clone();
                t.cmd_fx_n = Some(vec![0.0; trial.len()]);
                t.cmd_fy_n = Some(vec![0.0; trial.len()]);
                skipped.extend(BalanceSignals::from_trial(entry, &t, rate)?);
            }
        }
        let (a, b) = (SessionScale::of(signals), SessionScale::of(&skipped));
        Ok(SessionScale {
            v_max: a.v_max.max(b.v_max),
            a_max: a.a_max.max(b.a_max),
            f_max: a.f_max.max(b.f_max),
        })
    }
}

fn p(params: &std::collections::BTreeMap<String, f64>, k: &str) -> f64 {
    params.get(k).copied().unwrap_or(f64::NAN)
}

/// Why the fitted parameters of the catalog effect `kind` are not a finding (empty when
/// they are, and for what is not in the catalog), by the module's table; `latency_ms` is
/// the nominal latency.
#[must_use]
pub fn immaterial(
    kind: Option<EffectKind>,
    params: &std::collections::BTreeMap<String, f64>,
    scale: &SessionScale,
    latency_ms: f64,
) -> Vec<String> {
    let r = FORCE_RESOLUTION_N;
    let mut why = Vec::new();
    let Some(kind) = kind else {
        return why;
    };
    match kind {
        EffectKind::RailFriction => {
            let (fc, b) = (p(params, "coulomb_n"), p(params, "viscous_n_s_per_m"));
            if fc < -0.05 || b < -0.5 {
                why.push(format!(
                    "friction must resist motion: coulomb {fc:.3} N, viscous {b:.3} N s/m"
                ));
            }
            let peak = fc.abs() + b.abs() * scale.v_max;
            if peak < r {
                why.push(format!(
                    "immaterial: at most {peak:.3} N at {:.3} m/s, below the rig's {r} N",
                    scale.v_max
                ));
            }
        }
        EffectKind::ForceRipple => {
            let (ax, ay) = (p(params, "amplitude_x_n"), p(params, "amplitude_y_n"));
            if ax.max(ay).is_nan() || ax.max(ay) < r {
                why.push(format!(
                    "immaterial: amplitudes x {ax:.3} N, y {ay:.3} N, both below the rig's {r} N"
                ));
            }
        }
        EffectKind::SensorRotation => {
            let th = p(params, "angle_deg");
            let f = th.to_radians().sin().abs() * scale.f_max;
            if th.abs() < 0.5 || f < r {
                why.push(format!(
                    "immaterial: {th:.2}° turns at most {f:.3} N of the session's {:.1} N into the other axis",
                    scale.f_max
                ));
            }
        }
        EffectKind::ActuationDelay => {
            let d = p(params, "delay_ms");
            if d - latency_ms < 0.25 - 1e-9 {
                why.push(format!(
                    "immaterial: {d:.3} ms is within one 4 kHz tick of the nominal latency {latency_ms:.3} ms"
                ));
            }
        }
        EffectKind::HandleMass => {
            let m = p(params, "extra_mass_kg");
            let f = m * scale.a_max;
            if f < r {
                why.push(format!(
                    "immaterial: {m:.3} kg makes at most {f:.3} N at {:.2} m/s²",
                    scale.a_max
                ));
            }
        }
        EffectKind::GripCompliance => {
            let k = p(params, "stiffness_n_per_m");
            let stretch = scale.f_max / k;
            if stretch < 0.25e-3 {
                why.push(format!(
                    "immaterial: {k:.0} N/m stretches {:.3} mm under the session's {:.1} N",
                    stretch * 1e3,
                    scale.f_max
                ));
            }
        }
        EffectKind::StretchReflex => {
            let g = p(params, "gain");
            if g < 25.0 {
                why.push(format!(
                    "immaterial: reflex gain {g:.1} N s/m, below 25 N s/m"
                ));
            }
        }
    }
    why
}

/// Why setting `s` of a candidate with `settings` settings, fitted to `params`, is at
/// the edge of its search range (empty when it is not).
#[must_use]
pub fn at_edge(
    kind: Option<EffectKind>,
    setting: (&str, f64),
    s: usize,
    settings: usize,
    params: &BTreeMap<String, f64>,
) -> Vec<String> {
    if settings < 2 {
        return Vec::new();
    }
    // A friction knee at its sharpest setting is the sign-function limit of the law, and
    // a delay's first setting is no lag beyond the nominal latency: neither is an edge.
    let open_below = matches!(
        kind,
        Some(EffectKind::RailFriction | EffectKind::ActuationDelay)
    );
    // The knee shapes the Coulomb force alone: beside a Coulomb force the rig does not
    // resolve, a viscous friction puts the knee anywhere, its softest setting included,
    // and nothing was pushed there.
    let knee_shapes_nothing =
        kind == Some(EffectKind::RailFriction) && p(params, "coulomb_n").abs() < FORCE_RESOLUTION_N;
    let first = s == 0 && !open_below;
    let last = s + 1 == settings && !knee_shapes_nothing;
    if first || last {
        vec![format!(
            "at the edge of its search range: {} {:.4} is the {} setting",
            setting.0,
            setting.1,
            if first { "first" } else { "last" }
        )]
    } else {
        Vec::new()
    }
}

/// Why a grip whose stiffness the folds cannot tell from the stiffest searched is not
/// told from a rigid grip (empty when its `range`, [`crate::Ranked::parameter_range`],
/// stays below the grid's stiff end [`GRIP_STIFFNESS_N_PER_M`], or holds no stiffness).
///
/// The edge rule above reads the point estimate; a grip one step below the grid's end,
/// whose range reaches it, is as unbounded: the data put no ceiling on its stiffness,
/// and a grip stiffer than any searched is the rigid grip the baseline already is. The
/// one such fit seen named (1 s reaches hiding nothing) was 47 kN/m with 693 N s/m, a
/// damping no grasp has (5–30 N s/m). A grasp through skin and soft tissue is a few kN/m (the generator's 2–6 kN/m, the
/// independent rig's 1.5 kN/m); its range ends well inside the grid.
#[must_use]
pub fn unbounded_grip(range: &BTreeMap<String, [f64; 2]>) -> Vec<String> {
    let stiffest = GRIP_STIFFNESS_N_PER_M.1;
    match range.get("stiffness_n_per_m") {
        Some(&[lo, hi]) if hi >= stiffest * (1.0 - 1e-9) => vec![format!(
            "not told from a rigid grip: the folds cannot tell its stiffness ({:.1}–{:.1} kN/m) from {:.0} kN/m, the stiffest searched",
            lo / 1e3,
            hi / 1e3,
            stiffest / 1e3
        )],
        _ => Vec::new(),
    }
}

/// Why a cart-balance fit with coefficients `beta` and the Gram's `bounds` leans on
/// the motor gains' bound (empty when neither force gain sits at it, or the design
/// bounds none: a rig without a force sensor).
///
/// The bound ([`MOTOR_GAIN_TOLERANCE`]) keeps the command's scale from taking up an
/// effect; a fit that sits at it wants more scale than a force constant has, and what
/// the candidate's own columns then gain is that scale, not their law. Without a
/// perturbation the admittance makes the carts' velocity `(F − M a − ε)/D`, so a
/// viscous friction `b v` beside a motor gain `γ` with `b = γ D` is the mass and
/// `γ (u + D v − (m − M) a)`, which observes the current loop's noise the command
/// answers (`ε` the admittance's tracking error): on reaches without pulses a
/// friction of `D` times the bound, 1.4–1.6 N s/m at `D` = 15 N s/m, came out with
/// both gains at +10 %, and a held-out gain of 5 %. A real friction's fit leaves the
/// gains near their nominal values (the shared `example-friction`: 0.1 %).
#[must_use]
pub fn at_gain_bound(beta: &[f64], bounds: &[(usize, f64, f64)]) -> Vec<String> {
    let at: Vec<String> = bounds
        .iter()
        .filter_map(|&(col, lo, hi)| {
            let g = *beta.get(col)?;
            let edge = 1e-9 * (hi - lo);
            (g <= lo + edge || g >= hi - edge).then(|| {
                let axis = ["x", "y"][(col + NUISANCE_COLUMNS).saturating_sub(beta.len()).min(1)];
                format!("{axis} at {:+.0} %", 100.0 * g)
            })
        })
        .collect();
    if at.is_empty() {
        return Vec::new();
    }
    vec![format!(
        "it leans on the motor gains' bound of ±{:.0} % ({}): what it gains is the command's scale beyond a force constant's tolerance, not its own law",
        100.0 * MOTOR_GAIN_TOLERANCE,
        at.join(", ")
    )]
}

/// `R²` of the fitted law against the binned partial residual, for a candidate whose
/// effect is a function of the carts' state (`None` for the others, or with too few
/// filled bins): friction against velocity, ripple against position, both axes pooled.
///
/// # Errors
/// A signal-processing error while forming the residual.
pub fn evidence_r2(
    c: &dyn Candidate,
    s: usize,
    beta: &[f64],
    signals: &[BalanceSignals],
    latency_s: f64,
) -> Result<Option<f64>, DiscrepancyError> {
    let by_velocity = match c.kind() {
        Some(EffectKind::RailFriction) => true,
        Some(EffectKind::ForceRipple) => false,
        Some(
            EffectKind::ActuationDelay
            | EffectKind::SensorRotation
            | EffectKind::StretchReflex
            | EffectKind::GripCompliance
            | EffectKind::HandleMass,
        )
        | None => return Ok(None),
    };
    // Coordinate, partial residual and law at every evaluated row.
    let mut pts: Vec<(f64, f64, f64)> = Vec::new();
    for sig in signals {
        let res = c.residual(sig, s, beta, latency_s)?;
        for (axis, e) in res.iter().enumerate() {
            let q = sig.at_rows(&sig.q[axis]);
            let v = sig.at_rows(&sig.v[axis]);
            for r in 0..e.len() {
                let Some(f) = c.effect_force(s, beta, axis, q[r], v[r]) else {
                    return Ok(None);
                };
                // The fit carries the effect as `−f` on the target side.
                let law = -f;
                let x = if by_velocity { v[r] } else { q[r] };
                pts.push((x, e[r] + law, law));
            }
        }
    }
    if pts.is_empty() {
        return Ok(None);
    }
    let lo = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Ok(None);
    }
    let mut bins = vec![(0.0, 0.0, 0usize); BINS];
    for (x, partial, law) in &pts {
        let k = (((x - lo) / (hi - lo)) * BINS as f64).floor() as usize;
        let b = &mut bins[k.min(BINS - 1)];
        b.0 += partial;
        b.1 += law;
        b.2 += 1;
    }
    // Bins with at least 1 % of the rows, weighted by their counts.
    let min_n = pts.len() / 100;
    let filled: Vec<(f64, f64, f64)> = bins
        .iter()
        .filter(|b| b.2 > min_n.max(10))
        .map(|b| (b.0 / b.2 as f64, b.1 / b.2 as f64, b.2 as f64))
        .collect();
    if filled.len() < 4 {
        return Ok(None);
    }
    let w: f64 = filled.iter().map(|b| b.2).sum();
    let mean = filled.iter().map(|b| b.0 * b.2).sum::<f64>() / w;
    let ss_tot: f64 = filled.iter().map(|b| b.2 * (b.0 - mean).powi(2)).sum();
    let ss_res: f64 = filled.iter().map(|b| b.2 * (b.0 - b.1).powi(2)).sum();
    Ok((ss_tot > 0.0).then(|| 1.0 - ss_res / ss_tot))
}

/// A named effect's parameters that the data cannot determine, each with why (empty
/// when every one is determined): a friction's knee shapes its Coulomb force alone, so
/// beside a Coulomb force below the rig's resolution (a viscous friction) it is
/// whatever the folds put it at, and a lab should not read it.
#[must_use]
pub fn undetermined(
    kind: EffectKind,
    parameters: &BTreeMap<String, f64>,
) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    if let (EffectKind::RailFriction, Some(fc)) = (kind, parameters.get("coulomb_n"))
        && fc.abs() < FORCE_RESOLUTION_N
    {
        out.insert(
            "smooth_velocity_m_per_s".to_string(),
            format!(
                "the knee of coulomb_n · tanh(v / knee) shapes the Coulomb force alone, \
                 here {fc:.3} N, below the rig's {FORCE_RESOLUTION_N} N"
            ),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::candidate::gain_bounds;

    /// A friction's knee is flagged as undetermined beside a Coulomb force below the
    /// rig's 0.25 N (a viscous friction), not beside one above it, and no other
    /// effect's parameters are flagged.
    #[test]
    fn a_knee_beside_no_coulomb_force_is_undetermined() {
        let friction = |fc: f64| {
            [
                ("coulomb_n".to_string(), fc),
                ("viscous_n_s_per_m".to_string(), 2.0),
                ("smooth_velocity_m_per_s".to_string(), 0.01),
            ]
            .into_iter()
            .collect()
        };
        let flagged = undetermined(EffectKind::RailFriction, &friction(0.02));
        assert_eq!(
            flagged.keys().collect::<Vec<_>>(),
            ["smooth_velocity_m_per_s"]
        );
        assert!(
            flagged["smooth_velocity_m_per_s"].contains("0.020 N"),
            "{flagged:?}"
        );
        assert_eq!(
            undetermined(EffectKind::RailFriction, &friction(-0.1)).len(),
            1
        );
        assert!(undetermined(EffectKind::RailFriction, &friction(0.3)).is_empty());
        assert!(undetermined(EffectKind::HandleMass, &friction(0.0)).is_empty());
    }

    /// A friction at its softest knee (the last of 35) is at the edge while its Coulomb
    /// force is one the rig resolves (0.3 N), and not when it is not (a viscous
    /// friction of 5 N s/m beside 1 mN of Coulomb force: the knee shapes nothing); the
    /// sharpest knee is never an edge, and a reflex delay at either end always is.
    #[test]
    fn a_soft_knee_is_an_edge_only_beside_a_coulomb_force() {
        let friction = |fc: f64| {
            BTreeMap::from([
                ("coulomb_n".to_string(), fc),
                ("viscous_n_s_per_m".to_string(), 5.0),
            ])
        };
        let knee = |s: usize, fc: f64| {
            at_edge(
                Some(EffectKind::RailFriction),
                ("smooth_velocity_m_per_s", 0.01),
                s,
                35,
                &friction(fc),
            )
        };
        assert_eq!(knee(34, 0.3).len(), 1);
        assert!(knee(34, -0.001).is_empty());
        assert!(knee(34, 0.2).is_empty());
        assert!(knee(0, 0.3).is_empty());
        let reflex = |s: usize| {
            at_edge(
                Some(EffectKind::StretchReflex),
                ("delay_ms", 10.0),
                s,
                41,
                &friction(0.0),
            )
        };
        assert_eq!(reflex(0).len(), 1);
        assert_eq!(reflex(40).len(), 1);
    }

    /// The masses, one own column, then the two gains: only a gain at ±10 % is the
    /// bound (within a part in 10⁹ of the bound's width, as the box solver returns it),
    /// named by its axis; a design without bounds (no force sensor) has none.
    #[test]
    fn a_gain_at_its_bound_is_named_by_axis() {
        let bounds = gain_bounds(5);
        assert!(at_gain_bound(&[9.0, 3.0, 1.5, 0.02, -0.099_999], &bounds).is_empty());
        let why = at_gain_bound(&[9.0, 3.0, 1.5, 0.02, -0.1], &bounds);
        assert_eq!(why.len(), 1);
        assert!(why[0].contains("(y at -10 %)"), "{why:?}");
        let why = at_gain_bound(&[9.0, 3.0, 1.5, 0.1, 0.1], &bounds);
        assert!(why[0].contains("(x at +10 %, y at +10 %)"), "{why:?}");
        assert!(at_gain_bound(&[9.0, 3.0, 1.5, 0.1, 0.1], &[]).is_empty());
    }

    /// A grip's range reaching the stiffness grid's last value (as `searched_range`
    /// returns it there: the kept grid value itself, no midpoint beyond) is not told
    /// from a rigid grip, whatever its point estimate; a range ending one grid step
    /// below (5.9 %) is bounded, as is a soft grip's; a range of another parameter is
    /// not read.
    #[test]
    fn a_grip_whose_range_reaches_the_stiffest_searched_is_not_told_from_rigid() {
        let range = |k: &str, lo: f64, hi: f64| BTreeMap::from([(k.to_string(), [lo, hi])]);
        let last = GRIP_STIFFNESS_N_PER_M.2 * crate::hand::GRIP_TIME_S.2 - 1;
        let top = crate::hand::grip_setting(last).0;
        let why = unbounded_grip(&range("stiffness_n_per_m", 44_600.0, top));
        assert_eq!(why.len(), 1);
        assert!(why[0].contains("44.6–50.0 kN/m"), "{why:?}");
        let step = (GRIP_STIFFNESS_N_PER_M.1 / GRIP_STIFFNESS_N_PER_M.0)
            .powf(1.0 / (GRIP_STIFFNESS_N_PER_M.2 - 1) as f64);
        assert!(unbounded_grip(&range("stiffness_n_per_m", 40e3, top / step)).is_empty());
        assert!(unbounded_grip(&range("stiffness_n_per_m", 1.3e3, 1.8e3)).is_empty());
        assert!(unbounded_grip(&range("delay_ms", 20.0, GRIP_STIFFNESS_N_PER_M.1)).is_empty());
    }
}
