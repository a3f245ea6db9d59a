//! The control clock. Every time in this crate is a whole number of 4 kHz ticks;
//! seconds are derived from a tick count by one division, never accumulated.

/// Rate of the rig's control clock \[Hz\]: `rigtwin_device::Rate::CONTROL`, restated
/// because the arm must not depend on the rig's code; `tests/tests/one_clock.rs` holds
/// the two equal.
pub const TICK_HZ: u64 = 4000;

/// Seconds corresponding to a tick count \[s\].
pub fn ticks_to_s(ticks: u64) -> f64 {
    ticks as f64 / TICK_HZ as f64
}

/// A duration in milliseconds as a whole number of periods of `divisor` ticks,
/// or `None` when it is not a whole number (to 1e-9 of a period) or is negative.
pub fn ms_to_periods(ms: f64, divisor: u32) -> Option<u64> {
    if !(ms.is_finite() && ms >= 0.0) || divisor == 0 {
        return None;
    }
    let periods = ms * 1e-3 * TICK_HZ as f64 / f64::from(divisor);
    let rounded = periods.round();
    ((periods - rounded).abs() < 1e-9).then_some(rounded as u64)
}
