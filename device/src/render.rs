//! Position rendering: the carts track the reference with a PD on the encoder error
//! plus feed-forward of the reference acceleration,
//! `F = m_ff ẍ_ref + K_p (x_ref − x) + K_d (ẋ_ref − ẋ)` per axis (the "high gain PD" of
//! 000_* section 5.1). It runs on motor ticks only; the command is held in between.

use crate::config::RenderConfig;

/// The PD + feed-forward law.
#[derive(Debug, Clone, PartialEq)]
pub struct Renderer {
    feedforward_mass_kg: [f64; 2],
    kp_n_per_m: [f64; 2],
    kd_n_s_per_m: [f64; 2],
}

impl Renderer {
    /// From a validated config.
    #[must_use]
    pub fn new(config: &RenderConfig) -> Self {
        Renderer {
            feedforward_mass_kg: config.feedforward_mass_kg,
            kp_n_per_m: config.kp_n_per_m,
            kd_n_s_per_m: config.kd_n_s_per_m,
        }
    }

    /// Motor force per axis, N.
    #[must_use]
    pub fn command(
        &self,
        ref_position_m: [f64; 2],
        ref_velocity_m_per_s: [f64; 2],
        ref_acceleration_m_per_s2: [f64; 2],
        position_m: [f64; 2],
        velocity_m_per_s: [f64; 2],
    ) -> [f64; 2] {
        let f = |i: usize| {
            self.feedforward_mass_kg[i] * ref_acceleration_m_per_s2[i]
                + self.kp_n_per_m[i] * (ref_position_m[i] - position_m[i])
                + self.kd_n_s_per_m[i] * (ref_velocity_m_per_s[i] - velocity_m_per_s[i])
        };
        [f(0), f(1)]
    }
}
