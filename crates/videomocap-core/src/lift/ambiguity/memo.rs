//! The pose prior's costs of each frame's candidates, kept between the whole-clip solves of one
//! lift: the calibration poses and the facing's trials solve the clip again and again, and on
//! most frames a group's candidates hang from the same joints as before, so their prior (and
//! the spine's look ahead, 36 mixtures per candidate) is read back rather than evaluated again.
//! A group's candidates are a function of the joints they hang from and of the frame's rays
//! and the subject, fixed for one lift; the prior reads the key triangle's frame too. So the
//! costs are kept under the frame, the group and the positions of exactly those joints.

use super::super::prior::{PriorGroup, Side};
use super::GROUP_COUNT;
use crate::skeleton::Joint::{self, *};
use crate::skeleton::PerJoint;
use nalgebra::Point3;
use std::cell::RefCell;

/// The most joints a group's prior reads besides its own: the key triangle and three more.
const MAX_INPUTS: usize = 5;

/// Entries kept per frame and group (the oldest goes first): the calibration poses times the
/// facings a frame takes in one lift, a handful.
const KEPT: usize = 8;

/// One group's prior costs on one frame for one placement of the joints it hangs from.
#[derive(Clone)]
struct Entry {
    /// The joints' coordinates the group's candidates hang from ([`inputs`]).
    inputs: [f64; 3 * MAX_INPUTS],
    /// Per candidate (combination of roots): its prior cost (nats) and the spine's look ahead
    /// (nats; 0 for the other groups).
    costs: [(f64, f64); 4],
}

/// The prior's costs of every frame's candidates, per group, from the solves of one lift
/// ([`super::resolve_with`]); one lift's rays and subject only.
pub(crate) struct PriorMemo {
    entries: RefCell<Vec<Vec<Entry>>>,
}

impl PriorMemo {
    /// An empty memo for a clip of `frames` frames.
    pub(crate) fn new(frames: usize) -> PriorMemo {
        PriorMemo {
            entries: RefCell::new(vec![Vec::new(); frames * GROUP_COUNT]),
        }
    }

    /// Group `g`'s candidates' costs on frame `t` whose joints stand at `p` (before the group
    /// is placed): kept ones if the joints the prior reads are where they were, else
    /// `compute`'s, kept.
    pub(crate) fn costs(
        &self,
        t: usize,
        g: usize,
        group: PriorGroup,
        p: &PerJoint<Point3<f64>>,
        compute: impl FnOnce() -> [(f64, f64); 4],
    ) -> [(f64, f64); 4] {
        let mut inputs = [0.0; 3 * MAX_INPUTS];
        for (k, &j) in [LeftShoulder, RightShoulder, Chest]
            .iter()
            .chain(extra_inputs(group))
            .enumerate()
        {
            inputs[3 * k..3 * k + 3].copy_from_slice(p[j].coords.as_slice());
        }
        let slot = t * GROUP_COUNT + g;
        if let Some(e) = self.entries.borrow().get(slot).and_then(|kept| {
            kept.iter().find(|e| {
                e.inputs
                    .iter()
                    .zip(&inputs)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            })
        }) {
            return e.costs;
        }
        let costs = compute();
        if let Some(kept) = self.entries.borrow_mut().get_mut(slot) {
            if kept.len() >= KEPT {
                kept.remove(0);
            }
            kept.push(Entry { inputs, costs });
        }
        costs
    }
}

/// The joints besides the key triangle a group's candidates and their prior depend on: the
/// joint the group hangs from (the key triangle's chest for the head and the spine), the
/// other hip for a leg (the pelvis's frame), an arm's own hip and knee (its thigh).
fn extra_inputs(group: PriorGroup) -> &'static [Joint] {
    match group {
        PriorGroup::Head | PriorGroup::Spine => &[],
        PriorGroup::Hips => &[Pelvis],
        PriorGroup::Leg(_) => &[LeftHip, RightHip],
        PriorGroup::Arm(Side::Left) => &[LeftHip, LeftKnee],
        PriorGroup::Arm(Side::Right) => &[RightHip, RightKnee],
    }
}
