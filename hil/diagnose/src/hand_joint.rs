//! Forward selection on the hand balance: the human-side effects already named, each at
//! the setting it was named with, and one more candidate searched over its settings.
//!
//! A subject can hold a heavy handle *and* answer a stretch with a reflex; a grip can be
//! soft on a heavy handle. Fitted alone, one effect's candidate takes up part of the
//! other's response, and the second is judged against a baseline that still carries
//! the first one's. [`HandJoint`] fits them together, like the cart balance's
//! `joint.rs`: the baseline's regressors on the hand's kinematics (through the grip's
//! spring when a grip is a member), then every member's own regressors. A handle mass
//! acts on the handle's acceleration and a reflex on the hand's velocity
//! ([`HandCandidate::extra`]), so the members combine without double counting. A grip's
//! spring carries the extra mass's inertial force as well as the hand's, so with both
//! members the hand's kinematics depend on the mass ([`HandJoint::grip_load_kg`],
//! settled by [`settle_grip_load`]).
//! Its held-out gain is measured against the named effects alone
//! ([`HandJoint::given`]), so it is the gain of the new effect *given* the others.

use std::sync::Arc;

use rayon::prelude::*;

use super::crossval::{CvFit, Folds, cross_validate};
use super::error::DiscrepancyError;
use super::gram::Gram;
use super::hand::{
    HandBaseline, HandCandidate, HandJudgement, Kin, Whitening, base_columns, grip_coarse_settings,
    grip_setting, hand_gram, hand_grams, visit_rows,
};
use super::hand_signals::HandResponse;
use crate::effect::EffectKind;

/// A named human-side effect at the setting it was named with.
pub type HandMember = (Arc<dyn HandCandidate>, usize);

/// A member's effect and catalog parameters (units in the names).
pub type HandMemberParameters = (Option<EffectKind>, Vec<(String, f64)>);

/// Named effects at fixed settings plus one candidate searched over its settings.
#[derive(Clone)]
pub struct HandJoint {
    /// The effects already named, each with its setting.
    pub fixed: Vec<HandMember>,
    /// The candidate searched.
    pub next: Arc<dyn HandCandidate>,
    /// Mass on the handle's side of a grip member's spring beyond the manifest's, kg:
    /// the spring carries `ΔF_hand + m Δa` ([`Kin::grip_loaded`]). 0 without a grip or a
    /// handle-mass member.
    pub grip_load_kg: f64,
}

impl std::fmt::Debug for HandJoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HandJoint")
            .field(
                "fixed",
                &self
                    .fixed
                    .iter()
                    .map(|(c, s)| (c.name(), *s))
                    .collect::<Vec<_>>(),
            )
            .field("next", &self.next.name())
            .field("grip_load_kg", &self.grip_load_kg)
            .finish()
    }
}

impl HandJoint {
    /// The named effects alone (the baseline of the next round's test): the joint model
    /// whose new member is the hand baseline.
    #[must_use]
    pub fn given(fixed: Vec<HandMember>) -> HandJoint {
        HandJoint {
            fixed,
            next: Arc::new(HandBaseline),
            grip_load_kg: 0.0,
        }
    }

    /// The members with the searched one at setting `s`: what this model names once
    /// it enters.
    #[must_use]
    pub fn members_at(&self, s: usize) -> Vec<HandMember> {
        let mut members = self.fixed.clone();
        members.push((self.next.clone(), s));
        members
    }

    /// `fixed` plus `next`, with the grip's load settled ([`settle_grip_load`]): how
    /// forward selection builds each joint it fits.
    ///
    /// # Errors
    /// [`DiscrepancyError::Singular`] when a fit cannot be made.
    pub fn settled(
        fixed: Vec<HandMember>,
        next: Arc<dyn HandCandidate>,
        h: &HandJudgement,
    ) -> Result<HandJoint, DiscrepancyError> {
        settle_grip_load(
            HandJoint {
                fixed,
                next,
                grip_load_kg: 0.0,
            },
            h,
        )
    }

    /// Every member with its setting, the new one at `s` last.
    fn members(&self, s: usize) -> impl Iterator<Item = (&dyn HandCandidate, usize)> {
        self.fixed
            .iter()
            .map(|(c, cs)| (c.as_ref(), *cs))
            .chain([(self.next.as_ref(), s)])
    }

    /// The coefficients of member `i` (`fixed` in order, then `next` at
    /// `i == fixed.len()`) as that member alone lays them out: the baseline's, then its own.
    #[must_use]
    pub fn slice(&self, i: usize, beta: &[f64]) -> Vec<f64> {
        let nb = base_columns();
        let own: Vec<usize> = self.members(0).map(|(c, _)| c.extra_columns()).collect();
        let start = nb + own[..i].iter().sum::<usize>();
        let len = own.get(i).copied().unwrap_or(0);
        beta.iter()
            .take(nb)
            .chain(beta.iter().skip(start).take(len))
            .copied()
            .collect()
    }

    /// Every member's effect and catalog parameters from the joint fit at setting `s` of
    /// the new member, named effects first.
    #[must_use]
    pub fn member_parameters(
        &self,
        s: usize,
        beta: &[f64],
        fb_delay_s: f64,
    ) -> Vec<HandMemberParameters> {
        self.members(s)
            .enumerate()
            .map(|(i, (c, cs))| (c.kind(), c.parameters(cs, &self.slice(i, beta), fb_delay_s)))
            .collect()
    }
}

impl HandCandidate for HandJoint {
    fn kind(&self) -> Option<EffectKind> {
        self.next.kind()
    }
    fn name(&self) -> &'static str {
        self.next.name()
    }
    fn settings(&self) -> usize {
        self.next.settings()
    }
    fn setting(&self, s: usize) -> (&'static str, f64) {
        self.next.setting(s)
    }
    fn search_position(&self, s: usize) -> (usize, usize) {
        self.next.search_position(s)
    }
    fn on_the_line_of(&self, s: usize, of: usize) -> bool {
        self.next.on_the_line_of(s, of)
    }
    fn columns(&self) -> usize {
        base_columns()
            + self
                .members(0)
                .map(|(c, _)| c.extra_columns())
                .sum::<usize>()
    }
    fn rows(&self, r: &HandResponse, s: usize, fb: f64, f: &mut dyn FnMut(&[f64], f64, f64)) {
        // The hand's kinematics: a grip member's (at most one grip is a member),
        // loaded with the extra mass when one is a member too.
        let kin = self
            .members(s)
            .find_map(|(c, cs)| {
                if self.grip_load_kg != 0.0 && c.kind() == Some(EffectKind::GripCompliance) {
                    let (k, tau) = grip_setting(cs);
                    Some(Kin::grip_loaded(r, k, tau, self.grip_load_kg))
                } else {
                    c.hand_kin(r, cs)
                }
            })
            .unwrap_or_else(|| Kin::rigid(r));
        let members: Vec<(&dyn HandCandidate, usize)> = self.members(s).collect();
        visit_rows(
            r,
            &kin,
            fb * r.rate_hz,
            self.columns(),
            |axis, j, out| {
                let mut at = 0;
                for (c, cs) in &members {
                    let n = c.extra_columns();
                    c.extra(r, &kin, *cs, axis, j, &mut out[at..at + n]);
                    at += n;
                }
            },
            f,
        );
    }
    fn parameters(&self, s: usize, beta: &[f64], fb: f64) -> Vec<(String, f64)> {
        self.next
            .parameters(s, &self.slice(self.fixed.len(), beta), fb)
    }
    fn physical(&self, s: usize, beta: &[f64]) -> bool {
        self.members(s)
            .enumerate()
            .all(|(i, (c, cs))| c.physical(cs, &self.slice(i, beta)))
    }
    /// Every member's bounds on its own columns, where the joint lays them out.
    fn bounds(&self) -> Vec<(usize, f64, f64)> {
        let nb = base_columns();
        let mut at = nb;
        let mut out = Vec::new();
        for (c, _) in self.members(0) {
            for (col, lo, hi) in c.bounds() {
                out.push((if col < nb { col } else { at + col - nb }, lo, hi));
            }
            at += c.extra_columns();
        }
        out
    }
}

/// A candidate's fit on the hand balance's units and, when the units average
/// repetitions, on the independent repetitions the test runs on.
#[derive(Debug)]
pub struct HandJointFit {
    /// On the fitted units (parameters, gain).
    pub fit: CvFit,
    /// On the repetitions (the test), when there are.
    pub test: Option<CvFit>,
}

/// Cross-validates `c` on the units and the repetitions of `h`, with its feedback delay
/// and weighting.
///
/// # Errors
/// [`DiscrepancyError::Singular`] when a fold cannot be fitted.
pub fn fit_on_units(
    h: &HandJudgement,
    c: &dyn HandCandidate,
) -> Result<HandJointFit, DiscrepancyError> {
    let cv = |units: &[HandResponse], folds: &Folds| {
        let grams: Vec<_> = units
            .par_iter()
            .map(|r| hand_grams(c, r, h.fb_delay_s, &h.whitening))
            .collect();
        cross_validate(&grams, folds, c.name())
    };
    let fit = cv(&h.responses, &h.folds)?;
    let test = h
        .replicates
        .as_ref()
        .map(|rep| cv(&rep.units, &rep.folds))
        .transpose()?;
    Ok(HandJointFit { fit, test })
}

/// Coordinate descent over the named members' settings, as on the cart balance: each
/// member but the last is searched again with every other member at its setting (on all
/// units, the setting the cross-validation chooses on all of them), once in order.
///
/// # Errors
/// [`DiscrepancyError::Singular`] when a member cannot be fitted.
pub fn refine(
    members: &[HandMember],
    h: &HandJudgement,
) -> Result<Vec<HandMember>, DiscrepancyError> {
    let mut m = members.to_vec();
    for i in 0..m.len().saturating_sub(1) {
        if m[i].0.settings() < 2 {
            continue;
        }
        let fixed = m
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, x)| x.clone())
            .collect();
        let joint = HandJoint::settled(fixed, m[i].0.clone(), h)?;
        let grams: Vec<_> = h
            .responses
            .par_iter()
            .map(|r| hand_grams(&joint, r, h.fb_delay_s, &h.whitening))
            .collect();
        m[i].1 = cross_validate(&grams, &h.folds, joint.name())?.setting;
    }
    Ok(m)
}

/// Grip loads searched, kg: `(first, last, count)`, a uniform grid (20 g a step) from
/// none to 3 kg, then a parabola through the least and its neighbours. An adapter or
/// a grip tube weighs well under a kilogram; 3 kg is a second cart's worth, beyond
/// which a load is not an unlisted part.
pub const GRIP_LOAD_KG: (f64, f64, usize) = (0.0, 3.0, 151);

/// Most rounds of [`settle_grip_load`]'s polish (the searched member's setting, then
/// the load at it); it stops earlier when a round chooses the setting of the round
/// before. From the profile's load, on a reflex study's sessions hiding a grip and a
/// mass, it mostly settles within 4 (at most 9).
pub const GRIP_LOAD_ROUNDS: usize = 10;

/// Every how many points of [`GRIP_LOAD_KG`] [`settle_grip_load`]'s profile evaluates
/// (0.2 kg apart: 16 loads). The profile is smooth on that scale: the grip's stiffness
/// and the load trade along a ridge a few hundred grams wide.
pub const GRIP_PROFILE_STRIDE: usize = 10;

/// `joint` with [`HandJoint::grip_load_kg`] set to the load that fits it best, when a
/// grip and a handle mass are both members: the mass enters the grip's kinematics,
/// which the balance multiplies by the subject's unknown `D` and `K`, so it is not a
/// linear coefficient there. The load is one number, chosen like a setting, in two
/// steps:
/// 1. **The profile**, when the searched member is the grip. On every
///    [`GRIP_PROFILE_STRIDE`]-th load of [`GRIP_LOAD_KG`], the least squared error on
///    all units over the grip's coarse settings (every other stiffness, every third
///    time constant); the load whose best setting leaves the least error starts the
///    polish (otherwise it starts from no load). A soft grip and a heavier
///    handle trade along a ridge, and a walk along it from no load, where a soft grip
///    fits worst, first takes the stiffest grip of the grid and then the heaviest load
///    (a 2.6 kN/m grip behind 0.99 kg came out 5.6 kN/m and 1.27 kg after 12 rounds,
///    the error still falling every round).
/// 2. **The polish.** Rounds of the setting the cross-validation chooses on all units
///    at the current load, then the load whose joint fit at that setting leaves the
///    least squared error ([`least_sse_load`], on the whole grid), until a round
///    chooses the setting the round before chose (a fixed point), at most
///    [`GRIP_LOAD_ROUNDS`]. A fixed two rounds stopped on the ridge (5000 N/m and
///    0.50 kg for 5734 N/m and 0.45 kg), leaving a misfit that a later round named as
///    a reflex.
///
/// The folds that judge the joint see no more of the held-out units than the setting
/// does. The load is searched rather than taken from the mass the last fit found: that
/// fixed point converges slowly where the grip is soft, and can run to a negative mass
/// (the measurements: `hil/docs/notes/2026-12-03-hand-balance-settings.md`,
/// `hil/docs/notes/2026-12-04-grip-time-grid.md`). Other joints are returned as they
/// are.
///
/// # Errors
/// [`DiscrepancyError::Singular`] when a fit cannot be made.
pub fn settle_grip_load(
    mut joint: HandJoint,
    h: &HandJudgement,
) -> Result<HandJoint, DiscrepancyError> {
    let kinds: Vec<Option<EffectKind>> = joint.members(0).map(|(c, _)| c.kind()).collect();
    if !kinds.contains(&Some(EffectKind::HandleMass))
        || !kinds.contains(&Some(EffectKind::GripCompliance))
    {
        return Ok(joint);
    }
    if joint.next.kind() == Some(EffectKind::GripCompliance) {
        let (first, last, n) = GRIP_LOAD_KG;
        let step = (last - first) / (n - 1) as f64;
        let mut profile = Vec::new();
        let coarse: Vec<usize> = grip_coarse_settings().collect();
        for i in (0..n).step_by(GRIP_PROFILE_STRIDE) {
            joint.grip_load_kg = first + step * i as f64;
            if let Some(sse) = least_sse(&joint, &coarse, h) {
                profile.push((joint.grip_load_kg, sse));
            }
        }
        joint.grip_load_kg = profile
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or_else(|| DiscrepancyError::Singular {
                what: format!("{} with a loaded grip", joint.name()),
            })?
            .0;
    }
    let mut last = None;
    for _ in 0..GRIP_LOAD_ROUNDS {
        let grams: Vec<_> = h
            .responses
            .par_iter()
            .map(|r| hand_grams(&joint, r, h.fb_delay_s, &h.whitening))
            .collect();
        let setting = cross_validate(&grams, &h.folds, joint.name())?.setting;
        if last == Some(setting) {
            break;
        }
        joint.grip_load_kg =
            least_sse_load(&joint, setting, &h.responses, h.fb_delay_s, &h.whitening)?;
        last = Some(setting);
    }
    Ok(joint)
}

/// The least squared error of `joint`'s fit on all units over `settings` of its
/// searched member; `None` when none can be fitted.
fn least_sse(joint: &HandJoint, settings: &[usize], h: &HandJudgement) -> Option<f64> {
    settings
        .par_iter()
        .filter_map(|&s| sse_on_all(joint, s, &h.responses, h.fb_delay_s, &h.whitening))
        .filter(|sse| sse.is_finite())
        .min_by(f64::total_cmp)
}

/// The squared error of `joint`'s fit at `setting` on all `responses` together
/// (weighted by `w`, with the feedback delay `fb_delay_s`); `None` when it cannot be
/// fitted.
fn sse_on_all(
    joint: &HandJoint,
    setting: usize,
    responses: &[HandResponse],
    fb_delay_s: f64,
    w: &Whitening,
) -> Option<f64> {
    let grams: Vec<Gram> = responses
        .iter()
        .map(|r| hand_gram(joint, r, setting, fb_delay_s, w))
        .collect();
    let g = Gram::sum(joint.columns(), grams.iter());
    g.solve().map(|b| g.sse(&b))
}

/// The grip load of [`GRIP_LOAD_KG`] whose joint fit at `setting` on all `responses`
/// (weighted by `w`, with the feedback delay `fb_delay_s`) leaves the least squared
/// error, refined by a parabola through the grid's least point and its neighbours (the
/// grid point itself at the grid's ends or where the parabola opens downwards).
///
/// # Errors
/// [`DiscrepancyError::Singular`] when no load can be fitted.
pub fn least_sse_load(
    joint: &HandJoint,
    setting: usize,
    responses: &[HandResponse],
    fb_delay_s: f64,
    w: &Whitening,
) -> Result<f64, DiscrepancyError> {
    let (first, last, n) = GRIP_LOAD_KG;
    let step = (last - first) / (n - 1) as f64;
    let sse: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut j = joint.clone();
            j.grip_load_kg = first + step * i as f64;
            sse_on_all(&j, setting, responses, fb_delay_s, w).unwrap_or(f64::INFINITY)
        })
        .collect();
    let best = (0..n)
        .filter(|i| sse[*i].is_finite())
        .min_by(|a, b| sse[*a].total_cmp(&sse[*b]))
        .ok_or_else(|| DiscrepancyError::Singular {
            what: format!("{} with a loaded grip", joint.name()),
        })?;
    let at = first + step * best as f64;
    if best == 0 || best == n - 1 {
        return Ok(at);
    }
    let (a, b, c) = (sse[best - 1], sse[best], sse[best + 1]);
    let curvature = a - 2.0 * b + c;
    Ok(if curvature > 0.0 && curvature.is_finite() {
        at + 0.5 * step * (a - c) / curvature
    } else {
        at
    })
}
