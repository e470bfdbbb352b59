//! Camera calibration on the key triangle (Pan et al., eqs. 6–9): the pose of the object-space
//! triangle (both shoulders and the chest) whose projection lies on the image's key lines.
//!
//! Eq. 6 rotates the model, `X' = R·X_w`, with `R` kept as a rotation and updated by small
//! rotation vectors `(ΔW_x, ΔW_y, ΔW_z)` as in the paper. Eq. 7 in the paper adds `D_x, D_y` in
//! the image plane (Lowe's approximation, exact only for a flat object); we use the exact
//! pinhole form `u = f·(X' + D_x)/(Z' + D_z) + c_x` so that exact tracks give an exact skeleton.
//! Eq. 8's residual is the distance of each marked end point from the projected key line; two
//! end points on each of the three key lines give the six equations of eq. 9, solved with damped
//! Newton steps and analytic partial derivatives.

use super::error::LiftError;
use super::newton::levenberg_marquardt;
use crate::camera::PinholeCamera;
use crate::skeleton::{Bone, Joint, SubjectModel};
use nalgebra::{Matrix2, Matrix2x3, Point2, Point3, Rotation3, SMatrix, SVector, Vector2, Vector3};

/// A key-triangle calibration fits when its residual is below this RMS, pixels: a pixel is
/// what a careful click or a good track gives.
pub(super) const CALIBRATION_TOLERANCE_PX: f64 = 1.0;

/// The key joints in the order used by every array of this module.
pub const KEY_JOINTS: [Joint; 3] = [Joint::LeftShoulder, Joint::RightShoulder, Joint::Chest];

/// The key lines as pairs of indices into [`KEY_JOINTS`]: the shoulder line and the two
/// chest–shoulder lines.
pub(super) const KEY_LINES: [(usize, usize); 3] = [(0, 1), (2, 0), (2, 1)];

/// Six residuals by six parameters.
type Jacobian6 = SMatrix<f64, 6, 6>;

/// The key triangle in object space: the subject's left along +X, up along −Y, facing −Z (so
/// the identity pose faces the camera), the shoulder line through the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyTriangle {
    /// Left shoulder, right shoulder, chest.
    pub points: [Point3<f64>; 3],
}

impl KeyTriangle {
    /// The triangle of a subject: shoulder width and the two chest–shoulder bone lengths.
    pub fn from_subject(subject: &SubjectModel) -> Result<Self, LiftError> {
        let w = subject.shoulder_width_m;
        let a = subject.bone_length(Bone::new(Joint::Chest, Joint::LeftShoulder));
        let b = subject.bone_length(Bone::new(Joint::Chest, Joint::RightShoulder));
        // Chest (x, h): (x − w/2)² + h² = a², (x + w/2)² + h² = b².
        let x = (b * b - a * a) / (2.0 * w);
        let h2 = a * a - (x - w / 2.0).powi(2);
        if !(h2 > 1e-6 && w > 0.0) {
            return Err(LiftError::BadKeyTriangle {
                chest_shoulder_m: a.min(b),
                shoulder_width_m: w,
            });
        }
        Ok(KeyTriangle {
            points: [
                Point3::new(w / 2.0, 0.0, 0.0),
                Point3::new(-w / 2.0, 0.0, 0.0),
                Point3::new(x, h2.sqrt(), 0.0),
            ],
        })
    }

    /// Distance between two key joints.
    pub fn side(&self, i: usize, j: usize) -> f64 {
        (self.points[i] - self.points[j]).norm()
    }
}

/// Where the object space sits in the camera: `X_c = R·X_w + D`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Pose {
    /// `R` of eq. 6.
    pub rotation: Rotation3<f64>,
    /// `(D_x, D_y, D_z)`, metres.
    pub translation: Vector3<f64>,
}

impl Pose {
    /// A model point in camera space.
    pub(super) fn apply(&self, p: &Point3<f64>) -> Point3<f64> {
        self.rotation * p + self.translation
    }

    /// The pose after a step `(ΔD_x, ΔD_y, ΔD_z, ΔW_x, ΔW_y, ΔW_z)`: `D + ΔD`, `exp(ΔW)·R`.
    pub(super) fn stepped(&self, delta: &SVector<f64, 6>) -> Pose {
        Pose {
            rotation: Rotation3::new(Vector3::new(delta[3], delta[4], delta[5])) * self.rotation,
            translation: self.translation + Vector3::new(delta[0], delta[1], delta[2]),
        }
    }
}

/// Which residuals the calibration fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Residuals {
    /// Eq. 8: distance of each marked end point from its projected key line (the paper).
    Lines,
    /// Image distance of each projected key joint from its marked point, x and y. Used when the
    /// image triangle is too thin for lines to be defined (shoulders on top of each other in a
    /// side view).
    Points,
}

/// A calibrated pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Calibration {
    /// The pose found.
    pub pose: Pose,
    /// Root mean square of the six residuals, pixels.
    pub rms_px: f64,
}

/// Projection and its derivative with respect to the step parameters, for one model point.
fn project_with_derivative(
    cam: &PinholeCamera,
    pose: &Pose,
    model: &Point3<f64>,
) -> (Vector2<f64>, SMatrix<f64, 2, 6>) {
    let rotated = pose.rotation * model;
    let x = rotated + pose.translation;
    let inv_z = 1.0 / x.z;
    let f = cam.focal_px;
    let p = Vector2::new(f * x.x * inv_z + cam.cx, f * x.y * inv_z + cam.cy);
    // ∂π/∂X (eq. 7 with the exact translation).
    let dpi = Matrix2x3::new(
        f * inv_z,
        0.0,
        -f * x.x * inv_z * inv_z,
        0.0,
        f * inv_z,
        -f * x.y * inv_z * inv_z,
    );
    // ∂X/∂ΔD = I; ∂X/∂ΔW = −[R·X_w]× (a small rotation turns v into v + ΔW × v).
    let skew = -rotated.coords.cross_matrix();
    let mut d = SMatrix::<f64, 2, 6>::zeros();
    d.fixed_view_mut::<2, 3>(0, 0).copy_from(&dpi);
    d.fixed_view_mut::<2, 3>(0, 3).copy_from(&(dpi * skew));
    (p, d)
}

/// The six residuals and their analytic Jacobian (eq. 9's coefficients) at a pose.
pub(super) fn residuals(
    cam: &PinholeCamera,
    triangle: &KeyTriangle,
    image: &[Point2<f64>; 3],
    pose: &Pose,
    kind: Residuals,
) -> (SVector<f64, 6>, Jacobian6) {
    let projected = triangle
        .points
        .map(|p| project_with_derivative(cam, pose, &p));
    let mut r = SVector::<f64, 6>::zeros();
    let mut jac = Jacobian6::zeros();
    match kind {
        Residuals::Points => {
            for (k, (p, d)) in projected.iter().enumerate() {
                let e = p - image[k].coords;
                r[2 * k] = e.x;
                r[2 * k + 1] = e.y;
                jac.fixed_view_mut::<2, 6>(2 * k, 0).copy_from(d);
            }
        }
        Residuals::Lines => {
            // perp(x, y) = (−y, x): the normal of eq. 8 is perp(e)/|e| = (−m, 1)/√(m² + 1).
            let perp = Matrix2::new(0.0, -1.0, 1.0, 0.0);
            for (line, &(i, j)) in KEY_LINES.iter().enumerate() {
                let (p, dp) = &projected[i];
                let (q, dq) = &projected[j];
                let e = q - p;
                let len = e.norm().max(1e-9);
                let n = perp * e / len;
                let de = dq - dp;
                // ∂n = (I − n nᵀ)·perp·∂e / |e|.
                let dn = (Matrix2::identity() - n * n.transpose()) * perp * de / len;
                for (end, a) in [image[i], image[j]].iter().enumerate() {
                    let row = 2 * line + end;
                    let offset = a.coords - p;
                    // E = n·(a − p), the signed distance of eq. 8 (d = n·p).
                    r[row] = n.dot(&offset);
                    let d = offset.transpose() * dn - n.transpose() * dp;
                    jac.fixed_view_mut::<1, 6>(row, 0).copy_from(&d);
                }
            }
        }
    }
    (r, jac)
}

/// Thinness of an image triangle: twice its area over its longest side squared (0 when the
/// three points are collinear, about 0.4–0.8 for a shoulder triangle seen from the front).
pub(super) fn shape(image: &[Point2<f64>; 3]) -> f64 {
    let a = image[1] - image[0];
    let b = image[2] - image[0];
    let area2 = (a.x * b.y - a.y * b.x).abs();
    let longest = longest_side(image);
    if longest <= 0.0 {
        0.0
    } else {
        area2 / (longest * longest)
    }
}

/// The longest side of an image triangle, pixels.
pub(super) fn longest_side(image: &[Point2<f64>; 3]) -> f64 {
    [
        (image[1] - image[0]).norm(),
        (image[2] - image[0]).norm(),
        (image[2] - image[1]).norm(),
    ]
    .into_iter()
    .fold(0.0, f64::max)
}

/// Below this [`shape`], lines are not used (see [`Residuals::Points`]).
pub(super) const THIN_TRIANGLE: f64 = 0.08;

/// Damped Newton from one start.
pub(super) fn calibrate_from(
    cam: &PinholeCamera,
    triangle: &KeyTriangle,
    image: &[Point2<f64>; 3],
    start: Pose,
    kind: Residuals,
) -> Calibration {
    let solved = levenberg_marquardt(
        start,
        |pose: &Pose| residuals(cam, triangle, image, pose, kind),
        |pose, delta| pose.stepped(delta),
        60,
    );
    Calibration {
        pose: solved.state,
        rms_px: solved.residual_norm / 6f64.sqrt(),
    }
}

/// Plausible starting poses: the triangle turned by yaws of 0° (facing the camera), ±45°, ±135°
/// and 180° (turned away), each pitched by 0° and ±30°, at the depth implied by the least
/// foreshortened side of the image triangle, its centroid on the centroid's ray. The yaws turn
/// about the body's own up as the image shows it ([`image_roll`]), not the camera's: a body
/// upside down or lying in the image starts from the same poses, turned with it, as upright.
pub(super) fn starting_poses(
    cam: &PinholeCamera,
    triangle: &KeyTriangle,
    image: &[Point2<f64>; 3],
) -> Vec<Pose> {
    let mut ratio = f64::INFINITY;
    for (i, j) in KEY_LINES {
        let pixels = (image[i] - image[j]).norm();
        if pixels > 1.0 {
            ratio = ratio.min(triangle.side(i, j) / pixels);
        }
    }
    let depth = if ratio.is_finite() {
        cam.focal_px * ratio
    } else {
        3.0
    };
    let centroid_img = (image[0].coords + image[1].coords + image[2].coords) / 3.0;
    let ray = Vector3::new(
        (centroid_img.x - cam.cx) / cam.focal_px,
        (centroid_img.y - cam.cy) / cam.focal_px,
        1.0,
    );
    let centroid_model =
        (triangle.points[0].coords + triangle.points[1].coords + triangle.points[2].coords) / 3.0;
    let roll = Rotation3::from_axis_angle(&Vector3::z_axis(), image_roll(image));
    let mut poses = Vec::new();
    for yaw in [0.0f64, 45.0, -45.0, 135.0, -135.0, 180.0] {
        for pitch in [0.0f64, 30.0, -30.0] {
            let rotation = roll
                * Rotation3::from_axis_angle(&Vector3::y_axis(), yaw.to_radians())
                * Rotation3::from_axis_angle(&Vector3::x_axis(), pitch.to_radians());
            poses.push(Pose {
                rotation,
                translation: ray * depth - rotation * centroid_model,
            });
        }
    }
    poses
}

/// How far the body's up is turned in the image from the camera's up (radians about the
/// optical axis), to the nearest quarter turn: the direction from the chest to the shoulders'
/// midpoint against the image's up (−y). An upright body gives 0 (the starts already cover a
/// lean: pitches of ±30°, yaws 45° apart), a body upside down half a turn, one lying a quarter.
fn image_roll(image: &[Point2<f64>; 3]) -> f64 {
    let up = nalgebra::center(&image[0], &image[1]) - image[2];
    if up.norm() < 1e-9 {
        return 0.0;
    }
    // The angle that turns the image's up (0, −1) onto `up`.
    let angle = up.y.atan2(up.x) + std::f64::consts::FRAC_PI_2;
    (angle / std::f64::consts::FRAC_PI_2).round() * std::f64::consts::FRAC_PI_2
}

/// Every distinct pose that fits the image within `tolerance_px`, best fit first. A three-point
/// pose has up to four exact solutions; choosing among them needs the rest of the body and is
/// done by the caller.
pub(super) fn calibrate_all(
    cam: &PinholeCamera,
    triangle: &KeyTriangle,
    image: &[Point2<f64>; 3],
    tolerance_px: f64,
) -> Vec<Calibration> {
    let kind = if shape(image) < THIN_TRIANGLE {
        Residuals::Points
    } else {
        Residuals::Lines
    };
    let mut found: Vec<Calibration> = Vec::new();
    for start in starting_poses(cam, triangle, image) {
        let c = calibrate_from(cam, triangle, image, start, kind);
        let in_front = triangle.points.iter().all(|p| c.pose.apply(p).z > 0.05);
        if !(c.rms_px.is_finite() && c.rms_px <= tolerance_px && in_front) {
            continue;
        }
        let same = |o: &Calibration| {
            o.pose.rotation.angle_to(&c.pose.rotation) < 2f64.to_radians()
                && (o.pose.translation - c.pose.translation).norm()
                    < 0.01 * c.pose.translation.norm()
        };
        if !found.iter().any(same) {
            found.push(c);
        }
    }
    found.sort_by(|a, b| a.rms_px.total_cmp(&b.rms_px));
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup() -> (PinholeCamera, KeyTriangle, Pose, [Point2<f64>; 3]) {
        let cam = PinholeCamera::centred(900.0, 640, 480);
        let tri = KeyTriangle::from_subject(&SubjectModel::default()).unwrap();
        let pose = Pose {
            rotation: Rotation3::from_euler_angles(0.2, 0.6, -0.1),
            translation: Vector3::new(0.3, -0.2, 3.5),
        };
        let image = tri.points.map(|p| cam.project(&pose.apply(&p)).unwrap());
        (cam, tri, pose, image)
    }

    #[test]
    fn analytic_partial_derivatives_match_finite_differences() {
        let (cam, tri, pose, image) = setup();
        let noisy = [
            image[0] + Vector2::new(3.0, -2.0),
            image[1] + Vector2::new(-1.0, 4.0),
            image[2] + Vector2::new(2.0, 1.0),
        ];
        for kind in [Residuals::Lines, Residuals::Points] {
            let (r0, jac) = residuals(&cam, &tri, &noisy, &pose, kind);
            for k in 0..6 {
                let h = 1e-6;
                let mut d = SVector::<f64, 6>::zeros();
                d[k] = h;
                let (rp, _) = residuals(&cam, &tri, &noisy, &pose.stepped(&d), kind);
                d[k] = -h;
                let (rm, _) = residuals(&cam, &tri, &noisy, &pose.stepped(&d), kind);
                let numeric = (rp - rm) / (2.0 * h);
                for row in 0..6 {
                    let a = jac[(row, k)];
                    let n = numeric[row];
                    assert!(
                        (a - n).abs() <= 1e-5 * (1.0 + n.abs()),
                        "{kind:?} ∂r{row}/∂p{k}: analytic {a}, numeric {n}"
                    );
                }
            }
            assert!(r0.norm() > 1.0);
        }
    }

    #[test]
    fn exact_key_lines_give_back_the_pose() {
        let (cam, tri, pose, image) = setup();
        let all = calibrate_all(&cam, &tri, &image, 1e-6);
        assert!(!all.is_empty());
        let best = all
            .iter()
            .map(|c| {
                tri.points
                    .iter()
                    .map(|p| (c.pose.apply(p) - pose.apply(p)).norm())
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(best < 1e-6, "closest solution is {best} m off");
    }

    #[test]
    fn a_thin_triangle_uses_points() {
        let thin = [
            Point2::new(100.0, 100.0),
            Point2::new(101.0, 100.5),
            Point2::new(100.5, 160.0),
        ];
        assert!(shape(&thin) < THIN_TRIANGLE);
        let (_, _, _, image) = setup();
        assert!(shape(&image) > THIN_TRIANGLE);
    }
}
