//! The laws of the plant effects, kept apart from the rapier world so that tests can
//! check each law against what the simulation applied.

use std::f64::consts::PI;

use crate::config::{CableSpring, ForceRipple, RailFriction, SensorEffect};

/// Rail friction force on a cart moving at `v_m_per_s` along its rail, N:
/// `−(Fc · tanh(v / v_s) + b · v)`.
#[must_use]
pub fn friction_force_n(f: &RailFriction, v_m_per_s: f64) -> f64 {
    -(f.coulomb_n * (v_m_per_s / f.smooth_velocity_m_per_s).tanh()
        + f.viscous_n_s_per_m * v_m_per_s)
}

/// Cable carrier's pull on the cart of `axis` at rail position `q_m`, N.
#[must_use]
pub fn cable_force_n(c: &CableSpring, axis: usize, q_m: f64) -> f64 {
    -c.stiffness_n_per_m[axis] * (q_m - c.rest_m[axis])
}

/// Cogging force added to the motor of `axis` (0 = x, 1 = y) whose cart is at `q_m`
/// on its rail, N.
#[must_use]
pub fn ripple_force_n(r: &ForceRipple, axis: usize, q_m: f64) -> f64 {
    r.amplitude_n[axis] * (2.0 * PI * q_m / r.pitch_m + r.phase_rad[axis]).sin()
}

/// A fixed-length delay line of motor commands, in whole ticks. Preallocated; `push`
/// returns the command written `len` pushes ago (zero force before that).
#[derive(Debug, Clone)]
pub struct DelayLine {
    buf: Vec<[f64; 2]>,
    head: usize,
}

impl DelayLine {
    /// A delay of `ticks` ticks (0 passes commands straight through).
    #[must_use]
    pub fn new(ticks: usize) -> Self {
        DelayLine {
            buf: vec![[0.0; 2]; ticks],
            head: 0,
        }
    }

    /// The delay in ticks.
    #[must_use]
    pub fn ticks(&self) -> usize {
        self.buf.len()
    }

    /// Push this tick's command, get the one that takes effect now.
    pub fn push(&mut self, cmd: [f64; 2]) -> [f64; 2] {
        if self.buf.is_empty() {
            return cmd;
        }
        let out = self.buf[self.head];
        self.buf[self.head] = cmd;
        self.head = (self.head + 1) % self.buf.len();
        out
    }
}

/// The force sensor's own dynamics and calibration errors, applied to the true force
/// (the force the handle exerts on the cart through the sensor), before the noise.
#[derive(Debug, Clone, Copy)]
pub struct SensorModel {
    cos: f64,
    sin: f64,
    offset_n: [f64; 2],
    /// Low-pass coefficient α in `y += α (x − y)`; 1 means no filter.
    alpha: f64,
    state: [f64; 2],
}

impl SensorModel {
    /// The ideal sensor (identity) or the one that `effect` describes, sampled every `dt_s`.
    #[must_use]
    pub fn new(effect: Option<&SensorEffect>, dt_s: f64) -> Self {
        match effect {
            None => SensorModel {
                cos: 1.0,
                sin: 0.0,
                offset_n: [0.0; 2],
                alpha: 1.0,
                state: [0.0; 2],
            },
            Some(e) => {
                let th = e.rotation_deg.to_radians();
                // Exact discretisation of a first-order lag at the sample period.
                let alpha = if e.lowpass_hz > 0.0 {
                    1.0 - (-2.0 * PI * e.lowpass_hz * dt_s).exp()
                } else {
                    1.0
                };
                SensorModel {
                    cos: th.cos(),
                    sin: th.sin(),
                    offset_n: e.offset_n,
                    alpha,
                    state: [0.0; 2],
                }
            }
        }
    }

    /// One sample: low-pass the true rig-frame force, rotate it counter-clockwise by
    /// `rotation_deg` (a sensor mounted rotated by −θ about the handle axis reads the
    /// rig-frame force rotated by +θ), add the offset. N in, N out.
    pub fn sample(&mut self, true_n: [f64; 2]) -> [f64; 2] {
        for (s, x) in self.state.iter_mut().zip(true_n) {
            *s += self.alpha * (x - *s);
        }
        let [fx, fy] = self.state;
        [
            self.cos * fx - self.sin * fy + self.offset_n[0],
            self.sin * fx + self.cos * fy + self.offset_n[1],
        ]
    }
}
