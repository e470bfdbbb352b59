//! The square crop the network sees: centred on the body, turned upright along the
//! pelvis → head-top axis (as MediaPipe turns its region of interest), sized to hold the whole
//! body, sampled bilinearly into the network's 256 × 256 input.

use crate::skeleton::{Joint, PerJoint};
use image::RgbImage;
use nalgebra::{Point2, Rotation2, Vector2};

/// Side of the network's input, pixels.
pub const INPUT_PX: usize = 256;

/// The crop's side over twice the pelvis → head-top distance (MediaPipe's ROI: a circle
/// around the hips through the head top, enlarged 1.25 times).
const MARGIN: f64 = 1.25;

/// A square region of a frame, turned by `angle_rad`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Crop {
    /// Centre, image pixels.
    pub centre: Point2<f64>,
    /// Side, image pixels.
    pub side_px: f64,
    /// Turn of the crop's up axis from the image's up, radians (positive: clockwise on screen).
    pub angle_rad: f64,
}

impl Crop {
    /// The crop around a body whose joints (image pixels) are `points`: centred on the pelvis,
    /// up along pelvis → head top, wide enough for the whole body (every joint within the
    /// circle the crop is made from, so a body bent over towards the camera, its head near its
    /// pelvis, is not cut to its trunk). `None` when the head top and pelvis coincide.
    pub fn around(points: &PerJoint<Point2<f64>>) -> Option<Crop> {
        let pelvis = points[Joint::Pelvis];
        let up = points[Joint::HeadTop] - pelvis;
        let reach = points
            .iter()
            .map(|(_, p)| (p - pelvis).norm())
            .fold(0.0, f64::max);
        let norm = up.norm();
        if !(norm.is_finite() && norm > 1.0 && reach.is_finite()) {
            return None;
        }
        Self::aligned(pelvis, pelvis + up * (reach / norm))
    }

    /// The crop centred on `centre`, its up axis along `centre → top`, its side 2 × 1.25 times
    /// that distance (MediaPipe's alignment-point region). `None` when the two coincide.
    pub fn aligned(centre: Point2<f64>, top: Point2<f64>) -> Option<Crop> {
        let pelvis = centre;
        let up = top - pelvis;
        let reach = up.norm();
        if !(reach.is_finite() && reach > 1.0) {
            return None;
        }
        // The image's up is -y; the angle that turns it onto `up`.
        let angle_rad = up.x.atan2(-up.y);
        Some(Crop {
            centre: pelvis,
            side_px: 2.0 * reach * MARGIN,
            angle_rad,
        })
    }

    /// The image point at crop pixel `(u, v)` (0–256, pixel centres at half-integers as the
    /// network reports them).
    pub fn to_image(&self, u: f64, v: f64) -> Point2<f64> {
        let scale = self.side_px / INPUT_PX as f64;
        let local = Vector2::new(
            (u - INPUT_PX as f64 / 2.0) * scale,
            (v - INPUT_PX as f64 / 2.0) * scale,
        );
        self.centre + Rotation2::new(self.angle_rad) * local
    }

    /// The crop's pixels as the network's input: RGB in [0, 1], row-major, 256 × 256 × 3; black
    /// outside the frame.
    pub fn sample(&self, frame: &RgbImage) -> Vec<f32> {
        let mut out = vec![0.0f32; INPUT_PX * INPUT_PX * 3];
        self.sample_into(frame, &mut out);
        out
    }

    /// [`Crop::sample`] written into `out` (256 × 256 × 3 values, the network's input in
    /// place). Each crop pixel's image point is computed anew ([`Crop::to_image`]), as before:
    /// stepping along the crop's axes changes the input by 1e-7, enough to turn a tracking
    /// decision (`docs/log.md`, 2026-12-06).
    pub(crate) fn sample_into(&self, frame: &RgbImage, out: &mut [f32]) {
        let (w, h) = (i64::from(frame.width()), i64::from(frame.height()));
        let raw = frame.as_raw();
        let at = |x: i64, y: i64| -> [f32; 3] {
            if x < 0 || y < 0 || x >= w || y >= h {
                return [0.0; 3];
            }
            let i = ((y * w + x) * 3) as usize;
            [raw[i], raw[i + 1], raw[i + 2]].map(f32::from)
        };
        for (v, row) in out.chunks_exact_mut(INPUT_PX * 3).enumerate() {
            for (u, px) in row.chunks_exact_mut(3).enumerate() {
                let p = self.to_image(u as f64 + 0.5, v as f64 + 0.5);
                let (fx, fy) = (p.x.floor(), p.y.floor());
                let (tx, ty) = ((p.x - fx) as f32, (p.y - fy) as f32);
                let (x0, y0) = (fx as i64, fy as i64);
                let (a, b) = (at(x0, y0), at(x0 + 1, y0));
                let (c, d) = (at(x0, y0 + 1), at(x0 + 1, y0 + 1));
                for k in 0..3 {
                    let top = a[k] * (1.0 - tx) + b[k] * tx;
                    let bottom = c[k] * (1.0 - tx) + d[k] * tx;
                    px[k] = (top * (1.0 - ty) + bottom * ty) / 255.0;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn standing(tilt: f64) -> PerJoint<Point2<f64>> {
        let pelvis = Point2::new(100.0, 200.0);
        let up = Rotation2::new(tilt) * Vector2::new(0.0, -80.0);
        PerJoint::from_fn(|j| match j {
            Joint::HeadTop => pelvis + up,
            _ => pelvis,
        })
    }

    #[test]
    fn an_upright_body_gives_an_unturned_crop_holding_it() {
        let c = Crop::around(&standing(0.0)).unwrap();
        assert!(c.angle_rad.abs() < 1e-12);
        assert!((c.side_px - 200.0).abs() < 1e-9);
        // The crop's top centre is above the head top.
        let top = c.to_image(128.0, 0.0);
        assert!((top.x - 100.0).abs() < 1e-9 && top.y < 120.0, "{top}");
    }

    #[test]
    fn a_leaning_body_is_turned_upright() {
        let c = Crop::around(&standing(0.5)).unwrap();
        // The head top maps to straight above the crop's centre.
        let head = Point2::new(100.0, 200.0) + Rotation2::new(0.5) * Vector2::new(0.0, -80.0);
        let above = c.to_image(128.0, 128.0 - 80.0 * 256.0 / c.side_px);
        assert!((above - head).norm() < 1e-9, "{above} vs {head}");
    }

    #[test]
    fn sampling_reads_the_frame_and_black_outside() {
        let frame = RgbImage::from_pixel(50, 50, image::Rgb([255, 0, 0]));
        let c = Crop {
            centre: Point2::new(24.5, 24.5),
            side_px: 100.0,
            angle_rad: 0.0,
        };
        let s = c.sample(&frame);
        let px = |u: usize, v: usize| &s[(v * INPUT_PX + u) * 3..(v * INPUT_PX + u) * 3 + 3];
        assert_eq!(px(128, 128), &[1.0, 0.0, 0.0]);
        assert_eq!(px(2, 2), &[0.0, 0.0, 0.0]);
    }
}
