//! # rigtwin-world — the plant
//!
//! A rapier2d-f64 world of the Börner manipulandum (000_* section 5.1) and the arm or
//! calibration rig that holds its handle, behind the rig's own boundary:
//! [`SimRig`] implements [`rigtwin_device::RigIo`] in rig units.
//!
//! (documentation completed below)

pub mod config;
pub mod effects;
pub mod endstop;
pub mod error;
pub mod reduced;
pub mod rig;

pub use config::{Attachment, Grasp, PlantEffects, RigConfig, SolverConfig};
pub use error::WorldError;
pub use reduced::ReducedPlant;
pub use rig::{SimRig, StepTruth, TICK_S};
