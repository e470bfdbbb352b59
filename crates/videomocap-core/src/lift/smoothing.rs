//! Temporal smoothing of the 2D tracks before the per-frame solve, by a width chosen from each
//! track's own noise.
//!
//! The per-frame solve amplifies 2D noise (a 2 px error on a shoulder moves its depth by
//! centimetres), but smoothing exact tracks only cuts the peaks off fast motion. So each joint's
//! track gets the Gaussian width that minimises its expected squared error: with white noise of
//! standard deviation σ and a motion whose second difference has RMS `a` (pixels per frame²),
//! a Gaussian of `s` frames leaves a bias of about `a·s²/2` and a noise variance of
//! `σ²/(2√π·s)`, least in total at `s⁵ = σ² / (2√π·a²)`. Both σ and `a` come from the track's
//! second differences: white noise makes consecutive second differences anti-correlated
//! (correlation −2/3) while motion keeps them correlated (about +1), so
//! `var − cov = 10σ²` and `var = a² + 6σ²`.

use crate::formats::Tracks2d;
use crate::skeleton::{JOINT_COUNT, Joint, PerJoint};
use crate::track::smooth::gaussian_mean;
use nalgebra::{Point2, Vector2};

/// Widest Gaussian the adaptive choice takes, frames (beyond it motion is cut, not noise).
pub(super) const MAX_ADAPTIVE_SIGMA: f64 = 3.0;

/// The width used is this many times the 2D optimum: the per-frame solve amplifies what noise
/// is left (a bone's depth is `√(L² − l²)`, steep where the bone is nearly parallel to the
/// image), so the 3D optimum lies wider. Measured on the synthetic suite with 2 px noise and
/// true lengths: ×1 gave 124 mm MPJPE, ×1.6 77.5 mm, ×2.2 75.4 mm; with exact tracks ×1.6 left
/// the 31 mm of no smoothing unchanged and ×2.2 raised it to 33.5 mm.
pub(super) const WIDTH_FACTOR: f64 = 1.6;

/// The estimated white-noise deviation and motion RMS of one track, per axis, both in pixels
/// (per frame² for the motion), from its second differences; `None` below five frames.
pub(super) fn noise_and_motion(track: &[Point2<f64>]) -> Option<(f64, f64)> {
    if track.len() < 5 {
        return None;
    }
    let d2: Vec<Vector2<f64>> = track
        .windows(3)
        .map(|w| w[2].coords - w[1].coords * 2.0 + w[0].coords)
        .collect();
    // Per axis: mean square and lag-one covariance (second differences have mean ≈ 0).
    let var = d2.iter().map(|d| d.norm_squared()).sum::<f64>() / (2 * d2.len()) as f64;
    let cov = d2.windows(2).map(|w| w[0].dot(&w[1])).sum::<f64>() / (2 * (d2.len() - 1)) as f64;
    let noise_var = ((var - cov) / 10.0).max(0.0);
    let motion_var = (var - 6.0 * noise_var).max(0.0);
    Some((noise_var.sqrt(), motion_var.sqrt()))
}

/// [`WIDTH_FACTOR`] times the Gaussian width (frames) that minimises a 2D track's expected
/// squared error, at most [`MAX_ADAPTIVE_SIGMA`]; 0 for a track without noise.
pub(super) fn adaptive_sigma(noise_px: f64, motion_px: f64) -> f64 {
    if noise_px <= 0.0 {
        return 0.0;
    }
    let a2 = motion_px.max(1e-3).powi(2);
    let s5 = noise_px * noise_px / (2.0 * std::f64::consts::PI.sqrt() * a2);
    (WIDTH_FACTOR * s5.powf(0.2)).min(MAX_ADAPTIVE_SIGMA)
}

/// A Gaussian narrower than this (frames) leaves a series as it is: its neighbours would weigh
/// less than 1e-4.
const UNTOUCHED_BELOW: f64 = 0.3;

/// The tracks smoothed over time, joint `j` by a Gaussian of `sigma[j]` frames (0 = untouched),
/// each point weighted by its trust ([`super::refine::track_weight`]).
pub(super) fn smoothed_images(
    tracks: &Tracks2d,
    sigma: &PerJoint<f64>,
) -> Vec<PerJoint<Point2<f64>>> {
    let raw: Vec<PerJoint<Point2<f64>>> = tracks
        .frames
        .iter()
        .map(|f| f.points.map(|_, p| p.pos))
        .collect();
    let n = raw.len();
    (0..n)
        .map(|t| {
            PerJoint::from_fn(|j| {
                let s = sigma[j];
                if s < UNTOUCHED_BELOW {
                    return raw[t][j];
                }
                Point2::from(gaussian_mean(t, n, s, |u| {
                    let w = super::refine::track_weight(&tracks.frames[u].points[j]);
                    Some((raw[u][j].coords, w))
                }))
            })
        })
        .collect()
}

/// Each joint's adaptive Gaussian width (frames) for these tracks.
pub(super) fn adaptive_sigmas(tracks: &Tracks2d) -> PerJoint<f64> {
    let mut out = PerJoint([0.0; JOINT_COUNT]);
    for j in Joint::ALL {
        let track: Vec<Point2<f64>> = tracks.frames.iter().map(|f| f.points[j].pos).collect();
        if let Some((noise, motion)) = noise_and_motion(&track) {
            out.0[j.index()] = adaptive_sigma(noise, motion);
        }
    }
    out
}

/// The median over `joints` of their tracks' white-noise deviation, pixels (0 below five
/// frames): how noisy the 2D input is (as a whole with [`Joint::ALL`]).
pub(super) fn median_noise_px(tracks: &Tracks2d, joints: &[Joint]) -> f64 {
    let mut noise: Vec<f64> = joints
        .iter()
        .filter_map(|&j| {
            let track: Vec<Point2<f64>> = tracks.frames.iter().map(|f| f.points[j].pos).collect();
            noise_and_motion(&track).map(|(n, _)| n)
        })
        .collect();
    noise.sort_by(f64::total_cmp);
    noise.get(noise.len() / 2).copied().unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::FrameIndex;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A smooth path: a point swinging on a circle, about 3 px per frame.
    fn swing(n: usize) -> Vec<Point2<f64>> {
        (0..n)
            .map(|t| {
                let a = t as f64 * 0.05;
                Point2::new(300.0 + 60.0 * a.cos(), 200.0 + 60.0 * a.sin())
            })
            .collect()
    }

    #[test]
    fn the_noise_of_a_track_is_recovered_from_its_second_differences() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        for sigma in [0.5, 2.0, 4.0] {
            let normal = Normal::new(0.0, sigma).expect("valid deviation");
            let noisy: Vec<Point2<f64>> = swing(400)
                .into_iter()
                .map(|p| p + Vector2::new(normal.sample(&mut rng), normal.sample(&mut rng)))
                .collect();
            let (noise, _) = noise_and_motion(&noisy).expect("enough frames");
            assert!(
                (noise / sigma - 1.0).abs() < 0.15,
                "σ {sigma}: estimated {noise}"
            );
        }
        let (noise, motion) = noise_and_motion(&swing(400)).expect("enough frames");
        assert!(noise < 0.01, "an exact path has no noise: {noise}");
        // Per axis: the circle's second difference (60 · 0.05² px) shared by x and y.
        assert!(
            (motion - 60.0 * 0.05 * 0.05 / 2f64.sqrt()).abs() < 0.005,
            "{motion}"
        );
        assert_eq!(noise_and_motion(&swing(4)), None);
    }

    #[test]
    fn noisier_tracks_get_wider_smoothing_and_exact_ones_none() {
        assert_eq!(adaptive_sigma(0.0, 1.0), 0.0);
        let (a, b) = (adaptive_sigma(0.5, 1.0), adaptive_sigma(2.0, 1.0));
        assert!(a < b, "{a} {b}");
        assert!(
            adaptive_sigma(2.0, 5.0) < b,
            "faster motion is smoothed less"
        );
        assert_eq!(adaptive_sigma(100.0, 0.0), MAX_ADAPTIVE_SIGMA);
    }

    #[test]
    fn smoothing_brings_a_noisy_track_closer_to_the_truth() {
        use crate::formats::{FrameTracks, PointSource, SourceInfo, TrackedPoint};
        let truth = swing(120);
        let mut rng = rand::rngs::StdRng::seed_from_u64(9);
        let normal = Normal::new(0.0, 2.0).expect("valid deviation");
        let tracks = Tracks2d {
            source: SourceInfo {
                path: "swing".into(),
                width: 640,
                height: 480,
                fps: 30.0,
                frame_count: truth.len(),
            },
            frames: truth
                .iter()
                .enumerate()
                .map(|(index, p)| FrameTracks {
                    index: FrameIndex(index),
                    body3d: None,
                    points: PerJoint::from_fn(|_| TrackedPoint {
                        pos: p + Vector2::new(normal.sample(&mut rng), normal.sample(&mut rng)),
                        confidence: 1.0,
                        source: PointSource::Tracked,
                    }),
                })
                .collect(),
        };
        let sigma = adaptive_sigmas(&tracks);
        assert!(sigma[Joint::Neck] > 1.0, "{:?}", sigma.0);
        let smoothed = smoothed_images(&tracks, &sigma);
        let err = |f: &dyn Fn(usize) -> Point2<f64>| {
            (0..truth.len())
                .map(|t| (f(t) - truth[t]).norm())
                .sum::<f64>()
                / truth.len() as f64
        };
        let raw = err(&|t| tracks.frames[t].points[Joint::Neck].pos);
        let smooth = err(&|t| smoothed[t][Joint::Neck]);
        assert!(smooth < 0.6 * raw, "raw {raw} smoothed {smooth}");
    }
}
