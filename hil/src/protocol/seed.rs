//! Seed derivation. Every random stream of a rehearsal comes from the session seed and
//! the position of the thing it drives (subject, trial, stream), never from the order
//! in which worker threads pick work up, so the output does not depend on `--jobs`.

/// SplitMix64's finaliser: a bijective mix of 64 bits with full avalanche.
#[must_use]
pub fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A seed from a list of integers (session seed, subject, trial, stream...): each is
/// folded in through [`splitmix`], so different lists give unrelated seeds.
#[must_use]
pub fn mix(parts: &[u64]) -> u64 {
    parts
        .iter()
        .fold(0x243F_6A88_85A3_08D3, |acc, p| splitmix(acc ^ splitmix(*p)))
}

/// The streams of one trial.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// The plant's sensor noise.
    Plant = 1,
    /// The arm's motor noise.
    Arm = 2,
    /// The trial's own draws (position-perturbation directions).
    Schedule = 3,
    /// The trial's nuisances (`super::nuisance`).
    Nuisance = 4,
}

/// Seed of `stream` in trial `trial` (0-based) of subject `subject` (1-based).
#[must_use]
pub fn trial_seed(session_seed: u64, subject: u32, trial: u32, stream: Stream) -> u64 {
    mix(&[
        session_seed,
        u64::from(subject),
        u64::from(trial),
        stream as u64,
    ])
}

/// Seed of the session-level schedule (which trials are perturbed, at which angle).
#[must_use]
pub fn schedule_seed(session_seed: u64, subject: u32) -> u64 {
    mix(&[session_seed, u64::from(subject), 0x5C4E_D01E])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_differ_and_are_stable() {
        let a = trial_seed(7, 1, 0, Stream::Plant);
        assert_eq!(a, trial_seed(7, 1, 0, Stream::Plant));
        assert_ne!(a, trial_seed(7, 1, 0, Stream::Arm));
        assert_ne!(a, trial_seed(7, 1, 1, Stream::Plant));
        assert_ne!(a, trial_seed(7, 2, 0, Stream::Plant));
        assert_ne!(a, trial_seed(8, 1, 0, Stream::Plant));
    }
}
