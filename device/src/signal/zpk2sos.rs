//! Zeros, poles and gain to second-order sections, as `scipy.signal.zpk2sos` with
//! its default digital pairing `'nearest'`.
//!
//! The pairing and ordering are reproduced step by step (same sort keys, same
//! "worst pole last" rule, same tie-breaking by first index) so that the sections
//! equal scipy's, not merely describe the same filter.

use nalgebra::Complex;

use super::error::SignalError;

type C = Complex<f64>;

/// A digital filter as zeros, poles and gain.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Zpk {
    pub z: Vec<C>,
    pub p: Vec<C>,
    pub k: f64,
}

fn is_real(c: C) -> bool {
    c.im == 0.0
}

/// scipy's `_cplxreal`: one representative (positive imaginary part, averaged with
/// its conjugate) per complex pair, sorted by real part then |imag|, followed by the
/// real values sorted by value. Returned concatenated, as `zpk2sos` uses it.
fn cplxreal(z: &[C]) -> Result<Vec<C>, SignalError> {
    let tol = 100.0 * f64::EPSILON;
    let mut z: Vec<C> = z.to_vec();
    // Stable sort, primary key real part, secondary |imag| (np.lexsort).
    z.sort_by(|a, b| {
        a.re.total_cmp(&b.re)
            .then_with(|| a.im.abs().total_cmp(&b.im.abs()))
    });
    let (reals, cplx): (Vec<C>, Vec<C>) = z.into_iter().partition(|c| c.im.abs() <= tol * c.norm());
    let zr: Vec<C> = reals.into_iter().map(|c| C::new(c.re, 0.0)).collect();
    let mut zp: Vec<C> = cplx.iter().copied().filter(|c| c.im > 0.0).collect();
    let mut zn: Vec<C> = cplx.iter().copied().filter(|c| c.im < 0.0).collect();
    if zp.len() != zn.len() {
        return Err(SignalError::BadCoefficients {
            why: "a complex root has no conjugate",
        });
    }
    // Runs of (approximately) equal real part are sorted by |imag|.
    let mut start = 0;
    while start < zp.len() {
        let mut stop = start + 1;
        while stop < zp.len() && zp[stop].re - zp[stop - 1].re <= tol * zp[stop - 1].norm() {
            stop += 1;
        }
        zp[start..stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        zn[start..stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        start = stop;
    }
    let mut out = Vec::with_capacity(zp.len() + zr.len());
    for (a, b) in zp.iter().zip(&zn) {
        if (a - b.conj()).norm() > tol * b.norm() {
            return Err(SignalError::BadCoefficients {
                why: "a complex root has no conjugate",
            });
        }
        out.push((a + b.conj()) / 2.0);
    }
    out.extend(zr);
    Ok(out)
}

/// Index of the first minimum of `key` over `v` (np.argmin).
fn argmin_by(v: &[C], key: impl Fn(C) -> f64) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, c) in v.iter().enumerate() {
        let k = key(*c);
        if best.is_none_or(|(_, b)| k < b) {
            best = Some((i, k));
        }
    }
    best.map(|(i, _)| i)
}

/// "Worst" digital pole: the one closest to the unit circle.
fn idx_worst(p: &[C]) -> Option<usize> {
    argmin_by(p, |c| (1.0 - c.norm()).abs())
}

#[derive(Clone, Copy, PartialEq)]
enum Which {
    Real,
    Complex,
    Any,
}

/// scipy's `_nearest_real_complex_idx`: nearest element of `fro` to `to` that is real,
/// complex, or either. Stable order among equal distances.
fn nearest_idx(fro: &[C], to: C, which: Which) -> Option<usize> {
    let mut order: Vec<usize> = (0..fro.len()).collect();
    order.sort_by(|&a, &b| (fro[a] - to).norm().total_cmp(&(fro[b] - to).norm()));
    order.into_iter().find(|&i| match which {
        Which::Any => true,
        Which::Real => is_real(fro[i]),
        Which::Complex => !is_real(fro[i]),
    })
}

/// Monic polynomial with the given (up to two) roots, as `np.poly`, real part taken.
fn poly(roots: &[C]) -> Vec<f64> {
    let mut c: Vec<C> = vec![C::new(1.0, 0.0)];
    for r in roots {
        let mut next = vec![C::new(0.0, 0.0); c.len() + 1];
        for (i, ci) in c.iter().enumerate() {
            next[i] += ci;
            next[i + 1] += ci * (-r);
        }
        c = next;
    }
    c.iter().map(|v| v.re).collect()
}

/// scipy's `_single_zpksos` with unit gain: right-aligned b and a in one section.
fn single_section(z: &[C], p: &[C]) -> [f64; 6] {
    let mut s = [0.0; 6];
    let b = poly(z);
    let a = poly(p);
    s[3 - b.len()..3].copy_from_slice(&b);
    s[6 - a.len()..6].copy_from_slice(&a);
    s
}

/// Removes and returns the element that `pick` selects.
fn take(v: &mut Vec<C>, pick: impl FnOnce(&[C]) -> Option<usize>) -> Result<C, SignalError> {
    match pick(v) {
        Some(i) if i < v.len() => Ok(v.remove(i)),
        _ => Err(SignalError::BadCoefficients {
            why: "zeros and poles cannot be paired into sections",
        }),
    }
}

/// `scipy.signal.zpk2sos(z, p, k)` for a digital filter (pairing `'nearest'`).
pub(crate) fn zpk2sos(zpk: &Zpk) -> Result<Vec<[f64; 6]>, SignalError> {
    if zpk.z.is_empty() && zpk.p.is_empty() {
        return Ok(vec![[zpk.k, 0.0, 0.0, 1.0, 0.0, 0.0]]);
    }
    let mut p = zpk.p.clone();
    let mut z = zpk.z.clone();
    let zero = C::new(0.0, 0.0);
    while p.len() < z.len() {
        p.push(zero);
    }
    while z.len() < p.len() {
        z.push(zero);
    }
    let n_sections = p.len().div_ceil(2);
    if p.len() % 2 == 1 {
        p.push(zero);
        z.push(zero);
    }
    let mut z = cplxreal(&z)?;
    let mut p = cplxreal(&p)?;
    let mut sos = vec![[0.0; 6]; n_sections];
    for si in (0..n_sections).rev() {
        let p1 = take(&mut p, idx_worst)?;
        let n_real_p = p.iter().filter(|c| is_real(**c)).count();
        let n_real_z = z.iter().filter(|c| is_real(**c)).count();
        if is_real(p1) && n_real_p == 0 {
            // Special case (1): last remaining real pole.
            let z1 = take(&mut z, |z| nearest_idx(z, p1, Which::Real))?;
            sos[si] = single_section(&[z1, zero], &[p1, zero]);
        } else if p.len() + 1 == z.len() && !is_real(p1) && n_real_p == 1 && n_real_z == 1 {
            // Special case (2): one real pole and one real zero left; pair this
            // complex pole with a complex zero.
            let z1 = take(&mut z, |z| nearest_idx(z, p1, Which::Complex))?;
            sos[si] = single_section(&[z1, z1.conj()], &[p1, p1.conj()]);
        } else {
            let p2 = if is_real(p1) {
                let real_idx: Vec<usize> = (0..p.len()).filter(|&i| is_real(p[i])).collect();
                let reals: Vec<C> = real_idx.iter().map(|&i| p[i]).collect();
                let j = idx_worst(&reals).map(|j| real_idx[j]);
                take(&mut p, |_| j)?
            } else {
                p1.conj()
            };
            if z.is_empty() {
                sos[si] = single_section(&[], &[p1, p2]);
            } else {
                let z1 = take(&mut z, |z| nearest_idx(z, p1, Which::Any))?;
                if !is_real(z1) {
                    sos[si] = single_section(&[z1, z1.conj()], &[p1, p2]);
                } else if !z.is_empty() {
                    let z2 = take(&mut z, |z| nearest_idx(z, p1, Which::Real))?;
                    sos[si] = single_section(&[z1, z2], &[p1, p2]);
                } else {
                    sos[si] = single_section(&[z1], &[p1, p2]);
                }
            }
        }
    }
    if !(p.is_empty() && z.is_empty()) {
        return Err(SignalError::BadCoefficients {
            why: "zeros and poles cannot be paired into sections",
        });
    }
    for c in &mut sos[0][..3] {
        *c *= zpk.k;
    }
    Ok(sos)
}
