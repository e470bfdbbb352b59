//! A tracked body part (its block, angle history, colour model and reliability) and what
//! every part does each frame: predicted from its motion, searched under its prior, moved,
//! learning its new appearance, or held when nothing can be matched. Used by the body tracker
//! (`body`) and the limb chains (`limb`).

use super::block::{MorphBlock, wrap_angle};
use super::params::Tuning;
use super::search::{Found, Prior};
use super::similarity::{Extent, FrameView, Template};
use crate::camera::point_in_frame;
use crate::skeleton::BodyPart;
use nalgebra::Point2;

/// A tracked body part: its block, its angle one frame earlier and its colour model.
#[derive(Debug, Clone)]
pub(super) struct Part {
    pub(super) block: MorphBlock,
    /// θ of the previous frame (for the angular velocity).
    pub(super) prev_theta: f64,
    /// The colour model.
    pub(super) template: Template,
    pub(super) reliability: f32,
    /// Longest plausible image length of the bone on the marked frame, pixels (proportions ×
    /// marked stature); it grows with the head's zoom (`BodyTracker::zoom`).
    pub(super) max_len: f64,
    /// How far along its bone the part is sampled.
    pub(super) extent: Extent,
    /// What the block pays per unit of ln(full length / length) when shorter than its full
    /// length: [`Tuning::short_penalty`] for the legs and upper arms, the forearms' own
    /// [`Tuning::forearm_short_penalty`], 0 for the head, trunk and hip patch.
    pub(super) short_penalty: f32,
}

/// A limb's longest plausible image length over its full length from the proportions (people
/// differ from the table, and marks are not exact).
pub(super) const LENGTH_SLACK: f64 = 1.2;

/// Whether a part is an upper arm or a forearm: the parts whose blocks weigh the foreground
/// lane ([`Tuning::arm_foreground`]).
pub(super) fn is_arm(part: BodyPart) -> bool {
    matches!(
        part,
        BodyPart::LeftUpperArm
            | BodyPart::RightUpperArm
            | BodyPart::LeftForearm
            | BodyPart::RightForearm
    )
}

/// The sampled extent of each part along its bone (see [`Extent`]): the head block reaches a
/// little above the calvaria, limb blocks past their far joint (into the forearm, the hand,
/// the shank, the foot).
pub(super) fn extent(part: BodyPart) -> Extent {
    let (start, end) = match part {
        BodyPart::Head => (0.0, 1.0),
        BodyPart::Trunk => (0.0, 1.1),
        BodyPart::LeftUpperArm | BodyPart::RightUpperArm => (0.0, 1.15),
        BodyPart::LeftForearm | BodyPart::RightForearm => (0.0, 1.3),
        BodyPart::LeftThigh | BodyPart::RightThigh => (0.0, 1.15),
        BodyPart::LeftShank | BodyPart::RightShank => (0.0, 1.2),
    };
    Extent { start, end }
}

/// A block's similarity cost mapped to a reliability in [0, 1]: `c0 / (c0 + cost)`.
pub(super) fn reliability(cost: f32, c0: f32) -> f32 {
    if cost.is_finite() {
        c0 / (c0 + cost.max(0.0))
    } else {
        0.0
    }
}

/// The predicted block of a part anchored at `anchor`. Without a parent (the trunk) its angle
/// advances by its own angular velocity; with one (`[θ now, θ one frame ago, θ two frames ago]`
/// of the parent) its angle relative to the parent advances by its relative angular velocity,
/// so a forearm follows its upper arm. Velocities are damped by `damping`; the length is kept.
pub(super) fn predict_anchored(
    part: &Part,
    anchor: Point2<f64>,
    parent: Option<[f64; 3]>,
    damping: f64,
) -> MorphBlock {
    let theta = match parent {
        None => part.block.theta + damping * wrap_angle(part.block.theta - part.prev_theta),
        Some([now, before, older]) => {
            let rel = wrap_angle(part.block.theta - before);
            let rel_prev = wrap_angle(part.prev_theta - older);
            now + rel + damping * wrap_angle(rel - rel_prev)
        }
    };
    MorphBlock {
        origin: anchor,
        theta,
        ..part.block
    }
}

/// The motion prior of an anchored part around its prediction; its length limits are the
/// marked ones times the head's `zoom`, and a block shorter than the part's full length pays
/// the part's `short_penalty` per unit of log ratio.
pub(super) fn prior(part: &Part, pred: &MorphBlock, p: &Tuning, zoom: f64) -> Prior {
    Prior {
        theta: pred.theta,
        m: pred.m,
        per_degree: p.angle_penalty,
        per_log_length: p.length_penalty,
        per_log_short: part.short_penalty,
        m_full: part.max_len * zoom / LENGTH_SLACK,
        m_min: 0.2 * part.max_len * zoom,
        m_max: part.max_len * zoom,
    }
}

/// Takes a search result: the block moves, the angle history shifts, the reliability is the
/// mapped similarity, and the adaptive colour model learns the new appearance when reliable.
pub(super) fn accept(part: &mut Part, found: Found, frame: FrameView, p: &Tuning) {
    move_to(part, found.block);
    learn(part, frame, p);
}

/// Moves a part to a block found in a new frame: the angle history shifts.
pub(super) fn move_to(part: &mut Part, block: MorphBlock) {
    part.prev_theta = part.block.theta;
    part.block = block;
}

/// The part learns from its block in the new frame: its reliability is the mapped similarity,
/// and the adaptive colour model learns the new appearance when reliable.
pub(super) fn learn(part: &mut Part, frame: FrameView, p: &Tuning) {
    // The reliability comes from the colours alone, without the prior's penalty or the
    // foreground lane.
    let cost = part.template.appearance_cost(frame, &part.block);
    part.reliability = reliability(cost, p.reliability_c0);
    if part.reliability >= p.weak_reliability {
        part.template.update(frame, &part.block, p.update_rate);
    }
}

/// Whether a point lies off the image.
pub(super) fn off_image(q: Point2<f64>, frame: FrameView) -> bool {
    // Frame sides come from u32 image sizes.
    !point_in_frame(&q, frame.width() as u32, frame.height() as u32)
}

/// Holds a part at its angle to its parent (no angular velocity, which would spin it) with
/// reliability 0: a joint off the image, or a match refused.
pub(super) fn hold(part: &mut Part, anchor: Point2<f64>, parent: [f64; 3]) {
    part.prev_theta = part.block.theta;
    part.block = predict_anchored(part, anchor, Some(parent), 0.0);
    part.reliability = 0.0;
}
