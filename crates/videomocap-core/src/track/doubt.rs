//! Doubt that points at the errors (issue 90, item 3), its evidence: per joint-frame the numbers
//! ([`DOUBT_FEATURES`]) from which `scripts/fit_doubt.py` calibrates, on `bench learned
//! --doubt-dump`'s output from the `dev` split, the probability that the joint-frame is more
//! than 0.2 torso off. A calibrated doubt from them was tried in the product and not kept (it
//! pointed at fewer errors on `test` than the jumps shown weak do: `docs/method.md`, "Whose
//! joints"). The evidence: how far the chosen place is from VBA's and from the network's joint,
//! the network's own doubt, a jump from the frames around, the bone to its parent against its
//! length over the clip, how near the joint's key is, how side-on the network sees the
//! shoulders (where left and right are easy to swap), whether the choice is the network's
//! other-side joint, and whether the joint is tracked at all.

use super::evidence::NetworkFrames;
use crate::formats::{KeyFrames, PointSource, Tracks2d};
use crate::skeleton::{Joint, PerJoint};

/// How many numbers describe a joint-frame's doubt.
pub const FEATURE_COUNT: usize = 9;

/// The names of the doubt's evidence, in order (the columns of `bench learned --doubt-dump`).
pub const DOUBT_FEATURES: [&str; FEATURE_COUNT] = [
    "vba_off",
    "net_off",
    "net_unsure",
    "jump",
    "length",
    "key_near",
    "shoulders",
    "swap",
    "lost",
];

/// Frames over which a key's nearness fades.
const KEY_NEAR_FRAMES: f64 = 8.0;

/// What the doubt reads over the whole clip: each frame's torso length in pixels, each bone's
/// median length in torso lengths, each joint's key frames.
struct ClipReading {
    torso: Vec<f64>,
    median: PerJoint<f64>,
    key_frames: PerJoint<Vec<usize>>,
}

/// Per frame and joint, the doubt's evidence ([`DOUBT_FEATURES`]) about `out` (the chosen
/// tracks) from VBA's tracks `vba`, the network's frames and the keys.
pub fn doubt_features(
    vba: &Tracks2d,
    net: &NetworkFrames,
    keys: &KeyFrames,
    out: &Tracks2d,
) -> Vec<PerJoint<[f64; FEATURE_COUNT]>> {
    let clip = ClipReading::new(net, keys, out);
    (0..out.frames.len())
        .map(|t| PerJoint::from_fn(|j| joint_features(&clip, vba, net, out, t, j)))
        .collect()
}

impl ClipReading {
    /// Reads the clip: the torso from the chosen tracks or the network's, whichever is
    /// longer (at least a pixel).
    fn new(net: &NetworkFrames, keys: &KeyFrames, out: &Tracks2d) -> ClipReading {
        let n = out.frames.len();
        let torso: Vec<f64> = (0..n)
            .map(|t| {
                let seen = net
                    .get(t)
                    .and_then(|f| f.joints.as_ref())
                    .map_or(0.0, |j| (j[Joint::Neck].pos - j[Joint::Pelvis].pos).norm());
                out.frames[t].torso_px().max(seen).max(1.0)
            })
            .collect();
        let median: PerJoint<f64> = PerJoint::from_fn(|j| {
            let mut v: Vec<f64> = (0..n).filter_map(|t| bone(out, &torso, t, j)).collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(0.0)
        });
        let key_frames: PerJoint<Vec<usize>> = PerJoint::from_fn(|j| {
            out.frames
                .iter()
                .enumerate()
                .filter(|(_, f)| keys.is_key(f.index, j))
                .map(|(t, _)| t)
                .collect()
        });
        ClipReading {
            torso,
            median,
            key_frames,
        }
    }
}

/// Joint `j`'s bone to its parent on frame `t` of `out`, in torso lengths (none for the root).
fn bone(out: &Tracks2d, torso: &[f64], t: usize, j: Joint) -> Option<f64> {
    j.parent()
        .map(|p| (out.frames[t].points[j].pos - out.frames[t].points[p].pos).norm() / torso[t])
}

/// Joint `j`'s evidence on frame `t`, in the order of [`DOUBT_FEATURES`].
fn joint_features(
    clip: &ClipReading,
    vba: &Tracks2d,
    net: &NetworkFrames,
    out: &Tracks2d,
    t: usize,
    j: Joint,
) -> [f64; FEATURE_COUNT] {
    let n = out.frames.len();
    let f = &out.frames[t];
    let torso = clip.torso[t];
    let p = f.points[j].pos;
    let off = |q: nalgebra::Point2<f64>| ((p - q).norm() / torso).min(1.0);
    let seen = net.get(t).and_then(|s| s.joints.as_ref());
    let (net_off, net_unsure, swap) = match seen.map(|s| (s[j], s[j.mirrored()])) {
        Some((own, other)) => {
            let swapped = off(other.pos) + 0.05 < off(own.pos);
            (
                off(own.pos),
                1.0 - own.confidence,
                if swapped { 1.0 } else { 0.0 },
            )
        }
        None => (1.0, 1.0, 0.0),
    };
    let jump = if t > 0 && t + 1 < n {
        let mid = nalgebra::center(
            &out.frames[t - 1].points[j].pos,
            &out.frames[t + 1].points[j].pos,
        );
        off(mid)
    } else {
        0.0
    };
    let median = clip.median[j];
    let length = match bone(out, &clip.torso, t, j) {
        Some(l) if median > 1e-6 && l > 1e-6 => (l / median).ln().abs().min(2.0),
        _ => 0.0,
    };
    let key_near = clip.key_frames[j]
        .iter()
        .map(|&k| k.abs_diff(t))
        .min()
        .map_or(0.0, |d| (-(d as f64) / KEY_NEAR_FRAMES).exp());
    let shoulders = seen.map_or(0.0, |s| {
        ((s[Joint::LeftShoulder].pos - s[Joint::RightShoulder].pos).norm() / torso).min(1.0)
    });
    let lost = match f.points[j].source {
        PointSource::Tracked => 0.0,
        _ => 1.0,
    };
    [
        off(vba.frames[t].points[j].pos),
        net_off,
        net_unsure,
        jump,
        length,
        key_near,
        shoulders,
        swap,
        lost,
    ]
}
