//! The pinhole camera shared by rendering, reconstruction and the skeleton3d format.
//!
//! Spaces: `image` (pixels, x right, y down, pixel centres at integer coordinates) and `camera`
//! (metres, X right, Y down, Z forward). No lens distortion.

use nalgebra::{Point2, Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Intrinsics of a pinhole camera: focal length and principal point in pixels, image size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PinholeCamera {
    /// Focal length in pixels (the same along x and y: square pixels).
    pub focal_px: f64,
    /// Principal point, x (pixels).
    pub cx: f64,
    /// Principal point, y (pixels).
    pub cy: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl PinholeCamera {
    /// A camera whose principal point is the image centre, `((w-1)/2, (h-1)/2)` with pixel
    /// centres at integers.
    pub fn centred(focal_px: f64, width: u32, height: u32) -> Self {
        PinholeCamera {
            focal_px,
            cx: (f64::from(width) - 1.0) / 2.0,
            cy: (f64::from(height) - 1.0) / 2.0,
            width,
            height,
        }
    }

    /// Focal length in pixels that gives a horizontal field of view of `fov_deg` degrees.
    pub fn focal_from_horizontal_fov(fov_deg: f64, width: u32) -> f64 {
        f64::from(width) / 2.0 / (fov_deg.to_radians() / 2.0).tan()
    }

    /// Projects a point in camera space to the image; `None` if it is not in front of the camera.
    pub fn project(&self, point_in_camera: &Point3<f64>) -> Option<Point2<f64>> {
        let p = point_in_camera;
        if p.z <= f64::EPSILON {
            return None;
        }
        Some(Point2::new(
            self.focal_px * p.x / p.z + self.cx,
            self.focal_px * p.y / p.z + self.cy,
        ))
    }

    /// Unit direction, in camera space, of the ray through an image point.
    pub fn ray(&self, point_in_image: &Point2<f64>) -> Vector3<f64> {
        Vector3::new(
            (point_in_image.x - self.cx) / self.focal_px,
            (point_in_image.y - self.cy) / self.focal_px,
            1.0,
        )
        .normalize()
    }

    /// Whether an image point lies on the image (pixel centres at integers, so the image covers
    /// `[-0.5, width - 0.5] × [-0.5, height - 0.5]`).
    pub fn contains(&self, point_in_image: &Point2<f64>) -> bool {
        point_in_frame(point_in_image, self.width, self.height)
    }
}

/// Field of view across the longer image side assumed when the focal length is neither given
/// nor estimated: 60°, what phone main cameras and most webcams film at (the real sample's
/// calibrated camera: 59.5°). Perspective cues of one person are weak, so on the synthetic suite
/// this default was closer to the truth than `lift::focal::estimate_focal` (see the README's
/// lift figures). Here, not in the lift, because the tracker's side-view trunk uses it too.
pub const DEFAULT_FOV_LONG_SIDE_DEG: f64 = 60.0;

/// The default focal length for an image: [`DEFAULT_FOV_LONG_SIDE_DEG`] across its longer side.
pub fn default_focal(width: u32, height: u32) -> f64 {
    PinholeCamera::focal_from_horizontal_fov(DEFAULT_FOV_LONG_SIDE_DEG, width.max(height))
}

/// Whether an image point lies on a `width × height` image with pixel centres at integers.
pub fn point_in_frame(p: &Point2<f64>, width: u32, height: u32) -> bool {
    p.x >= -0.5 && p.y >= -0.5 && p.x <= f64::from(width) - 0.5 && p.y <= f64::from(height) - 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_on_the_optical_axis_projects_to_the_principal_point() {
        let cam = PinholeCamera::centred(500.0, 640, 480);
        let p = cam.project(&Point3::new(0.0, 0.0, 3.0)).unwrap();
        assert_eq!((p.x, p.y), (319.5, 239.5));
        assert!(cam.project(&Point3::new(0.0, 0.0, -1.0)).is_none());
    }

    #[test]
    fn ray_and_projection_agree() {
        let cam = PinholeCamera::centred(800.0, 1080, 1920);
        let x = Point3::new(0.3, -0.7, 2.5);
        let uv = cam.project(&x).unwrap();
        let back = cam.ray(&uv) * x.coords.norm();
        assert!((back - x.coords).norm() < 1e-9);
    }

    #[test]
    fn ninety_degrees_of_view_puts_the_edge_at_half_the_width() {
        let f = PinholeCamera::focal_from_horizontal_fov(90.0, 640);
        assert!((f - 320.0).abs() < 1e-9);
    }
}
