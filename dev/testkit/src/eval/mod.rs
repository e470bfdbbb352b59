//! Accuracy of 2D tracks against ground truth (`gt.json`): mean error in pixels, error over the
//! torso length (neck–pelvis in the reference, per frame), PCK@0.1 and PCK@0.2 of the torso
//! length, and the share lost (error above half the torso), per joint and overall, visible and
//! occluded joints apart. Joints the reference marks as derived are not scored. The 3D
//! measures live in [`pose3d`].

pub mod correction;
pub mod doubt;
pub mod motion;
pub mod pose3d;
pub mod suite;
pub mod volume;

use crate::synth::GroundTruth;
use nalgebra::Point2;
use serde::Serialize;
use videomocap_core::formats::Tracks2d;
use videomocap_core::skeleton::{Joint, PerJoint};

/// A joint further than this from the reference, in torso lengths, counts as lost.
pub const LOST_TORSO: f64 = 0.5;

/// Accumulated errors of a set of (joint, frame) samples.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Accuracy {
    /// Samples scored.
    pub count: usize,
    /// Sum of errors, pixels.
    sum_px: f64,
    /// Sum of errors over torso length.
    sum_torso: f64,
    /// Samples within 0.1 torso.
    within_01: usize,
    /// Samples within 0.2 torso.
    within_02: usize,
    /// Samples beyond 0.5 torso.
    lost: usize,
}

impl Accuracy {
    /// Adds one sample: its error in pixels and the frame's torso length in pixels.
    pub fn add(&mut self, error_px: f64, torso_px: f64) {
        let rel = error_px / torso_px.max(1.0);
        self.count += 1;
        self.sum_px += error_px;
        self.sum_torso += rel;
        self.within_01 += usize::from(rel <= 0.1);
        self.within_02 += usize::from(rel <= 0.2);
        self.lost += usize::from(rel > LOST_TORSO);
    }

    /// Merges another accumulator into this one.
    pub fn merge(&mut self, o: &Accuracy) {
        self.count += o.count;
        self.sum_px += o.sum_px;
        self.sum_torso += o.sum_torso;
        self.within_01 += o.within_01;
        self.within_02 += o.within_02;
        self.lost += o.lost;
    }

    fn ratio(&self, x: f64) -> f64 {
        if self.count == 0 {
            f64::NAN
        } else {
            x / self.count as f64
        }
    }

    /// Mean error, pixels.
    pub fn mean_px(&self) -> f64 {
        self.ratio(self.sum_px)
    }

    /// Mean error over torso length.
    pub fn mean_torso(&self) -> f64 {
        self.ratio(self.sum_torso)
    }

    /// Share within 0.1 torso.
    pub fn pck01(&self) -> f64 {
        self.ratio(self.within_01 as f64)
    }

    /// Share within 0.2 torso.
    pub fn pck02(&self) -> f64 {
        self.ratio(self.within_02 as f64)
    }

    /// Share beyond 0.5 torso.
    pub fn lost(&self) -> f64 {
        self.ratio(self.lost as f64)
    }
}

/// Scores of one clip.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClipScore {
    /// Per joint (derived joints stay empty).
    pub per_joint: PerJoint<Accuracy>,
    /// All visible samples.
    pub visible: Accuracy,
    /// All occluded samples (hidden or off the image).
    pub occluded: Accuracy,
    /// Everything.
    pub overall: Accuracy,
}

/// Whether a joint is one of the limb joints the real-sample target counts: every joint but
/// the head's two (head top, neck) and the chest (derived on the real sample), i.e. the four
/// chains and the pelvis, 13.
pub fn is_limb_joint(j: Joint) -> bool {
    !matches!(j, Joint::HeadTop | Joint::Neck | Joint::Chest)
}

impl ClipScore {
    /// The limb joints' samples together ([`is_limb_joint`]).
    pub fn limbs(&self) -> Accuracy {
        let mut a = Accuracy::default();
        for j in Joint::ALL.into_iter().filter(|&j| is_limb_joint(j)) {
            a.merge(&self.per_joint[j]);
        }
        a
    }
}

/// The ground truth does not fit the tracks.
#[derive(Debug, thiserror::Error)]
#[error("ground truth has {gt} frames but the tracks cover frame {frame}")]
pub struct EvalError {
    gt: usize,
    frame: usize,
}

/// Scores positions per frame (`predicted(frame) → joints`) against the reference.
pub fn score_positions(
    gt: &GroundTruth,
    frames: impl IntoIterator<Item = (usize, PerJoint<Point2<f64>>)>,
) -> Result<ClipScore, EvalError> {
    let derived = gt.derived();
    let mut s = ClipScore::default();
    for (index, predicted) in frames {
        let f = gt.frames.get(index).ok_or(EvalError {
            gt: gt.frames.len(),
            frame: index,
        })?;
        let truth = f.points2d();
        let torso = (truth[Joint::Neck] - truth[Joint::Pelvis]).norm();
        for j in Joint::ALL {
            if derived.contains(&j) {
                continue;
            }
            let e = (predicted[j] - truth[j]).norm();
            s.per_joint[j].add(e, torso);
            if f.visible.get(j.index()).copied().unwrap_or(true) {
                s.visible.add(e, torso);
            } else {
                s.occluded.add(e, torso);
            }
            s.overall.add(e, torso);
        }
    }
    Ok(s)
}

/// Scores tracks against the reference.
pub fn score_tracks(gt: &GroundTruth, tracks: &Tracks2d) -> Result<ClipScore, EvalError> {
    score_positions(
        gt,
        tracks
            .frames
            .iter()
            .map(|f| (f.index.get(), f.points.map(|_, p| p.pos))),
    )
}

/// Joint-frames (scored joints) within `tolerance` torso lengths of the reference in `before`
/// and beyond it in `after`: what a change (a correction's re-track) spoiled.
pub fn moved_out(gt: &GroundTruth, before: &Tracks2d, after: &Tracks2d, tolerance: f64) -> usize {
    let derived = gt.derived();
    let mut n = 0;
    for (b, a) in before.frames.iter().zip(&after.frames) {
        let Some(f) = gt.frames.get(b.index.get()) else {
            continue;
        };
        let truth = f.points2d();
        let torso = (truth[Joint::Neck] - truth[Joint::Pelvis]).norm().max(1.0);
        for j in Joint::ALL.into_iter().filter(|j| !derived.contains(j)) {
            let off = |p: Point2<f64>| (p - truth[j]).norm() / torso;
            n += usize::from(off(b.points[j].pos) <= tolerance && off(a.points[j].pos) > tolerance);
        }
    }
    n
}

#[cfg(test)]
mod moved_tests {
    use super::*;
    use crate::eval::pose3d::tracks_from_truth;

    #[test]
    fn a_joint_frame_pushed_out_of_the_tolerance_counts_and_one_already_out_does_not() {
        let gt = crate::eval::correction::tests_reference(3);
        let before = tracks_from_truth(&gt, 0.0, 0);
        let mut after = before.clone();
        // 100 px torso: 15 px is out of 0.1; frame 2's wrist was out before already.
        after.frames[1].points[Joint::LeftWrist].pos.x += 15.0;
        let mut before2 = before.clone();
        before2.frames[2].points[Joint::LeftWrist].pos.x += 30.0;
        after.frames[2].points[Joint::LeftWrist].pos.x += 40.0;
        after.frames[0].points[Joint::LeftKnee].pos.x += 5.0;
        assert_eq!(moved_out(&gt, &before2, &after, 0.1), 1);
    }
}
