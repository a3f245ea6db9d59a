//! Forward selection's joint model: the plant effects already named, each at the
//! setting it was named with, and one more candidate searched over its settings.
//!
//! A rig has friction *and* cogging; fitted alone, each candidate takes up part of the
//! other's force (a ripple's slow sine leans on a friction's reversals), and a second
//! effect is judged against a baseline that still carries the first one's residual.
//! [`Joint`] fits them together: the regressors are the masses, the named effects' own
//! regressors, the new candidate's and the force gains; the balance's command and
//! sensor force are reshaped by whichever member delays or turns them
//! ([`Design::joined`]). Its held-out gain is measured against the named effects alone
//! ([`Joint::given`] with the [`Baseline`] as the new member), so it is the gain of the
//! new effect *given* the others.
//!
//! The named effects keep their settings (pitch, delay, angle, knee); their linear
//! coefficients are refitted with the new member's, so the joint parameters of every
//! member are read from one fit ([`Joint::member_parameters`]).

use std::sync::Arc;

use rayon::prelude::*;

use super::candidate::{Baseline, Candidate, Design, Designed, NUISANCE_COLUMNS, Reshape};
use super::error::DiscrepancyError;
use super::gram::Gram;
use super::signals::BalanceSignals;

/// A named effect at the setting it was named with.
pub type Member = (Arc<dyn Candidate>, usize);

/// A member's catalog name and parameters (units in the names).
pub type MemberParameters = (&'static str, Vec<(String, f64)>);

/// Named effects at fixed settings plus one candidate searched over its settings.
#[derive(Clone)]
pub struct Joint {
    /// The effects already named, each with its setting.
    pub fixed: Vec<Member>,
    /// The candidate searched.
    pub next: Arc<dyn Candidate>,
}

impl std::fmt::Debug for Joint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Joint")
            .field(
                "fixed",
                &self
                    .fixed
                    .iter()
                    .map(|(c, s)| (c.name(), *s))
                    .collect::<Vec<_>>(),
            )
            .field("next", &self.next.name())
            .finish()
    }
}

impl Joint {
    /// The named effects alone (the baseline of the next round's test): the joint model
    /// whose new member is the nominal balance.
    #[must_use]
    pub fn given(fixed: Vec<Member>) -> Joint {
        Joint {
            fixed,
            next: Arc::new(Baseline),
        }
    }

    /// The named effects' balance on one trial, every member at its setting.
    ///
    /// # Errors
    /// A signal-processing error while smoothing a regressor.
    pub fn base(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Design, DiscrepancyError> {
        let mut d = Design::nominal(sig, latency_s);
        for (c, s) in &self.fixed {
            d = d.joined(&c.design(sig, *s, latency_s)?, c.reshapes());
        }
        Ok(d)
    }

    /// Own regressors of a member (masses and force gains excluded).
    fn own(c: &dyn Candidate) -> usize {
        c.columns().saturating_sub(2)
    }

    /// The coefficients of member `i` (`fixed` in order, then `next` at
    /// `i == fixed.len()`) as that member alone lays them out: masses, its own, the
    /// force gains.
    #[must_use]
    pub fn slice(&self, i: usize, beta: &[f64]) -> Vec<f64> {
        let members: Vec<&dyn Candidate> = self
            .fixed
            .iter()
            .map(|(c, _)| c.as_ref())
            .chain([self.next.as_ref()])
            .collect();
        let start = 2 + members[..i].iter().map(|c| Joint::own(*c)).sum::<usize>();
        let len = members.get(i).map_or(0, |c| Joint::own(*c));
        let n = beta.len();
        beta.iter()
            .take(2)
            .chain(beta.iter().skip(start).take(len))
            .chain(beta.iter().skip(n.saturating_sub(NUISANCE_COLUMNS)))
            .copied()
            .collect()
    }

    /// Every member's catalog parameters from the joint fit at setting `s` of the new
    /// member, named effects first.
    #[must_use]
    pub fn member_parameters(
        &self,
        s: usize,
        beta: &[f64],
        latency_s: f64,
    ) -> Vec<MemberParameters> {
        self.fixed
            .iter()
            .enumerate()
            .map(|(i, (c, cs))| (c.name(), c.parameters(*cs, &self.slice(i, beta), latency_s)))
            .chain([(
                self.next.name(),
                self.next
                    .parameters(s, &self.slice(self.fixed.len(), beta), latency_s),
            )])
            .collect()
    }
}

/// Coordinate descent over the named members' settings: each member but the last
/// (which was just searched with the others fixed) is searched again with every other
/// member at its setting, on all trials (least total squared residual), once in
/// order. A setting chosen alone can be pulled by an effect it did not model (a
/// friction knee by cogging at the reversals); given the others it returns to its own.
///
/// # Errors
/// A signal-processing error while smoothing a regressor; [`DiscrepancyError::Singular`]
/// when no setting of a member can be fitted.
pub fn refine(
    members: &[Member],
    signals: &[BalanceSignals],
    latency_s: f64,
) -> Result<Vec<Member>, DiscrepancyError> {
    let mut m = members.to_vec();
    for i in 0..m.len().saturating_sub(1) {
        let joint = Joint {
            fixed: m
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, x)| x.clone())
                .collect(),
            next: m[i].0.clone(),
        };
        let grams = signals
            .par_iter()
            .map(|s| joint.grams(s, latency_s))
            .collect::<Result<Vec<_>, _>>()?;
        let p = joint.columns() + NUISANCE_COLUMNS;
        let sse = |s: usize| {
            let g = Gram::sum(p, grams.iter().map(|t| &t[s]));
            g.solve().map_or(f64::INFINITY, |b| g.sse(&b))
        };
        m[i].1 = (0..joint.settings())
            .map(|s| (s, sse(s)))
            .filter(|(_, e)| e.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(s, _)| s)
            .ok_or_else(|| DiscrepancyError::Singular {
                what: format!("{} given the other named effects", joint.name()),
            })?;
    }
    Ok(m)
}

impl Designed for Joint {
    fn design(
        &self,
        sig: &BalanceSignals,
        s: usize,
        latency_s: f64,
    ) -> Result<Design, DiscrepancyError> {
        Ok(self
            .base(sig, latency_s)?
            .joined(&self.next.design(sig, s, latency_s)?, self.next.reshapes()))
    }
}

impl Candidate for Joint {
    /// The new member's name: the joint model judges it.
    fn name(&self) -> &'static str {
        self.next.name()
    }
    fn kind(&self) -> Option<crate::effect::EffectKind> {
        self.next.kind()
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
    fn columns(&self) -> usize {
        2 + self
            .fixed
            .iter()
            .map(|(c, _)| Joint::own(c.as_ref()))
            .sum::<usize>()
            + Joint::own(self.next.as_ref())
    }
    fn grams(&self, sig: &BalanceSignals, latency_s: f64) -> Result<Vec<Gram>, DiscrepancyError> {
        let base = self.base(sig, latency_s)?;
        self.next.grams_given(sig, latency_s, &base)
    }
    fn reshapes(&self) -> Reshape {
        self.next.reshapes()
    }
    /// The new member's parameters (the named ones': [`Joint::member_parameters`]).
    fn parameters(&self, s: usize, beta: &[f64], latency_s: f64) -> Vec<(String, f64)> {
        self.next
            .parameters(s, &self.slice(self.fixed.len(), beta), latency_s)
    }
    fn effect_force(&self, s: usize, beta: &[f64], axis: usize, q: f64, v: f64) -> Option<f64> {
        self.next
            .effect_force(s, &self.slice(self.fixed.len(), beta), axis, q, v)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use std::f64::consts::TAU;

    use super::*;
    use crate::candidate::tests::simulate_carts;
    use crate::delay::ActuationDelay;
    use crate::friction::RailFriction;
    use crate::ripple::ForceRipple;
    use crate::rotation::SensorRotation;

    const TICK_S: f64 = 2.5e-4;
    const MASS_KG: [f64; 2] = [12.0, 4.0];
    const COULOMB_N: f64 = 2.0;
    const VISCOUS_N_S_PER_M: f64 = 5.0;
    const KNEE_M_PER_S: f64 = 1e-3;
    const PITCH_M: f64 = 0.03;
    const AMPLITUDE_N: [f64; 2] = [1.5, 2.5];
    const PHASE_RAD: [f64; 2] = [0.4, -1.9];
    const ANGLE_DEG: f64 = 12.0;

    /// Carts of 12 and 4 kg integrated at 4 kHz (semi-implicit Euler) under a command
    /// tracking reaches back and forth over ±6 cm, a slow hand force, rail friction
    /// `−(Fc tanh(v/v_s) + b v)` and per-axis cogging `A sin(2π q/p + φ)`; the sensor
    /// reads the hand force turned by `angle_deg`; without cogging when `cog` is false.
    /// Logged at 1 kHz as 4-tick means.
    fn rig_trial(
        seed: f64,
        angle_deg: f64,
        cog: bool,
    ) -> (rigtwin_session::TrialEntry, rigtwin_session::Trial) {
        let (sn, cs) = angle_deg.to_radians().sin_cos();
        simulate_carts(16_000, |k, x, v| {
            let t = k as f64 * TICK_S;
            let goal = [
                0.06 * (TAU * 0.5 * t + seed).sin(),
                0.05 * (TAU * 0.37 * t + 2.0 * seed).cos(),
            ];
            let hand = [
                1.5 * (TAU * 1.3 * t + seed).sin(),
                1.0 * (TAU * 0.9 * t).cos(),
            ];
            let cmd: [f64; 2] =
                std::array::from_fn(|a| 400.0 * (goal[a] - x[a]) - 15.0 * v[a] * MASS_KG[a]);
            let read = [cs * hand[0] - sn * hand[1], sn * hand[0] + cs * hand[1]];
            let force = std::array::from_fn(|a| {
                let friction = COULOMB_N * (v[a] / KNEE_M_PER_S).tanh() + VISCOUS_N_S_PER_M * v[a];
                let cog = if cog {
                    AMPLITUDE_N[a] * (TAU * x[a] / PITCH_M + PHASE_RAD[a]).sin()
                } else {
                    0.0
                };
                cmd[a] + hand[a] + cog - friction
            });
            [read, cmd, force]
        })
    }

    fn signals(angle_deg: f64, cog: bool) -> Vec<BalanceSignals> {
        (0..4)
            .map(|i| {
                let (e, t) = rig_trial(0.7 * f64::from(i), angle_deg, cog);
                BalanceSignals::from_trial(&e, &t, 1000.0).unwrap().unwrap()
            })
            .collect()
    }

    fn fit(c: &dyn Candidate, sig: &[BalanceSignals]) -> (usize, Vec<f64>, f64) {
        let grams: Vec<Vec<Gram>> = sig.iter().map(|s| c.grams(s, 0.0).unwrap()).collect();
        (0..c.settings())
            .map(|s| {
                let g = Gram::sum(c.columns() + NUISANCE_COLUMNS, grams.iter().map(|t| &t[s]));
                let b = g.solve().unwrap();
                let e = (g.sse(&b) / g.norm_sq).sqrt();
                (s, b, e)
            })
            .min_by(|a, b| a.2.total_cmp(&b.2))
            .unwrap()
    }

    fn param(p: &[(String, f64)], k: &str) -> f64 {
        p.iter().find(|(n, _)| n == k).map(|(_, v)| *v).unwrap()
    }

    /// Friction and cogging on one rig: joined, the ripple's search given friction
    /// finds the true pitch; with friction's knee refined given the ripple, both laws'
    /// parameters come out to 3 % (the simulated law is exact, the tolerance covers the
    /// 4-tick logging and the balance filter, which passes the ripple ~1 % low), with a
    /// residual below 1 % of the command (friction alone on the same rig without
    /// cogging: 0.23 %); each alone leaves at least 10 times the joint residual.
    #[test]
    fn friction_and_ripple_are_fitted_jointly() {
        let sig = signals(0.0, true);
        let friction: Arc<dyn Candidate> = Arc::new(RailFriction);
        let ripple: Arc<dyn Candidate> = Arc::new(ForceRipple::for_travel(0.12));
        let (sf, _, e_friction) = fit(friction.as_ref(), &sig);
        let (_, _, e_ripple) = fit(ripple.as_ref(), &sig);
        let joint = Joint {
            fixed: vec![(friction.clone(), sf)],
            next: ripple.clone(),
        };
        let (s, _, e_first) = fit(&joint, &sig);
        // Friction's knee, chosen alone, is pulled by the cogging; refined given the
        // ripple it returns to its own, and the ripple is searched again given it.
        let refined = refine(&[(friction.clone(), sf), (ripple.clone(), s)], &sig, 0.0).unwrap();
        assert_eq!(refined[1].1, s, "the last member keeps its setting");
        let joint = Joint {
            fixed: vec![refined[0].clone()],
            next: ripple.clone(),
        };
        let (s, beta, e_joint) = fit(&joint, &sig);
        eprintln!(
            "NRMSE: friction {e_friction:.4}, ripple {e_ripple:.4}, joint {e_first:.4}, refined {e_joint:.4}; knee {} -> {}",
            friction.setting(sf).1,
            friction.setting(refined[0].1).1
        );
        assert!(e_joint < 0.01, "joint NRMSE {e_joint}");
        assert!(e_friction > 10.0 * e_joint && e_ripple > 10.0 * e_joint);
        let members = joint.member_parameters(s, &beta, 0.0);
        assert_eq!(members[0].0, "rail-friction");
        let (f, r) = (&members[0].1, &members[1].1);
        let close = |got: f64, want: f64, what: &str| {
            assert!(
                (got - want).abs() < 0.03 * want.abs(),
                "{what}: {got} vs {want}"
            );
        };
        close(param(f, "coulomb_n"), COULOMB_N, "coulomb");
        close(param(f, "viscous_n_s_per_m"), VISCOUS_N_S_PER_M, "viscous");
        close(param(r, "pitch_m"), PITCH_M, "pitch");
        close(param(r, "amplitude_x_n"), AMPLITUDE_N[0], "amplitude x");
        close(param(r, "amplitude_y_n"), AMPLITUDE_N[1], "amplitude y");
        close(beta[0], MASS_KG[0], "mass x");
        close(beta[1], MASS_KG[1], "mass y");
    }

    /// The fast paths given a base equal the joined designs' Grams: ripple and rotation
    /// after friction, rotation after a delay (the base reshapes the command), and the
    /// default path of a delay after a rotation (the base reshapes the force).
    #[test]
    fn joined_fast_grams_equal_the_joined_designs() {
        let sig = &signals(ANGLE_DEG, true)[0];
        let friction: Arc<dyn Candidate> = Arc::new(RailFriction);
        let delay: Arc<dyn Candidate> = Arc::new(ActuationDelay::candidate());
        let rotation: Arc<dyn Candidate> = Arc::new(SensorRotation::default());
        let ripple: Arc<dyn Candidate> = Arc::new(ForceRipple::for_travel(0.12));
        for (fixed, next, settings) in [
            ((friction.clone(), 2), ripple.clone(), vec![0, 40, 170]),
            ((friction.clone(), 2), rotation.clone(), vec![0, 1140, 1800]),
            ((delay.clone(), 40), rotation.clone(), vec![3, 1140]),
            ((rotation.clone(), 1140), delay.clone(), vec![0, 40]),
        ] {
            let joint = Joint {
                fixed: vec![fixed],
                next,
            };
            let fast = joint.grams(sig, 1e-4).unwrap();
            for s in settings {
                let slow = joint.design(sig, s, 1e-4).unwrap().gram(sig);
                crate::candidate::tests::assert_same_gram(&fast[s], &slow);
            }
        }
    }

    /// A rotated sensor on a rig with friction: the rotation searched given friction
    /// finds the angle to 0.1° and friction keeps its parameters to 3 %.
    #[test]
    fn rotation_given_friction_finds_the_angle() {
        let sig = signals(ANGLE_DEG, false);
        let friction: Arc<dyn Candidate> = Arc::new(RailFriction);
        let rotation: Arc<dyn Candidate> = Arc::new(SensorRotation::default());
        let (sf, _, _) = fit(friction.as_ref(), &sig);
        let joint = Joint {
            fixed: vec![(friction, sf)],
            next: rotation,
        };
        let (s, beta, e) = fit(&joint, &sig);
        let members = joint.member_parameters(s, &beta, 0.0);
        let angle = param(&members[1].1, "angle_deg");
        eprintln!("angle {angle:.3}°, NRMSE {e:.4}");
        assert!((angle - ANGLE_DEG).abs() < 0.1, "angle {angle}");
        let fc = param(&members[0].1, "coulomb_n");
        assert!((fc - COULOMB_N).abs() < 0.03 * COULOMB_N, "coulomb {fc}");
    }
}
