//! The diagnosis of a measured session: what the nominal model of rig and subject gets
//! wrong about it, which physical cause explains it, and how much the extended model gains,
//! judged on the recorded signals alone (nothing here re-simulates the session; `rigtwin
//! compare` in the `rigtwin` crate does, and uses this crate's model and bands).
//!
//! | file | idea |
//! |---|---|
//! | `effect.rs` | the catalog as types: [`EffectKind`] (names, sides) and [`Effect`] (parameters in the world's and the arm's types) |
//! | `glitch.rs` | glitches (runs of one to three bad samples, and stale runs of up to 20 rows while the handle moves) in a recorded channel, found and bridged before the fits ([`glitch::Glitch`]) |
//! | `hold.rs` | channels the logger wrote faster than their sensor read them, each reading held for several rows: found, and the held rows filled between the readings before the fits ([`hold::Held`]) |
//! | `slip.rs` | runs of samples a logger lost while keeping its clock, found from the position and put back, and frames it wrote more than once, taken out, before the fits ([`slip::Slip`], [`slip::Repeat`]) |
//! | `reaches.rs` | test data for the sample repairs' unit tests: a reach as a 1 kHz log records it |
//! | `signals.rs` | the balance filter: one frequency response for every term of the cart balance ([`BalanceSignals`]) |
//! | `candidate.rs` | the cart force balance, the [`Candidate`] interface, the baseline |
//! | `friction.rs`, `ripple.rs`, `delay.rs`, `rotation.rs` | the plant-side catalog effects |
//! | `unexplained.rs` | the library of force laws outside the catalog ([`Term`]) for what the catalog leaves |
//! | `joint.rs` | forward selection's joint model: named effects at their settings plus one more ([`Joint`]) |
//! | `hand_signals.rs` | the variational response to each force pulse, against aligned unperturbed trials |
//! | `hand.rs` | the hand balance and the human-side catalog effects ([`HandCandidate`]) |
//! | `hand_joint.rs` | forward selection's joint model on the hand balance (`HandJoint`) |
//! | `gram.rs` | least squares as sums of per-trial sufficient statistics |
//! | `crossval.rs` | folds of whole trials; held-out error |
//! | `stats.rs` | Student's t and the jackknife behind the chance threshold |
//! | `decide.rs` | the physical checks before a cause is named: material, inside its range, its own evidence agreeing |
//! | `diagnose.rs` | ranking, decision, evidence ([`diagnose`], [`Diagnosis`]) |
//! | `predict.rs` | held-out predictions of the motor command per trial and model ([`HeldOut`]), for the viewer |
//! | `model.rs` | the extended model as TOML (`--write-model`) |
//! | `plots.rs` | the PNG figures of `diagnosis.md` |
//! | `bands.rs` | frequency content of a discrepancy: Welch band powers per channel |
//! | `report.rs` | the table a person reads and `diagnosis.md` |

mod bands;
mod candidate;
mod crossval;
pub mod decide;
mod delay;
mod diagnose;
mod effect;
mod error;
mod friction;
pub mod glitch;
mod gram;
mod hand;
mod hand_joint;
mod hand_library;
mod hand_signals;
pub mod hold;
mod joint;
pub mod jump;
mod model;
pub mod plots;
mod predict;
#[cfg(test)]
mod reaches;
mod report;
mod ripple;
mod rotation;
mod signals;
pub mod slip;
pub mod stats;
pub mod unexplained;

pub use bands::{BANDS_HZ, BandError, CHANNELS, SEGMENT_S, band_errors, channels_of};
pub use candidate::{
    Baseline, Candidate, MOTOR_GAIN_TOLERANCE, NUISANCE_COLUMNS, Reshape, UnitResidual,
    force_gains, gain_bounds, masses, nominal_target, push_rows, residual_rows,
};
pub use crossval::{CvFit, FoldFit, Folds, cross_validate};
pub use delay::{ActuationDelay, MAX_DELAY_S, NOMINAL_LATENCY_MAX_S};
pub use diagnose::{
    Analysis, CandidateFit, Cause, DiagnoseOptions, Diagnosis, FAULT_RATIO, FoundTerm, HUMAN_SIDE,
    MAX_SET_ASIDE_SHARE, NotJudged, PLANT_SIDE, Ranked, SetAside, Threshold, Unexplained, diagnose,
    faults, nominal_parameters,
};
pub use effect::{Effect, EffectKind, MissingParameter, Side, UnknownEffect};
pub use error::DiscrepancyError;
pub use friction::{RailFriction, SMOOTH_VELOCITY_STEPS, smooth_velocity_m_per_s};
pub use gram::{Gram, Intercepts};
pub use hand::{
    ARM_INERTIA_TOLERANCE, FEEDBACK_DELAYS_MS, FIT_ARM_MASS_SCALE, GRIP_STIFFNESS_N_PER_M,
    GRIP_TIME_S, GripCompliance, HandBaseline, HandCandidate, HandFit, HandJudgement, HandleMass,
    IMPEDANCE_RATE_COLUMNS, Kin, REFLEX_DELAY_MS, RESPONSE_OFFSET_COLUMNS, ReplicateTest,
    StretchReflex, SubjectArm, hand_fit_rows, hand_grams, judge_hand,
};
pub use hand_signals::{
    ArmPosture, HAND_LEAD_S, HAND_WINDOW_S, HandArm, HandData, HandResponse, MIN_REACH_M,
    MUSCLE_PAIRS, SAME_REACH_DEG, hand_responses, reach_groups,
};
pub use joint::{Joint, Member, MemberParameters};
pub use model::ExtendedModel;
pub use predict::HeldOut;
pub use report::{convention, table, write_report};
pub use ripple::{ForceRipple, MAX_PITCH_M, MIN_PITCH_M};
pub use rotation::SensorRotation;
pub use signals::{
    BalanceSignals, EVALUATION_RATE_HZ, REST_SPEED_M_PER_S, SMOOTHING_ORDER, SMOOTHING_WINDOW_S,
    window_for_rate,
};
pub use unexplained::{LIBRARY, Term};
