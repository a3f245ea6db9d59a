//! Known linear systems for validating the estimators, shared by the
//! `estimate_*` tests and the `estimate` bench (included with `#[path]`).
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::needless_range_loop
)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub type Mat2 = [[f64; 2]; 2];

/// Börner Table 1 (000_*): damping, N s/m (non-symmetric, as measured).
pub const D_TABLE1: Mat2 = [[10.98, -7.94], [-8.54, 6.75]];
/// Börner Table 1 stiffness, symmetrised (K21 = −106.04 there), N/m.
pub const K_TABLE1: Mat2 = [[110.52, -106.05], [-106.05, 313.75]];
/// An endpoint inertia with coupling, kg (within the 0.5–3 kg of arm-parameters.md).
pub const M_ARM: Mat2 = [[1.5, 0.3], [0.3, 2.2]];
/// Börner rig admittance (000_* section 5.1).
pub const M_ADM: Mat2 = [[5.0, 0.0], [0.0, 5.0]];
pub const D_ADM: Mat2 = [[15.0, 0.0], [0.0, 15.0]];
pub const M_HANDLE: Mat2 = [[0.6, 0.0], [0.0, 0.6]];
/// The seed's perturbation angles, deg (000_* section 4.2).
pub const ANGLES_DEG: [f64; 8] = [30.0, 60.0, 120.0, 150.0, 210.0, 240.0, 300.0, 330.0];

/// Normalised force pulse `u_p(t)` of 000_* eq. 22 integrated, scaled to a peak of 1,
/// for `t` seconds after the onset and total duration `t_pert_s` (three sections).
pub fn pulse(t: f64, t_pert_s: f64) -> f64 {
    let tp = t_pert_s / 3.0;
    let pi = std::f64::consts::PI;
    let u = if t <= 0.0 || t >= 3.0 * tp {
        0.0
    } else if t <= tp {
        // ∫ ½ sin((s/Tp + 3/2)π) + ½ = ½ (1 − cos(πs/Tp))
        0.5 * t - 0.5 * tp / pi * (pi * t / tp).sin()
    } else if t <= 2.0 * tp {
        let s = t - tp;
        0.5 * tp + tp / pi * (pi * s / tp).sin()
    } else {
        let s = t - 2.0 * tp;
        0.5 * tp - 0.5 * s - 0.5 * tp / pi * (pi * s / tp).sin()
    };
    u / (tp * (0.5 + 1.0 / pi))
}

fn mat_vec(a: &Mat2, v: [f64; 2]) -> [f64; 2] {
    [
        a[0][0] * v[0] + a[0][1] * v[1],
        a[1][0] * v[0] + a[1][1] * v[1],
    ]
}

fn inv(a: &Mat2) -> Mat2 {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    [
        [a[1][1] / det, -a[0][1] / det],
        [-a[1][0] / det, a[0][0] / det],
    ]
}

pub fn add(a: &Mat2, b: &Mat2) -> Mat2 {
    [
        [a[0][0] + b[0][0], a[0][1] + b[0][1]],
        [a[1][0] + b[1][0], a[1][1] + b[1][1]],
    ]
}

/// A perturbed trial of the linear system `M ẍ + D ẋ + K x = u(t)` at rest at
/// `x_offset`, driven by `amp_n · pulse · [cos φ, sin φ]`, integrated by RK4 with
/// `substeps` per sample and sampled at `fs_hz`.
#[derive(Debug)]
pub struct SimTrial {
    pub x_m: [Vec<f64>; 2],
    pub u_n: [Vec<f64>; 2],
    pub onset_index: usize,
}

#[allow(clippy::too_many_arguments)]
pub fn simulate_pulse(
    m: &Mat2,
    d: &Mat2,
    k: &Mat2,
    phi_deg: f64,
    amp_n: f64,
    t_pert_s: f64,
    fs_hz: f64,
    duration_s: f64,
    onset_s: f64,
    substeps: usize,
    x_offset: [f64; 2],
) -> SimTrial {
    let n = (duration_s * fs_hz).round() as usize;
    let onset_index = (onset_s * fs_hz).round() as usize;
    let t0 = onset_index as f64 / fs_hz;
    let dir = [phi_deg.to_radians().cos(), phi_deg.to_radians().sin()];
    let minv = inv(m);
    let force = |t: f64| {
        let p = amp_n * pulse(t - t0, t_pert_s);
        [p * dir[0], p * dir[1]]
    };
    let deriv = |s: [f64; 4], u: [f64; 2]| {
        let dv = mat_vec(d, [s[2], s[3]]);
        let kx = mat_vec(k, [s[0], s[1]]);
        let acc = mat_vec(&minv, [u[0] - dv[0] - kx[0], u[1] - dv[1] - kx[1]]);
        [s[2], s[3], acc[0], acc[1]]
    };
    let h = 1.0 / (fs_hz * substeps as f64);
    let mut s = [0.0; 4];
    let mut x = [Vec::with_capacity(n), Vec::with_capacity(n)];
    let mut u = [Vec::with_capacity(n), Vec::with_capacity(n)];
    for i in 0..n {
        let t = i as f64 / fs_hz;
        let ui = force(t);
        for a in 0..2 {
            x[a].push(s[a] + x_offset[a]);
            u[a].push(ui[a]);
        }
        for j in 0..substeps {
            let tj = t + j as f64 * h;
            let (u1, u2, u3) = (force(tj), force(tj + 0.5 * h), force(tj + h));
            let k1 = deriv(s, u1);
            let k2 = deriv(std::array::from_fn(|q| s[q] + 0.5 * h * k1[q]), u2);
            let k3 = deriv(std::array::from_fn(|q| s[q] + 0.5 * h * k2[q]), u2);
            let k4 = deriv(std::array::from_fn(|q| s[q] + h * k3[q]), u3);
            s = std::array::from_fn(|q| {
                s[q] + h / 6.0 * (k1[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q])
            });
        }
    }
    SimTrial {
        x_m: x,
        u_n: u,
        onset_index,
    }
}

/// Zero-mean Gaussian samples of standard deviation `sigma` (Box–Muller on ChaCha8).
pub fn gaussian_noise(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let u1: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
            let u2: f64 = rng.random::<f64>();
            sigma * (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        })
        .collect()
}

/// Minimum-snap rest-to-rest profile `s(τ) = 35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷` on τ ∈ [0, 1]
/// (zero velocity, acceleration and jerk at both ends) and its first two
/// derivatives with respect to τ.
pub fn min_snap(tau: f64) -> [f64; 3] {
    if tau <= 0.0 {
        return [0.0; 3];
    }
    if tau >= 1.0 {
        return [1.0, 0.0, 0.0];
    }
    let t = tau;
    [
        35.0 * t.powi(4) - 84.0 * t.powi(5) + 70.0 * t.powi(6) - 20.0 * t.powi(7),
        140.0 * t.powi(3) - 420.0 * t.powi(4) + 420.0 * t.powi(5) - 140.0 * t.powi(6),
        420.0 * t.powi(2) - 1680.0 * t.powi(3) + 2100.0 * t.powi(4) - 840.0 * t.powi(5),
    ]
}

/// Position perturbation of 001_*: `amp_m` reached through a `ramp_s` min-snap
/// transition, held, and returned by a second transition, `total_s` in all;
/// returns displacement, velocity, acceleration along the perturbation direction.
pub fn position_pulse(t: f64, amp_m: f64, ramp_s: f64, total_s: f64) -> [f64; 3] {
    let up = min_snap(t / ramp_s);
    let down = min_snap((t - (total_s - ramp_s)) / ramp_s);
    [
        amp_m * (up[0] - down[0]),
        amp_m * (up[1] - down[1]) / ramp_s,
        amp_m * (up[2] - down[2]) / (ramp_s * ramp_s),
    ]
}

/// An imposed-motion trial of 001_*: a sinusoid of `amp_m` at `freq_hz` along
/// `axis` for `n_cycles`, with two position perturbations per cycle at the zero
/// crossings (8 mm, 300 ms, 100 ms min-snap transitions), directions drawn from
/// {kπ/4}; the force is that of the passive system `M ẍ + B ẋ + K x` (the calibrated
/// rig of Appendix B) plus optional sensor noise.
#[derive(Debug)]
pub struct ImposedTrial {
    pub x_m: [Vec<f64>; 2],
    pub force_n: [Vec<f64>; 2],
    /// (onset index, cycle) of each perturbation.
    pub perturbations: Vec<(usize, usize)>,
    pub n_cycles: usize,
}

#[allow(clippy::too_many_arguments)]
pub fn imposed_motion(
    m: &Mat2,
    b: &Mat2,
    k: &Mat2,
    fs_hz: f64,
    n_cycles: usize,
    axis: usize,
    force_noise_n: f64,
    seed: u64,
) -> ImposedTrial {
    let amp = 0.10;
    let freq = 0.125;
    let lead_s = 1.0;
    let period = 1.0 / freq;
    let duration = lead_s + n_cycles as f64 * period + 1.0;
    let n = (duration * fs_hz).round() as usize;
    let w = 2.0 * std::f64::consts::PI * freq;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut onsets = Vec::new();
    let mut dirs = Vec::new();
    for c in 0..n_cycles {
        for half in 0..2 {
            let t_on = lead_s + c as f64 * period + half as f64 * period / 2.0;
            let idx = (t_on * fs_hz).round() as usize;
            let kdir = rng.random_range(1..=8) as f64;
            let ang = kdir * std::f64::consts::FRAC_PI_4;
            onsets.push((idx, c));
            dirs.push([ang.cos(), ang.sin()]);
        }
    }
    let noise = [
        gaussian_noise(n, force_noise_n, seed ^ 0x5eed),
        gaussian_noise(n, force_noise_n, seed ^ 0xf00d),
    ];
    let mut x = [vec![0.0; n], vec![0.0; n]];
    let mut f = [vec![0.0; n], vec![0.0; n]];
    for i in 0..n {
        let t = i as f64 / fs_hz;
        let ph = w * (t - lead_s);
        let mut pos = [0.0; 2];
        let mut vel = [0.0; 2];
        let mut acc = [0.0; 2];
        pos[axis] = amp * ph.sin();
        vel[axis] = amp * w * ph.cos();
        acc[axis] = -amp * w * w * ph.sin();
        for ((idx, _), dir) in onsets.iter().zip(&dirs) {
            let tp = t - *idx as f64 / fs_hz;
            if (0.0..0.3).contains(&tp) {
                let p = position_pulse(tp, 0.008, 0.1, 0.3);
                for a in 0..2 {
                    pos[a] += p[0] * dir[a];
                    vel[a] += p[1] * dir[a];
                    acc[a] += p[2] * dir[a];
                }
            }
        }
        let ma = mat_vec(m, acc);
        let bv = mat_vec(b, vel);
        let kx = mat_vec(k, pos);
        for a in 0..2 {
            x[a][i] = pos[a];
            f[a][i] = ma[a] + bv[a] + kx[a] + noise[a][i];
        }
    }
    ImposedTrial {
        x_m: x,
        force_n: f,
        perturbations: onsets,
        n_cycles,
    }
}

/// Relative error `|est − truth| / |truth|`.
pub fn rel(est: f64, truth: f64) -> f64 {
    (est - truth).abs() / truth.abs()
}
