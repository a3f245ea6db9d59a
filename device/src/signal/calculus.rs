//! Numerical integration and differentiation of uniformly sampled signals, as
//! `scipy.integrate.cumulative_trapezoid` and `numpy.gradient`.

/// Running trapezoidal integral of `y` sampled every `dt_s` seconds, as
/// `scipy.integrate.cumulative_trapezoid(y, dx=dt_s, initial=0)`: same length as
/// `y`, starting at 0, in `[y]·s`. Empty input gives empty output.
pub fn cumulative_trapezoid(y: &[f64], dt_s: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(y.len());
    if y.is_empty() {
        return out;
    }
    out.push(0.0);
    out.extend(cumulative_trapezoid_increments(y, dt_s));
    out
}

/// As [`cumulative_trapezoid`] without the leading 0 (scipy's default
/// `initial=None`): length `y.len() − 1` (empty for fewer than two samples).
pub fn cumulative_trapezoid_no_initial(y: &[f64], dt_s: f64) -> Vec<f64> {
    cumulative_trapezoid_increments(y, dt_s).collect()
}

fn cumulative_trapezoid_increments(y: &[f64], dt_s: f64) -> impl Iterator<Item = f64> + '_ {
    y.windows(2).scan(0.0, move |acc, w| {
        *acc += dt_s * (w[0] + w[1]) / 2.0;
        Some(*acc)
    })
}

/// Derivative of `y` sampled every `dt_s` seconds, as `numpy.gradient(y, dt_s)`:
/// second-order central differences inside, first-order one-sided differences at
/// the two ends; same length, in `[y]/s`. numpy refuses fewer than two samples;
/// here one sample gives `[0.0]` (no slope is observable) and none gives `[]`.
pub fn gradient(y: &[f64], dt_s: f64) -> Vec<f64> {
    let n = y.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let mut out = Vec::with_capacity(n);
    out.push((y[1] - y[0]) / dt_s);
    out.extend(y.windows(3).map(|w| (w[2] - w[0]) / (2.0 * dt_s)));
    out.push((y[n - 1] - y[n - 2]) / dt_s);
    out
}
