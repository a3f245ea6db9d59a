//! The imposed sinusoid of 001_*: the handle is carried along one axis,
//! `x_a(t) = c + e(t) · A · sin(2π f t)`, `t` from the first active tick.
//!
//! Smooth start and stop: the envelope `e(t)` is a raised-cosine ramp
//! `½(1 − cos(π t / T_r))` over `T_r = ramp_s`, then exactly 1 for `cycles` full cycles,
//! then the mirror ramp down, then 0. Position, velocity and acceleration are therefore
//! continuous everywhere and zero at both ends; with the default `T_r` of half a period
//! the full-amplitude part starts and ends at zero crossings.
//!
//! During the full-amplitude part the acceleration `−A ω² sin(ω t)` vanishes at the zero
//! crossings `t = m / (2f)`, where 001_* applies its position perturbations (twice a
//! cycle, with the hand at the centre).

use core::f64::consts::PI;

use crate::config::{Axis, ImposedMotionConfig};
use crate::time::Rate;

/// Position, velocity and acceleration of a reference along one axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Kinematics1 {
    /// m
    pub position_m: f64,
    /// m/s
    pub velocity_m_per_s: f64,
    /// m/s²
    pub acceleration_m_per_s2: f64,
}

/// The imposed motion, evaluated in closed form from an integer tick count.
#[derive(Debug, Clone, PartialEq)]
pub struct ImposedMotion {
    axis: Axis,
    amplitude_m: f64,
    frequency_hz: f64,
    ramp_s: f64,
    full_s: f64,
    rate: Rate,
}

impl ImposedMotion {
    /// From a validated config at the control rate.
    #[must_use]
    pub fn new(config: &ImposedMotionConfig, rate: Rate) -> Self {
        ImposedMotion {
            axis: config.axis,
            amplitude_m: config.amplitude_m,
            frequency_hz: config.frequency_hz,
            ramp_s: config.ramp_s,
            full_s: f64::from(config.cycles) / config.frequency_hz,
            rate,
        }
    }

    /// The axis the motion runs along.
    #[must_use]
    pub fn axis(&self) -> Axis {
        self.axis
    }

    /// Total duration (ramp in, full cycles, ramp out), s.
    #[must_use]
    pub fn duration_s(&self) -> f64 {
        2.0 * self.ramp_s + self.full_s
    }

    /// True once `ticks` since the start is past the end of the motion.
    #[must_use]
    pub fn finished(&self, ticks: u64) -> bool {
        ticks as f64 / f64::from(self.rate.hz()) >= self.duration_s()
    }

    /// Envelope and its first two time derivatives at `t` s.
    fn envelope(&self, t: f64) -> (f64, f64, f64) {
        let end = self.duration_s();
        if t < 0.0 || t >= end {
            return (0.0, 0.0, 0.0);
        }
        let r = self.ramp_s;
        let ramp = |tau: f64, sign: f64| {
            let k = PI / r;
            (
                0.5 * (1.0 - (k * tau).cos()),
                sign * 0.5 * k * (k * tau).sin(),
                0.5 * k * k * (k * tau).cos(),
            )
        };
        if t < r {
            ramp(t, 1.0)
        } else if t <= r + self.full_s {
            (1.0, 0.0, 0.0)
        } else {
            ramp(end - t, -1.0)
        }
    }

    /// Offset from the centre along the motion's axis at `ticks` since the start.
    #[must_use]
    pub fn at(&self, ticks: u64) -> Kinematics1 {
        self.at_seconds(ticks as f64 / f64::from(self.rate.hz()))
    }

    /// Offset from the centre along the motion's axis at `t` s since the start.
    #[must_use]
    pub fn at_seconds(&self, t: f64) -> Kinematics1 {
        let (e, de, dde) = self.envelope(t);
        let w = 2.0 * PI * self.frequency_hz;
        let (s, c) = (w * t).sin_cos();
        let a = self.amplitude_m;
        Kinematics1 {
            position_m: a * e * s,
            velocity_m_per_s: a * (de * s + e * w * c),
            acceleration_m_per_s2: a * (dde * s + 2.0 * de * w * c - e * w * w * s),
        }
    }

    /// The first zero-acceleration point of the full-amplitude part at or after `ticks`
    /// since the start, in ticks since the start; `None` when none is left. The full
    /// amplitude part holds `2 · cycles` of them (50 with the 001_* defaults).
    #[must_use]
    pub fn next_zero_acceleration(&self, ticks: u64) -> Option<u64> {
        let hz = f64::from(self.rate.hz());
        let half_period_s = 0.5 / self.frequency_hz;
        let first = (self.ramp_s / half_period_s - 1e-9).ceil().max(0.0);
        let from = (ticks as f64 / hz / half_period_s - 1e-9).ceil().max(first) - 1.0;
        // Step through the crossings after a conservative starting index; at most two
        // steps are needed because rounding to ticks moves a crossing by < 1 tick.
        let mut m = from.max(first);
        for _ in 0..4 {
            let t = m * half_period_s;
            if t >= self.ramp_s + self.full_s - 1e-9 {
                return None;
            }
            let tick = (t * hz).round();
            if tick >= ticks as f64 {
                return Some(tick as u64);
            }
            m += 1.0;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_give_fifty_zero_acceleration_points_at_the_centre() {
        let m = ImposedMotion::new(&ImposedMotionConfig::default(), Rate::CONTROL);
        let mut n = 0;
        let mut k = 0;
        while let Some(t) = m.next_zero_acceleration(k) {
            let s = m.at(t);
            // At 0.125 Hz a crossing falls on an exact tick (every 16 000 ticks), so the
            // position is A sin(mπ) ~ 1e-15 m and the acceleration ~ 1e-15 m/s².
            assert!(s.position_m.abs() < 1e-12 && s.acceleration_m_per_s2.abs() < 1e-12);
            n += 1;
            k = t + 1;
        }
        // 001_*: 25 cycles, 2 perturbations per cycle.
        assert_eq!(n, 50);
    }

    #[test]
    fn starts_and_ends_at_rest() {
        let m = ImposedMotion::new(&ImposedMotionConfig::default(), Rate::CONTROL);
        let end = (m.duration_s() * f64::from(Rate::CONTROL.hz())).round() as u64;
        for k in [0, end] {
            let s = m.at(k);
            // Envelope and its derivatives vanish at the ends exactly, up to rounding.
            assert!(s.position_m.abs() < 1e-12 && s.velocity_m_per_s.abs() < 1e-12);
            assert!(s.acceleration_m_per_s2.abs() < 1e-9);
        }
    }
}
