//! The pose network as evidence beside VBA: each frame cropped around the body the network saw
//! on the frame before, starting from the user's marks (so it follows the person the user
//! marked, whoever else is in the frame), the network's
//! joints corrected by the offset the key frames show between its landmarks and the user's
//! joints, and per joint one choice over the whole clip among VBA's point, the network's and
//! the network's other-side point (its left/right swaps), by dynamic programming: each
//! candidate's own confidence, the continuity of the motion, and keys that always win.

use super::run::TrackError;
use crate::formats::{KeyFrames, PointSource, TrackedPoint, Tracks2d};
use crate::network::{Crop, NetJoint, PoseNetwork};
use crate::skeleton::{Joint, PerJoint};
use crate::video::Video;
use nalgebra::{Point2, Rotation2, Vector2};
use std::sync::atomic::{AtomicBool, Ordering};

/// How the evidence is weighed. Costs are in the unit of one torso² of motion between frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvidenceParams {
    /// Weight of VBA's doubt (1 − its reliability). Default 2 (dev sweep, `docs/method.md`).
    pub vba_doubt: f64,
    /// Weight of the network's doubt (1 − its confidence). Default 0.5.
    pub net_doubt: f64,
    /// Extra cost of taking the network's other-side joint (a left/right swap of its own).
    /// Default 1.
    pub swap_cost: f64,
    /// Weight of a joint's squared move between frames, per torso². Default 4.
    pub motion: f64,
    /// Frames over which a key's certainty fades for VBA (its track is exact at the key).
    /// Default 8.
    pub key_fade_frames: f64,
    /// Moves longer than this (torso lengths) cost no more: a switch between two candidates
    /// far apart is one jump, not a reason to stay with a track that drifted. Default 0.5.
    pub jump_cap_torso: f64,
}

impl Default for EvidenceParams {
    fn default() -> Self {
        EvidenceParams {
            vba_doubt: 2.0,
            net_doubt: 0.5,
            swap_cost: 1.0,
            motion: 4.0,
            key_fade_frames: 8.0,
            jump_cap_torso: 0.5,
        }
    }
}
/// The network's presence below which its frame is not used.
const MIN_PRESENCE: f64 = 0.5;

/// What the network saw on each frame (`None`: no person, or no crop).
pub type NetworkFrames = Vec<Option<PerJoint<NetJoint>>>;

/// Runs the network on every frame of `video`, each crop around the body the network saw on
/// the frame before, so that it follows the person the user marked: on a key frame the crop is
/// made from VBA's body there (the user's joints), and where the network finds no person from
/// VBA's body too.
pub fn run_network(
    video: &mut Video,
    tracks: &Tracks2d,
    network: &PoseNetwork,
    keys: &KeyFrames,
    cancel: &AtomicBool,
) -> Result<NetworkFrames, TrackError> {
    let mut out = Vec::with_capacity(tracks.frames.len());
    let mut body: Option<PerJoint<Point2<f64>>> = None;
    for f in &tracks.frames {
        if cancel.load(Ordering::Relaxed) {
            return Err(TrackError::Cancelled);
        }
        let vba = f.points.map(|_, p| p.pos);
        let around = match body {
            Some(b) if !keys.frames.contains_key(&f.index) => b,
            _ => vba,
        };
        let pose = match (video.frame(f.index), Crop::around(&around)) {
            (Ok(frame), Some(crop)) => network.run(&frame.image, &crop).ok(),
            _ => None,
        };
        match pose.filter(|p| p.presence >= MIN_PRESENCE) {
            Some(p) => {
                body = Some(p.joints.map(|_, j| j.pos));
                out.push(Some(p.joints));
            }
            None => {
                body = Some(vba);
                out.push(None);
            }
        }
    }
    Ok(out)
}

/// The trunk's frame of the network's body on one frame: (rotation taking the image's down
/// onto neck → pelvis, torso length in pixels).
fn trunk_frame(j: &PerJoint<NetJoint>) -> Option<(Rotation2<f64>, f64)> {
    let axis = j[Joint::Pelvis].pos - j[Joint::Neck].pos;
    let torso = axis.norm();
    (torso > 1.0).then(|| (Rotation2::rotation_between(&Vector2::y(), &axis), torso))
}

/// Per joint, the mean offset from the network's landmark to the user's joint over the key
/// frames, in the trunk's frame over the torso length: for the trunk, the shoulders and the
/// hips, which a user marks elsewhere than the network puts them; none for the elbows, wrists,
/// knees and ankles, which sit where the network's do (an offset read on one frame and turned
/// with the trunk moved them off; dev 0.829 → see `docs/method.md`).
fn key_offsets(net: &NetworkFrames, tracks: &Tracks2d, keys: &KeyFrames) -> PerJoint<Vector2<f64>> {
    let mut sum = PerJoint::from_fn(|_| (Vector2::zeros(), 0.0));
    for (frame, joints) in &keys.frames {
        let Some(k) = tracks.frames.iter().position(|f| f.index == *frame) else {
            continue;
        };
        let Some(Some(pose)) = net.get(k) else {
            continue;
        };
        let Some((rot, torso)) = trunk_frame(pose) else {
            continue;
        };
        for j in Joint::ALL.into_iter().filter(|&j| carries_offset(j)) {
            if let Some(mark) = joints[j] {
                let local = rot.inverse() * (mark - pose[j].pos) / torso;
                sum[j].0 += local;
                sum[j].1 += 1.0;
            }
        }
    }
    sum.map(|_, &(s, n)| if n > 0.0 { s / n } else { Vector2::zeros() })
}

/// Whether the network's joint is defined elsewhere than the user's (see [`key_offsets`]).
fn carries_offset(j: Joint) -> bool {
    use Joint::*;
    matches!(
        j,
        HeadTop | Neck | Chest | Pelvis | LeftShoulder | RightShoulder | LeftHip | RightHip
    )
}

/// The joint on the body's other side (itself for the trunk's).
fn other_side(j: Joint) -> Joint {
    use Joint::*;
    match j {
        LeftShoulder => RightShoulder,
        RightShoulder => LeftShoulder,
        LeftElbow => RightElbow,
        RightElbow => LeftElbow,
        LeftWrist => RightWrist,
        RightWrist => LeftWrist,
        LeftHip => RightHip,
        RightHip => LeftHip,
        LeftKnee => RightKnee,
        RightKnee => LeftKnee,
        LeftAnkle => RightAnkle,
        RightAnkle => LeftAnkle,
        other => other,
    }
}

/// One candidate for a joint on a frame: position and the cost of its own doubt.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    pos: Point2<f64>,
    cost: f64,
    confidence: f32,
    from_network: bool,
}

/// VBA's tracks with the network's evidence weighed in (see the module's text). Joints placed by
/// hand on key frames keep their place.
pub fn weigh(
    tracks: &Tracks2d,
    net: &NetworkFrames,
    keys: &KeyFrames,
    params: &EvidenceParams,
) -> Tracks2d {
    let offsets = key_offsets(net, tracks, keys);
    let n = tracks.frames.len();
    let key_index: Vec<Option<usize>> = tracks
        .frames
        .iter()
        .map(|f| keys.frames.contains_key(&f.index).then_some(f.index))
        .collect();
    // Frames to the nearest key, for the key's fading certainty.
    let key_frames: Vec<usize> = key_index.iter().flatten().copied().collect();
    let to_key = |index: usize| {
        key_frames
            .iter()
            .map(|&k| k.abs_diff(index))
            .min()
            .map_or(f64::INFINITY, |d| d as f64)
    };
    let mut out = tracks.clone();
    for j in Joint::ALL {
        let candidates: Vec<Vec<Candidate>> = (0..n)
            .map(|t| {
                let f = &tracks.frames[t];
                let p = f.points[j];
                let keyed = keys.frames.get(&f.index).and_then(|k| k[j]);
                let vba_doubt = if keyed.is_some() {
                    0.0
                } else {
                    let r = match p.source {
                        PointSource::Lost => 0.0,
                        _ => f64::from(p.confidence),
                    };
                    params.vba_doubt
                        * (1.0 - r)
                        * (1.0 - (-to_key(f.index) / params.key_fade_frames).exp())
                };
                let mut c = vec![Candidate {
                    pos: p.pos,
                    cost: vba_doubt,
                    confidence: p.confidence,
                    from_network: false,
                }];
                if keyed.is_some() || p.source == PointSource::OffFrame {
                    return c;
                }
                if let Some(Some(pose)) = net.get(t)
                    && let Some((rot, torso)) = trunk_frame(pose)
                {
                    for (side, extra) in [(j, 0.0), (other_side(j), params.swap_cost)] {
                        if side == j && extra > 0.0 {
                            continue;
                        }
                        let q = pose[side];
                        c.push(Candidate {
                            pos: q.pos + rot * offsets[j] * torso,
                            cost: params.net_doubt * (1.0 - q.confidence) + extra,
                            confidence: q.confidence as f32,
                            from_network: true,
                        });
                    }
                }
                c
            })
            .collect();
        let torso: Vec<f64> = tracks.frames.iter().map(|f| f.torso_px()).collect();
        let chosen = choose(&candidates, &torso, params);
        for (t, c) in chosen.into_iter().enumerate() {
            if c.from_network {
                out.frames[t].points[j] = TrackedPoint {
                    pos: c.pos,
                    confidence: c.confidence,
                    source: PointSource::Tracked,
                };
            }
        }
    }
    out
}

/// The cheapest path through the candidates (Viterbi): each candidate's own cost plus
/// `motion` × the squared move (capped at `jump_cap_torso`) between frames over the torso.
fn choose(candidates: &[Vec<Candidate>], torso: &[f64], params: &EvidenceParams) -> Vec<Candidate> {
    let n = candidates.len();
    if n == 0 {
        return Vec::new();
    }
    let mut cost: Vec<Vec<f64>> = vec![candidates[0].iter().map(|c| c.cost).collect()];
    let mut back: Vec<Vec<usize>> = vec![vec![0; candidates[0].len()]];
    for t in 1..n {
        let scale = torso[t].max(1.0);
        let mut row = Vec::with_capacity(candidates[t].len());
        let mut from = Vec::with_capacity(candidates[t].len());
        for c in &candidates[t] {
            let (best, k) = candidates[t - 1]
                .iter()
                .enumerate()
                .map(|(k, p)| {
                    let d = ((c.pos - p.pos).norm() / scale).min(params.jump_cap_torso);
                    (cost[t - 1][k] + params.motion * d * d, k)
                })
                .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a });
            row.push(best + c.cost);
            from.push(k);
        }
        cost.push(row);
        back.push(from);
    }
    let mut k = cost[n - 1]
        .iter()
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |a, (i, &c)| if c < a.1 { (i, c) } else { a },
        )
        .0;
    let mut path = vec![candidates[n - 1][k]; n];
    for t in (0..n).rev() {
        path[t] = candidates[t][k];
        k = back[t][k];
    }
    path
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::{FrameTracks, SourceInfo};

    /// A standing body 100 px of torso; the left wrist at `wrist(t)` in VBA's tracks.
    fn tracks(n: usize, wrist: impl Fn(usize) -> Point2<f64>, confidence: f32) -> Tracks2d {
        let frames = (0..n)
            .map(|t| FrameTracks {
                index: t,
                points: PerJoint::from_fn(|j| TrackedPoint {
                    pos: match j {
                        Joint::Neck => Point2::new(100.0, 100.0),
                        Joint::Pelvis => Point2::new(100.0, 200.0),
                        Joint::LeftWrist => wrist(t),
                        _ => Point2::new(100.0, 150.0),
                    },
                    confidence,
                    source: PointSource::Tracked,
                }),
            })
            .collect();
        Tracks2d {
            source: SourceInfo {
                path: "x".into(),
                width: 400,
                height: 400,
                fps: 30.0,
                frame_count: n,
            },
            frames,
        }
    }

    /// The network sees the same body with the left wrist at `wrist(t)`, sure of it.
    fn network(n: usize, wrist: impl Fn(usize) -> Point2<f64>) -> NetworkFrames {
        let t = tracks(n, wrist, 1.0);
        t.frames
            .iter()
            .map(|f| {
                Some(f.points.map(|_, p| NetJoint {
                    pos: p.pos,
                    confidence: 0.95,
                }))
            })
            .collect()
    }

    fn keys_at(frames: &[usize], t: &Tracks2d) -> KeyFrames {
        KeyFrames {
            frames: frames
                .iter()
                .map(|&k| (k, t.frames[k].points.map(|_, p| Some(p.pos))))
                .collect(),
        }
    }

    #[test]
    fn a_limb_vba_lost_is_taken_from_a_sure_network_and_the_key_keeps_its_place() {
        // VBA's wrist slides away from frame 10 on; the network keeps it at the hip.
        let truth = |_: usize| Point2::new(60.0, 190.0);
        let vba = tracks(
            40,
            |t| Point2::new(60.0 + 6.0 * t.saturating_sub(10) as f64, 190.0),
            0.6,
        );
        let net = network(40, truth);
        let keys = keys_at(&[0], &vba);
        let out = weigh(&vba, &net, &keys, &EvidenceParams::default());
        assert_eq!(
            out.frames[0].points[Joint::LeftWrist].pos,
            vba.frames[0].points[Joint::LeftWrist].pos
        );
        for t in 25..40 {
            let p = out.frames[t].points[Joint::LeftWrist].pos;
            assert!((p - truth(t)).norm() < 1.0, "frame {t}: {p}");
        }
    }

    #[test]
    fn where_the_two_agree_vba_is_kept_and_no_network_means_vba_alone() {
        let vba = tracks(20, |_| Point2::new(60.0, 190.0), 0.9);
        let net = network(20, |_| Point2::new(61.0, 190.0));
        let keys = keys_at(&[0], &vba);
        let out = weigh(&vba, &net, &keys, &EvidenceParams::default());
        // Within a pixel either way, and never a jump.
        for f in &out.frames {
            assert!((f.points[Joint::LeftWrist].pos - Point2::new(60.5, 190.0)).norm() <= 0.5);
        }
        let none: NetworkFrames = vec![None; 20];
        assert_eq!(weigh(&vba, &none, &keys, &EvidenceParams::default()), vba);
    }
}
