//! Image-difference head prediction (Pan et al., "Head", eqs. 1–5 of the feature-tracking
//! section): where will the calvaria (head_top) be in the next frame?
//!
//! The head is a circle H of diameter L (head_top to neck) and centre O. In the difference
//! region Ω (radius 2L around O) the colour difference of two frames is nonzero only where the
//! head left or arrived. Along 36 diameters of Ω (from 90° in 5° steps) the difference is summed
//! (eq. 4); the diameter with the largest sum is the motion direction (eq. 5). Along it the
//! difference profile has two peaks D1 and D2 (the head's trailing and leading crescents): cut
//! at `a·p` (a = the profile's mean), their mean length is the displacement, and the peak farther
//! from O gives the side. `p` adapts: raised when the prediction overshot, lowered when it fell
//! short.

use super::similarity::FrameView;
use nalgebra::{Point2, Vector2};

/// The head predictor with its adaptive threshold `p`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct HeadPredictor {
    /// The profile cut, as a fraction of the profile's mean (the paper's `p`, default 0.5).
    pub p: f64,
}

/// Smallest and largest `p`, and the change per adaptation.
const P_RANGE: (f64, f64) = (0.2, 1.5);
const P_STEP: f64 = 0.05;
/// Mean difference per sample (sum over R, G, B, levels) below which the head is taken as still.
const STILL_LEVEL: f64 = 12.0;

/// What the predictor found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct HeadMotion {
    /// Predicted displacement of the head, pixels.
    pub displacement: Vector2<f64>,
    /// The motion direction α of eq. 5, degrees.
    pub alpha_deg: f64,
}

impl Default for HeadPredictor {
    fn default() -> Self {
        HeadPredictor { p: 0.5 }
    }
}

impl HeadPredictor {
    /// Predicts the head's displacement from frame k (`prev`) to k + 1 (`next`), given the
    /// head_top and neck of frame k.
    pub(super) fn predict(
        &self,
        prev: FrameView,
        next: FrameView,
        head_top: Point2<f64>,
        neck: Point2<f64>,
    ) -> HeadMotion {
        let still = HeadMotion {
            displacement: Vector2::zeros(),
            alpha_deg: 90.0,
        };
        let l = (head_top - neck).norm();
        if !(l.is_finite() && l >= 2.0) {
            return still;
        }
        let o = Point2::from((head_top.coords + neck.coords) / 2.0);
        let half = (2.0 * l).round() as i64; // each line runs 4L through O
        let difference = |t: f64, dir: Vector2<f64>| -> f64 {
            let p = o + dir * t;
            if p.x < 0.0
                || p.y < 0.0
                || p.x > (prev.width() - 1) as f64
                || p.y > (prev.height() - 1) as f64
            {
                return 0.0;
            }
            let (x, y) = (p.x.round() as usize, p.y.round() as usize);
            let a = prev.pixel(x, y);
            let b = next.pixel(x, y);
            // eqs. 1–3, summed over the channels as in eq. 4
            f64::from((a[0] - b[0]).abs() + (a[1] - b[1]).abs() + (a[2] - b[2]).abs())
        };
        // eqs. 4–5: 36 directions from 90° in 5° steps; keep the one with the largest sum.
        let mut best = (f64::NEG_INFINITY, 0usize);
        for n in 0..36 {
            let alpha = (90.0 + 5.0 * n as f64).to_radians();
            let dir = Vector2::new(alpha.cos(), alpha.sin());
            let sum: f64 = (-half..=half).map(|t| difference(t as f64, dir)).sum();
            if sum > best.0 {
                best = (sum, n);
            }
        }
        let alpha_deg = 90.0 + 5.0 * best.1 as f64;
        let alpha = alpha_deg.to_radians();
        let dir = Vector2::new(alpha.cos(), alpha.sin());
        let profile: Vec<f64> = (-half..=half).map(|t| difference(t as f64, dir)).collect();
        let a = profile.iter().sum::<f64>() / profile.len() as f64;
        if a < STILL_LEVEL / 4.0 {
            return HeadMotion { alpha_deg, ..still };
        }
        // Runs of the profile above a·p (small gaps of ≤ 2 samples bridged).
        let mut runs = runs_above(&profile, a * self.p);
        if runs.len() < 2 {
            return HeadMotion { alpha_deg, ..still };
        }
        runs.sort_by(|x, y| y.2.total_cmp(&x.2));
        let (d1, d2) = (runs[0], runs[1]);
        let length = |r: (usize, usize, f64)| (r.1 - r.0 + 1) as f64;
        let displacement = (length(d1) + length(d2)) / 2.0;
        // The side: the peak farther from O.
        let centre = |r: (usize, usize, f64)| (r.0 + r.1) as f64 / 2.0 - half as f64;
        let (c1, c2) = (centre(d1), centre(d2));
        let far = if c1.abs() > c2.abs() { c1 } else { c2 };
        HeadMotion {
            displacement: dir * displacement * far.signum(),
            alpha_deg,
        }
    }

    /// Adapts `p` from how good the prediction was: an overshoot raises the cut (shorter runs,
    /// smaller displacements next time), a shortfall lowers it.
    pub(super) fn adapt(&mut self, predicted: Vector2<f64>, actual: Vector2<f64>) {
        let (p, a) = (predicted.norm(), actual.norm());
        if (p - a).abs() < 0.5 {
            return;
        }
        self.p = if p > a {
            self.p + P_STEP
        } else {
            self.p - P_STEP
        }
        .clamp(P_RANGE.0, P_RANGE.1);
    }
}

/// The runs of `profile` above `cut` (gaps of up to 2 samples below it bridged): each its
/// first and last sample above the cut and its mass (the profile summed over the run).
fn runs_above(profile: &[f64], cut: f64) -> Vec<(usize, usize, f64)> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < profile.len() {
        if profile[i] > cut {
            let start = i;
            let mut end = i;
            let mut gap = 0;
            while i < profile.len() && gap <= 2 {
                if profile[i] > cut {
                    end = i;
                    gap = 0;
                } else {
                    gap += 1;
                }
                i += 1;
            }
            let mass: f64 = profile[start..=end].iter().sum();
            runs.push((start, end, mass));
        } else {
            i += 1;
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::similarity::FloatFrame;
    use image::{Rgb, RgbImage};

    /// A grey background with a uniform red disc of diameter `l` at `centre`.
    fn disc(centre: Point2<f64>, l: f64) -> RgbImage {
        RgbImage::from_fn(200, 200, |x, y| {
            let d = (Point2::new(f64::from(x), f64::from(y)) - centre).norm();
            if d <= l / 2.0 {
                Rgb([200, 40, 40])
            } else {
                Rgb([90, 90, 90])
            }
        })
    }

    #[test]
    fn a_moving_disc_is_predicted_in_direction_and_size() {
        let l = 30.0;
        let c0 = Point2::new(100.0, 100.0);
        for &(dx, dy) in &[(8.0, 0.0), (-6.0, 0.0), (0.0, 7.0), (5.0, -5.0)] {
            let c1 = c0 + Vector2::new(dx, dy);
            let (a, b) = (disc(c0, l), disc(c1, l));
            let top = c0 - Vector2::new(0.0, l / 2.0);
            let neck = c0 + Vector2::new(0.0, l / 2.0);
            let m = HeadPredictor::default().predict(
                FloatFrame::new(&a).view(),
                FloatFrame::new(&b).view(),
                top,
                neck,
            );
            let err = (m.displacement - Vector2::new(dx, dy)).norm();
            assert!(
                err < 3.0,
                "moved ({dx},{dy}) predicted {:?}",
                m.displacement
            );
        }
    }

    #[test]
    fn a_still_head_is_predicted_still() {
        let a = disc(Point2::new(100.0, 100.0), 30.0);
        let m = HeadPredictor::default().predict(
            FloatFrame::new(&a).view(),
            FloatFrame::new(&a).view(),
            Point2::new(100.0, 85.0),
            Point2::new(100.0, 115.0),
        );
        assert_eq!(m.displacement, Vector2::zeros());
    }

    #[test]
    fn p_rises_after_an_overshoot_and_falls_after_a_shortfall() {
        let mut h = HeadPredictor::default();
        h.adapt(Vector2::new(10.0, 0.0), Vector2::new(5.0, 0.0));
        assert!(h.p > 0.5);
        let mut h = HeadPredictor::default();
        h.adapt(Vector2::new(2.0, 0.0), Vector2::new(6.0, 0.0));
        assert!(h.p < 0.5);
    }
}
