//! Sensor calibration: raw force-sensor reading → rig frame, encoder counts → metres.

use serde::{Deserialize, Serialize};

use crate::check::Checker;

/// The force sensor's calibration: `F_rig = matrix · (F_raw − offset_n)`.
///
/// On the Börner rig `matrix` is the rotation from the sensor frame to the rig frame
/// (the sensor is mounted turned on the handle); a general non-singular matrix is
/// accepted so per-axis gain corrections can be folded in.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ForceCalibration {
    /// Row-major 2x2 matrix from the sensor frame to the rig frame (identity by default).
    pub matrix: [[f64; 2]; 2],
    /// Bias of the raw reading in the sensor frame, N, subtracted before the rotation.
    pub offset_n: [f64; 2],
}

impl Default for ForceCalibration {
    fn default() -> Self {
        ForceCalibration {
            matrix: [[1.0, 0.0], [0.0, 1.0]],
            offset_n: [0.0, 0.0],
        }
    }
}

impl ForceCalibration {
    /// A pure rotation by `angle_rad` (sensor frame → rig frame, counter-clockwise)
    /// after subtracting `offset_n`.
    #[must_use]
    pub fn rotation(angle_rad: f64, offset_n: [f64; 2]) -> Self {
        let (s, c) = angle_rad.sin_cos();
        ForceCalibration {
            matrix: [[c, -s], [s, c]],
            offset_n,
        }
    }

    /// Apply the calibration to a raw reading, N → N (rig frame).
    #[must_use]
    pub fn apply(&self, raw_n: [f64; 2]) -> [f64; 2] {
        let d = [raw_n[0] - self.offset_n[0], raw_n[1] - self.offset_n[1]];
        let m = &self.matrix;
        [
            m[0][0] * d[0] + m[0][1] * d[1],
            m[1][0] * d[0] + m[1][1] * d[1],
        ]
    }

    pub(crate) fn check(&self, key: &str, c: &mut Checker) {
        let mut finite = true;
        for (i, row) in self.matrix.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                finite &= c.finite(&format!("{key}.matrix[{i}][{j}]"), *v);
            }
        }
        for (i, v) in self.offset_n.iter().enumerate() {
            c.finite(&format!("{key}.offset_n[{i}]"), *v);
        }
        let m = &self.matrix;
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        // A calibration that collapses the plane cannot be right: require |det| well
        // away from zero (a rotation has det 1).
        if finite && det.abs() < 1e-6 {
            c.fail(
                format!("{key}.matrix"),
                format!("must be non-singular, got determinant {det}"),
            );
        }
    }
}

/// Encoder counts → rig-frame position, m.
#[must_use]
pub fn counts_to_m(counts: [i64; 2], m_per_count: [f64; 2]) -> [f64; 2] {
    [
        counts[0] as f64 * m_per_count[0],
        counts[1] as f64 * m_per_count[1],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_maps_sensor_x_to_rig_direction() {
        // A 30° mounting: a 10 N pull along sensor x appears at 30° in the rig frame.
        // Tolerance 1e-12 N: one rotation of values of order 10, a few ulps.
        let cal = ForceCalibration::rotation(30f64.to_radians(), [1.0, -2.0]);
        let f = cal.apply([11.0, -2.0]);
        assert!((f[0] - 10.0 * 30f64.to_radians().cos()).abs() < 1e-12);
        assert!((f[1] - 10.0 * 30f64.to_radians().sin()).abs() < 1e-12);
    }
}
