//! What the lift reports beside the skeleton: per frame, what it noticed (flags: a bone longer
//! in the image than it can be, beyond the tracks' noise and the lengths' doubt; a joint off the
//! frame or lost; a key triangle that did not fit), and per bone how sure its depth choice was.

use super::backproject::Root;
use super::job::LiftJob;
use super::smoothing::median_noise_px;
use crate::camera::PinholeCamera;
use crate::formats::FrameIndex;
use crate::skeleton::{BONE_COUNT, Bone, Joint, PerJoint};
use nalgebra::{Point2, Point3};
use std::fmt;

/// Something worth knowing about one frame of the result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFlag {
    /// No pose of the key triangle fits the frame's three points; the closest fit is kept.
    KeyTriangleNotConverged,
    /// The bone's 2D image is longer than its 3D length allows: the joint is off its ray.
    TooLong(Bone),
    /// The joint's 2D track was off the frame: its 3D position rests on the tracker's estimate.
    OffFrame(Joint),
    /// The joint's 2D track was lost (a weak run too long to fill): it rests on a guess.
    Lost(Joint),
    /// The pose network saw no body on this frame while it did on others: the depth choices
    /// here rest on the geometry alone.
    NoImageDepth,
    /// The pose learned from motion capture ([`super::PosePrior`]) finds this frame's pose
    /// unusual: its summed cost is beyond what 999 in 1000 learned poses reach.
    UnusualPose,
}

impl fmt::Display for FrameFlag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameFlag::KeyTriangleNotConverged => f.write_str("key_triangle_not_converged"),
            FrameFlag::TooLong(b) => write!(f, "too_long:{}", b.key()),
            FrameFlag::OffFrame(j) => write!(f, "{}{}", crate::formats::OFF_FRAME_FLAG, j.name()),
            FrameFlag::Lost(j) => write!(f, "{}{}", crate::formats::LOST_FLAG, j.name()),
            FrameFlag::NoImageDepth => f.write_str(crate::formats::NO_IMAGE_DEPTH_FLAG),
            FrameFlag::UnusualPose => f.write_str(crate::formats::UNUSUAL_POSE_FLAG),
        }
    }
}

/// The per-frame report.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameReport {
    /// Video frame number.
    pub index: FrameIndex,
    /// RMS residual of eq. 11 for the key triangle, metres.
    pub key_rms_m: f64,
    /// Flags.
    pub flags: Vec<FrameFlag>,
}

/// The margin under which a bone's depth choice is shown unsure ([`BoneDepth::unsure`]), nats:
/// the pose prior's log-likelihood ratio of its two roots below ln 19, i.e. with both roots
/// alike beforehand, the other root keeps at least a 5 % chance (derived, not tuned: the
/// usual 95 %). Measured in `docs/method.md` (issue 94, "Unsure from the prior").
pub const UNSURE_MARGIN: f64 = 2.944_438_979_166_44;

/// One bone's depth choice on one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoneDepth {
    /// The root taken.
    pub root: Root,
    /// The bone's two roots were one point (its 2D image too long for its length): flipping
    /// it there changes nothing.
    pub single_root: bool,
    /// How sure the root is, nats: the pose prior's log-likelihood ratio of the chosen root
    /// against the other (without the prior, the clip-wide cost of taking the other root, at
    /// the prior's exchange rate); infinite where the user forced the root.
    pub margin: f64,
}

impl BoneDepth {
    /// Whether the choice was close: the other root explains the clip almost as well, so the
    /// bone is worth a look (a single root has nothing to choose).
    pub fn unsure(&self) -> bool {
        !self.single_root && self.margin < UNSURE_MARGIN
    }
}

/// How many times the tracks' own white noise a bone's child must miss its image point before
/// the bone is flagged too long ([`too_long_beyond_noise`]).
pub(super) const TOO_LONG_NOISE_TIMES: f64 = 3.0;

/// The share of a bone's own image length its child may miss its image point by before the bone
/// is flagged too long: the lengths read from the clip are uncertain by a few per cent (the
/// median bone within 2–5 % on the benchmark), so a bone a little short of its image says
/// nothing about the tracks.
pub(super) const TOO_LONG_LENGTH_SHARE: f64 = 0.05;

/// Whether a bone whose image is longer than its length allows misses by more than the 2D
/// noise and the length's own uncertainty explain: its child's image point lies farther from
/// where the placed child projects than [`TOO_LONG_NOISE_TIMES`] the tracks' noise (`noise_px`)
/// plus [`TOO_LONG_LENGTH_SHARE`] and the lengths' doubt of the bone's image length as read,
/// and half a pixel. `length` is the length solved with, the doubt to allow (a share of it:
/// its own and its ancestors'), its own doubt, and whether it was solved that much shorter than
/// read (a bone of doubtful length leans square to its ray, so it misses by that share wherever
/// it lies square to the camera). Only such a bone is flagged,
/// so the flag points at a tracking slip or a wrong length, not at the frames where a bone
/// lies square to the camera.
pub(crate) fn too_long_beyond_noise(
    cam: &PinholeCamera,
    points: &PerJoint<Point3<f64>>,
    image: &PerJoint<Point2<f64>>,
    bone: Bone,
    (length_m, doubt, own_doubt, shortened): (f64, f64, f64, bool),
    noise_px: f64,
) -> bool {
    let Some(placed) = cam.project(&points[bone.child]) else {
        return true;
    };
    let miss_px = (placed - image[bone.child]).norm();
    let depth = points[bone.parent].z.max(1e-6);
    let read_m = if shortened {
        length_m / (1.0 - own_doubt).max(1e-6)
    } else {
        length_m
    };
    let length_px = cam.focal_px * read_m / depth;
    miss_px > TOO_LONG_NOISE_TIMES * noise_px + (TOO_LONG_LENGTH_SHARE + doubt) * length_px + 0.5
}

/// A solved clip against its images: joints per frame, the 2D points they were solved from, and
/// the bone lengths solved with.
pub(super) type Solved<'a> = (
    &'a [PerJoint<Point3<f64>>],
    &'a [PerJoint<Point2<f64>>],
    &'a [f64; BONE_COUNT],
);

/// Flags, on each frame of `reports`, the bones of the solved `points` (with bone `lengths`)
/// whose child misses its `images` point beyond noise and doubt ([`too_long_beyond_noise`]),
/// replacing any earlier such flags.
pub(super) fn flag_too_long(
    job: &LiftJob<'_>,
    reports: &mut [FrameReport],
    (points, images, lengths): Solved<'_>,
    doubt: &[f64; BONE_COUNT],
    shortened: bool,
) {
    let noise_px = median_noise_px(job.tracks, &Joint::ALL);
    // A bone's doubt with its ancestors': a parent of doubtful length is itself placed off by
    // up to that much, and the child's bone must bridge it. As a share of the bone's length.
    let read = |b: usize| {
        if shortened {
            lengths[b] / (1.0 - doubt[b]).max(1e-6)
        } else {
            lengths[b]
        }
    };
    let chain: [f64; BONE_COUNT] = std::array::from_fn(|b| {
        let mut metres = 0.0;
        let mut joint = Bone::ALL[b].parent;
        while let Some(up) = Bone::to(joint) {
            metres += doubt[up.index()] * read(up.index());
            joint = up.parent;
        }
        doubt[b] + metres / read(b).max(1e-6)
    });
    for (t, report) in reports.iter_mut().enumerate() {
        report.flags.retain(|f| !matches!(f, FrameFlag::TooLong(_)));
        for (b, bone) in Bone::ALL.iter().enumerate() {
            let length = (lengths[b], chain[b], doubt[b], shortened);
            if too_long_beyond_noise(&job.camera, &points[t], &images[t], *bone, length, noise_px) {
                report.flags.push(FrameFlag::TooLong(*bone));
            }
        }
    }
}
