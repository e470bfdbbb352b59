//! The top-down body tracker (Pan et al., "Trunk and Limb"): head first (image-difference
//! prediction + spiral search), then the trunk anchored at the tracked neck, then each limb
//! chain shoulder→elbow→wrist and hip→knee→ankle, every child block anchored at its tracked
//! parent joint and its search centred on a motion prediction (the bone's angular velocity
//! relative to its parent). The four limb chains are independent and run in parallel. Beyond
//! the paper, a patch around the hips holds the pelvis when the spine bends
//! (`BodyTracker::hips_hold`), and the bones' length limits follow the head's zoom.
//!
//! Works in one image scale (the caller converts to and from video pixels).

use super::background::Background;
use super::block::MorphBlock;
use super::head::HeadPredictor;
use super::limb::{shoulder_spring, track_limb};
use super::params::Tuning;
use super::part::{LENGTH_SLACK, Part, accept, extent, is_arm, predict_anchored, prior};
use super::search::{AngularParams, ChainRoot, Found, SpiralParams, angular, spiral};
use super::similarity::{Extent, FloatFrame, FrameView, Template};
use crate::skeleton::{BodyPart, Joint, PerJoint, Proportions};
use image::RgbImage;
use nalgebra::Point2;
use rayon::prelude::*;
use std::sync::Arc;

/// The four limb chains: root joint, middle joint, end joint.
pub(super) const CHAINS: [[Joint; 3]; 4] = [
    [Joint::LeftShoulder, Joint::LeftElbow, Joint::LeftWrist],
    [Joint::RightShoulder, Joint::RightElbow, Joint::RightWrist],
    [Joint::LeftHip, Joint::LeftKnee, Joint::LeftAnkle],
    [Joint::RightHip, Joint::RightKnee, Joint::RightAnkle],
];

/// Joints carried rigidly by the trunk block (in its block coordinates).
const TRUNK_JOINTS: [Joint; 5] = [
    Joint::Chest,
    Joint::LeftShoulder,
    Joint::RightShoulder,
    Joint::LeftHip,
    Joint::RightHip,
];

/// Per chain of [`CHAINS`]: where its root joint is in [`TRUNK_JOINTS`].
const CHAIN_ROOTS: [usize; 4] = [1, 2, 3, 4];

/// One joint's result in one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct JointResult {
    /// Position, pixels (tracker scale).
    pub pos: Point2<f64>,
    /// Reliability in [0, 1]: the block's similarity mapped by `c0 / (c0 + cost)`.
    pub reliability: f32,
}

/// Block widths in pixels, from the proportions scaled to the marked body.
fn widths(
    pose: &PerJoint<Point2<f64>>,
    proportions: &Proportions,
    scale: f64,
) -> impl Fn(BodyPart) -> f64 {
    let stature = stature_px(pose, proportions);
    let shoulders = (pose[Joint::LeftShoulder] - pose[Joint::RightShoulder]).norm();
    let hips = (pose[Joint::LeftHip] - pose[Joint::RightHip]).norm();
    let p = proportions.clone();
    move |part| {
        let w = p.breadth_fraction(part.breadth()) * stature;
        if part == BodyPart::Trunk {
            // wide enough to carry the shoulders and hips
            w.max(shoulders).max(hips)
        } else {
            (w * scale).max(3.0)
        }
    }
}

/// The subject's stature in pixels estimated from marked bones: the longest of the trunk chain
/// and each limb divided by its fraction of the stature (foreshortening only shortens, so the
/// longest estimate is the least foreshortened).
pub fn stature_px(pose: &PerJoint<Point2<f64>>, proportions: &Proportions) -> f64 {
    let chains: [&[Joint]; 5] = [
        &[Joint::HeadTop, Joint::Neck, Joint::Chest, Joint::Pelvis],
        &CHAINS[0],
        &CHAINS[1],
        &CHAINS[2],
        &CHAINS[3],
    ];
    let mut best = 0.0f64;
    for chain in chains {
        let (mut px, mut frac) = (0.0, 0.0);
        for w in chain.windows(2) {
            px += (pose[w[1]] - pose[w[0]]).norm();
            frac += proportions.fraction_between(w[0], w[1]);
        }
        if frac > 0.0 {
            best = best.max(px / frac);
        }
    }
    best.max(20.0)
}

/// Tracks the body frame by frame.
#[derive(Debug, Clone)]
pub(super) struct BodyTracker {
    params: Tuning,
    head: Part,
    trunk: Part,
    /// Per chain: the upper and lower part.
    limbs: [[Part; 2]; 4],
    /// The hip patch: a block centred on the pelvis (see `BodyTracker::hips_hold`).
    hips: Part,
    /// Chest, shoulders and hips in the trunk block's (u, v) coordinates.
    trunk_points: [(f64, f64); 5],
    /// Per chain: its root joint's shift from where the rigid trunk puts it, in the trunk
    /// block's (u, v) units (a shoulder rising with its arm).
    root_shift: [(f64, f64); 4],
    predictor: HeadPredictor,
    /// The head block's length on the marked frame, pixels.
    marked_head_m: f64,
    /// The static camera's background, when there is one: the fourth lane of every frame.
    background: Option<Arc<Background>>,
    /// The head's zoom since the marking (never below 1): every length limit is multiplied by
    /// it.
    zoom: f64,
    /// The head's displacement over the last frame, pixels.
    head_velocity: nalgebra::Vector2<f64>,
    /// The last frame, converted for sampling.
    prev: FloatFrame,
    /// A spare buffer the next frame is converted into (reused: no allocation per frame).
    spare: FloatFrame,
}

impl BodyTracker {
    /// Starts from a pose on `image` (a key frame): blocks from the pose, widths from the
    /// proportions scaled to it, colour models sampled from the image.
    pub(super) fn new(
        image: &RgbImage,
        pose: &PerJoint<Point2<f64>>,
        proportions: &Proportions,
        params: Tuning,
        background: Option<Arc<Background>>,
    ) -> BodyTracker {
        let mut floats = FloatFrame::default();
        floats.fill_with(image, background.as_deref());
        let width = widths(pose, proportions, params.block_width_scale);
        let start = PartStart {
            frame: floats.view(),
            width: &width,
            stature: stature_px(pose, proportions),
            proportions,
            params: &params,
        };
        // The head block runs from the calvaria down to the neck (its anchor is head_top).
        let head = start.part(pose[Joint::HeadTop], pose[Joint::Neck], BodyPart::Head);
        let trunk = start.part(pose[Joint::Neck], pose[Joint::Pelvis], BodyPart::Trunk);
        let trunk_block = trunk.block;
        let limb_parts = [
            [BodyPart::LeftUpperArm, BodyPart::LeftForearm],
            [BodyPart::RightUpperArm, BodyPart::RightForearm],
            [BodyPart::LeftThigh, BodyPart::LeftShank],
            [BodyPart::RightThigh, BodyPart::RightShank],
        ];
        let limbs = std::array::from_fn(|c| {
            let [a, b, e] = CHAINS[c];
            [
                start.part(pose[a], pose[b], limb_parts[c][0]),
                start.part(pose[b], pose[e], limb_parts[c][1]),
            ]
        });
        let hips = start.hips(&trunk_block);
        BodyTracker {
            params,
            marked_head_m: head.block.m,
            head,
            trunk,
            hips,
            limbs,
            trunk_points: TRUNK_JOINTS.map(|j| trunk_block.to_block(pose[j])),
            root_shift: [(0.0, 0.0); 4],
            predictor: HeadPredictor::default(),
            background,
            zoom: 1.0,
            head_velocity: nalgebra::Vector2::zeros(),
            prev: floats,
            spare: FloatFrame::default(),
        }
    }

    /// Re-starts on a key frame from `pose`, as [`BodyTracker::new`], except that every part
    /// none of whose two joints the key `placed` goes on as it was (its block, colour models
    /// and reliability; its length limit carried over to the re-started head's zoom): a
    /// correction of one joint re-learns no other part at a place the user did not confirm
    /// (issue 90). With every joint placed it is `new`.
    pub(crate) fn restart(
        &mut self,
        image: &RgbImage,
        pose: &PerJoint<Point2<f64>>,
        placed: &PerJoint<bool>,
        proportions: &Proportions,
    ) {
        let fresh = BodyTracker::new(
            image,
            pose,
            proportions,
            self.params,
            self.background.clone(),
        );
        let old = std::mem::replace(self, fresh);
        let keep = |new: &mut Part, old_part: &Part, (a, b): (Joint, Joint)| {
            if !placed[a] && !placed[b] {
                *new = old_part.clone();
                new.max_len *= old.zoom;
            }
        };
        keep(&mut self.head, &old.head, BodyPart::Head.ends());
        keep(&mut self.trunk, &old.trunk, BodyPart::Trunk.ends());
        keep(&mut self.hips, &old.hips, (Joint::Pelvis, Joint::Pelvis));
        for (c, [a, b, e]) in CHAINS.iter().enumerate() {
            let [upper, lower] = &mut self.limbs[c];
            keep(upper, &old.limbs[c][0], (*a, *b));
            keep(lower, &old.limbs[c][1], (*b, *e));
        }
        // The shoulders and hips where `pose` has them, on the trunk block kept or made.
        self.trunk_points = TRUNK_JOINTS.map(|j| self.trunk.block.to_block(pose[j]));
    }

    /// This tracker without its frame buffers, for a re-track ([`BodyTracker::resumed`]).
    pub(super) fn checkpoint(&mut self) -> BodyTracker {
        let frames = (
            std::mem::take(&mut self.prev),
            std::mem::take(&mut self.spare),
        );
        let copy = self.clone();
        (self.prev, self.spare) = frames;
        copy
    }

    /// A checkpoint tracking again from `image`, the frame it last saw (`step`'s conversion).
    pub(super) fn resumed(mut self, image: &RgbImage) -> BodyTracker {
        self.prev.fill_with(image, self.background.as_deref());
        self
    }

    /// The current pose (after the last step, or the starting pose).
    pub(super) fn pose(&self) -> PerJoint<JointResult> {
        let mut out = PerJoint::from_fn(|_| JointResult {
            pos: Point2::origin(),
            reliability: 0.0,
        });
        let set = |out: &mut PerJoint<JointResult>, j: Joint, pos: Point2<f64>, r: f32| {
            out[j] = JointResult {
                pos,
                reliability: r,
            }
        };
        set(
            &mut out,
            Joint::HeadTop,
            self.head.block.origin,
            self.head.reliability,
        );
        set(
            &mut out,
            Joint::Neck,
            self.head.block.end(),
            self.head.reliability,
        );
        set(
            &mut out,
            Joint::Pelvis,
            self.trunk.block.end(),
            self.trunk.reliability,
        );
        for (k, j) in TRUNK_JOINTS.iter().enumerate() {
            let (u, v) = self.trunk_point(k);
            set(
                &mut out,
                *j,
                self.trunk.block.to_image(u, v),
                self.trunk.reliability,
            );
        }
        for (c, chain) in CHAINS.iter().enumerate() {
            let [upper, lower] = &self.limbs[c];
            set(&mut out, chain[1], upper.block.end(), upper.reliability);
            set(&mut out, chain[2], lower.block.end(), lower.reliability);
        }
        out
    }

    /// Trunk point `k` of [`TRUNK_JOINTS`] in the trunk block's (u, v), with its chain's root
    /// shift.
    fn trunk_point(&self, k: usize) -> (f64, f64) {
        let (u, v) = self.trunk_points[k];
        match CHAIN_ROOTS.iter().position(|&r| r == k) {
            Some(c) => (u + self.root_shift[c].0, v + self.root_shift[c].1),
            None => (u, v),
        }
    }

    /// Tracks the body into the next frame and returns its pose: the head, the trunk hung
    /// from its neck, then the four limb chains from the trunk.
    pub(super) fn step(&mut self, image: &RgbImage) -> PerJoint<JointResult> {
        // Both frames are taken out of `self` while the parts are updated, and put back at the
        // end with their roles swapped.
        let mut floats = std::mem::take(&mut self.spare);
        floats.fill_with(image, self.background.as_deref());
        let previous = std::mem::take(&mut self.prev);
        let (frame, prev) = (floats.view(), previous.view());

        let hips_found = self.step_head(prev, frame);
        // Beyond the paper: a person walking towards the camera grows in the image. The head
        // block zooms with them (the spiral searches its length), so every bone's length limit
        // grows by the head's zoom since the marking; without this the trunk and limbs stop at
        // their marked-size limits and the hips and feet are left behind.
        self.zoom = (self.head.block.m / self.marked_head_m.max(1e-9)).max(1.0);
        let trunk_before = self.step_trunk(frame, hips_found);
        self.step_limbs(frame, trunk_before);

        self.spare = previous;
        self.prev = floats;
        self.pose()
    }

    /// The head: image-difference prediction (eqs. 1–5), then the spiral search path
    /// (Fig. 6). Beyond the paper, the spiral also starts from the constant-velocity
    /// prediction and from the unmoved head, and the best of the three ends wins: the
    /// difference image is fooled when arms move inside Ω, and the spiral stops at the first
    /// ring without improvement, so one wrong start would lose the head. Returns the hip
    /// patch's spiral, run beside the head's (it starts where the patch was, not from the
    /// head).
    fn step_head(&mut self, prev: FrameView, frame: FrameView) -> Option<Found> {
        let p = self.params;
        let motion =
            self.predictor
                .predict(prev, frame, self.head.block.origin, self.head.block.end());
        let spiral_params = SpiralParams {
            step_px: p.head_step_px,
            d_theta: p.head_d_theta_deg.to_radians(),
            d_m: p.head_d_m,
            max_rings: p.head_max_rings,
            m_bounds: (0.0, f64::INFINITY),
        };
        let starts = self.head_starts(motion.displacement);
        let head_template = &self.head.template;
        let search_head = || -> Vec<Found> {
            let one = |b: &MorphBlock| spiral(head_template, frame, b, &spiral_params);
            if p.parallel {
                starts.par_iter().map(one).collect()
            } else {
                starts.iter().map(one).collect()
            }
        };
        let search_hips = || p.hip_patch.then(|| self.hips_spiral(frame, &p));
        let (ends, hips_found) = if p.parallel {
            rayon::join(search_head, search_hips)
        } else {
            (search_head(), search_hips())
        };
        // The best end wins; on a tie the earlier start.
        let found = ends
            .into_iter()
            .reduce(|best, f| if f.cost < best.cost { f } else { best })
            .unwrap_or(Found {
                block: self.head.block,
                cost: f32::INFINITY,
            });
        let moved = found.block.origin - self.head.block.origin;
        self.predictor.adapt(motion.displacement, moved);
        self.head_velocity = moved;
        accept(&mut self.head, found, frame, &p);
        hips_found
    }

    /// The head spiral's starting blocks: moved by the image-difference prediction
    /// `predicted`, by the damped constant velocity and not at all, less any within a step of
    /// an earlier one.
    fn head_starts(&self, predicted: nalgebra::Vector2<f64>) -> Vec<MorphBlock> {
        let p = &self.params;
        let starts = [
            predicted,
            self.head_velocity * p.velocity_damping,
            nalgebra::Vector2::zeros(),
        ];
        starts
            .iter()
            .enumerate()
            .filter(|&(k, d)| !starts[..k].iter().any(|e| (e - d).norm() < p.head_step_px))
            .map(|(_, d)| MorphBlock {
                origin: self.head.block.origin + d,
                ..self.head.block
            })
            .collect()
    }

    /// The trunk, anchored at the neck, then the hips held by their patch (`hips_found`, when
    /// the patch is on). Its width stays as marked (times the zoom): letting it narrow as a
    /// body turns side-on was tried and not kept (docs/method.md, Tracking, "The trunk's width").
    /// Returns the trunk's angle and previous angle before this frame.
    fn step_trunk(&mut self, frame: FrameView, hips_found: Option<Found>) -> (f64, f64) {
        let p = self.params;
        let neck = self.head.block.end();
        let trunk_before = (self.trunk.block.theta, self.trunk.prev_theta);
        let trunk_pred = predict_anchored(&self.trunk, neck, None, p.velocity_damping);
        let found = angular(
            &self.trunk.template,
            frame,
            &trunk_pred,
            &AngularParams {
                range_theta: p.trunk_range_deg.to_radians(),
                step_theta: p.coarse_step_deg.to_radians(),
                range_m: p.trunk_range_m,
                m_count: 5,
                scale_width: false,
            },
            &prior(&self.trunk, &trunk_pred, &p, self.zoom),
        );
        accept(&mut self.trunk, found, frame, &p);
        if let Some(hips_found) = hips_found {
            self.hips_hold(frame, neck, hips_found, &p);
        }
        trunk_before
    }

    /// The four limb chains, each from its root joint on the trunk, in parallel;
    /// `trunk_before` is the trunk's angle and previous angle before this frame. A shoulder's
    /// spring leaves its root shifted from the rigid trunk's place, kept for the next frame.
    fn step_limbs(&mut self, frame: FrameView, trunk_before: (f64, f64)) {
        let p = self.params;
        let zoom = self.zoom;
        let pose_now = self.pose();
        let trunk_angles = [self.trunk.block.theta, trunk_before.0, trunk_before.1];
        let roots = CHAINS.map(|c| pose_now[c[0]].pos);
        let rigid = CHAIN_ROOTS.map(|k| {
            let (u, v) = self.trunk_points[k];
            self.trunk.block.to_image(u, v)
        });
        let chain_root = |k: usize| ChainRoot {
            at: roots[k],
            spring: shoulder_spring(k, &p).map(|s| (rigid[k], s)),
        };
        let track_chain = |parts: &mut [Part; 2], k: usize| {
            track_limb(parts, chain_root(k), trunk_angles, frame, &p, zoom)
        };
        let [a, b, c, d] = &mut self.limbs;
        let new_roots = if p.parallel {
            let ((ra, rb), (rc, rd)) = rayon::join(
                || rayon::join(|| track_chain(a, 0), || track_chain(b, 1)),
                || rayon::join(|| track_chain(c, 2), || track_chain(d, 3)),
            );
            [ra, rb, rc, rd]
        } else {
            [
                track_chain(a, 0),
                track_chain(b, 1),
                track_chain(c, 2),
                track_chain(d, 3),
            ]
        };
        for (c, r) in new_roots.iter().enumerate() {
            if shoulder_spring(c, &p).is_some() {
                let (u, v) = self.trunk.block.to_block(*r);
                let (u0, v0) = self.trunk_points[CHAIN_ROOTS[c]];
                self.root_shift[c] = (u - u0, v - v0);
            }
        }
    }
}

/// What a part started on a key frame is made from: the key frame, the parts' widths, the
/// subject's stature in pixels and proportions, and the tuning.
struct PartStart<'a> {
    frame: FrameView<'a>,
    width: &'a dyn Fn(BodyPart) -> f64,
    stature: f64,
    proportions: &'a Proportions,
    params: &'a Tuning,
}

impl PartStart<'_> {
    /// The body part `kind` as a block from `from` to `to`, its colour model sampled from the
    /// key frame and its length limit from the proportions.
    fn part(&self, from: Point2<f64>, to: Point2<f64>, kind: BodyPart) -> Part {
        let block = MorphBlock::along(from, to, (self.width)(kind));
        let (a, b) = kind.ends();
        let fraction = if kind == BodyPart::Trunk {
            self.proportions.fraction_between(Joint::Neck, Joint::Chest)
                + self
                    .proportions
                    .fraction_between(Joint::Chest, Joint::Pelvis)
        } else {
            self.proportions.fraction_between(a, b)
        };
        let p = self.params;
        let mut template = Template::sample(self.frame, &block, extent(kind), p.weights);
        if is_arm(kind) {
            template.set_foreground(p.arm_foreground);
        }
        Part {
            block,
            prev_theta: block.theta,
            template,
            reliability: 1.0,
            max_len: (LENGTH_SLACK * fraction * self.stature).max(block.m * 1.05),
            extent: extent(kind),
            short_penalty: match kind {
                BodyPart::Head | BodyPart::Trunk => 0.0,
                BodyPart::LeftForearm | BodyPart::RightForearm => p.forearm_short_penalty,
                _ => p.short_penalty,
            },
        }
    }

    /// The hip patch around the trunk's pelvis end (see [`BodyTracker::hips_hold`]).
    fn hips(&self, trunk: &MorphBlock) -> Part {
        let block = hip_patch(trunk.end(), trunk.theta, trunk.m, trunk.n);
        Part {
            block,
            prev_theta: block.theta,
            template: Template::sample(self.frame, &block, Extent::BLOCK, self.params.weights),
            reliability: 1.0,
            max_len: block.m,
            extent: Extent::BLOCK,
            short_penalty: 0.0,
        }
    }
}

/// The hip patch around `pelvis`: as wide as the trunk, reaching 0.3 of the trunk's length above
/// and below the pelvis along the trunk's angle `theta`.
fn hip_patch(pelvis: Point2<f64>, theta: f64, trunk_m: f64, trunk_n: f64) -> MorphBlock {
    let half = 0.3 * trunk_m;
    let dir = nalgebra::Vector2::new(theta.cos(), theta.sin());
    MorphBlock {
        origin: pelvis - dir * half,
        m: 2.0 * half,
        n: trunk_n,
        theta,
    }
}

impl BodyTracker {
    /// The hip patch searched by the head's spiral from where it was (for [`Self::hips_hold`]).
    fn hips_spiral(&self, frame: FrameView, p: &Tuning) -> Found {
        spiral(
            &self.hips.template,
            frame,
            &self.hips.block,
            &SpiralParams {
                step_px: p.head_step_px,
                d_theta: p.head_d_theta_deg.to_radians(),
                d_m: 0.0,
                max_rings: p.head_max_rings,
                m_bounds: (0.0, f64::INFINITY),
            },
        )
    }

    /// Beyond the paper: the trunk is one rigid block hung from the neck, so when the spine
    /// bends (a bow, a reach) the block keeps its angle and the pelvis swings away with the
    /// neck, while the hips in fact stay. The hip patch, sampled on the key frame, is searched
    /// by the head's spiral from where it was (`found`, from [`Self::hips_spiral`]); when it
    /// matches clearly better there than where the trunk put the pelvis, the trunk is re-hung
    /// from the neck to the patch's centre.
    fn hips_hold(&mut self, frame: FrameView, neck: Point2<f64>, found: Found, p: &Tuning) {
        let t = self.trunk.block;
        let at_trunk = hip_patch(t.end(), t.theta, t.m, t.n);
        let c_trunk = self
            .hips
            .template
            .cost(frame, &at_trunk, false, f32::INFINITY);
        let centre = found.block.to_image(0.5, 0.0);
        let len = (centre - neck).norm();
        if found.cost + p.hip_margin < c_trunk
            && len > 0.5 * t.m
            && len <= self.trunk.max_len * self.zoom
        {
            let block = MorphBlock::along(neck, centre, t.n);
            let cost = self
                .trunk
                .template
                .cost(frame, &block, false, f32::INFINITY);
            // The trunk was accepted this frame already: keep its angle history.
            let prev = self.trunk.prev_theta;
            accept(&mut self.trunk, Found { block, cost }, frame, p);
            self.trunk.prev_theta = prev;
            accept(&mut self.hips, found, frame, p);
        } else {
            accept(
                &mut self.hips,
                Found {
                    block: at_trunk,
                    cost: c_trunk,
                },
                frame,
                p,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A figure standing in a 200 × 300 image of noise (the image shifted by `dx` pixels).
    fn figure(dx: u32) -> (RgbImage, PerJoint<Point2<f64>>) {
        let image = RgbImage::from_fn(200, 300, |x, y| {
            let v = ((x + dx) * 7919 + y * 104_729) % 251;
            image::Rgb([v as u8, (v * 3 % 251) as u8, (v * 5 % 251) as u8])
        });
        let at = |x: f64, y: f64| Point2::new(x, y);
        let pose = PerJoint::from_fn(|j| match j {
            Joint::HeadTop => at(100.0, 40.0),
            Joint::Neck => at(100.0, 80.0),
            Joint::Chest => at(100.0, 110.0),
            Joint::Pelvis => at(100.0, 160.0),
            Joint::LeftShoulder => at(120.0, 85.0),
            Joint::LeftElbow => at(130.0, 120.0),
            Joint::LeftWrist => at(135.0, 155.0),
            Joint::RightShoulder => at(80.0, 85.0),
            Joint::RightElbow => at(70.0, 120.0),
            Joint::RightWrist => at(65.0, 155.0),
            Joint::LeftHip => at(112.0, 160.0),
            Joint::LeftKnee => at(115.0, 210.0),
            Joint::LeftAnkle => at(117.0, 260.0),
            Joint::RightHip => at(88.0, 160.0),
            Joint::RightKnee => at(85.0, 210.0),
            Joint::RightAnkle => at(83.0, 260.0),
        });
        (image, pose)
    }

    #[test]
    fn a_restart_placing_one_joint_leaves_the_parts_away_from_it_as_they_were() {
        let (first, pose) = figure(0);
        let params = crate::track::TrackerParams::default().tuning(30.0, 1);
        let proportions = Proportions::default();
        let mut t = BodyTracker::new(&first, &pose, &proportions, params, None);
        let (next, _) = figure(3);
        t.step(&next);
        let before = t.pose();
        // Some part lost confidence on the changed image (else the test could not fail).
        assert!(Joint::ALL.iter().any(|&j| before[j].reliability < 1.0));
        let mut fixed = before.map(|_, r| r.pos);
        fixed[Joint::LeftWrist] += nalgebra::Vector2::new(5.0, -4.0);
        let placed = PerJoint::from_fn(|j| j == Joint::LeftWrist);
        t.restart(&next, &fixed, &placed, &proportions);
        let after = t.pose();
        assert!((after[Joint::LeftWrist].pos - fixed[Joint::LeftWrist]).norm() < 1e-6);
        // Every joint but the wrist keeps its place and its reliability (a fresh tracker
        // would make each 1).
        for j in Joint::ALL {
            if j == Joint::LeftWrist {
                continue;
            }
            assert!((after[j].pos - before[j].pos).norm() < 1e-6, "{}", j.name());
            assert_eq!(after[j].reliability, before[j].reliability, "{}", j.name());
        }
        // With every joint placed it is a fresh start.
        t.restart(&next, &fixed, &PerJoint::from_fn(|_| true), &proportions);
        assert!(Joint::ALL.iter().all(|&j| t.pose()[j].reliability == 1.0));
    }

    #[test]
    fn each_chain_root_index_names_that_chains_root_joint() {
        for (c, chain) in CHAINS.iter().enumerate() {
            assert_eq!(TRUNK_JOINTS[CHAIN_ROOTS[c]], chain[0]);
        }
    }
}
