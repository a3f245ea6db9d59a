//! The Piovesan virtual spring, 001_* eq. 4, per axis:
//! `M_e ẍ_e + B_e (ẋ_e − ẋ_a) + K_e (x_e − x_a) = F`.
//!
//! How it maps onto this rig: `x_e` is a virtual mass that the hand force `F` pushes
//! and that a spring-damper ties to the anchor `x_a`, the imposed motion (the
//! "commanded virtual motion" of 001_*). The carts render `x_e`, so the handle follows
//! the sinusoid through a stiff, critically damped coupling (7.1 Hz with the defaults)
//! and yields `F / K_e` to a steady push.
//!
//! Per axis this is `ṡ = A s + b w` with `s = [x_e, ẋ_e]`,
//! `A = [[0, 1], [−K/M, −B/M]]`, `b = [0, 1/M]` and `w = F + B ẋ_a + K x_a` held over the
//! tick. The update `s⁺ = Φ s + Γ w` is exact for the held `w`: `Φ = e^{A h}` and
//! `Γ = ∫₀ʰ e^{Aτ} dτ b`, both read off the exponential of the augmented 3x3 matrix
//! `[[A h, b h], [0, 0]]`, computed once at configuration.

use nalgebra::{Matrix2, Matrix3, Vector2};

#[derive(Debug, Clone, Copy, PartialEq)]
struct AxisStep {
    mass_kg: f64,
    stiffness_n_per_m: f64,
    damping_n_s_per_m: f64,
    phi: Matrix2<f64>,
    gamma: Vector2<f64>,
}

impl AxisStep {
    fn new(mass_kg: f64, stiffness_n_per_m: f64, damping_n_s_per_m: f64, h: f64) -> Self {
        let mut aug = Matrix3::zeros();
        aug[(0, 1)] = h;
        aug[(1, 0)] = -stiffness_n_per_m / mass_kg * h;
        aug[(1, 1)] = -damping_n_s_per_m / mass_kg * h;
        aug[(1, 2)] = h / mass_kg;
        let e = aug.exp();
        AxisStep {
            mass_kg,
            stiffness_n_per_m,
            damping_n_s_per_m,
            phi: Matrix2::new(e[(0, 0)], e[(0, 1)], e[(1, 0)], e[(1, 1)]),
            gamma: Vector2::new(e[(0, 2)], e[(1, 2)]),
        }
    }

    fn drive(&self, force_n: f64, anchor_m: f64, anchor_m_per_s: f64) -> f64 {
        force_n + self.damping_n_s_per_m * anchor_m_per_s + self.stiffness_n_per_m * anchor_m
    }
}

/// Two-axis virtual-spring state and its exact one-tick update.
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualSpring {
    axes: [AxisStep; 2],
    /// Virtual-mass position `x_e`, m, rig frame.
    pub position_m: [f64; 2],
    /// Virtual-mass velocity `ẋ_e`, m/s.
    pub velocity_m_per_s: [f64; 2],
}

impl VirtualSpring {
    /// A virtual mass at rest at the origin, stepping `period_s` per update.
    #[must_use]
    pub fn new(
        mass_kg: [f64; 2],
        stiffness_n_per_m: [f64; 2],
        damping_n_s_per_m: [f64; 2],
        period_s: f64,
    ) -> Self {
        VirtualSpring {
            axes: [
                AxisStep::new(
                    mass_kg[0],
                    stiffness_n_per_m[0],
                    damping_n_s_per_m[0],
                    period_s,
                ),
                AxisStep::new(
                    mass_kg[1],
                    stiffness_n_per_m[1],
                    damping_n_s_per_m[1],
                    period_s,
                ),
            ],
            position_m: [0.0; 2],
            velocity_m_per_s: [0.0; 2],
        }
    }

    /// Place the virtual mass at `position_m` with velocity `velocity_m_per_s`.
    pub fn reset(&mut self, position_m: [f64; 2], velocity_m_per_s: [f64; 2]) {
        self.position_m = position_m;
        self.velocity_m_per_s = velocity_m_per_s;
    }

    /// Advance one period with the hand force `force_n` and the anchor position and
    /// velocity held constant over it (exact for that held input).
    pub fn step(&mut self, force_n: [f64; 2], anchor_m: [f64; 2], anchor_m_per_s: [f64; 2]) {
        for (i, a) in self.axes.iter().enumerate() {
            let w = a.drive(force_n[i], anchor_m[i], anchor_m_per_s[i]);
            let s =
                a.phi * Vector2::new(self.position_m[i], self.velocity_m_per_s[i]) + a.gamma * w;
            self.position_m[i] = s[0];
            self.velocity_m_per_s[i] = s[1];
        }
    }

    /// Virtual-mass acceleration at the current state for the given inputs, m/s².
    #[must_use]
    pub fn acceleration(
        &self,
        force_n: [f64; 2],
        anchor_m: [f64; 2],
        anchor_m_per_s: [f64; 2],
    ) -> [f64; 2] {
        let acc = |i: usize| {
            let a = &self.axes[i];
            (a.drive(force_n[i], anchor_m[i], anchor_m_per_s[i])
                - a.damping_n_s_per_m * self.velocity_m_per_s[i]
                - a.stiffness_n_per_m * self.position_m[i])
                / a.mass_kg
        };
        [acc(0), acc(1)]
    }
}
