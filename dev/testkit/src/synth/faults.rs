//! Silhouettes with the faults of real segmentation, made from the synthetic renders (issue 67):
//! edges eroded or dilated on some views, a forearm missing on one view, a shadow on the floor
//! joined to the feet, and a second person standing nearby. What a carving set-up written by
//! [`super::write_carving_setup`] puts into its masks.

use image::GrayImage;
use imageproc::distance_transform::Norm;
use nalgebra::{Point3, Vector3};
use videomocap_core::skeleton::{Joint, PerJoint, segment_distance};

/// The faults drawn into the masks of a carving set-up.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SilhouetteFaults {
    /// Per view (cycled over the views), pixels the mask's edge moves outwards (dilated, > 0) or
    /// inwards (eroded, < 0); empty: clean edges.
    pub edge_px: Vec<i8>,
    /// The view whose mask misses the right forearm and hand.
    pub missing_forearm_view: Option<usize>,
    /// A shadow on the floor, joined to the feet, on every view.
    pub shadow: bool,
    /// A second person (the same motion half a clip later), this far to the side (+X), metres.
    pub second_person_m: Option<f64>,
}

impl SilhouetteFaults {
    /// The faults of `bench volume`'s faulty carving: edges eroded by 2 px on the first view and
    /// dilated by 2 px on the second, the right forearm missing on the third, a shadow at the
    /// feet, and a second person 1.2 m to the side.
    pub fn typical() -> SilhouetteFaults {
        SilhouetteFaults {
            edge_px: vec![-2, 2, 0, 0],
            missing_forearm_view: Some(2),
            shadow: true,
            second_person_m: Some(1.2),
        }
    }

    /// Whether any fault is drawn.
    pub fn any(&self) -> bool {
        self.edge_px.iter().any(|&e| e != 0)
            || self.missing_forearm_view.is_some()
            || self.shadow
            || self.second_person_m.is_some()
    }

    /// The points of the right forearm and hand (within 7 cm of the elbow → a third past the
    /// wrist), which the mask of `missing_forearm_view` leaves out.
    pub fn is_forearm(&self, joints: &PerJoint<Point3<f64>>, p: &Point3<f64>) -> bool {
        let (e, w) = (joints[Joint::RightElbow], joints[Joint::RightWrist]);
        segment_distance(p, &e, &(w + (w - e) * 0.3)) <= 0.07
    }

    /// Points of a shadow on the floor (the lowest body point's height) spaced `step_m`: an
    /// ellipse 0.8 × 0.35 m from between the ankles away from the light (+X, +Z).
    pub fn shadow_points(
        joints: &PerJoint<Point3<f64>>,
        floor_y: f64,
        step_m: f64,
    ) -> Vec<Point3<f64>> {
        let feet = nalgebra::center(&joints[Joint::LeftAnkle], &joints[Joint::RightAnkle]);
        let along = Vector3::new(1.0, 0.0, 0.5).normalize();
        let across = Vector3::new(-along.z, 0.0, along.x);
        let (half_len, half_wide) = (0.4, 0.175);
        let centre = Point3::new(feet.x, floor_y, feet.z) + along * half_len;
        let n = (half_len / step_m).ceil() as i64;
        let mut out = Vec::new();
        for a in -n..=n {
            for b in -n..=n {
                let (s, t) = (a as f64 * step_m, b as f64 * step_m);
                if (s / half_len).powi(2) + (t / half_wide).powi(2) <= 1.0 {
                    out.push(centre + along * s + across * t);
                }
            }
        }
        out
    }

    /// Moves the mask's edge by `edge_px` for view `view` (dilated or eroded, chessboard norm).
    pub fn edges(&self, view: usize, mask: GrayImage) -> GrayImage {
        let k = if self.edge_px.is_empty() {
            0
        } else {
            self.edge_px[view % self.edge_px.len()]
        };
        match k {
            0 => mask,
            k if k > 0 => imageproc::morphology::dilate(&mask, Norm::LInf, k.unsigned_abs()),
            k => imageproc::morphology::erode(&mask, Norm::LInf, k.unsigned_abs()),
        }
    }
}
