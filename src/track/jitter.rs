//! Beyond the paper: the tracks smoothed over time, a few pixels of frame-to-frame jitter
//! taken out (after weak runs are filled, before the gait completion).
//!
//! Each frame's block search lands a pixel or two off on its own (the sampling grid, the
//! adaptive colour model), independently of the frames around it, so the jitter is measured in
//! frames, not seconds: a Gaussian of [`crate::track::TrackerParams::jitter_sigma_frames`]
//! frames over each joint's track takes most of it out and leaves motion alone. Points placed
//! by hand stay where they were put (they still weigh on their neighbours); points off the
//! frame are the tracker's estimates and neither move nor weigh.

use crate::formats::{FrameTracks, PointSource};
use crate::skeleton::Joint;
use nalgebra::Vector2;

/// Smooths every joint's track in `frames[from..]` by a Gaussian of `sigma` frames (0 leaves
/// them as they are). `frames` must hold consecutive frame indices; frames before `from` (an
/// earlier result kept by a re-track) are read but not changed. `is_key(frame position,
/// joint)` marks hand-placed joints.
pub fn smooth_jitter(
    frames: &mut [FrameTracks],
    sigma: f64,
    from: usize,
    is_key: &dyn Fn(usize, Joint) -> bool,
) {
    if sigma.is_nan() || sigma <= 0.0 || frames.is_empty() {
        return;
    }
    let reach = (3.0 * sigma).ceil() as usize;
    let weights: Vec<f64> = (0..=reach)
        .map(|d| (-0.5 * (d as f64 / sigma).powi(2)).exp())
        .collect();
    let n = frames.len();
    for joint in Joint::ALL {
        let before: Vec<_> = frames.iter().map(|f| f.points[joint]).collect();
        for i in from.min(n)..n {
            if is_key(i, joint) || before[i].source == PointSource::OffFrame {
                continue;
            }
            let (mut sum, mut total) = (Vector2::zeros(), 0.0);
            for (q, p) in before
                .iter()
                .enumerate()
                .take((i + reach + 1).min(n))
                .skip(i.saturating_sub(reach))
            {
                if p.source != PointSource::OffFrame {
                    let w = weights[q.abs_diff(i)];
                    sum += p.pos.coords * w;
                    total += w;
                }
            }
            // `total` includes the point's own weight, 1.
            frames[i].points[joint].pos = (sum / total).into();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::TrackedPoint;
    use crate::skeleton::PerJoint;
    use nalgebra::Point2;
    use rand::{Rng, SeedableRng};

    /// Frames whose neck moves along `x`, every other joint at the origin.
    fn track(x: &[f64]) -> Vec<FrameTracks> {
        x.iter()
            .enumerate()
            .map(|(index, &x)| {
                let mut points = PerJoint::from_fn(|_| TrackedPoint {
                    pos: Point2::origin(),
                    confidence: 0.9,
                    source: PointSource::Tracked,
                });
                points.0[Joint::Neck.index()].pos.x = x;
                FrameTracks { index, points }
            })
            .collect()
    }

    fn neck(f: &[FrameTracks]) -> Vec<f64> {
        f.iter().map(|f| f.points[Joint::Neck].pos.x).collect()
    }

    #[test]
    fn jitter_is_taken_out_and_steady_motion_left_alone() {
        let truth: Vec<f64> = (0..60).map(|i| 3.0 * i as f64).collect();
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let noisy: Vec<f64> = truth
            .iter()
            .map(|t| t + rng.random_range(-2.0..2.0))
            .collect();
        let mut f = track(&noisy);
        smooth_jitter(&mut f, 1.0, 0, &|_, _| false);
        // Inside the track (away from its ends, where the window is one-sided).
        let err = |x: &[f64]| (5..55).map(|i| (x[i] - truth[i]).abs()).sum::<f64>() / 50.0;
        let (raw, smooth) = (err(&noisy), err(&neck(&f)));
        assert!(smooth < 0.7 * raw, "raw {raw} smoothed {smooth}");
        // A straight, steady track is its own average.
        let mut line = track(&truth);
        smooth_jitter(&mut line, 1.0, 0, &|_, _| false);
        assert!((5..55).all(|i| (neck(&line)[i] - truth[i]).abs() < 1e-9));
    }

    #[test]
    fn keys_earlier_frames_and_off_frame_points_stay() {
        let x = [0.0, 10.0, 0.0, 10.0, 0.0, 10.0, 0.0, 10.0];
        let mut f = track(&x);
        f[5].points.0[Joint::Neck.index()].source = PointSource::OffFrame;
        smooth_jitter(&mut f, 1.0, 2, &|i, j| i == 3 && j == Joint::Neck);
        let out = neck(&f);
        // Frames before `from`, the key and the off-frame point are untouched...
        for i in [0, 1, 3, 5] {
            assert_eq!(out[i], x[i], "frame {i}: {out:?}");
        }
        // ...the rest are drawn towards their neighbours.
        for i in [2, 4, 6, 7] {
            assert!((out[i] - 5.0).abs() < (x[i] - 5.0).abs() - 1.0, "{out:?}");
        }
        // Off-frame points weigh nothing: frame 4 sees 0 and 10 on each side but not frame 5.
        let mut g = track(&x);
        g[5].points.0[Joint::Neck.index()].pos.x = 1e6;
        g[5].points.0[Joint::Neck.index()].source = PointSource::OffFrame;
        smooth_jitter(&mut g, 1.0, 0, &|_, _| false);
        assert!(neck(&g)[4] < 10.0, "{:?}", neck(&g));
    }

    #[test]
    fn zero_width_changes_nothing() {
        let x = [0.0, 10.0, 0.0, 10.0];
        let mut f = track(&x);
        smooth_jitter(&mut f, 0.0, 0, &|_, _| false);
        assert_eq!(neck(&f), x);
    }
}
