//! The Börner admittance, 000_* eq. 20, per axis:
//! `M_adm ẍ_r + D_adm ẋ_r = u` with `u = F_meas + u_pert (+ wall force)`.
//!
//! The input is held over each tick, so the update is the exact solution of the linear
//! ODE for a piecewise-constant input, not an Euler step. With `a = D/M`, `z = a h`:
//!
//! ```text
//! v⁺ = e^{−z} v + (h/M) φ(z) u                    φ(z) = (1 − e^{−z}) / z
//! x⁺ = x + h φ(z) v + (h²/M) ψ(z) u               ψ(z) = (z − 1 + e^{−z}) / z²
//! ```
//!
//! Both functions are evaluated without cancellation (`expm1`, and a series for `ψ` at
//! small `z`), and `D = 0` is the exact double integrator (`φ = 1`, `ψ = ½`).

/// Coefficients of one axis for one tick, computed once at configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
struct AxisStep {
    mass_kg: f64,
    damping_n_s_per_m: f64,
    decay: f64,
    v_per_n: f64,
    x_per_v: f64,
    x_per_n: f64,
}

/// `φ(z) = (1 − e^{−z}) / z`, with `φ(0) = 1`.
#[must_use]
pub fn phi1(z: f64) -> f64 {
    if z.abs() < 1e-300 {
        1.0
    } else {
        -(-z).exp_m1() / z
    }
}

/// `ψ(z) = (z − 1 + e^{−z}) / z²`, with `ψ(0) = ½`.
#[must_use]
pub fn phi2(z: f64) -> f64 {
    if z.abs() < 0.1 {
        // ψ(z) = Σ_k (−z)^k / (k + 2)!; 12 terms leave < 1e-20 for |z| < 0.1, where the
        // closed form would lose digits to cancellation.
        let mut term = 0.5;
        let mut sum = 0.0;
        for k in 0..12u32 {
            sum += term;
            term *= -z / f64::from(k + 3);
        }
        sum
    } else {
        (z + (-z).exp_m1()) / (z * z)
    }
}

impl AxisStep {
    fn new(mass_kg: f64, damping_n_s_per_m: f64, h: f64) -> Self {
        let z = damping_n_s_per_m / mass_kg * h;
        AxisStep {
            mass_kg,
            damping_n_s_per_m,
            decay: (-z).exp(),
            v_per_n: h / mass_kg * phi1(z),
            x_per_v: h * phi1(z),
            x_per_n: h * h / mass_kg * phi2(z),
        }
    }
}

/// The two-axis admittance state and its exact one-tick update.
#[derive(Debug, Clone, PartialEq)]
pub struct Admittance {
    axes: [AxisStep; 2],
    /// Reference position `x_r`, m, rig frame.
    pub position_m: [f64; 2],
    /// Reference velocity `ẋ_r`, m/s.
    pub velocity_m_per_s: [f64; 2],
}

impl Admittance {
    /// An admittance at rest at the origin, stepping `period_s` per update.
    #[must_use]
    pub fn new(mass_kg: [f64; 2], damping_n_s_per_m: [f64; 2], period_s: f64) -> Self {
        Admittance {
            axes: [
                AxisStep::new(mass_kg[0], damping_n_s_per_m[0], period_s),
                AxisStep::new(mass_kg[1], damping_n_s_per_m[1], period_s),
            ],
            position_m: [0.0; 2],
            velocity_m_per_s: [0.0; 2],
        }
    }

    /// Place the reference at `position_m` with velocity `velocity_m_per_s`.
    pub fn reset(&mut self, position_m: [f64; 2], velocity_m_per_s: [f64; 2]) {
        self.position_m = position_m;
        self.velocity_m_per_s = velocity_m_per_s;
    }

    /// Advance one period with `force_n` held constant over it (exact).
    pub fn step(&mut self, force_n: [f64; 2]) {
        for (i, a) in self.axes.iter().enumerate() {
            let v = self.velocity_m_per_s[i];
            self.position_m[i] += a.x_per_v * v + a.x_per_n * force_n[i];
            self.velocity_m_per_s[i] = a.decay * v + a.v_per_n * force_n[i];
        }
    }

    /// Reference acceleration `(u − D ẋ_r) / M` for input `force_n` at the current state, m/s².
    #[must_use]
    pub fn acceleration(&self, force_n: [f64; 2]) -> [f64; 2] {
        let acc = |i: usize| {
            let a = &self.axes[i];
            (force_n[i] - a.damping_n_s_per_m * self.velocity_m_per_s[i]) / a.mass_kg
        };
        [acc(0), acc(1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psi_series_and_closed_form_agree_at_the_switch() {
        // At z = 0.1 the closed form loses ~2 eps / z ≈ 4e-15 to cancellation, so the
        // two evaluations must agree to 1e-13.
        let z: f64 = 0.0999999999;
        let closed = (z + (-z).exp_m1()) / (z * z);
        assert!((phi2(z) - closed).abs() < 1e-13);
        assert!((phi2(0.0) - 0.5).abs() < 1e-16);
    }
}
