//! Values checked as they are deserialized: finite, positive and non-negative numbers
//! (TOML floats or integers) and pairs of them, so that a bad value is a serde error at
//! its own span.

#[allow(clippy::wildcard_imports)]
use super::*;

/// A finite number, as TOML float or integer.
pub(super) struct Finite(pub(super) f64);

impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f64::deserialize(d)?;
        if v.is_finite() {
            Ok(Finite(v))
        } else {
            Err(de::Error::custom(format!("{v} is not finite")))
        }
    }
}

/// A finite number > 0.
pub(super) struct Positive(pub(super) f64);

impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Finite(v) = Finite::deserialize(d)?;
        if v > 0.0 {
            Ok(Positive(v))
        } else {
            Err(de::Error::custom(format!("must be > 0, found {v}")))
        }
    }
}

/// A recording rate a reader can check time against, Hz: from [`MIN_RATE_HZ`] to
/// [`MAX_RATE_HZ`]. Below the range the time check's tolerance (a fraction of a sample
/// period) grows without bound — at `5e-324` it would accept any time column — and above
/// it no rig in this format's scope samples.
pub(super) struct SampleRate(pub(super) f64);

impl<'de> Deserialize<'de> for SampleRate {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Finite(v) = Finite::deserialize(d)?;
        if (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&v) {
            Ok(SampleRate(v))
        } else {
            Err(de::Error::custom(format!(
                "must be from {MIN_RATE_HZ} to {MAX_RATE_HZ} Hz, found {v}"
            )))
        }
    }
}

/// A finite number ≥ 0.
pub(super) struct NonNegative(pub(super) f64);

impl<'de> Deserialize<'de> for NonNegative {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Finite(v) = Finite::deserialize(d)?;
        if v >= 0.0 {
            Ok(NonNegative(v))
        } else {
            Err(de::Error::custom(format!("must be ≥ 0, found {v}")))
        }
    }
}

/// Exactly two elements (`[f64; 2]` alone would accept `[1.0, 2.0, 3.0]`).
pub(super) struct Pair<T>(pub(super) [T; 2]);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Pair<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = Pair<T>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an array of two numbers [x, y]")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Pair<T>, A::Error> {
                let a = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let b = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(1, &self))?;
                let mut n = 2;
                while seq.next_element::<de::IgnoredAny>()?.is_some() {
                    n += 1;
                }
                if n == 2 {
                    Ok(Pair([a, b]))
                } else {
                    Err(de::Error::invalid_length(n, &self))
                }
            }
        }
        d.deserialize_seq(V(std::marker::PhantomData))
    }
}

pub(super) fn finite2(p: Pair<Finite>) -> [f64; 2] {
    let [Finite(a), Finite(b)] = p.0;
    [a, b]
}

pub(super) fn positive2(p: Pair<Positive>) -> [f64; 2] {
    let [Positive(a), Positive(b)] = p.0;
    [a, b]
}

pub(super) fn non_negative2(p: Pair<NonNegative>) -> [f64; 2] {
    let [NonNegative(a), NonNegative(b)] = p.0;
    [a, b]
}
