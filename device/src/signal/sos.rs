//! Second-order sections: filtering with state, steady-state initial conditions and
//! zero-phase forward-backward filtering, as scipy's `sosfilt`, `sosfilt_zi` and
//! `sosfiltfilt`.

use super::error::{SignalError, check_finite};
use super::pad::odd_ext;

/// A cascade of biquads, each `[b0, b1, b2, a0, a1, a2]` as in scipy's `sos` arrays
/// (`H(z) = (b0 + b1 z⁻¹ + b2 z⁻²) / (a0 + a1 z⁻¹ + a2 z⁻²)`). Designs from
/// [`butter`](super::butter) have `a0 = 1`; filtering divides by `a0` otherwise.
#[derive(Debug, Clone, PartialEq)]
pub struct Sos {
    /// The sections, applied first to last.
    pub sections: Vec<[f64; 6]>,
}

impl Sos {
    /// Checks that there is at least one section, every coefficient is finite and
    /// every `a0` is non-zero.
    ///
    /// # Errors
    /// [`SignalError::BadCoefficients`] naming what is wrong.
    pub fn validate(&self) -> Result<(), SignalError> {
        if self.sections.is_empty() {
            return Err(SignalError::BadCoefficients {
                why: "an SOS filter needs at least one section",
            });
        }
        if self.sections.iter().flatten().any(|c| !c.is_finite()) {
            return Err(SignalError::BadCoefficients {
                why: "an SOS coefficient is not finite",
            });
        }
        if self.sections.iter().any(|s| s[3] == 0.0) {
            return Err(SignalError::BadCoefficients {
                why: "an SOS section has a0 = 0",
            });
        }
        Ok(())
    }

    /// Complex frequency response `H(e^{iω})` at `freq_hz` for sample rate `fs_hz`,
    /// as `(re, im)`.
    pub fn response(&self, freq_hz: f64, fs_hz: f64) -> (f64, f64) {
        let w = 2.0 * std::f64::consts::PI * freq_hz / fs_hz;
        // z^-1 = e^{-iω}, z^-2 = e^{-2iω}.
        let (c1, s1) = (w.cos(), -w.sin());
        let (c2, s2) = ((2.0 * w).cos(), -(2.0 * w).sin());
        let mut h = (1.0, 0.0);
        for s in &self.sections {
            let num = (s[0] + s[1] * c1 + s[2] * c2, s[1] * s1 + s[2] * s2);
            let den = (s[3] + s[4] * c1 + s[5] * c2, s[4] * s1 + s[5] * s2);
            let d2 = den.0 * den.0 + den.1 * den.1;
            let q = (
                (num.0 * den.0 + num.1 * den.1) / d2,
                (num.1 * den.0 - num.0 * den.1) / d2,
            );
            h = (h.0 * q.0 - h.1 * q.1, h.0 * q.1 + h.1 * q.0);
        }
        h
    }

    /// Gain `|H|` at `freq_hz` for sample rate `fs_hz`.
    pub fn gain(&self, freq_hz: f64, fs_hz: f64) -> f64 {
        let (re, im) = self.response(freq_hz, fs_hz);
        re.hypot(im)
    }

    /// Sections divided through by their `a0`.
    fn normalised(&self) -> Vec<[f64; 6]> {
        self.sections
            .iter()
            .map(|s| {
                let a0 = s[3];
                [s[0] / a0, s[1] / a0, s[2] / a0, 1.0, s[4] / a0, s[5] / a0]
            })
            .collect()
    }
}

/// Runs normalised sections over `x` in place (transposed direct form II, the same
/// recurrence and operation order as scipy's `_sosfilt`), updating `state`.
fn run(sections: &[[f64; 6]], x: &mut [f64], state: &mut [[f64; 2]]) {
    for v in x.iter_mut() {
        let mut cur = *v;
        for (s, zi) in sections.iter().zip(state.iter_mut()) {
            let new = s[0] * cur + zi[0];
            zi[0] = s[1] * cur - s[4] * new + zi[1];
            zi[1] = s[2] * cur - s[5] * new;
            cur = new;
        }
        *v = cur;
    }
}

/// Filters `x` through `sos` from rest (zero initial state), as
/// `scipy.signal.sosfilt(sos, x)`. Sections with `a0 ≠ 1` are normalised; a
/// section with `a0 = 0` or a non-finite sample gives non-finite output (use
/// [`Sos::validate`] first when the coefficients come from outside).
pub fn sosfilt(sos: &Sos, x: &[f64]) -> Vec<f64> {
    let sections = sos.normalised();
    let mut state = vec![[0.0; 2]; sections.len()];
    let mut y = x.to_vec();
    run(&sections, &mut y, &mut state);
    y
}

/// Filters `x` through `sos` starting from, and updating, `state` (one `[z0, z1]`
/// per section), as `scipy.signal.sosfilt(sos, x, zi=state)` returning `(y, zf)`.
///
/// # Errors
/// [`SignalError::BadCoefficients`] from [`Sos::validate`] or when `state` does not
/// have one entry per section.
pub fn sosfilt_with_state(
    sos: &Sos,
    x: &[f64],
    state: &mut [[f64; 2]],
) -> Result<Vec<f64>, SignalError> {
    sos.validate()?;
    if state.len() != sos.sections.len() {
        return Err(SignalError::BadCoefficients {
            why: "the state needs one [z0, z1] per section",
        });
    }
    let sections = sos.normalised();
    let mut y = x.to_vec();
    run(&sections, &mut y, state);
    Ok(y)
}

/// Initial state of each section for the steady-state response to a unit step, as
/// `scipy.signal.sosfilt_zi(sos)`; multiply by the first sample to start without a
/// transient.
///
/// # Errors
/// [`SignalError::BadCoefficients`] from [`Sos::validate`], or when a section has a
/// pole at z = 1 (no steady state).
pub fn sosfilt_zi(sos: &Sos) -> Result<Vec<[f64; 2]>, SignalError> {
    sos.validate()?;
    let mut scale = 1.0;
    let mut zi = Vec::with_capacity(sos.sections.len());
    for s in &sos.sections {
        let b = [s[0] / s[3], s[1] / s[3], s[2] / s[3]];
        let a = [1.0, s[4] / s[3], s[5] / s[3]];
        // lfilter_zi for a biquad: solve (I − companion(a)ᵀ) z = b[1..] − a[1..]·b0,
        // i.e. [[1 + a1, −1], [a2, 1]] z = [b1 − a1 b0, b2 − a2 b0].
        let det = 1.0 + a[1] + a[2];
        if det == 0.0 {
            return Err(SignalError::BadCoefficients {
                why: "a section has a pole at z = 1 and no steady state",
            });
        }
        let r0 = b[1] - a[1] * b[0];
        let r1 = b[2] - a[2] * b[0];
        let z0 = (r0 + r1) / det;
        let z1 = r1 - a[2] * z0;
        zi.push([scale * z0, scale * z1]);
        scale *= (s[0] + s[1] + s[2]) / (s[3] + s[4] + s[5]);
    }
    Ok(zi)
}

/// Zero-phase forward-backward filtering, as `scipy.signal.sosfiltfilt(sos, x)` with
/// its defaults: odd extension by `padlen = 3·(2·n_sections + 1 − min(#b2=0,
/// #a2=0))` samples and steady-state initial conditions in both directions. The
/// magnitude response is `|H|²`; the phase is zero.
///
/// # Errors
/// [`SignalError::BadCoefficients`] as [`sosfilt_zi`]; [`SignalError::TooShort`]
/// unless `x.len() > padlen`; [`SignalError::NonFinite`] for a bad sample.
pub fn sosfiltfilt(sos: &Sos, x: &[f64]) -> Result<Vec<f64>, SignalError> {
    let zi = sosfilt_zi(sos)?;
    let n_sections = sos.sections.len();
    let b2_zero = sos.sections.iter().filter(|s| s[2] == 0.0).count();
    let a2_zero = sos.sections.iter().filter(|s| s[5] == 0.0).count();
    let ntaps = 2 * n_sections + 1 - b2_zero.min(a2_zero);
    let edge = 3 * ntaps;
    if x.len() <= edge {
        return Err(SignalError::TooShort {
            needed: edge + 1,
            got: x.len(),
            what: "sosfiltfilt (more than its padding)",
        });
    }
    check_finite(x)?;
    let sections = sos.normalised();
    let mut y = odd_ext(x, edge);
    let x0 = y[0];
    let mut state: Vec<[f64; 2]> = zi.iter().map(|z| [z[0] * x0, z[1] * x0]).collect();
    run(&sections, &mut y, &mut state);
    y.reverse();
    let y0 = y[0];
    let mut state: Vec<[f64; 2]> = zi.iter().map(|z| [z[0] * y0, z[1] * y0]).collect();
    run(&sections, &mut y, &mut state);
    y.reverse();
    Ok(y[edge..y.len() - edge].to_vec())
}
