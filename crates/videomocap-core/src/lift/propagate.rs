//! The key joints of the next frame (Pan et al., eqs. 10–11): each key joint lies on its
//! viewing ray at an unknown depth `Z_i` (eq. 10), and the three mutual distances of the key
//! triangle do not change (eq. 11). Three equations in three depths, solved from the previous
//! frame's depths by damped Gauss–Newton (the paper's "grads method").

use super::calibrate::KEY_LINES;
use super::newton::levenberg_marquardt;
use crate::camera::PinholeCamera;
use nalgebra::{Matrix3, Point2, Point3, Vector3};

/// A calibrated key-triangle pose is made exact by eqs. 10–11 when they then hold within this
/// RMS residual, metres: half a centimetre, under the sides' own doubt.
pub(super) const PROPAGATION_TOLERANCE_M: f64 = 0.005;

/// The key joints' depths found for one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct KeyDepths {
    /// Camera-space key joints (left shoulder, right shoulder, chest).
    pub points: [Point3<f64>; 3],
    /// Root mean square of the three distance residuals of eq. 11, metres.
    pub rms_m: f64,
}

/// The ray of eq. 10 scaled so that its Z is 1: `P = Z·ray`.
pub(super) fn depth_ray(cam: &PinholeCamera, p: &Point2<f64>) -> Vector3<f64> {
    Vector3::new(
        (p.x - cam.cx) / cam.focal_px,
        (p.y - cam.cy) / cam.focal_px,
        1.0,
    )
}

/// Solves eqs. 10–11 for the key joints seen at `image`, with side lengths `sides` (in
/// [`KEY_LINES`] order), starting from the depths `start`.
pub(super) fn key_depths(
    cam: &PinholeCamera,
    image: &[Point2<f64>; 3],
    sides: &[f64; 3],
    start: [f64; 3],
) -> KeyDepths {
    let rays = image.map(|p| depth_ray(cam, &p));
    let eval = |z: &Vector3<f64>| {
        let mut r = Vector3::zeros();
        let mut jac = Matrix3::zeros();
        for (k, &(i, j)) in KEY_LINES.iter().enumerate() {
            let diff = rays[i] * z[i] - rays[j] * z[j];
            let dist = diff.norm().max(1e-12);
            // Eq. 11: d(P_i, P_j) equals the model distance.
            r[k] = dist - sides[k];
            jac[(k, i)] = diff.dot(&rays[i]) / dist;
            jac[(k, j)] = -diff.dot(&rays[j]) / dist;
        }
        (r, jac)
    };
    let solved = levenberg_marquardt(
        Vector3::from(start),
        eval,
        |z, d| (z + d).map(|v| v.max(0.05)),
        50,
    );
    let z = solved.state;
    KeyDepths {
        points: [0, 1, 2].map(|k| Point3::from(rays[k] * z[k])),
        rms_m: solved.residual_norm / 3f64.sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depths_follow_a_moving_triangle() {
        let cam = PinholeCamera::centred(800.0, 640, 480);
        let before = [
            Point3::new(0.2, -0.3, 3.0),
            Point3::new(-0.2, -0.3, 3.1),
            Point3::new(0.0, -0.15, 3.05),
        ];
        let sides = KEY_LINES.map(|(i, j)| (before[i] - before[j]).norm());
        // Turn by 10° about the vertical and step 5 cm away.
        let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), 0.17);
        let after = before.map(|p| turn * p + Vector3::new(0.02, 0.0, 0.05));
        let image = after.map(|p| cam.project(&p).unwrap());
        let found = key_depths(&cam, &image, &sides, before.map(|p| p.z));
        assert!(found.rms_m < 1e-9);
        for (k, (f, a)) in found.points.iter().zip(&after).enumerate() {
            assert!((f - a).norm() < 1e-6, "joint {k}");
        }
    }
}
