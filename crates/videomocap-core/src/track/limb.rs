//! One limb chain per frame (Pan et al., "Limb"): the upper block anchored at its root joint,
//! the lower at the found middle joint, each searched around its motion prediction, widened for
//! fast limbs, held off the image or when folded back; then the chain refined as one figure.

use super::block::{MorphBlock, wrap_angle};
use super::params::Tuning;
use super::part::{Part, hold, learn, move_to, off_image, predict_anchored, prior, reliability};
use super::search::{AngularParams, ChainRoot, ChainSegment, Prior, angular, refine_chain};
use super::similarity::FrameView;
use nalgebra::Point2;

/// First step of a limb chain's joint refinement, tracker pixels (see [`refine_chain`]).
pub(super) const CHAIN_STEP_PX: f64 = 1.0;
/// Steps of a limb chain's joint refinement: 1, ½ and ¼ px. Measured on the suite and the real
/// sample: a first step of 0.5 or 2 px, or four levels, did no better.
pub(super) const CHAIN_LEVELS: usize = 3;

/// A limb segment's search around its prediction: `limb_range_deg` in coarse steps, the length
/// within `limb_range_m`.
pub(super) fn limb_search(p: &Tuning) -> AngularParams {
    AngularParams {
        range_theta: p.limb_range_deg.to_radians(),
        step_theta: p.coarse_step_deg.to_radians(),
        range_m: p.limb_range_m,
        m_count: 5,
        scale_width: false,
    }
}

/// `search` widened for fast limbs: `wide_range_deg` in steps twice the coarse step.
pub(super) fn widened(search: AngularParams, p: &Tuning) -> AngularParams {
    AngularParams {
        range_theta: p.wide_range_deg.to_radians(),
        step_theta: 2.0 * p.coarse_step_deg.to_radians(),
        ..search
    }
}

/// One limb chain: the upper block anchored at the root, the lower at the found middle joint.
/// A weak result from the narrow search around the prediction is searched again over the wide
/// range (fast limbs), unless the prediction has left the image: then the part is held at its
/// angle to its parent, reliability 0, until its prediction comes back. An arm whose forearm
/// When both segments moved, the chain is refined as one figure ([`refine_chain`], `chain_refine`) before either learns
/// its new appearance. Returns the root joint, moved when it has a spring.
pub(super) fn track_limb(
    parts: &mut [Part; 2],
    root: ChainRoot,
    trunk_angles: [f64; 3],
    frame: FrameView,
    p: &Tuning,
    zoom: f64,
) -> Point2<f64> {
    let mut parent = trunk_angles;
    let mut anchor = root.at;
    // The segments moved this frame (not held), with their priors; they learn their new
    // appearance once the chain is settled.
    let mut moved: [Option<Prior>; 2] = [None, None];
    for (k, part) in parts.iter_mut().enumerate() {
        let before = (part.block.theta, part.prev_theta);
        let pred = predict_anchored(part, anchor, Some(parent), p.velocity_damping);
        let narrow = limb_search(p);
        let prior = prior(part, &pred, p, zoom);
        let predicted_off = off_image(pred.end(), frame);
        let narrow = if off_image(pred.to_image(part.extent.end, 0.0), frame) {
            // The far end of the sampled part is cut off by the image's edge, so its length
            // cannot be seen: search the angle only.
            AngularParams {
                range_m: 0.0,
                m_count: 1,
                ..narrow
            }
        } else {
            narrow
        };
        // Beyond the paper: a forearm or shank never folds back onto its upper segment (elbows
        // and knees flex to about 150°; seen from the side, the image angle is the true one).
        // A lower segment found folded further than `fold_limit_deg` is a lock on the wrong
        // thing (the other leg, the floor); it is held like a joint off the image.
        let folded = |b: &MorphBlock| k == 1 && folded_back(parent[0], b.theta, p);
        let mut found = angular(&part.template, frame, &pred, &narrow, &prior);
        let weak = reliability(found.cost, p.reliability_c0) < p.weak_reliability;
        if weak && predicted_off {
            // The joint left the frame: nothing to match until its prediction is back.
            hold(part, anchor, parent);
        } else {
            if weak || folded(&found.block) {
                let wide = widened(narrow, p);
                let again = angular(&part.template, frame, &pred, &wide, &prior);
                if again.cost < found.cost && !folded(&again.block) || folded(&found.block) {
                    found = again;
                }
            }
            if folded(&found.block) {
                hold(part, anchor, parent);
            } else {
                move_to(part, found.block);
                moved[k] = Some(prior);
            }
        }
        parent = [part.block.theta, before.0, before.1];
        anchor = part.block.end();
    }
    if let [Some(upper), Some(lower)] = &moved
        && p.chain_refine
    {
        let ([u, l], _) = refine_chain(
            frame,
            root,
            [
                ChainSegment {
                    template: &parts[0].template,
                    n: parts[0].block.n,
                    prior: upper,
                },
                ChainSegment {
                    template: &parts[1].template,
                    n: parts[1].block.n,
                    prior: lower,
                },
            ],
            [parts[0].block.end(), parts[1].block.end()],
            CHAIN_STEP_PX,
            CHAIN_LEVELS,
            |u, l| !folded_back(u.theta, l.theta, p),
        );
        parts[0].block = u;
        parts[1].block = l;
    }
    for (part, moved) in parts.iter_mut().zip(moved) {
        if moved.is_some() {
            learn(part, frame, p);
        }
    }
    // The upper segment hangs from the root: where the chain refinement moved it, or where it
    // was (a found or held upper segment keeps its anchor).
    parts[0].block.origin
}

/// Whether a lower segment at image angle `lower` is folded back onto its upper segment at
/// `upper` further than `fold_limit_deg` (elbows and knees flex to about 150°).
pub(super) fn folded_back(upper: f64, lower: f64, p: &Tuning) -> bool {
    wrap_angle(lower - upper).abs() > p.fold_limit_deg.to_radians()
}

/// The spring that ties chain `chain`'s root to the rigid trunk in its joint refinement: the
/// shoulders' (`shoulder_spring`, when above 0); the hips stay on the trunk (letting them move
/// measured worse on the side views, where the far leg pulls its hip onto the near one).
pub(super) fn shoulder_spring(chain: usize, p: &Tuning) -> Option<f32> {
    (chain < 2 && p.shoulder_spring > 0.0).then_some(p.shoulder_spring)
}
