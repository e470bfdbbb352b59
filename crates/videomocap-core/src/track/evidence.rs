//! The pose network as evidence beside VBA: each frame cropped where the network itself
//! proposed on the frame before, starting from the user's marks and re-started from them at
//! every key (so it follows the person the user marked, whoever else is in the frame), and
//! per joint one choice over the whole clip among VBA's point, the network's and the network's
//! other-side point (its left/right swaps), by dynamic programming: each candidate's own
//! confidence, the continuity of the motion, and keys that always win.

use crate::camera::point_in_frame;
use crate::formats::{
    FrameIndex, FrameTracks, KeyFrames, NetworkBody, PointSource, TrackedPoint, Tracks2d,
};
use crate::network::{Crop, NetJoint, PoseNetwork};
use crate::skeleton::{Joint, PerJoint};
use crate::video::Video;
use nalgebra::{Point2, Vector3};

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
    /// Weight of a joint's squared move between frames, per torso². Default 8.
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
            motion: 8.0,
            key_fade_frames: 8.0,
            jump_cap_torso: 0.5,
        }
    }
}
/// The network's presence below which its frame is not used.
const MIN_PRESENCE: f64 = 0.5;

/// What the network saw on one frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NetFrame {
    /// The crop it was shown (`None`: none could be made).
    pub crop: Option<Crop>,
    /// Its joints (`None`: no person in the crop).
    pub joints: Option<PerJoint<NetJoint>>,
    /// The crop it proposes for the next frame.
    pub next: Option<Crop>,
    /// Its 3D body (metres, origin between the hips, y down, z away from the camera; `None`:
    /// no person, or a cache written before the body was kept).
    #[serde(default)]
    pub world: Option<PerJoint<Vector3<f64>>>,
    /// Not run: the chain left the frame out (`track::chain`); its joints, if any, are its two
    /// neighbours' midway, and `crop` the one it would have been shown.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub skipped: bool,
}

impl NetFrame {
    /// The network's 3D body on this frame with its joints' confidences, for the lift.
    pub fn body(&self) -> Option<NetworkBody> {
        let (joints, world) = (self.joints.as_ref()?, self.world?);
        Some(NetworkBody {
            points: world,
            confidence: joints.map(|_, j| j.confidence as f32),
        })
    }
}

/// What the network saw on each frame of a clip, in order.
pub type NetworkFrames = Vec<NetFrame>;

/// A key's pelvis or head top further than this (torso lengths) from the network's means the
/// network follows someone else, or nobody: the frame is shown the marked body instead.
const REFUSED_TORSO: f64 = 0.5;

/// What the network sees on frame `t` in `crop`: taken from `reuse` when it ran on frame `t`
/// with exactly that crop (the network's output depends on nothing else), else run.
pub(crate) fn look(
    video: &mut Video,
    network: &PoseNetwork,
    t: usize,
    crop: Option<Crop>,
    reuse: Option<&NetworkFrames>,
) -> NetFrame {
    let Some(c) = crop else {
        return NetFrame {
            crop: None,
            joints: None,
            next: None,
            world: None,
            skipped: false,
        };
    };
    if let Some(b) = reuse
        .and_then(|p| p.get(t))
        .filter(|b| b.crop == Some(c) && !b.skipped)
    {
        return b.clone();
    }
    let pose = video
        .frame(t)
        .ok()
        .and_then(|image| network.run(&image.image, &c).ok())
        .filter(|p| p.presence >= MIN_PRESENCE);
    NetFrame {
        crop: Some(c),
        next: pose.as_ref().and_then(|p| p.next_crop),
        world: pose.as_ref().map(|p| p.world),
        joints: pose.map(|p| p.joints),
        skipped: false,
    }
}

/// Whether a key's pelvis or head top lies far from where the network sees them (or the network
/// saw nobody): the network's body is not the one the user marked.
pub(crate) fn refuses(key: &PerJoint<Option<Point2<f64>>>, seen: &NetFrame) -> bool {
    let placed = [Joint::Pelvis, Joint::HeadTop]
        .into_iter()
        .filter_map(|j| key[j].map(|p| (j, p)))
        .collect::<Vec<_>>();
    if placed.is_empty() {
        return false;
    }
    let Some(joints) = seen.joints.as_ref() else {
        return true;
    };
    let torso = (joints[Joint::Neck].pos - joints[Joint::Pelvis].pos)
        .norm()
        .max(1.0);
    placed
        .iter()
        .any(|&(j, p)| (joints[j].pos - p).norm() > REFUSED_TORSO * torso)
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
    let n = tracks.frames.len();
    // The body's size on each frame, for the motion costs: the larger of VBA's torso and the
    // network's (a VBA trunk that collapsed onto a point would make every move of the
    // network's joints look huge).
    let torso: Vec<f64> = (0..n)
        .map(|t| {
            let own = tracks.frames[t].torso_px();
            let seen = net
                .get(t)
                .and_then(|f| f.joints.as_ref())
                .map_or(0.0, |j| (j[Joint::Neck].pos - j[Joint::Pelvis].pos).norm());
            own.max(seen)
        })
        .collect();
    let mut out = tracks.clone();
    // The network's 3D body goes with the tracks, evidence for the lift's depth order.
    for (frame, seen) in out.frames.iter_mut().zip(net) {
        frame.body3d = seen.body().map(Box::new);
    }
    for j in Joint::ALL {
        let candidates: Vec<Vec<Candidate>> = (0..n)
            .map(|t| candidates(tracks, net, keys, params, t, j))
            .collect();
        let chosen = choose(&candidates, &torso, params);
        for (t, c) in chosen.into_iter().enumerate() {
            if c.from_network {
                // A place the network gives outside the image is off the frame, as VBA's are.
                let inside = point_in_frame(&c.pos, tracks.source.width, tracks.source.height);
                out.frames[t].points[j] = TrackedPoint {
                    pos: c.pos,
                    confidence: if inside { c.confidence } else { 0.0 },
                    source: if inside {
                        PointSource::Tracked
                    } else {
                        PointSource::OffFrame
                    },
                };
            }
        }
    }
    out
}

/// Frames from `index` to the nearest key of joint `j`, for the key's fading certainty: a key
/// that places other joints leaves this one's VBA track as it was (a correction of one joint
/// moves no other, issue 90).
fn to_key(keys: &KeyFrames, index: FrameIndex, j: Joint) -> f64 {
    keys.frames
        .iter()
        .filter(|(_, k)| k[j].is_some())
        .map(|(k, _)| k.get().abs_diff(index.get()))
        .min()
        .map_or(f64::INFINITY, |d| d as f64)
}

/// Joint `j`'s candidates on frame `t`: VBA's place, its doubt growing as its reliability
/// falls and its key fades; then, unless the joint is keyed or VBA carried it off the frame,
/// the network's joint and its other-side joint (for a swap).
fn candidates(
    tracks: &Tracks2d,
    net: &NetworkFrames,
    keys: &KeyFrames,
    params: &EvidenceParams,
    t: usize,
    j: Joint,
) -> Vec<Candidate> {
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
            * (1.0 - (-to_key(keys, f.index, j) / params.key_fade_frames).exp())
    };
    let mut c = vec![Candidate {
        pos: p.pos,
        cost: vba_doubt,
        confidence: p.confidence,
        from_network: false,
    }];
    // A joint VBA carried off the frame stays off it: at the image's edge the network puts an
    // arm that left inside the frame, and sure of it.
    if keyed.is_some() || p.source == PointSource::OffFrame {
        return c;
    }
    if let Some(pose) = net.get(t).and_then(|f| f.joints.as_ref()) {
        for (side, extra) in [(j, 0.0), (j.mirrored(), params.swap_cost)] {
            if side == j && extra > 0.0 {
                continue;
            }
            let q = pose[side];
            c.push(Candidate {
                pos: q.pos,
                cost: params.net_doubt * (1.0 - q.confidence) + extra,
                confidence: q.confidence as f32,
                from_network: true,
            });
        }
    }
    c
}

/// A joint further than this (torso lengths) from the middle of its places on the frames
/// before and after has jumped: shown weak (dev figures in `docs/method.md`).
const JUMP_TORSO: f64 = 0.1;

/// The reliability a jump leaves (below the default weak threshold, 0.45).
const JUMPED_RELIABILITY: f32 = 0.25;

/// Lowers the reliability of every joint-frame that jumped (see [`JUMP_TORSO`]), leaving its
/// place as it is (shown weak for review, not filled); keys keep theirs.
pub(crate) fn flag_jumps(frames: &mut [FrameTracks], keys: &KeyFrames) {
    let n = frames.len();
    for t in 1..n.saturating_sub(1) {
        let index = frames[t].index;
        let torso = frames[t].torso_px().max(1.0);
        for j in Joint::ALL {
            if keys.is_key(index, j) || frames[t].points[j].source != PointSource::Tracked {
                continue;
            }
            let (a, b) = (frames[t - 1].points[j].pos, frames[t + 1].points[j].pos);
            let p = &mut frames[t].points[j];
            if (p.pos - nalgebra::center(&a, &b)).norm() / torso > JUMP_TORSO {
                p.confidence = p.confidence.min(JUMPED_RELIABILITY);
            }
        }
    }
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
                index: FrameIndex(t),
                body3d: None,
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
            .map(|f| NetFrame {
                crop: None,
                world: None,
                joints: Some(f.points.map(|_, p| NetJoint {
                    pos: p.pos,
                    confidence: 0.95,
                })),
                next: None,
                skipped: false,
            })
            .collect()
    }

    fn keys_at(frames: &[usize], t: &Tracks2d) -> KeyFrames {
        KeyFrames {
            frames: frames
                .iter()
                .map(|&k| (FrameIndex(k), t.frames[k].points.map(|_, p| Some(p.pos))))
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
        let none: NetworkFrames = vec![
            NetFrame {
                crop: None,
                joints: None,
                next: None,
                world: None,
                skipped: false,
            };
            20
        ];
        assert_eq!(weigh(&vba, &none, &keys, &EvidenceParams::default()), vba);
    }

    #[test]
    fn a_joint_that_jumps_for_one_frame_is_shown_weak_where_it_is_and_a_smooth_one_is_not() {
        let vba = tracks(
            12,
            |t| {
                Point2::new(
                    60.0 + 2.0 * t as f64 + if t == 6 { 30.0 } else { 0.0 },
                    190.0,
                )
            },
            0.9,
        );
        let none: NetworkFrames = vec![
            NetFrame {
                crop: None,
                joints: None,
                next: None,
                world: None,
                skipped: false,
            };
            12
        ];
        let mut out = weigh(
            &vba,
            &none,
            &keys_at(&[0], &vba),
            &EvidenceParams::default(),
        );
        flag_jumps(&mut out.frames, &keys_at(&[0], &vba));
        let reliability = |t: usize, j: Joint| out.frames[t].points[j].confidence;
        // The spike (30 px on a 100 px torso) and its neighbours, whose middle it moves.
        assert!(reliability(6, Joint::LeftWrist) < 0.45);
        assert!(reliability(5, Joint::LeftWrist) < 0.45);
        assert!(reliability(9, Joint::LeftWrist) > 0.45);
        assert!(reliability(6, Joint::RightWrist) > 0.45);
        // The key keeps its certainty, the spike its place.
        assert_eq!(reliability(0, Joint::LeftWrist), 0.9);
        assert_eq!(out.frames[6].points[Joint::LeftWrist].pos.x, 102.0);
    }
}
