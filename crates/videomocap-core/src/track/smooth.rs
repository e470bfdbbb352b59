//! Beyond the paper: the finished tracks smoothed over time. Each frame's match is found on its
//! own, so a joint's track jitters by a pixel or two around the body part and now and then
//! jumps for a frame where a block fitted a little better beside the limb. A Gaussian window in
//! time, each neighbour weighted by its reliability, pulls a joint towards where its reliable
//! neighbours put it: a weak frame between sound ones moves most, a sound run hardly at all.
//!
//! What stays put: hand-placed joints (key frames; they still pull their neighbours, at full
//! reliability), joints off the frame (they neither move nor pull: their position is a guess
//! outside the image) and, in a re-track from a corrected frame, the earlier result up to that
//! frame (smoothed when it was tracked; smoothing it again at every correction would wear its
//! motion down). Reliabilities and sources are unchanged, so the weak-span report stays as it
//! was.
//!
//! Off by default (`smooth_s`; see there why: the lift measures each track's jitter and
//! smooths by it). Measured on `bench track`'s suite (misses at PCK@0.2 of 24208 joint-frames,
//! 1318 unsmoothed): at 0.01 / 0.02 / 0.03 / 0.04 s 1310 / 1288 / 1291 / 1295; the real sample
//! 0.805 throughout. Weighting the neighbours by the square of their reliability, or not at
//! all, gave 1288 / 1292 at 0.02 s. Smoothing the tracks as tracked, before the weak runs are
//! filled and the gait completed, gave 1303 (the real sample 0.801).

use crate::formats::{FrameIndex, FrameTracks, PointSource};
use crate::skeleton::Joint;
use nalgebra::Vector2;

/// The least weight a neighbour's reliability gives it: a lost joint (reliability near 0)
/// still counts a little, so that a run of weak frames is smoothed among itself rather than
/// left as tracked.
pub(crate) const MIN_WEIGHT: f64 = 0.05;

/// How far the window reaches, in standard deviations.
pub(crate) const REACH_SIGMAS: f64 = 3.0;

/// The Gaussian-weighted mean at position `t` of a series of `len` points: every position `u`
/// within [`REACH_SIGMAS`] standard deviations (`sigma`, in positions) gives `sample(u)`, its
/// point and weight (`None` leaves it out), weighed by `exp(−(u − t)² / 2σ²)` on top. The
/// weights that count must not all be 0. One window for the tracker's smoothing here and the
/// lift's (`lift::smoothing`), which differ only in what they weigh and leave out.
pub(crate) fn gaussian_mean(
    t: usize,
    len: usize,
    sigma: f64,
    mut sample: impl FnMut(usize) -> Option<(Vector2<f64>, f64)>,
) -> Vector2<f64> {
    let reach = (REACH_SIGMAS * sigma).ceil() as usize;
    let (mut sum, mut total) = (Vector2::zeros(), 0.0);
    for u in t.saturating_sub(reach)..(t + reach + 1).min(len) {
        if let Some((point, weight)) = sample(u) {
            let d = u as f64 - t as f64;
            let w = (-0.5 * d * d / (sigma * sigma)).exp() * weight;
            sum += point * w;
            total += w;
        }
    }
    sum * (1.0 / total)
}

/// Smooths every joint's track from position `first` of `frames` on (the frames before it
/// are neighbours only) with a Gaussian window of standard deviation `sigma_frames` (frames),
/// each neighbour weighted by its reliability (at least [`MIN_WEIGHT`]). Joints for which
/// `is_key(frame, joint)` holds and joints off the frame are left where they are;
/// off-frame joints are not used as neighbours. Does nothing when `sigma_frames` is not above
/// 0.
pub(crate) fn smooth_tracks(
    frames: &mut [FrameTracks],
    sigma_frames: f64,
    first: usize,
    is_key: &dyn Fn(FrameIndex, Joint) -> bool,
) {
    // A NaN window counts as none (the settings' check refuses it before this).
    if sigma_frames.is_nan() || sigma_frames <= 0.0 || frames.len() < 2 {
        return;
    }
    for joint in Joint::ALL {
        let smoothed: Vec<Option<Vector2<f64>>> = (0..frames.len())
            .map(|t| {
                let p = frames[t].points[joint];
                if t < first || is_key(frames[t].index, joint) || p.source == PointSource::OffFrame
                {
                    return None;
                }
                // The weights are not all 0: the frame itself is on the frame and weighs at
                // least MIN_WEIGHT.
                Some(gaussian_mean(t, frames.len(), sigma_frames, |u| {
                    let q = frames[u].points[joint];
                    let reliability = if is_key(frames[u].index, joint) {
                        1.0
                    } else {
                        f64::from(q.confidence).max(MIN_WEIGHT)
                    };
                    (q.source != PointSource::OffFrame).then_some((q.pos.coords, reliability))
                }))
            })
            .collect();
        for (frame, pos) in frames.iter_mut().zip(smoothed) {
            if let Some(pos) = pos {
                frame.points[joint].pos = pos.into();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::TrackedPoint;
    use crate::skeleton::PerJoint;
    use nalgebra::Point2;

    fn track(xs: &[(f64, f32, PointSource)]) -> Vec<FrameTracks> {
        xs.iter()
            .enumerate()
            .map(|(index, &(x, confidence, source))| FrameTracks {
                index: FrameIndex(index),
                body3d: None,
                points: PerJoint::from_fn(|_| TrackedPoint {
                    pos: Point2::new(x, 10.0),
                    confidence,
                    source,
                }),
            })
            .collect()
    }

    const T: PointSource = PointSource::Tracked;

    #[test]
    fn a_weak_outlier_between_sound_frames_is_pulled_back_and_sound_frames_hardly_move() {
        let mut frames = track(&[
            (0.0, 0.9, T),
            (1.0, 0.9, T),
            (12.0, 0.1, T),
            (3.0, 0.9, T),
            (4.0, 0.9, T),
        ]);
        smooth_tracks(&mut frames, 1.0, 0, &|_, _| false);
        let x = |t: usize| frames[t].points[Joint::LeftWrist].pos.x;
        // The outlier, 10 px off the line through its neighbours, ends within 2 px of it.
        assert!((x(2) - 2.0).abs() < 2.0, "{}", x(2));
        // A sound frame beside it moves by under a pixel.
        assert!((x(1) - 1.0).abs() < 1.0, "{}", x(1));
        // y is constant and stays so.
        assert!(
            frames
                .iter()
                .all(|f| (f.points[Joint::Neck].pos.y - 10.0).abs() < 1e-12)
        );
    }

    #[test]
    fn a_straight_steady_track_is_unchanged_inside() {
        let xs: Vec<(f64, f32, PointSource)> = (0..20).map(|t| (3.0 * t as f64, 0.8, T)).collect();
        let mut frames = track(&xs);
        smooth_tracks(&mut frames, 1.5, 0, &|_, _| false);
        // Away from the ends the window is symmetric: a straight line is its own average.
        for (t, f) in frames.iter().enumerate().take(15).skip(5) {
            assert!((f.points[Joint::Pelvis].pos.x - 3.0 * t as f64).abs() < 1e-9);
        }
    }

    #[test]
    fn key_frames_and_off_frame_joints_stay_put_and_off_frame_ones_do_not_pull() {
        let off = PointSource::OffFrame;
        let mut frames = track(&[
            (0.0, 1.0, T),
            (5.0, 0.9, T),
            (-500.0, 0.0, off),
            (5.0, 0.9, T),
        ]);
        smooth_tracks(&mut frames, 2.0, 0, &|t, _| t == FrameIndex(0));
        let x = |t: usize| frames[t].points[Joint::HeadTop].pos.x;
        assert_eq!(x(0), 0.0);
        assert_eq!(x(2), -500.0);
        // Frame 3 sees only frames 0, 1 and itself: pulled towards the key frame, never
        // towards the off-frame guess.
        assert!(x(3) > 2.0 && x(3) < 5.0, "{}", x(3));
    }

    #[test]
    fn a_re_track_leaves_the_earlier_result_as_it_was_but_reads_it() {
        let mut frames = track(&[(0.0, 0.9, T), (8.0, 0.2, T), (0.0, 0.9, T), (8.0, 0.2, T)]);
        smooth_tracks(&mut frames, 1.0, 2, &|_, _| false);
        let x = |t: usize| frames[t].points[Joint::RightKnee].pos.x;
        assert_eq!((x(0), x(1)), (0.0, 8.0));
        // Frame 3 is pulled towards frame 2 (reliable) and, further off, frame 1.
        assert!(x(3) < 6.0, "{}", x(3));
    }

    #[test]
    fn no_window_leaves_the_tracks_as_they_are() {
        let mut frames = track(&[(0.0, 0.9, T), (9.0, 0.1, T), (0.0, 0.9, T)]);
        let before = frames.clone();
        smooth_tracks(&mut frames, 0.0, 0, &|_, _| false);
        assert_eq!(frames, before);
    }
}
