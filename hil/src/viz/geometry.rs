//! The geometry behind the pictures: two-link inverse kinematics for measured sessions, the
//! image of the unit circle under an impedance matrix, and the variational response to a
//! perturbation.

use nalgebra::Matrix2;

use super::columns::ArmTrajectory;

/// Which elbow solution: the arm's own (`Elbow::Down`, positive elbow flexion, is the
/// right arm's posture; `Elbow::Up` its mirror).
pub use rigtwin_arm::kinematics::Elbow;

/// Two-link inverse kinematics of a hand path (law of cosines), for sessions that record the
/// handle but not the arm.
///
/// It is not `rigtwin_arm::kinematics::inverse`, which refuses a hand out of reach: a
/// picture of a measured session must still draw every sample, so this one clamps.
///
/// `shoulder_m` in the rig frame, segment lengths in m. Angles: shoulder from +x toward +y,
/// elbow relative to the upper arm. A hand out of reach (farther than `upper + fore` or nearer
/// than `|upper - fore|`) is drawn with the arm fully stretched or folded toward it, and
/// counted in [`ArmTrajectory::out_of_reach`].
pub fn two_link_inverse(
    shoulder_m: [f64; 2],
    upper_arm_m: f64,
    forearm_m: f64,
    hand_x_m: &[f64],
    hand_y_m: &[f64],
    elbow: Elbow,
) -> ArmTrajectory {
    let n = hand_x_m.len().min(hand_y_m.len());
    let (l1, l2) = (upper_arm_m, forearm_m);
    let mut arm = ArmTrajectory {
        shoulder_m,
        ..ArmTrajectory::default()
    };
    for (&hx, &hy) in hand_x_m.iter().zip(hand_y_m).take(n) {
        let (dx, dy) = (hx - shoulder_m[0], hy - shoulder_m[1]);
        let r2 = dx * dx + dy * dy;
        let cos_q2 = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
        if !(-1.0..=1.0).contains(&cos_q2) {
            arm.out_of_reach += 1;
        }
        let mut q2 = cos_q2.clamp(-1.0, 1.0).acos();
        if elbow == Elbow::Up {
            q2 = -q2;
        }
        let q1 = dy.atan2(dx) - (l2 * q2.sin()).atan2(l1 + l2 * q2.cos());
        let (ex, ey) = (shoulder_m[0] + l1 * q1.cos(), shoulder_m[1] + l1 * q1.sin());
        arm.elbow_x_m.push(ex);
        arm.elbow_y_m.push(ey);
        // The hand drawn is the forward kinematics of the angles, so that an unreachable
        // target shows the arm's real reach instead of a link of the wrong length.
        arm.hand_x_m.push(ex + l2 * (q1 + q2).cos());
        arm.hand_y_m.push(ey + l2 * (q1 + q2).sin());
        arm.shoulder_rad.push(q1);
        arm.elbow_rad.push(q2);
    }
    arm
}

/// The principal axes of the ellipse `{ M u : |u| = 1 }`: semi-axis lengths (singular values
/// of `M`, largest first, in the matrix's units) and unit directions (left singular vectors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EllipseAxes {
    /// Semi-axis lengths, largest first.
    pub lengths: [f64; 2],
    /// Unit direction of each semi-axis (sign chosen so that the larger `|component|` is
    /// positive, for a stable picture).
    pub directions: [[f64; 2]; 2],
}

/// The principal axes of the image of the unit circle under `m` (row-major `[[m00, m01],
/// [m10, m11]]`). For a symmetric positive matrix (a stiffness `K`, a damping `D`) these are
/// its eigenvalues and eigenvectors.
pub fn ellipse_axes(m: [[f64; 2]; 2]) -> EllipseAxes {
    let mat = Matrix2::new(m[0][0], m[0][1], m[1][0], m[1][1]);
    let svd = mat.svd(true, false);
    let s = svd.singular_values;
    let (i_big, i_small) = if s[0] >= s[1] { (0, 1) } else { (1, 0) };
    let u = svd.u.unwrap_or_else(Matrix2::identity);
    let dir = |i: usize| {
        let (a, b) = (u[(0, i)], u[(1, i)]);
        let flip = if a.abs() >= b.abs() { a < 0.0 } else { b < 0.0 };
        if flip { [-a, -b] } else { [a, b] }
    };
    EllipseAxes {
        lengths: [s[i_big], s[i_small]],
        directions: [dir(i_big), dir(i_small)],
    }
}

/// `segments + 1` points of the closed curve `center + scale * M [cos θ, sin θ]`.
///
/// θ starts at a right-singular direction of `M` (an eigenvector of MᵀM), so with
/// `segments` a multiple of 4 the outline passes exactly through the four vertices of the
/// ellipse: the drawn semi-axes are the matrix's singular values, not a sampled
/// approximation of them.
pub fn ellipse_outline(
    center: [f64; 2],
    m: [[f64; 2]; 2],
    scale: f64,
    segments: usize,
) -> Vec<[f64; 2]> {
    let segments = segments.max(3);
    // MᵀM = [[p, q], [q, r]]; its eigenvectors lie at 0.5·atan2(2q, p − r).
    let p = m[0][0] * m[0][0] + m[1][0] * m[1][0];
    let q = m[0][0] * m[0][1] + m[1][0] * m[1][1];
    let r = m[0][1] * m[0][1] + m[1][1] * m[1][1];
    let start = 0.5 * (2.0 * q).atan2(p - r);
    (0..=segments)
        .map(|k| {
            let theta = start + std::f64::consts::TAU * k as f64 / segments as f64;
            let (c, s) = (theta.cos(), theta.sin());
            [
                center[0] + scale * (m[0][0] * c + m[0][1] * s),
                center[1] + scale * (m[1][0] * c + m[1][1] * s),
            ]
        })
        .collect()
}

/// Length of the variational response shown after a perturbation onset, s.
pub const RESPONSE_WINDOW_S: f64 = 0.150;

/// The hand's deviation from its unperturbed course over the window after onset.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Response {
    /// Index of the first sample at or after onset.
    pub first: usize,
    /// Trial time of each response sample, s.
    pub t_s: Vec<f64>,
    /// Deviation from the baseline, m.
    pub dx_m: Vec<f64>,
    /// Deviation from the baseline, m.
    pub dy_m: Vec<f64>,
}

/// Position minus a straight-line baseline over `[onset, onset + window]`: the baseline
/// continues the hand's course at its velocity over the 10 ms before onset, so the response
/// starts at zero and shows how the perturbation bends the path. A view aid, not an estimator.
///
/// `None` when the onset is outside the samples.
pub fn variational_response(
    t_s: &[f64],
    x_m: &[f64],
    y_m: &[f64],
    onset_s: f64,
    window_s: f64,
) -> Option<Response> {
    let n = t_s.len().min(x_m.len()).min(y_m.len());
    let first = t_s[..n].iter().position(|&t| t >= onset_s)?;
    let t0 = t_s[first];
    let before = t_s[..first]
        .iter()
        .rposition(|&t| t <= t0 - 0.010)
        .unwrap_or(0);
    let (vx, vy) = if first > before {
        let dt = t0 - t_s[before];
        (
            (x_m[first] - x_m[before]) / dt,
            (y_m[first] - y_m[before]) / dt,
        )
    } else {
        (0.0, 0.0)
    };
    let mut out = Response {
        first,
        ..Response::default()
    };
    for i in first..n {
        let dt = t_s[i] - t0;
        if t_s[i] > onset_s + window_s {
            break;
        }
        out.t_s.push(t_s[i]);
        out.dx_m.push(x_m[i] - (x_m[first] + vx * dt));
        out.dy_m.push(y_m[i] - (y_m[first] + vy * dt));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn inverse_kinematics_reaches_the_hand_with_the_elbow_on_the_right() {
        let arm = two_link_inverse(
            [0.0, -0.425],
            0.33,
            0.34,
            &[0.0, 0.05],
            &[0.0, -0.1],
            Elbow::Down,
        );
        assert_eq!(arm.out_of_reach, 0);
        for i in 0..2 {
            let (ex, ey) = (arm.elbow_x_m[i], arm.elbow_y_m[i]);
            assert_relative_eq!(
                (ex.powi(2) + (ey + 0.425).powi(2)).sqrt(),
                0.33,
                epsilon = 1e-12
            );
            let (hx, hy) = ([0.0, 0.05][i], [0.0, -0.1][i]);
            assert_relative_eq!(arm.hand_x_m[i], hx, epsilon = 1e-12);
            assert_relative_eq!(arm.hand_y_m[i], hy, epsilon = 1e-12);
            assert_relative_eq!(
                ((hx - ex).powi(2) + (hy - ey).powi(2)).sqrt(),
                0.34,
                epsilon = 1e-12
            );
            assert!(arm.elbow_rad[i] > 0.0);
        }
        // Hand straight ahead of the shoulder: a right elbow points to +x.
        assert!(arm.elbow_x_m[0] > 0.0);
    }

    #[test]
    fn unreachable_hand_stretches_the_arm_and_is_counted() {
        let arm = two_link_inverse([0.0, 0.0], 0.3, 0.3, &[1.0], &[0.0], Elbow::Down);
        assert_eq!(arm.out_of_reach, 1);
        assert_relative_eq!(arm.hand_x_m[0], 0.6, epsilon = 1e-12);
        assert_relative_eq!(arm.elbow_rad[0], 0.0, epsilon = 1e-12);
    }

    #[test]
    fn ellipse_axes_of_a_symmetric_matrix_are_its_eigenpairs() {
        // K = R diag(400, 100) R^T with R a rotation by 30 degrees.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let k = [
            [400.0 * c * c + 100.0 * s * s, 300.0 * c * s],
            [300.0 * c * s, 400.0 * s * s + 100.0 * c * c],
        ];
        let axes = ellipse_axes(k);
        assert_relative_eq!(axes.lengths[0], 400.0, epsilon = 1e-9);
        assert_relative_eq!(axes.lengths[1], 100.0, epsilon = 1e-9);
        assert_relative_eq!(axes.directions[0][0], c, epsilon = 1e-12);
        assert_relative_eq!(axes.directions[0][1], s, epsilon = 1e-12);
        let outline = ellipse_outline([0.1, 0.2], k, 1e-4, 360);
        let radii: Vec<f64> = outline
            .iter()
            .map(|p| ((p[0] - 0.1).powi(2) + (p[1] - 0.2).powi(2)).sqrt())
            .collect();
        let max = radii.iter().copied().fold(f64::MIN, f64::max);
        let min = radii.iter().copied().fold(f64::MAX, f64::min);
        // The outline starts on a singular direction and 360 is a multiple of 4, so the
        // vertices are sampled exactly: only rounding separates them from the semi-axes.
        assert_relative_eq!(max, 0.04, max_relative = 1e-12);
        assert_relative_eq!(min, 0.01, max_relative = 1e-12);
    }

    #[test]
    fn response_of_a_straight_path_is_zero_and_a_bump_shows() {
        let t: Vec<f64> = (0..1000).map(|i| f64::from(i) / 1000.0).collect();
        let x: Vec<f64> = t.iter().map(|&t| 0.1 * t).collect();
        let mut y: Vec<f64> = t.iter().map(|&t| -0.2 + 0.05 * t).collect();
        let r = variational_response(&t, &x, &y, 0.5, RESPONSE_WINDOW_S).unwrap();
        assert_eq!(r.first, 500);
        assert!((150..=151).contains(&r.t_s.len()));
        assert!(r.dx_m.iter().chain(&r.dy_m).all(|d| d.abs() < 1e-12));
        for (i, yi) in y.iter_mut().enumerate().skip(500) {
            *yi += 0.002 * ((i - 500) as f64 / 150.0).min(1.0);
        }
        let r = variational_response(&t, &x, &y, 0.5, RESPONSE_WINDOW_S).unwrap();
        assert_relative_eq!(*r.dy_m.last().unwrap(), 0.002, epsilon = 1e-9);
        assert!(variational_response(&t, &x, &y, 2.0, RESPONSE_WINDOW_S).is_none());
    }
}
