//! The network's chain over the clip, run only where it adds (issue 95, item 3).
//!
//! Each frame is cropped where the network proposed on the frame before ([`run_network`]). A
//! frame may go without the network ([`may_skip`]) when the network's joints moved slowly over
//! the two frames it ran on before, never two frames in a row, never the first two frames or the
//! last; the chain then shows the next frame the crop the left-out one would have had. These
//! choices read no key, so a correction that does not re-start the crop leaves them as they
//! were: a key whose pelvis or head top may refuse the network's body ([`looked_at`]) on a
//! left-out frame is looked at in the crop it would have had, and that crop passed on. Once the
//! chain is done each skipped frame is settled ([`settle`]): it gets the network after all (in
//! the crop it would have had) where one of its two neighbours saw nobody or they are far apart
//! (the joints moved fast), or where VBA is sure of a joint and puts it away from the
//! neighbours' midway; elsewhere it takes the midway of its two neighbours.
//!
//! The rule reads nothing but the network's own output, so the worker that runs the chain ahead
//! of VBA's passes (`ahead`) skips the same frames; only the last check reads VBA's tracks.

use super::evidence::{NetFrame, NetworkFrames, look, refuses};
use super::shared::TrackError;
use crate::formats::{FrameIndex, FrameTracks, KeyFrames, PointSource, Tracks2d};
use crate::network::{Crop, NetJoint, PoseNetwork};
use crate::skeleton::{Joint, PerJoint};
use crate::video::Video;
use std::sync::atomic::{AtomicBool, Ordering};

/// When a frame may go without the network (see the module's text; figures in
/// `docs/method.md`, "Speed").
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SkipRule {
    /// The fastest any joint may move between the neighbours, torso lengths per frame.
    pub(crate) speed: f64,
    /// VBA's joint (where its reliability is at least `vba_sure`) further than this from the
    /// neighbours' midway, torso lengths, sends the frame to the network.
    pub(crate) agree: f64,
    /// VBA's reliability from which its joint is checked against the midway.
    pub(crate) vba_sure: f32,
}

impl Default for SkipRule {
    /// Joints moving at most 0.2 torso a frame,
    /// VBA checked where its reliability is 0.8 or more, at 0.3 torso: `bench learned`, dev
    /// 36 % of the frames left out, together 0.926 → 0.928 (PCK@0.2, limbs), test 33 %, 0.932
    /// → 0.933 (`docs/method.md`, "Speed").
    fn default() -> Self {
        SkipRule {
            speed: 0.2,
            agree: 0.3,
            vba_sure: 0.8,
        }
    }
}

/// The joints of a frame the network ran on (`None`: skipped, or nobody seen).
fn ran(frame: Option<&NetFrame>) -> Option<&PerJoint<NetJoint>> {
    frame.filter(|f| !f.skipped)?.joints.as_ref()
}

/// The network's torso on a frame, pixels (at least 1).
fn torso(joints: &PerJoint<NetJoint>) -> f64 {
    (joints[Joint::Neck].pos - joints[Joint::Pelvis].pos)
        .norm()
        .max(1.0)
}

/// Whether every joint moved at most `speed` torso per frame from `from`, `frames` frames
/// before.
fn steady(
    rule: &SkipRule,
    from: &PerJoint<NetJoint>,
    to: &PerJoint<NetJoint>,
    frames: f64,
) -> bool {
    let limit = rule.speed * frames * torso(to).max(torso(from));
    Joint::ALL
        .into_iter()
        .all(|j| (to[j].pos - from[j].pos).norm() <= limit)
}

/// Whether a key on frame `t` must be looked at by the network even where the chain leaves the
/// frame out: one that places the pelvis or head top, which may refuse the network's body
/// (`evidence::refuses`). A key placing every joint re-starts the crop from the marks anyway.
pub(crate) fn looked_at(keys: &KeyFrames, t: usize) -> bool {
    keys.frames
        .get(&FrameIndex(t))
        .is_some_and(|k| k[Joint::Pelvis].is_some() || k[Joint::HeadTop].is_some())
}

/// Whether the chain leaves frame `t` of `n` without the network, from what it saw before
/// (`seen(s)` for `s < t`) and the frames it left out before (`left_out[s]`): `t` neither of
/// the first two frames nor the last, `t − 1` not left out (so never two in a row), and every
/// joint moving slowly between the last two frames the network ran on.
///
/// It reads no key: a correction that does not re-start the crop leaves every choice of the
/// chain as it was (the chain looks at a frame it leaves out where [`looked_at`] says so, in
/// the crop it would have had, and passes that crop on unchanged), so a correction changes no
/// network frame away from it.
pub(crate) fn may_skip<'a>(
    rule: &SkipRule,
    n: usize,
    t: usize,
    left_out: &[bool],
    seen: impl Fn(usize) -> Option<&'a NetFrame>,
) -> bool {
    let out = |s: usize| left_out.get(s).copied().unwrap_or(false);
    if t < 2 || t + 1 >= n || out(t - 1) {
        return false;
    }
    let Some(last) = ran(seen(t - 1)) else {
        return false;
    };
    let before = if out(t - 2) {
        t.checked_sub(3)
    } else {
        Some(t - 2)
    };
    let Some(earlier) = before.and_then(|s| ran(seen(s)).map(|j| (s, j))) else {
        return false;
    };
    steady(rule, earlier.1, last, (t - 1 - earlier.0) as f64)
}

/// A frame the chain left out: the crop it would have been shown, carried on to the next frame;
/// no joints until [`settle`] gives it some.
pub(crate) fn skipped(crop: Option<Crop>) -> NetFrame {
    NetFrame {
        crop,
        joints: None,
        next: crop,
        world: None,
        skipped: true,
    }
}

/// Whether a skipped frame between `before` and `after` needs the network after all (module's
/// text); `vba`: VBA's tracks on the frame (`None`: the network's own checks only).
pub(crate) fn needs_network(
    rule: &SkipRule,
    before: Option<&NetFrame>,
    after: Option<&NetFrame>,
    vba: Option<&FrameTracks>,
) -> bool {
    let (Some(a), Some(b)) = (ran(before), ran(after)) else {
        return true;
    };
    if !steady(rule, a, b, 2.0) {
        return true;
    }
    let Some(vba) = vba else {
        return false;
    };
    let limit = rule.agree * torso(a).max(torso(b));
    Joint::ALL.into_iter().any(|j| {
        let p = vba.points[j];
        p.source == PointSource::Tracked
            && p.confidence >= rule.vba_sure
            && (p.pos - nalgebra::center(&a[j].pos, &b[j].pos)).norm() > limit
    })
}

/// The midway of a skipped frame's two neighbours (both run, both with joints): joints halfway
/// with the lower confidence, the 3D body halfway; still marked skipped.
fn midway(crop: Option<Crop>, before: &NetFrame, after: &NetFrame) -> NetFrame {
    let joints = before
        .joints
        .as_ref()
        .zip(after.joints.as_ref())
        .map(|(a, b)| {
            PerJoint::from_fn(|j| NetJoint {
                pos: nalgebra::center(&a[j].pos, &b[j].pos),
                confidence: a[j].confidence.min(b[j].confidence),
            })
        });
    let world = before
        .world
        .zip(after.world)
        .map(|(a, b)| PerJoint::from_fn(|j| (a[j] + b[j]) / 2.0));
    NetFrame {
        joints,
        world,
        ..skipped(crop)
    }
}

/// Settles every skipped frame of `out` (see the module's text): the network run on it in the
/// crop it would have had where [`needs_network`] says so (from `reuse` when it holds that
/// frame and crop), else its neighbours' midway.
pub(crate) fn settle(
    video: &mut Video,
    network: &PoseNetwork,
    out: &mut NetworkFrames,
    tracks: &Tracks2d,
    rule: &SkipRule,
    reuse: Option<&NetworkFrames>,
    cancel: &AtomicBool,
) -> Result<(), TrackError> {
    for t in 1..out.len().saturating_sub(1) {
        if !out[t].skipped {
            continue;
        }
        if cancel.load(Ordering::Relaxed) {
            return Err(TrackError::Cancelled);
        }
        let (before, after) = (out.get(t - 1), out.get(t + 1));
        out[t] = if needs_network(rule, before, after, tracks.frames.get(t)) {
            look(video, network, t, out[t].crop, reuse)
        } else {
            midway(out[t].crop, &out[t - 1], &out[t + 1])
        };
    }
    Ok(())
}

/// Runs the network on the frames of `video` where it adds (see the module's text), each crop
/// the one the network proposed on the frame before (its own tracking region), so that it
/// follows the person the user marked: on a key frame with every joint placed, after a frame
/// where it found no person, and where a key's pelvis or head top is far from the network's (it
/// followed someone else), the crop is made from VBA's body there (with the user's joints). A
/// frame whose crop is exactly the one it had in `reuse` (an earlier run on this video) is taken
/// from it instead of run again. `tick` is called once per frame.
pub fn run_network(
    video: &mut Video,
    tracks: &Tracks2d,
    network: &PoseNetwork,
    keys: &KeyFrames,
    reuse: Option<&NetworkFrames>,
    tick: &mut dyn FnMut(),
    cancel: &AtomicBool,
) -> Result<NetworkFrames, TrackError> {
    let n = tracks.frames.len();
    let previous = reuse.filter(|p| p.len() == n);
    let rule = SkipRule::default();
    let mut out: NetworkFrames = Vec::with_capacity(n);
    let mut left_out: Vec<bool> = Vec::with_capacity(n);
    let mut next: Option<Crop> = None;
    for (t, f) in tracks.frames.iter().enumerate() {
        if cancel.load(Ordering::Relaxed) {
            return Err(TrackError::Cancelled);
        }
        tick();
        let key = keys.frames.get(&f.index);
        let full = key.is_some_and(|k| k.iter().all(|(_, p)| p.is_some()));
        let leave = next.is_some() && !full && may_skip(&rule, n, t, &left_out, |s| out.get(s));
        if leave && !looked_at(keys, t) {
            out.push(skipped(next));
            left_out.push(true);
            continue;
        }
        let marked = || Crop::around(&f.points.map(|_, p| p.pos));
        let crop = match next {
            Some(c) if !full => Some(c),
            _ => marked(),
        };
        let mut frame = look(video, network, t, crop, previous);
        let restart = key.is_some_and(|k| !full && refuses(k, &frame)) && crop != marked();
        if restart {
            frame = look(video, network, t, marked(), previous);
        } else if leave {
            // A key on a frame the chain leaves out: seen in the crop it would have had, that
            // crop passed on, so the chain's later frames are as they were without the key.
            frame.next = crop;
        }
        left_out.push(leave && !restart);
        next = frame.next;
        out.push(frame);
    }
    settle(video, network, &mut out, tracks, &rule, previous, cancel)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::TrackedPoint;
    use nalgebra::{Point2, Vector3};

    /// The product's rule: 0.2 torso a frame, VBA checked from 0.8 at 0.3 torso.
    const RULE: SkipRule = SkipRule {
        speed: 0.2,
        agree: 0.3,
        vba_sure: 0.8,
    };

    /// A body of 100 px torso at `x`, every joint at `confidence`.
    fn seen(x: f64, confidence: f64) -> NetFrame {
        let joints = PerJoint::from_fn(|j| NetJoint {
            pos: Point2::new(x + 3.0 * j.index() as f64, 100.0 + 10.0 * j.index() as f64),
            confidence,
        });
        let joints = PerJoint::from_fn(|j| match j {
            Joint::Neck => NetJoint {
                pos: Point2::new(x, 100.0),
                confidence,
            },
            Joint::Pelvis => NetJoint {
                pos: Point2::new(x, 200.0),
                confidence,
            },
            _ => joints[j],
        });
        NetFrame {
            crop: None,
            joints: Some(joints),
            next: None,
            world: Some(PerJoint::from_fn(|_| Vector3::new(x, 0.0, 0.0))),
            skipped: false,
        }
    }

    /// The chain over `n` frames of a body moving `step` px a frame: per frame, whether it was
    /// left out and whether the network ran on it.
    fn chain(n: usize, keys: &KeyFrames, step: f64, confidence: f64) -> Vec<(bool, bool)> {
        let (mut out, mut left_out): (Vec<NetFrame>, Vec<bool>) = (Vec::new(), Vec::new());
        for t in 0..n {
            let leave = may_skip(&RULE, n, t, &left_out, |s| out.get(s));
            out.push(if leave && !looked_at(keys, t) {
                skipped(None)
            } else {
                seen(step * t as f64, confidence)
            });
            left_out.push(leave);
        }
        left_out
            .into_iter()
            .zip(out.iter().map(|f| !f.skipped))
            .collect()
    }

    fn key(t: usize, joints: &[Joint]) -> KeyFrames {
        let mut keys = KeyFrames::default();
        for &j in joints {
            keys.set(FrameIndex(t), j, Point2::new(1.0, 1.0));
        }
        keys
    }

    #[test]
    fn a_steady_sure_body_is_left_out_every_other_frame_and_a_key_changes_no_other_frame() {
        assert_eq!(RULE, SkipRule::default());
        let none = KeyFrames::default();
        let plain = chain(10, &none, 2.0, 0.95);
        let left: Vec<bool> = plain.iter().map(|c| c.0).collect();
        assert_eq!(
            left,
            [
                false, false, true, false, true, false, true, false, true, false
            ]
        );
        assert!(plain.iter().all(|&(l, ran)| l != ran));
        // A key on the pelvis (or the head top) of a left-out frame is looked at there, and
        // every other frame is as without it; a key on a limb alone is not looked at.
        let pelvis = chain(10, &key(4, &[Joint::Pelvis]), 2.0, 0.95);
        assert_eq!(pelvis[4], (true, true));
        for t in (0..10).filter(|&t| t != 4) {
            assert_eq!(pelvis[t], plain[t], "frame {t}");
        }
        assert_eq!(chain(10, &key(4, &[Joint::LeftWrist]), 2.0, 0.95), plain);
        // Moving fast (25 px a frame on a 100 px torso): every frame run.
        assert!(
            chain(10, &none, 25.0, 0.95)
                .iter()
                .all(|&(l, ran)| !l && ran)
        );
    }

    fn vba_at(x: f64, confidence: f32) -> FrameTracks {
        FrameTracks {
            index: FrameIndex(1),
            body3d: None,
            points: seen(x, 1.0).joints.unwrap().map(|_, p| TrackedPoint {
                pos: p.pos,
                confidence,
                source: PointSource::Tracked,
            }),
        }
    }

    #[test]
    fn a_skipped_frame_takes_the_midway_unless_the_neighbours_or_a_sure_vba_disagree() {
        let (a, b) = (seen(10.0, 0.95), seen(14.0, 0.9));
        assert!(!needs_network(
            &RULE,
            Some(&a),
            Some(&b),
            Some(&vba_at(12.0, 0.9))
        ));
        let mid = midway(None, &a, &b);
        let joints = mid.joints.unwrap();
        assert_eq!(joints[Joint::Neck].pos, Point2::new(12.0, 100.0));
        assert_eq!(joints[Joint::Neck].confidence, 0.9);
        assert_eq!(mid.world.unwrap()[Joint::Neck].x, 12.0);
        assert!(mid.skipped);
        // VBA sure and 35 px (0.35 torso) away; unsure and as far; a neighbour far (50 px in two
        // frames) or lost.
        assert!(needs_network(
            &RULE,
            Some(&a),
            Some(&b),
            Some(&vba_at(47.0, 0.9))
        ));
        assert!(!needs_network(
            &RULE,
            Some(&a),
            Some(&b),
            Some(&vba_at(47.0, 0.5))
        ));
        assert!(needs_network(
            &RULE,
            Some(&a),
            Some(&seen(60.0, 0.95)),
            None
        ));
        let mut lost = b.clone();
        lost.joints = None;
        assert!(needs_network(&RULE, Some(&a), Some(&lost), None));
    }
}
