//! Ellipse metrics of a 2x2 impedance (stiffness, damping or |Z(ω)|) as used by
//! Piovesan et al. (001_*, "Stiffness and Impedance Magnitude and Orientation",
//! Figs. 5–7): principal axes and orientation of the symmetric part, determinant,
//! area, the curl (antisymmetric part) with a significance test, and the impedance
//! `Z(jω) = K + jωB − ω²M` at a given frequency (the form of eq. 5; the seed
//! evaluates it at the movement frequency 0.125 Hz).

use nalgebra::Matrix2;

use super::Mat2;
use super::error::{EstimateError, check_finite_mat2};

/// Geometry of a 2x2 impedance matrix `Z`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EllipseMetrics {
    /// Larger eigenvalue of the symmetric part `(Z + Zᵀ)/2`, in the units of `Z`.
    pub major: f64,
    /// Smaller eigenvalue of the symmetric part.
    pub minor: f64,
    /// Direction of the major axis, degrees in `[0, 180)` from +x towards +y
    /// (001_*, Fig. 5: "major axis at 0 deg when aligned in the x direction").
    pub orientation_deg: f64,
    /// `det Z` of the full matrix (001_*, Fig. 5 and Table 2: det(K), det(Z)).
    pub determinant: f64,
    /// Area `π |λ_major λ_minor|` of the ellipse of the symmetric part, in units²
    /// (the ellipse whose semi-axes are the principal values).
    pub area: f64,
    /// Curl `(Z₂₁ − Z₁₂)/2`, the antisymmetric part; zero for a passive,
    /// conservative spring (000_* section 3.3; 001_* Table 3 and 5).
    pub curl: f64,
}

/// Ellipse metrics of `z` (row-major `[[Z11, Z12], [Z21, Z22]]`).
///
/// # Errors
/// [`EstimateError::NonFinite`] for a non-finite entry.
pub fn ellipse_metrics(z: &Mat2) -> Result<EllipseMetrics, EstimateError> {
    check_finite_mat2("impedance matrix", z)?;
    let [[a, b], [c, d]] = *z;
    let off = 0.5 * (b + c);
    let sym = Matrix2::new(a, off, off, d);
    let eig = sym.symmetric_eigen();
    let (i_max, i_min) = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let major = eig.eigenvalues[i_max];
    let minor = eig.eigenvalues[i_min];
    let v = eig.eigenvectors.column(i_max);
    let mut orientation_deg = v[1].atan2(v[0]).to_degrees().rem_euclid(180.0);
    if orientation_deg >= 180.0 {
        orientation_deg -= 180.0;
    }
    Ok(EllipseMetrics {
        major,
        minor,
        orientation_deg,
        determinant: a * d - b * c,
        area: std::f64::consts::PI * (major * minor).abs(),
        curl: 0.5 * (c - b),
    })
}

/// Outcome of testing whether the curl of an estimated matrix differs from zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurlTest {
    /// `(Z₂₁ − Z₁₂)/2`, units of `Z`.
    pub curl: f64,
    /// Standard error of the curl from the estimate's covariance.
    pub std_err: f64,
    /// `curl / std_err`.
    pub z_score: f64,
    /// Two-sided p-value under a normal reference distribution.
    pub p_value: f64,
    /// `p_value < alpha`.
    pub significant: bool,
}

/// Tests `H₀: Z₁₂ = Z₂₁` (no curl), the seed's test of whether the off-diagonal
/// terms differ (001_* "Statistical Analysis", Tables 3 and 5, significance at
/// p < 0.01), from the variances of the two off-diagonal estimates and their
/// covariance: `var(curl) = (var₁₂ + var₂₁ − 2 cov)/4`.
///
/// Uses a normal reference (a Wald test); with few independent groups behind the
/// covariance this is slightly liberal.
///
/// # Errors
/// [`EstimateError::BadParameter`] when the variance of the difference is not
/// positive and finite or `alpha` is outside (0, 1); [`EstimateError::NonFinite`]
/// for a non-finite entry of `z`.
pub fn curl_test(
    z: &Mat2,
    var_12: f64,
    var_21: f64,
    cov_12_21: f64,
    alpha: f64,
) -> Result<CurlTest, EstimateError> {
    check_finite_mat2("impedance matrix", z)?;
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(EstimateError::BadParameter {
            what: "alpha",
            value: alpha,
            why: "must lie in (0, 1)",
        });
    }
    let var = 0.25 * (var_12 + var_21 - 2.0 * cov_12_21);
    if !(var.is_finite() && var > 0.0) {
        return Err(EstimateError::BadParameter {
            what: "variance of the curl",
            value: var,
            why: "must be finite and > 0",
        });
    }
    let curl = 0.5 * (z[1][0] - z[0][1]);
    let std_err = var.sqrt();
    let z_score = curl / std_err;
    let p_value = erfc(z_score.abs() / std::f64::consts::SQRT_2);
    Ok(CurlTest {
        curl,
        std_err,
        z_score,
        p_value,
        significant: p_value < alpha,
    })
}

/// Complementary error function, fractional error below 1.2e-7 everywhere
/// (Chebyshev fit of Numerical Recipes, 3rd ed., `erfccheb`'s predecessor `erfcc`).
pub(crate) fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// The complex endpoint impedance `Z(jω) = K + jωB − ω²M` (form of 001_* eq. 5 in
/// the frequency domain, force over displacement), split into real and imaginary
/// 2x2 parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComplexImpedance {
    /// `K − ω²M`, N/m.
    pub re_n_per_m: Mat2,
    /// `ωB`, N/m.
    pub im_n_per_m: Mat2,
}

impl ComplexImpedance {
    /// Element-wise modulus `|Z_ij(ω)|`, N/m: the matrix whose ellipse 001_* draws
    /// (Fig. 6: "Magnitude is calculated for the specific angular frequency").
    pub fn modulus(&self) -> Mat2 {
        let mut out = [[0.0; 2]; 2];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = self.re_n_per_m[i][j].hypot(self.im_n_per_m[i][j]);
            }
        }
        out
    }
}

/// `Z(jω) = K + jωB − ω²M` at `omega_rad_s`.
///
/// # Errors
/// [`EstimateError::NonFinite`] for a non-finite matrix entry,
/// [`EstimateError::BadParameter`] for a negative or non-finite frequency.
pub fn impedance_at(
    k_n_per_m: &Mat2,
    b_ns_per_m: &Mat2,
    m_kg: &Mat2,
    omega_rad_s: f64,
) -> Result<ComplexImpedance, EstimateError> {
    check_finite_mat2("stiffness", k_n_per_m)?;
    check_finite_mat2("damping", b_ns_per_m)?;
    check_finite_mat2("inertia", m_kg)?;
    if !(omega_rad_s.is_finite() && omega_rad_s >= 0.0) {
        return Err(EstimateError::BadParameter {
            what: "omega_rad_s",
            value: omega_rad_s,
            why: "must be finite and >= 0",
        });
    }
    let w2 = omega_rad_s * omega_rad_s;
    let mut re = [[0.0; 2]; 2];
    let mut im = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            re[i][j] = k_n_per_m[i][j] - w2 * m_kg[i][j];
            im[i][j] = omega_rad_s * b_ns_per_m[i][j];
        }
    }
    Ok(ComplexImpedance {
        re_n_per_m: re,
        im_n_per_m: im,
    })
}
