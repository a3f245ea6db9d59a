//! Counts a position encoder gained or lost: a position that steps once and stays off
//! by the step, found and levelled before the balances are fitted.
//!
//! An incremental encoder counts the edges of its scale. Interference on its lines, a
//! smudge on the scale or an interpolator that loses track adds or drops a burst of
//! counts, and every later reading is off by them. In the log the position steps by
//! the burst within one row and goes on from there at its speed. The balances
//! differentiate the position twice, so the step becomes an acceleration doublet of
//! `±Δ/dt²`: four jumps of 0.2 mm in a session of 32 trials took a 1.575 ms delay's
//! held-out gain from 0.337 to 0.25, and four of 1 mm made the faulty-unit rule set
//! aside three good trials and left a gain of 0.067
//! (`hil/docs/notes/2026-12-07-encoder-jumps-and-lateral-reaches.md`).
//!
//! **The signature.** With `d_k = x_k − x_{k−1}`, a jump of `Δ` into row `i` makes
//! `d_i = v dt + Δ` while its neighbours carry `v dt`: a lone spike in `d` (the
//! [`super::glitch`] rule's run of one on `d`: above ten robust sigmas and the 20 µm
//! floor, its neighbours' departures opposite at 0.25–0.75 of it, the samples two away
//! under a quarter), as a lost sample makes. A jump is such a spike in one position
//! channel that [`super::slip`] did not take for lost samples (a whole number of the
//! neighbours' mean step, the other channel stretched alike) or a skipped reading. No
//! motion makes one: the handle would cover `Δ` more in one period and go on at its
//! old speed, an acceleration of at least `Δ/dt²` (20 000 m/s² for 20 µm at 1 kHz)
//! there and back within two periods, where a rig's motors and a hand give its carts a
//! few tens of m/s². A glitch leaves `d` a dipole instead (`+s`, then `−s`).
//!
//! **The levelling.** The channel from row `i` on is moved by `−Δ̂`, with
//! `Δ̂ = d_i − (d_{i−1} + d_{i+1})/2`, so that the step into `i` is its neighbours'
//! mean. A controller that works on the same count moves the carts to undo the step;
//! that motion is real, the levelled position shows it, and the balances see it with
//! the command that made it. The position after the levelling is the sensor's own
//! up to `Δ̂`'s error: the sample noise times √2.5 (the four samples it
//! takes) and the path's jerk times `dt³/2`. The files are never changed; [`Jump`] lists
//! each with its trial's file, channel, row and size.
//!
//! **Left as recorded or judged otherwise:**
//! - a jump smaller than 20 µm (20 counts of a 1 µm encoder), which moves no fit;
//! - a jump within a quarter of a whole number of the row's travel where the other
//!   channel's step allows it: [`super::slip`] takes it for lost samples, or, where
//!   the controller's reference steps on, for a skipped reading. The step's doublet is
//!   then undone all the same, but the position keeps the offset (and, taken for lost
//!   samples, every other column is a row late after it; 0.2 mm jumps at a reach's
//!   peak of 0.2 mm a row: two of four taken for skipped readings);
//! - a jump in a channel the logger held between readings ([`super::hold`] spreads it
//!   over the rows it fills: no lone spike is left);
//! - a jump into a trial's first two rows or its last (the rule needs a step on either
//!   side of the spiking one);
//! - a controller that closes its loop on the same count and pulls the position back
//!   within a row or two: the rule needs the step after the jump within a quarter of
//!   its size of its neighbours, which a position loop slower than about 100 Hz (a
//!   first-ms return of `Δ ω² dt² / 2`) leaves it.

use serde::Serialize;

use super::glitch;

/// A position encoder's count jump, levelled before the fits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Jump {
    /// The trial's file, as the manifest names it.
    pub file: String,
    /// The position channel, `x_m` or `y_m`.
    pub channel: &'static str,
    /// The recorded row whose reading is the first off by the jump (0 for the first
    /// after the header).
    pub row: usize,
    /// That row's time in its trial as recorded, s.
    pub t_s: f64,
    /// The jump, `Δ̂` (module docs), m.
    pub step_m: f64,
}

/// The lone spikes of the step of `x` (the glitch rule's runs of one on `d`, with both
/// neighbours): each as the row `i` the spiking step leads into, and the step's excess
/// over its neighbours' mean, `d_i − (d_{i−1} + d_{i+1})/2`.
#[must_use]
pub fn spikes(x: &[f64]) -> Vec<(usize, f64)> {
    if x.len() < 8 {
        return Vec::new();
    }
    let d: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    // d[k] is the step into row k + 1.
    glitch::find(&d, glitch::POSITION_FLOOR_M)
        .into_iter()
        .filter(|&(k, len)| len == 1 && k >= 1 && k + 1 < d.len())
        .map(|(k, _)| (k + 1, d[k] - 0.5 * (d[k - 1] + d[k + 1])))
        .collect()
}

/// `x` with each jump `(row, Δ̂)` of `jumps` levelled: every sample from the row on
/// moved by `−Δ̂`.
#[must_use]
pub fn levelled(x: &[f64], jumps: &[(usize, f64)]) -> Vec<f64> {
    let mut out = x.to_vec();
    for &(row, step) in jumps {
        for v in out.iter_mut().skip(row) {
            *v -= step;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reaches;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_jump_is_found_at_its_row_and_levelled_to_the_noise() {
        // A reach of 0.25 m in 0.6 s from 0.1 s at 1 kHz (0.78 m/s peak at row 400)
        // with 0.3 µm of white noise, on ten draws; jumps of +50 µm at rest (row 40),
        // −0.3 mm at peak speed (row 400) and +25 µm on the way (row 250). Each is found
        // at its row with its size within 2 µm: Δ̂ = x_i − x_{i−1} − (x_{i+1} − x_{i−2})/2
        // has the noise √2.5 · 0.3 µm ≈ 0.47 µm, and the path's jerk adds at most
        // 70 m/s³ · dt³ / 2 = 0.04 µm; 2 µm is four sd. Levelled, the channel is within
        // 3 µm of the clean one everywhere (after the last jump it is off by the sum of
        // three Δ̂ errors, sd 0.82 µm; 3 µm is 3.7 sd), where as recorded it was 0.3 mm
        // off. Without jumps nothing is found.
        for seed in 0..10 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let clean = reaches::noisy(&mut rng, 0.25, 0.1, (0..800).map(|i| i as f64));
            assert!(
                spikes(&clean).is_empty(),
                "seed {seed}: {:?}",
                spikes(&clean)
            );
            let put = [(40, 50e-6), (250, 25e-6), (400, -0.3e-3)];
            let jumped = levelled(&clean, &put.map(|(r, s)| (r, -s)));
            let found = spikes(&jumped);
            assert_eq!(found.len(), put.len(), "seed {seed}: {found:?}");
            for ((row, step), (r, s)) in found.iter().zip(put) {
                assert_eq!(*row, r, "seed {seed}");
                assert!((step - s).abs() < 2e-6, "seed {seed}: {step} for {s}");
            }
            let mended = levelled(&jumped, &found);
            let worst = mended
                .iter()
                .zip(&clean)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(worst < 3e-6, "seed {seed}: {worst}");
        }
    }
}
