//! Velocity from encoders: the backward difference of positions, low-passed by an exact
//! first-order filter, `v ← v + α (Δx/h − v)` with `α = 1 − e^{−2π f_c h}`.

/// The filtered-difference velocity estimator.
#[derive(Debug, Clone, PartialEq)]
pub struct VelocityEstimator {
    alpha: f64,
    period_s: f64,
    last_m: Option<[f64; 2]>,
    velocity_m_per_s: [f64; 2],
}

impl VelocityEstimator {
    /// A filter with cut-off `cutoff_hz` sampled every `period_s`.
    #[must_use]
    pub fn new(cutoff_hz: f64, period_s: f64) -> Self {
        VelocityEstimator {
            alpha: -(-2.0 * core::f64::consts::PI * cutoff_hz * period_s).exp_m1(),
            period_s,
            last_m: None,
            velocity_m_per_s: [0.0; 2],
        }
    }

    /// The filter gain `α` per sample.
    #[must_use]
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Forget the history (after a gap in the samples); the next update reads zero.
    pub fn reset(&mut self) {
        self.last_m = None;
        self.velocity_m_per_s = [0.0; 2];
    }

    /// Feed this tick's position, m; returns the velocity estimate, m/s.
    pub fn update(&mut self, position_m: [f64; 2]) -> [f64; 2] {
        if let Some(last) = self.last_m {
            for (i, v) in self.velocity_m_per_s.iter_mut().enumerate() {
                let raw = (position_m[i] - last[i]) / self.period_s;
                *v += self.alpha * (raw - *v);
            }
        }
        self.last_m = Some(position_m);
        self.velocity_m_per_s
    }

    /// The current estimate, m/s.
    #[must_use]
    pub fn velocity_m_per_s(&self) -> [f64; 2] {
        self.velocity_m_per_s
    }
}
