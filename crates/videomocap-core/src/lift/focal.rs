//! Beyond the paper: the focal length when the user does not know it.
//!
//! With the wrong focal length the perspective of the key triangle and of the bones does not
//! match the body's proportions, and some bones cannot reach their 2D image at their length.
//! We lift the sequence (per frame, eqs. 6–11) for focal lengths spanning horizontal fields of
//! view from 15° to 110° and keep the one whose skeleton best explains its tracks: the smallest
//! mean distance between each joint and its viewing ray. The scan is refined by golden-section
//! search around the best grid value.

use super::error::LiftError;
use super::job::LiftJob;
use super::solve::{lift_per_frame, miss_m};
use crate::camera::PinholeCamera;

pub use crate::camera::{DEFAULT_FOV_LONG_SIDE_DEG, default_focal};

/// The estimate and the scan behind it.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct FocalEstimate {
    /// The focal length chosen, pixels.
    pub focal_px: f64,
    /// Mean miss (metres per joint and frame) at that focal length.
    pub miss_m: f64,
    /// Every focal length tried with its mean miss.
    pub scanned: Vec<(f64, f64)>,
}

/// Mean miss of the per-frame lift at one focal length (infinite when it fails).
fn score(job: &LiftJob<'_>, focal_px: f64) -> f64 {
    let mut j = job.clone();
    j.camera.focal_px = focal_px;
    let Ok(per) = lift_per_frame(&j) else {
        return f64::INFINITY;
    };
    let total: f64 = per
        .resolved
        .points
        .iter()
        .zip(&job.tracks.frames)
        .map(|(p, f)| {
            let image = f.points.map(|_, q| q.pos);
            miss_m(&j.camera, p, &image)
        })
        .sum();
    total / (16.0 * per.resolved.points.len() as f64)
}

/// Estimates the focal length of `job.camera` (its focal length is ignored). Give it the
/// proportions table's lengths, not lengths fitted to the same tracks
/// (`super::subject_fit`): those are read as ratios in the image and fit any focal length
/// about equally (on the synthetic suite the estimate was off by a median factor of 2.12 with
/// fitted lengths, 1.53 with the table's).
pub(super) fn estimate_focal(job: &LiftJob<'_>) -> Result<FocalEstimate, LiftError> {
    let cam = job.camera;
    let width = cam.width.max(1);
    let focal_of = |fov: f64| PinholeCamera::focal_from_horizontal_fov(fov, width);
    let mut scanned: Vec<(f64, f64)> = Vec::new();
    let steps = 20;
    let (lo, hi) = (focal_of(110.0).ln(), focal_of(15.0).ln());
    for k in 0..=steps {
        let f = (lo + (hi - lo) * f64::from(k) / f64::from(steps)).exp();
        scanned.push((f, score(job, f)));
    }
    let (best_k, _) = scanned
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.1.total_cmp(&b.1.1))
        .ok_or(LiftError::NoFrames)?;
    if !scanned[best_k].1.is_finite() {
        // Nothing lifts at any focal length: report the reason at a middle one.
        let mut j = job.clone();
        j.camera.focal_px = focal_of(60.0);
        lift_per_frame(&j)?;
    }
    // Golden-section search on log f between the grid neighbours of the best value.
    let mut a = scanned[best_k.saturating_sub(1)].0.ln();
    let mut b = scanned[(best_k + 1).min(steps as usize)].0.ln();
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let mut fc = score(job, c.exp());
    let mut fd = score(job, d.exp());
    scanned.push((c.exp(), fc));
    scanned.push((d.exp(), fd));
    for _ in 0..12 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = score(job, c.exp());
            scanned.push((c.exp(), fc));
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = score(job, d.exp());
            scanned.push((d.exp(), fd));
        }
    }
    let (focal_px, miss_m) = scanned
        .iter()
        .copied()
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .ok_or(LiftError::NoFrames)?;
    scanned.sort_by(|x, y| x.0.total_cmp(&y.0));
    Ok(FocalEstimate {
        focal_px,
        miss_m,
        scanned,
    })
}
