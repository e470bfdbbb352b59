//! The timeline's strips as data: per joint, the runs of frames in one state (tracked, weak,
//! filled in, off the frame, lost, placed by hand), and the folded strip that colours each frame
//! by its most worrying joint. Made again whenever the tracks or the keys change.

use crate::views::frame_view::PointState;
use videomocap_core::formats::Tracks2d;
use videomocap_core::skeleton::{JOINT_COUNT, Joint};
use videomocap_core::track::KeyFrames;

/// Runs of frames in one state: `(first, last, state)` as positions in the tracks.
pub(super) type Runs = Vec<(usize, usize, PointState)>;

/// Per joint, runs of frames in one state; and the same for the folded strip, each frame in
/// the state of its most worrying joint.
#[derive(Debug, Clone, Default)]
pub(crate) struct Strips {
    runs: Vec<Runs>,
    worst: Runs,
}

/// Appends frame `k` in `state` to `runs`.
fn extend(runs: &mut Runs, k: usize, state: PointState) {
    match runs.last_mut() {
        Some(last) if last.2 == state && last.1 + 1 == k => last.1 = k,
        _ => runs.push((k, k, state)),
    }
}

/// The state at position `k` of `runs`.
fn state_in(runs: &Runs, k: usize) -> Option<PointState> {
    let i = runs.partition_point(|r| r.1 < k);
    runs.get(i).filter(|r| r.0 <= k).map(|r| r.2)
}

/// How much a state asks for the user's eye, for the folded strip: a guess most, then doubt,
/// off the frame, filled in, tracked, placed by hand.
fn concern(state: PointState) -> u8 {
    match state {
        PointState::Key => 0,
        PointState::Tracked => 1,
        PointState::Interpolated => 2,
        PointState::OffFrame => 3,
        PointState::Weak => 4,
        PointState::Lost => 5,
    }
}

impl Strips {
    /// Strips from tracks and the key frames; `weak` is the tracker's reliability threshold.
    pub(crate) fn new(tracks: &Tracks2d, keys: &KeyFrames, weak: f32) -> Strips {
        let mut runs = vec![Runs::new(); JOINT_COUNT];
        let mut worst = Runs::new();
        for (k, f) in tracks.frames.iter().enumerate() {
            let mut most = PointState::Key;
            for (j, runs) in Joint::ALL.into_iter().zip(&mut runs) {
                let state = if keys.is_key(f.index, j) {
                    PointState::Key
                } else {
                    PointState::of(&f.points[j], weak)
                };
                extend(runs, k, state);
                if concern(state) > concern(most) {
                    most = state;
                }
            }
            extend(&mut worst, k, most);
        }
        Strips { runs, worst }
    }

    /// `joint`'s runs (the `row`th joint's).
    pub(crate) fn runs(&self, row: usize) -> Option<&Runs> {
        self.runs.get(row)
    }

    /// The folded strip's runs: each frame in the state of its most worrying joint.
    pub(crate) fn worst(&self) -> &Runs {
        &self.worst
    }

    /// The state of `joint` at position `k` of the tracks.
    pub(crate) fn state_at(&self, joint: Joint, k: usize) -> Option<PointState> {
        state_in(self.runs.get(joint.index())?, k)
    }

    /// The state of the most worrying joint at position `k`, and the joints in that state.
    pub(crate) fn worst_at(&self, k: usize) -> Option<(PointState, Vec<Joint>)> {
        let state = state_in(&self.worst, k)?;
        let joints = Joint::ALL
            .into_iter()
            .filter(|&j| self.state_at(j, k) == Some(state))
            .collect();
        Some((state, joints))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;
    use videomocap_core::formats::{
        FrameIndex, FrameTracks, PointSource, SourceInfo, TrackedPoint,
    };
    use videomocap_core::skeleton::PerJoint;

    #[test]
    fn strips_keep_each_state_and_say_which_at_a_frame() {
        // Left wrist: tracked, weak, interpolated, off the frame, lost.
        let states = [
            (0.9, PointSource::Tracked),
            (0.2, PointSource::Tracked),
            (0.2, PointSource::Interpolated),
            (0.0, PointSource::OffFrame),
            (0.1, PointSource::Lost),
        ];
        let tracks = Tracks2d {
            source: SourceInfo {
                path: "clip.mp4".into(),
                width: 64,
                height: 48,
                fps: 30.0,
                frame_count: states.len(),
            },
            frames: states
                .iter()
                .enumerate()
                .map(|(i, &(confidence, source))| FrameTracks {
                    index: FrameIndex(i),
                    body3d: None,
                    points: PerJoint::from_fn(|j| TrackedPoint {
                        pos: Point2::new(10.0, 10.0),
                        confidence: if j == Joint::LeftWrist {
                            confidence
                        } else {
                            0.9
                        },
                        source: if j == Joint::LeftWrist {
                            source
                        } else {
                            PointSource::Tracked
                        },
                    }),
                })
                .collect(),
        };
        let strips = Strips::new(&tracks, &KeyFrames::default(), 0.45);
        let states: Vec<PointState> = strips.runs[Joint::LeftWrist.index()]
            .iter()
            .map(|r| r.2)
            .collect();
        assert_eq!(
            states,
            [
                PointState::Tracked,
                PointState::Weak,
                PointState::Interpolated,
                PointState::OffFrame,
                PointState::Lost,
            ]
        );
        assert_eq!(strips.state_at(Joint::LeftWrist, 4), Some(PointState::Lost));
        assert_eq!(strips.state_at(Joint::Neck, 4), Some(PointState::Tracked));
        assert_eq!(strips.state_at(Joint::Neck, 5), None);
    }
}
