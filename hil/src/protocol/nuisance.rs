//! A realistic rig and subject: the small imperfections every real session has, drawn
//! per session and per trial from the ranges of the protocol's `[nuisance]` table.
//!
//! None of them is a catalog effect. They are what a diagnosis must take as part of the
//! nominal model (and what makes the sessions a diagnosis is tested on look like a
//! lab's rather than like an ideal generator's). Per session: the force sensor's tare
//! error and the direction and size of its drift, its noise, each motor's force-constant
//! error and current-loop noise, the spread and bias of the subject's start and end
//! points, and the trend of the subject's impedance. Per trial: where the drift has got
//! to (linear in the trial's place in the session), a re-tare scatter, the reaction time
//! and the reach's duration (so trial files differ in length), the start and end points,
//! a trial-to-trial wobble of the impedance, and the trigger's lag (the pulse starts 0–4
//! ticks of the 4 kHz loop after the onset the rig logs; its perturbation columns hold
//! the pulse where it acted).
//!
//! The ranges of [`NuisanceConfig::REALISTIC`] are those a lab meets (force sensors tared
//! to a few tenths of a newton and drifting a tenth over a session; force constants
//! specified to a few percent and calibrated to about one; reaches paced by a 3 s
//! metronome that subjects keep to about ±10 %; reaction times of 200–350 ms; end points
//! scattered by a few millimetres; impedance that drifts with fatigue and attention by
//! up to ±10 % over a session; a trigger logged up to a millisecond before the pulse
//! acts), and they cover the disclosed nuisances of the shared
//! realistic sessions (`../shared/recordings/README.md`).
//!
//! Drawing is a pure function of the session seed, the subject and the trial index
//! ([`super::seed`]), so the same protocol and seed give the same sessions.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigtwin_world::RigNuisance;
use serde::{Deserialize, Serialize};

use super::seed::{Stream, mix, trial_seed};
use super::{Checker, Protocol, VirtualSubject, whole_ticks};

/// The ranges the nuisances are drawn from. A range `[lo, hi]` is drawn uniformly; a
/// single bound `b` is drawn uniformly in `[−b, b]` unless said otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NuisanceConfig {
    /// Size of the force sensor's tare error per axis, N (sign drawn), per session.
    pub sensor_offset_n: [f64; 2],
    /// Bound of the sensor's drift over the whole session per axis, N.
    pub sensor_drift_n: f64,
    /// Standard deviation of a per-trial re-tare scatter, N (0: the rig tares once).
    pub retare_sd_n: f64,
    /// Range of the sensor's white noise RMS per axis at 4 kHz, N, per session.
    pub sensor_noise_rms_n: [f64; 2],
    /// Bound of each motor's force-constant error, fraction.
    pub motor_gain_tolerance: f64,
    /// Range of the current-loop noise RMS, N, per session.
    pub motor_noise_rms_n: [f64; 2],
    /// Bandwidth of the current-loop noise, Hz.
    pub motor_noise_bw_hz: f64,
    /// Range of the reaction time (the still phase before the reach), s, per trial.
    pub reaction_s: [f64; 2],
    /// Bound of the reach duration's relative deviation from the protocol's, per trial.
    pub movement_spread: f64,
    /// Range of the standard deviation of start and end points per axis, m, per session.
    pub endpoint_sd_m: [f64; 2],
    /// Bound of the subject's endpoint bias per axis, m, per session.
    pub endpoint_bias_m: f64,
    /// Bound of the impedance's relative trend over the session.
    pub impedance_trend: f64,
    /// Standard deviation of the impedance's trial-to-trial relative wobble.
    pub impedance_wobble: f64,
    /// Bound of the trigger's lag, ticks of the 4 kHz loop: the pulse reaches the
    /// admittance input 0 to this many ticks after the onset the rig logs, drawn
    /// uniformly per trial (the perturbation columns hold the pulse where it acted).
    pub trigger_jitter_ticks: u32,
}

impl NuisanceConfig {
    /// A lab's rig and subject (module docs).
    pub const REALISTIC: NuisanceConfig = NuisanceConfig {
        sensor_offset_n: [0.05, 0.3],
        sensor_drift_n: 0.1,
        retare_sd_n: 0.0,
        sensor_noise_rms_n: [0.05, 0.15],
        motor_gain_tolerance: 0.01,
        motor_noise_rms_n: [0.1, 0.3],
        motor_noise_bw_hz: 200.0,
        reaction_s: [0.20, 0.35],
        movement_spread: 0.13,
        endpoint_sd_m: [0.002, 0.004],
        endpoint_bias_m: 0.0025,
        impedance_trend: 0.10,
        impedance_wobble: 0.02,
        trigger_jitter_ticks: 4,
    };
}

impl Default for NuisanceConfig {
    fn default() -> Self {
        NuisanceConfig::REALISTIC
    }
}

fn range(c: &mut Checker, key: &str, r: [f64; 2]) {
    c.non_negative2(key, r);
    if r[0] > r[1] {
        c.fail(key, format!("must be [lo, hi] with lo <= hi, got {r:?}"));
    }
}

impl NuisanceConfig {
    /// Every bound non-negative, every range ordered, the spread below 1.
    pub(super) fn check(&self, c: &mut Checker) {
        range(c, "nuisance.sensor_offset_n", self.sensor_offset_n);
        range(c, "nuisance.sensor_noise_rms_n", self.sensor_noise_rms_n);
        range(c, "nuisance.motor_noise_rms_n", self.motor_noise_rms_n);
        range(c, "nuisance.reaction_s", self.reaction_s);
        range(c, "nuisance.endpoint_sd_m", self.endpoint_sd_m);
        for (k, v) in [
            ("nuisance.sensor_drift_n", self.sensor_drift_n),
            ("nuisance.retare_sd_n", self.retare_sd_n),
            ("nuisance.endpoint_bias_m", self.endpoint_bias_m),
            ("nuisance.impedance_wobble", self.impedance_wobble),
        ] {
            c.non_negative(k, v);
        }
        for (k, v) in [
            ("nuisance.motor_gain_tolerance", self.motor_gain_tolerance),
            ("nuisance.movement_spread", self.movement_spread),
            ("nuisance.impedance_trend", self.impedance_trend),
        ] {
            c.non_negative(k, v);
            if v >= 0.5 {
                c.fail(k, format!("must be below 0.5, got {v}"));
            }
        }
        c.positive("nuisance.motor_noise_bw_hz", self.motor_noise_bw_hz);
    }
}

/// What one session draws once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionNuisance {
    /// Tare error per axis, N.
    pub sensor_offset_n: [f64; 2],
    /// Drift over the session per axis, N.
    pub sensor_drift_n: [f64; 2],
    /// Sensor noise RMS, N.
    pub sensor_noise_rms_n: f64,
    /// Force-constant ratio per axis.
    pub motor_gain: [f64; 2],
    /// Current-loop noise RMS, N.
    pub motor_noise_rms_n: f64,
    /// Scatter of start and end points per axis, m.
    pub endpoint_sd_m: [f64; 2],
    /// Endpoint bias per axis, m.
    pub endpoint_bias_m: [f64; 2],
    /// Relative impedance change from the first to the last trial.
    pub impedance_trend: f64,
}

fn uniform(rng: &mut ChaCha8Rng, r: [f64; 2]) -> f64 {
    if r[1] > r[0] {
        rng.random_range(r[0]..r[1])
    } else {
        r[0]
    }
}

fn symmetric(rng: &mut ChaCha8Rng, b: f64) -> f64 {
    if b > 0.0 {
        rng.random_range(-b..b)
    } else {
        0.0
    }
}

fn normal(rng: &mut ChaCha8Rng, sd: f64) -> f64 {
    use rand_distr::{Distribution, StandardNormal};
    let z: f64 = StandardNormal.sample(rng);
    sd * z
}

impl SessionNuisance {
    /// The draws of `subject`'s session with `session_seed`.
    #[must_use]
    pub fn draw(cfg: &NuisanceConfig, session_seed: u64, subject: u32) -> SessionNuisance {
        let mut rng =
            ChaCha8Rng::seed_from_u64(mix(&[session_seed, u64::from(subject), 0x4E55_15A4]));
        let signed = |rng: &mut ChaCha8Rng| {
            let m = uniform(rng, cfg.sensor_offset_n);
            if rng.random_bool(0.5) { m } else { -m }
        };
        let sensor_offset_n = [signed(&mut rng), signed(&mut rng)];
        let sensor_drift_n = [
            symmetric(&mut rng, cfg.sensor_drift_n),
            symmetric(&mut rng, cfg.sensor_drift_n),
        ];
        let sensor_noise_rms_n = uniform(&mut rng, cfg.sensor_noise_rms_n);
        let motor_gain = [
            1.0 + symmetric(&mut rng, cfg.motor_gain_tolerance),
            1.0 + symmetric(&mut rng, cfg.motor_gain_tolerance),
        ];
        let motor_noise_rms_n = uniform(&mut rng, cfg.motor_noise_rms_n);
        let sd = uniform(&mut rng, cfg.endpoint_sd_m);
        let endpoint_bias_m = [
            symmetric(&mut rng, cfg.endpoint_bias_m),
            symmetric(&mut rng, cfg.endpoint_bias_m),
        ];
        SessionNuisance {
            sensor_offset_n,
            sensor_drift_n,
            sensor_noise_rms_n,
            motor_gain,
            motor_noise_rms_n,
            endpoint_sd_m: [sd, sd],
            endpoint_bias_m,
            impedance_trend: symmetric(&mut rng, cfg.impedance_trend),
        }
    }
}

/// What one trial of a reach session is, nuisances included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialNuisance {
    /// The rig's nuisances in this trial.
    pub rig: RigNuisance,
    /// The sensor's noise RMS, N.
    pub force_noise_rms_n: f64,
    /// Where the subject's reach starts and ends, rig frame, m.
    pub start_m: [f64; 2],
    /// See `start_m`.
    pub goal_m: [f64; 2],
    /// The reaction time (still phase before the reach), s, whole ticks.
    pub still_before_s: f64,
    /// The reach's duration, s, whole ticks.
    pub movement_s: f64,
    /// The factor on the subject's co-contraction (impedance).
    pub impedance_scale: f64,
    /// Ticks of the 4 kHz loop from the onset the rig logs to the pulse's start.
    pub trigger_lag_ticks: u64,
}

impl TrialNuisance {
    /// Trial `trial` (0-based) of `trials` in the session of `subject`.
    #[must_use]
    pub fn draw(
        protocol: &Protocol,
        cfg: &NuisanceConfig,
        session: &SessionNuisance,
        session_seed: u64,
        subject: u32,
        trial: u32,
        trials: u32,
    ) -> TrialNuisance {
        let mut rng =
            ChaCha8Rng::seed_from_u64(trial_seed(session_seed, subject, trial, Stream::Nuisance));
        let place = if trials > 1 {
            f64::from(trial) / f64::from(trials - 1)
        } else {
            0.0
        };
        let sensor_offset_n = [0, 1].map(|a| {
            session.sensor_offset_n[a]
                + session.sensor_drift_n[a] * place
                + normal(&mut rng, cfg.retare_sd_n)
        });
        let r = protocol.reach();
        let scatter = |rng: &mut ChaCha8Rng, p: [f64; 2]| {
            [0, 1]
                .map(|a| p[a] + session.endpoint_bias_m[a] + normal(rng, session.endpoint_sd_m[a]))
        };
        let start_m = scatter(&mut rng, r.start_m);
        let goal_m = scatter(&mut rng, r.goal_m);
        let still_before_s = whole_ticks(uniform(&mut rng, cfg.reaction_s));
        let movement_s =
            whole_ticks(r.movement_s * (1.0 + symmetric(&mut rng, cfg.movement_spread)));
        let impedance_scale = (1.0 + session.impedance_trend * place)
            * (1.0 + normal(&mut rng, cfg.impedance_wobble));
        // Drawn last: the trial's other draws are those of a rig without it.
        let trigger_lag_ticks = rng.random_range(0..=u64::from(cfg.trigger_jitter_ticks));
        TrialNuisance {
            rig: RigNuisance {
                sensor_offset_n,
                motor_gain: session.motor_gain,
                motor_noise_rms_n: session.motor_noise_rms_n,
                motor_noise_bw_hz: cfg.motor_noise_bw_hz,
            },
            force_noise_rms_n: session.sensor_noise_rms_n,
            start_m,
            goal_m,
            still_before_s,
            movement_s,
            impedance_scale: impedance_scale.max(0.1),
            trigger_lag_ticks,
        }
    }
}

/// The protocol and subject one trial runs with: `protocol` and `subject` themselves
/// when the protocol has no `[nuisance]` table (or is not a reach), else copies with the
/// trial's nuisances in the plant, its reach (start, goal, reaction time, duration; the
/// trial's length follows) and the subject's co-contraction. The recorded task (the
/// targets a lab's rig logs) stays the protocol's own. The third value is the trigger's
/// lag, ticks of the 4 kHz loop by which the logged onset precedes the pulse (0 without
/// a `[nuisance]` table).
#[must_use]
pub fn realise(
    protocol: &Protocol,
    subject: &VirtualSubject,
    session_seed: u64,
    trial: u32,
) -> (Protocol, VirtualSubject, u64) {
    let (mut p, mut s) = (protocol.clone(), subject.clone());
    let (Some(cfg), Some(reach)) = (&protocol.nuisance, &protocol.reach) else {
        return (p, s, 0);
    };
    let session = SessionNuisance::draw(cfg, session_seed, subject.index);
    let n = TrialNuisance::draw(
        protocol,
        cfg,
        &session,
        session_seed,
        subject.index,
        trial,
        reach.trials,
    );
    p.plant.nuisance = n.rig;
    p.plant.force_noise_rms_n = n.force_noise_rms_n;
    if let Some(r) = p.reach.as_mut() {
        r.start_m = n.start_m;
        r.goal_m = n.goal_m;
        r.still_before_s = n.still_before_s;
        r.movement_s = n.movement_s;
    }
    s.co_contraction_level *= n.impedance_scale;
    (p, s, n.trigger_lag_ticks)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    fn reach_protocol() -> Protocol {
        let mut p = Protocol::builtin("reach-perturb").unwrap();
        p.nuisance = Some(NuisanceConfig::REALISTIC);
        p
    }

    /// The same seed gives the same trial; the drawn values lie in their ranges; the
    /// drift moves the offset by at most its bound from the first to the last trial.
    #[test]
    fn draws_are_seeded_and_in_range() {
        let p = reach_protocol();
        let subject = p.subjects.draw(7, 1);
        let cfg = NuisanceConfig::REALISTIC;
        let s = SessionNuisance::draw(&cfg, 7, subject.index);
        assert_eq!(s, SessionNuisance::draw(&cfg, 7, subject.index));
        assert_ne!(s, SessionNuisance::draw(&cfg, 8, subject.index));
        for a in 0..2 {
            assert!((0.05..=0.3).contains(&s.sensor_offset_n[a].abs()), "{s:?}");
            assert!(s.sensor_drift_n[a].abs() <= 0.1);
            assert!((s.motor_gain[a] - 1.0).abs() <= 0.01);
        }
        let trials = p.reach().trials;
        let first = TrialNuisance::draw(&p, &cfg, &s, 7, subject.index, 0, trials);
        let last = TrialNuisance::draw(&p, &cfg, &s, 7, subject.index, trials - 1, trials);
        for a in 0..2 {
            assert!((first.rig.sensor_offset_n[a] - s.sensor_offset_n[a]).abs() < 1e-15);
            let d = last.rig.sensor_offset_n[a] - first.rig.sensor_offset_n[a];
            assert!((d - s.sensor_drift_n[a]).abs() < 1e-15, "{d}");
        }
        for k in 0..trials {
            let t = TrialNuisance::draw(&p, &cfg, &s, 7, subject.index, k, trials);
            assert!((0.2..=0.35).contains(&t.still_before_s), "{t:?}");
            assert!((t.movement_s / p.reach().movement_s - 1.0).abs() <= 0.13 + 1e-4);
            assert!((t.start_m[1] - p.reach().start_m[1]).abs() < 0.03, "{t:?}");
            assert!(t.trigger_lag_ticks <= 4, "{t:?}");
        }
    }

    /// Without a `[nuisance]` table the trial runs the protocol and subject unchanged.
    #[test]
    fn no_table_changes_nothing() {
        let p = Protocol::builtin("reach-perturb").unwrap();
        let subject = p.subjects.draw(3, 1);
        let (q, s, lag) = realise(&p, &subject, 3, 5);
        assert_eq!(q, p);
        assert_eq!(s, subject);
        assert_eq!(lag, 0);
    }

    /// A range given the wrong way round, a negative bound or a spread of a half are
    /// refused by the protocol's check, with the key.
    #[test]
    fn bad_ranges_name_their_keys() {
        let mut p = reach_protocol();
        if let Some(n) = p.nuisance.as_mut() {
            n.reaction_s = [0.4, 0.2];
            n.sensor_drift_n = -1.0;
            n.movement_spread = 0.5;
        }
        let e = p.validate().unwrap_err();
        for k in [
            "nuisance.reaction_s",
            "nuisance.sensor_drift_n",
            "nuisance.movement_spread",
        ] {
            assert!(e.iter().any(|x| x.key == k), "{k} not in {e:?}");
        }
    }
}
