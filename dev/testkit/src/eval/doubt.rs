//! Whether the lift's doubts point at its mistakes: how often a depth choice it shows unsure
//! ([`BoneDepth::unsure`] at several margins) or a bone it flags too long is wrong, against how
//! often the others are; and the share of frames flagged.

use super::EvalError;
use super::pose3d::root_choice;
use crate::synth::GroundTruth;
use videomocap_core::formats::Skeleton3d;
use videomocap_core::lift::{BoneDepth, lift_order};
use videomocap_core::skeleton::{BONE_COUNT, Bone};

/// The margins tried for "unsure", nats (the product's is [`videomocap_core::lift::UNSURE_MARGIN`]).
pub const UNSURE_SWEEP: [f64; 5] = [0.5, 1.0, 2.0, videomocap_core::lift::UNSURE_MARGIN, 5.0];

/// Counts of depth choices that matter (their roots apart, not a coin flip), wrong or not, by
/// what the lift said of them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DoubtTally {
    /// Choices that matter.
    pub decided: usize,
    /// Of those, wrong.
    pub wrong: usize,
    /// Per margin of [`UNSURE_SWEEP`], choices shown unsure.
    pub unsure: [usize; 5],
    /// Of those, wrong.
    pub unsure_wrong: [usize; 5],
    /// Choices on bones flagged too long on their frame.
    pub flagged: usize,
    /// Of those, wrong.
    pub flagged_wrong: usize,
    /// Frames scored.
    pub frames: usize,
    /// Frames with any bone flagged too long.
    pub frames_flagged: usize,
}

impl DoubtTally {
    /// Adds another's counts.
    pub fn merge(&mut self, o: &DoubtTally) {
        self.decided += o.decided;
        self.wrong += o.wrong;
        for k in 0..UNSURE_SWEEP.len() {
            self.unsure[k] += o.unsure[k];
            self.unsure_wrong[k] += o.unsure_wrong[k];
        }
        self.flagged += o.flagged;
        self.flagged_wrong += o.flagged_wrong;
        self.frames += o.frames;
        self.frames_flagged += o.frames_flagged;
    }

    /// The share of frames with a bone flagged too long.
    pub fn frames_flagged_share(&self) -> f64 {
        self.frames_flagged as f64 / self.frames.max(1) as f64
    }

    /// At margin `k` of [`UNSURE_SWEEP`]: the share of choices shown unsure, how often an
    /// unsure one is wrong, how often a sure one is.
    pub fn unsure_rates(&self, k: usize) -> (f64, f64, f64) {
        let sure = self.decided - self.unsure[k];
        let sure_wrong = self.wrong - self.unsure_wrong[k];
        (
            self.unsure[k] as f64 / self.decided.max(1) as f64,
            self.unsure_wrong[k] as f64 / self.unsure[k].max(1) as f64,
            sure_wrong as f64 / sure.max(1) as f64,
        )
    }

    /// How often a flagged bone's choice is wrong, and an unflagged one's.
    pub fn flagged_rates(&self) -> (f64, f64) {
        (
            self.flagged_wrong as f64 / self.flagged.max(1) as f64,
            (self.wrong - self.flagged_wrong) as f64 / (self.decided - self.flagged).max(1) as f64,
        )
    }
}

/// Tallies the lift's final `skeleton` and its per-frame depth choices `bones` (in the
/// skeleton's frame order) against the reference.
pub fn tally_doubt(
    gt: &GroundTruth,
    skeleton: &Skeleton3d,
    bones: &[[BoneDepth; BONE_COUNT]],
) -> Result<DoubtTally, EvalError> {
    let derived = gt.derived();
    let mut s = DoubtTally::default();
    for (frame, depth) in skeleton.frames.iter().zip(bones) {
        let truth = gt
            .frames
            .get(frame.index.get())
            .ok_or(EvalError {
                gt: gt.frames.len(),
                frame: frame.index.get(),
            })?
            .points3d();
        s.frames += 1;
        let too_long = |b: Bone| frame.flags.contains(&format!("too_long:{}", b.key()));
        s.frames_flagged += usize::from(frame.flags.iter().any(|f| f.starts_with("too_long:")));
        for bone in Bone::ALL {
            let (known, solved) = lift_order(bone);
            if derived.contains(&known) || derived.contains(&solved) {
                continue;
            }
            let p = &frame.points;
            let Some(choice) = root_choice(p[known], p[solved], truth[solved] - truth[known])
            else {
                continue;
            };
            if choice.coin_flip {
                continue;
            }
            let d = depth[bone.index()];
            s.decided += 1;
            s.wrong += usize::from(choice.wrong);
            for (k, &m) in UNSURE_SWEEP.iter().enumerate() {
                let unsure = !d.single_root && d.margin < m;
                s.unsure[k] += usize::from(unsure);
                s.unsure_wrong[k] += usize::from(unsure && choice.wrong);
            }
            let flagged = too_long(bone);
            s.flagged += usize::from(flagged);
            s.flagged_wrong += usize::from(flagged && choice.wrong);
        }
    }
    Ok(s)
}
