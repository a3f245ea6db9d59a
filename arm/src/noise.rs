//! Signal-dependent motor noise (000_* section 4: zero-mean Brownian motion scaled with
//! the command).
//!
//! Each muscle carries an Ornstein–Uhlenbeck process w (leaky Brownian motion) of unit
//! stationary variance and correlation time τ_n, updated once per neural tick:
//! `w ← φ w + √(1 − φ²) ξ`, `φ = exp(−Δt/τ_n)`, ξ ~ N(0, 1). The noise activation is
//! `a_N = cv · a · w` \[N\], so its standard deviation is `cv` times the activation.
//! A pure Brownian motion would wander without bound over a session; the leak keeps it
//! zero-mean and stationary while it stays Brownian on time scales below τ_n.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::muscles::MUSCLES;

/// Noise parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseParams {
    /// Coefficient of variation of the activation \[-\]. Default 0.02 (unverified;
    /// set 0 for a noiseless arm).
    pub activation_cv: f64,
    /// Correlation time τ_n of the leaky Brownian motion \[ms\]. Default 50 ms (unverified).
    pub time_constant_ms: f64,
}

impl Default for NoiseParams {
    fn default() -> Self {
        NoiseParams {
            activation_cv: 0.02,
            time_constant_ms: 50.0,
        }
    }
}

/// The per-muscle noise processes, driven by a seeded ChaCha8 stream.
#[derive(Debug, Clone)]
pub struct MotorNoise {
    rng: ChaCha8Rng,
    w: [f64; MUSCLES],
    phi: f64,
    drive: f64,
    cv: f64,
}

impl MotorNoise {
    /// Noise updated every `period_s` \[s\]; the initial state is drawn from the
    /// stationary distribution so there is no start-up transient.
    pub fn new(params: &NoiseParams, period_s: f64, mut rng: ChaCha8Rng) -> MotorNoise {
        let tau_s = params.time_constant_ms * 1e-3;
        let phi = if tau_s > 0.0 {
            (-period_s / tau_s).exp()
        } else {
            0.0
        };
        let w = std::array::from_fn(|_| rng.sample::<f64, _>(StandardNormal));
        MotorNoise {
            rng,
            w,
            phi,
            drive: (1.0 - phi * phi).max(0.0).sqrt(),
            cv: params.activation_cv,
        }
    }

    /// Advances one neural tick and returns the noise activations \[N\] for the
    /// noiseless activations `a` \[N\].
    pub fn step(&mut self, activations_n: &[f64; MUSCLES]) -> [f64; MUSCLES] {
        for w in &mut self.w {
            let xi: f64 = self.rng.sample(StandardNormal);
            *w = self.phi * *w + self.drive * xi;
        }
        std::array::from_fn(|i| self.cv * activations_n[i].max(0.0) * self.w[i])
    }
}
