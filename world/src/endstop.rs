//! Rail end-stops: parry2d blocks at the rail limits and a rubber-bumper law.
//!
//! Each rail has a block at each end; the cart is a block too. When parry reports
//! penetration `d` (m) at approach speed `ḋ` (m/s), the bumper pushes the cart back with
//! `k·d + c·ḋ` (never pulling). The force is applied as an external force rather than as
//! a rapier contact so that the force-sensor accounting (see [`crate::rig`]) knows it
//! exactly, and so that the rapier step needs no collision detection.

use parry2d_f64::math::{Pose, Vector};
use parry2d_f64::query::contact;
use parry2d_f64::shape::Cuboid;

/// Half-length of the cart block along its rail, m (its size does not change the law).
const CART_HALF_M: f64 = 0.02;
/// Half-length of a stop block along the rail, m.
const STOP_HALF_M: f64 = 0.01;
/// Half-width of all blocks across the rail, m.
const HALF_WIDTH_M: f64 = 0.03;

/// The two stops of one rail.
#[derive(Debug, Clone)]
pub struct RailStops {
    /// Rail direction: 0 = x, 1 = y.
    axis: usize,
    cart: Cuboid,
    stop: Cuboid,
    /// Stop block centres along the rail, m.
    stop_centres_m: [f64; 2],
    limits_m: [f64; 2],
    stiffness_n_per_m: f64,
    damping_n_s_per_m: f64,
}

impl RailStops {
    /// Stops whose inner faces meet the cart block when the cart is at `limits_m`.
    #[must_use]
    pub fn new(
        axis: usize,
        limits_m: [f64; 2],
        stiffness_n_per_m: f64,
        damping_n_s_per_m: f64,
    ) -> Self {
        let half = |along: f64| {
            if axis == 0 {
                Vector::new(along, HALF_WIDTH_M)
            } else {
                Vector::new(HALF_WIDTH_M, along)
            }
        };
        RailStops {
            axis,
            cart: Cuboid::new(half(CART_HALF_M)),
            stop: Cuboid::new(half(STOP_HALF_M)),
            stop_centres_m: [
                limits_m[0] - CART_HALF_M - STOP_HALF_M,
                limits_m[1] + CART_HALF_M + STOP_HALF_M,
            ],
            limits_m,
            stiffness_n_per_m,
            damping_n_s_per_m,
        }
    }

    fn along(&self, s: f64) -> Vector {
        if self.axis == 0 {
            Vector::new(s, 0.0)
        } else {
            Vector::new(0.0, s)
        }
    }

    /// Bumper force on a cart at `pos_m` moving at `vel_m_per_s` along the rail, N.
    #[must_use]
    pub fn force_n(&self, pos_m: f64, vel_m_per_s: f64) -> f64 {
        // Cheap reject: parry is only asked when the cart is within a centimetre of a stop.
        if pos_m > self.limits_m[0] + 0.01 && pos_m < self.limits_m[1] - 0.01 {
            return 0.0;
        }
        let cart_pose = Pose::from_translation(self.along(pos_m));
        let mut total = 0.0;
        for centre in self.stop_centres_m {
            let stop_pose = Pose::from_translation(self.along(centre));
            // parry's generic query (its `contact_cuboid_cuboid` fast path reports zero
            // depth for 2-D boxes that overlap face to face; the dispatcher is exact here).
            if let Ok(Some(c)) = contact(&cart_pose, &self.cart, &stop_pose, &self.stop, 0.0)
                && c.dist < 0.0
            {
                // normal1 points from the cart into the stop, world frame.
                let n = if self.axis == 0 {
                    c.normal1.x
                } else {
                    c.normal1.y
                };
                let depth = -c.dist;
                let rate = vel_m_per_s * n;
                let push =
                    (self.stiffness_n_per_m * depth + self.damping_n_s_per_m * rate).max(0.0);
                total -= n * push;
            }
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bumper_pushes_back_by_its_law_and_is_silent_inside() {
        let s = RailStops::new(0, [-0.16, 0.16], 2.0e5, 0.0);
        // 1 mm past the upper stop: 200 N back towards the centre (exact law; parry's
        // penetration depth of two axis-aligned boxes is exact to round-off).
        let f = s.force_n(0.161, 0.0);
        assert!((f + 200.0).abs() < 1e-6, "{f}");
        let f = s.force_n(-0.1605, 0.0);
        assert!((f - 100.0).abs() < 1e-6, "{f}");
        assert_eq!(s.force_n(0.0, 1.0), 0.0);
        assert_eq!(s.force_n(0.155, 1.0), 0.0);
    }
}
