//! Where to look for a block in the next frame: the spiral search path of the head (Pan et al.,
//! Fig. 6) and the angular search of blocks anchored at a tracked parent joint (trunk, limbs).
//! Both end with a local refinement that halves its steps down to sub-pixel size; a limb's two
//! segments are then refined together as one chain ([`refine_chain`]).

use super::block::{MorphBlock, wrap_angle};
use super::similarity::{FrameView, Template};
use nalgebra::{Point2, Vector2};
use rayon::prelude::*;

/// The best block found and its cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Found {
    /// The block.
    pub block: MorphBlock,
    /// Its cost: the appearance cost (mean weighted difference, 8-bit levels) plus the prior's
    /// penalty.
    pub cost: f32,
}

/// A soft motion prior on anchored blocks (beyond the paper): a penalty, in the cost's units,
/// for turning away from the predicted angle and for changing length, and hard bounds on the
/// length from the body's proportions. Without it a uniformly coloured limb slides or shrinks
/// along flat stretches of the cost surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Prior {
    /// Predicted angle, radians.
    pub theta: f64,
    /// Predicted length, pixels.
    pub m: f64,
    /// Penalty per degree away from the predicted angle.
    pub per_degree: f32,
    /// Penalty per unit of |ln(m / predicted m)|.
    pub per_log_length: f32,
    /// Penalty per unit of ln(m_full / m) when the block is shorter than `m_full`.
    pub per_log_short: f32,
    /// The part's full (not foreshortened) image length, pixels.
    pub m_full: f64,
    /// Shortest allowed length, pixels.
    pub m_min: f64,
    /// Longest allowed length, pixels.
    pub m_max: f64,
}

impl Prior {
    /// No prior.
    pub(super) const NONE: Prior = Prior {
        theta: 0.0,
        m: 1.0,
        per_degree: 0.0,
        per_log_length: 0.0,
        per_log_short: 0.0,
        m_full: 0.0,
        m_min: 0.0,
        m_max: f64::INFINITY,
    };

    /// The penalty of a candidate (infinite outside the length bounds).
    pub(super) fn penalty(&self, b: &MorphBlock) -> f32 {
        if b.m < self.m_min || b.m > self.m_max {
            return f32::INFINITY;
        }
        let mut p = 0.0f32;
        if self.per_degree > 0.0 {
            p += self.per_degree * wrap_angle(b.theta - self.theta).abs().to_degrees() as f32;
        }
        if self.per_log_length > 0.0 && self.m > 0.0 {
            p += self.per_log_length * (b.m / self.m).ln().abs() as f32;
        }
        if self.per_log_short > 0.0 && b.m < self.m_full {
            p += self.per_log_short * (self.m_full / b.m).ln() as f32;
        }
        p
    }
}

/// Appearance cost plus prior, with early exit against `bound`.
fn total_cost(
    template: &Template,
    frame: FrameView,
    b: &MorphBlock,
    prior: &Prior,
    coarse: bool,
    bound: f32,
) -> f32 {
    let pen = prior.penalty(b);
    if pen >= bound {
        return f32::INFINITY;
    }
    template.cost(frame, b, coarse, bound - pen) + pen
}

/// Ranges of the spiral search (the paper's Δθ and Δm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SpiralParams {
    /// Distance between neighbouring points of the path, pixels.
    pub step_px: f64,
    /// Δθ: each point is tried at θ − Δθ, θ and θ + Δθ, radians.
    pub d_theta: f64,
    /// Δm as a fraction of m: each point is tried at m − Δm, m and m + Δm (n in proportion).
    pub d_m: f64,
    /// Most rings walked (a bound on the time spent on a lost head).
    pub max_rings: usize,
    /// Shortest and longest length a block may take, pixels.
    pub m_bounds: (f64, f64),
}

/// The morph variants tried at each point of the spiral: {θ−Δθ, θ, θ+Δθ} × {m−Δm, m, m+Δm},
/// n scaled with m (the head zooms as a whole); with Δm = 0 only the three angles.
fn variants(b: &MorphBlock, p: &SpiralParams) -> impl Iterator<Item = MorphBlock> {
    let b = *b;
    let scales: &[f64] = if p.d_m == 0.0 {
        &[0.0]
    } else {
        &[0.0, -1.0, 1.0]
    };
    let d_m = p.d_m;
    [0.0, -p.d_theta, p.d_theta]
        .into_iter()
        .flat_map(move |dt| {
            scales.iter().map(move |k| {
                let s = 1.0 + k * d_m;
                MorphBlock {
                    m: b.m * s,
                    n: b.n * s,
                    theta: b.theta + dt,
                    ..b
                }
            })
        })
}

/// The spiral search of Fig. 6 around `predicted` (origin, m, n, θ): ring by ring outwards,
/// stopping after the first ring that finds nothing better than the best so far; then a local
/// refinement of position, angle and size down to a quarter of a pixel.
pub(super) fn spiral(
    template: &Template,
    frame: FrameView,
    predicted: &MorphBlock,
    p: &SpiralParams,
) -> Found {
    // The start brought within the length bounds, its width in proportion.
    let m = predicted
        .m
        .clamp(p.m_bounds.0, p.m_bounds.1.max(p.m_bounds.0));
    let start = MorphBlock {
        m,
        n: if predicted.m > 0.0 {
            predicted.n * m / predicted.m
        } else {
            predicted.n
        },
        ..*predicted
    };
    let predicted = &start;
    let mut best = Found {
        block: *predicted,
        cost: f32::INFINITY,
    };
    try_point(template, frame, predicted, predicted.origin, p, &mut best);
    for ring in 1..=p.max_rings {
        let r = ring as i64;
        // The ring's points are tried in parallel, each against the best before the ring; the ring's
        // winner is the first of the lowest, exactly as when walked one by one.
        let ring_best = (0..(8 * r))
            .into_par_iter()
            .map(|k| {
                let o = ring_point(predicted.origin, r, k, p.step_px);
                let mut local = best;
                try_point(template, frame, predicted, o, p, &mut local);
                local
            })
            .reduce(|| best, |a, b| if b.cost < a.cost { b } else { a });
        if ring_best.cost >= best.cost {
            break;
        }
        best = ring_best;
    }
    spiral_refine(template, frame, best, p)
}

/// Point `k` (0 ≤ k < 8r) of the square ring at Chebyshev distance `r` (in steps of `step`
/// pixels) around `centre`, walked clockwise from its top-left corner.
fn ring_point(centre: Point2<f64>, r: i64, k: i64, step: f64) -> Point2<f64> {
    let (side, t) = (k / (2 * r), k % (2 * r));
    let (dx, dy) = match side {
        0 => (-r + t, -r),
        1 => (r, -r + t),
        2 => (r - t, r),
        _ => (-r, r - t),
    };
    centre + Vector2::new(dx as f64, dy as f64) * step
}

/// The morph variants of `predicted` moved to `origin`, each kept in `best` if it beats it;
/// whether one did.
fn try_point(
    template: &Template,
    frame: FrameView,
    predicted: &MorphBlock,
    origin: Point2<f64>,
    p: &SpiralParams,
    best: &mut Found,
) -> bool {
    let mut improved = false;
    for v in variants(
        &MorphBlock {
            origin,
            ..*predicted
        },
        p,
    )
    .filter(|v| v.m >= p.m_bounds.0 && v.m <= p.m_bounds.1)
    {
        let c = template.cost(frame, &v, false, best.cost);
        if c < best.cost {
            *best = Found { block: v, cost: c };
            improved = true;
        }
    }
    improved
}

/// The spiral's last step: a local refinement of position, angle and size from the best ring
/// point, its steps half the spiral's, halved three times.
fn spiral_refine(template: &Template, frame: FrameView, best: Found, p: &SpiralParams) -> Found {
    refine(
        template,
        frame,
        best,
        &Steps {
            position: p.step_px / 2.0,
            theta: p.d_theta / 2.0,
            scale: p.d_m / 2.0,
            scale_width: true,
            move_origin: true,
            levels: 3,
        },
        &Prior {
            m_min: p.m_bounds.0,
            m_max: p.m_bounds.1,
            ..Prior::NONE
        },
    )
}

/// Step sizes of a local refinement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Steps {
    /// First position step, pixels.
    pub position: f64,
    /// First angle step, radians.
    pub theta: f64,
    /// First relative length step.
    pub scale: f64,
    /// Whether the width scales with the length (head) or stays (limbs: foreshortening shortens
    /// a limb's image, not its width).
    pub scale_width: bool,
    /// Whether the origin may move (free blocks) or is a fixed parent joint (anchored blocks).
    pub move_origin: bool,
    /// How many times the steps are halved.
    pub levels: usize,
}

/// Coordinate descent from `start`: tries ± each step on each free parameter until nothing
/// improves, then halves the steps.
pub(super) fn refine(
    template: &Template,
    frame: FrameView,
    start: Found,
    s: &Steps,
    prior: &Prior,
) -> Found {
    let mut best = start;
    let (mut dp, mut dt, mut ds) = (s.position, s.theta, s.scale);
    for _ in 0..s.levels {
        for _ in 0..8 {
            let b = best.block;
            let mut cands: [Option<MorphBlock>; 8] = [None; 8];
            cands[0] = Some(MorphBlock {
                theta: b.theta + dt,
                ..b
            });
            cands[1] = Some(MorphBlock {
                theta: b.theta - dt,
                ..b
            });
            if ds > 0.0 {
                for (k, f) in [(2, 1.0 + ds), (3, 1.0 / (1.0 + ds))] {
                    cands[k] = Some(MorphBlock {
                        m: b.m * f,
                        n: if s.scale_width { b.n * f } else { b.n },
                        ..b
                    });
                }
            }
            if s.move_origin {
                for (k, d) in [
                    (4, (dp, 0.0)),
                    (5, (-dp, 0.0)),
                    (6, (0.0, dp)),
                    (7, (0.0, -dp)),
                ] {
                    cands[k] = Some(MorphBlock {
                        origin: b.origin + Vector2::new(d.0, d.1),
                        ..b
                    });
                }
            }
            let mut improved = false;
            for c in cands.into_iter().flatten() {
                let cost = total_cost(template, frame, &c, prior, false, best.cost);
                if cost < best.cost {
                    best = Found { block: c, cost };
                    improved = true;
                }
            }
            if !improved {
                break;
            }
        }
        dp /= 2.0;
        dt /= 2.0;
        ds /= 2.0;
    }
    best
}

/// Ranges of the search of an anchored block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct AngularParams {
    /// Half-width of the angle range around the predicted angle, radians.
    pub range_theta: f64,
    /// Angle step of the coarse scan, radians.
    pub step_theta: f64,
    /// Half-width of the relative length range around the predicted length.
    pub range_m: f64,
    /// Number of lengths scanned across that range (odd).
    pub m_count: usize,
    /// Whether the width scales with the length.
    pub scale_width: bool,
}

/// Searches a block anchored at a fixed joint: a coarse scan of angle × length on the coarse
/// grid, then a refinement of the three best on the full grid.
pub(super) fn angular(
    template: &Template,
    frame: FrameView,
    predicted: &MorphBlock,
    p: &AngularParams,
    prior: &Prior,
) -> Found {
    angular_below(template, frame, predicted, p, prior, f32::INFINITY)
}

/// How much more than the wanted cost a coarse-grid candidate of [`angular_below`] may cost
/// and still be refined: a coarse candidate lies up to half a step from the best block and
/// samples every other row and column, so its cost only estimates where the refinement will
/// get. A heuristic, measured: with 1.5 and 2 the suite's and the real sample's tracks are
/// byte-identical to an uncapped search (1.0 changed three clips); the unit test's sharp
/// synthetic bar needs about 5. The arm rescue's cost on the real sample (instructions to
/// decode and track it, counted by cachegrind; 10.4 G without the rescue): uncapped 16.9 G, 2
/// 14.0 G, 1.5 11.3 G.
pub(super) const COARSE_SLACK: f32 = 1.5;

/// [`angular`] for a caller that only wants a block costing under `cap`: coarse candidates
/// costing more than [`COARSE_SLACK`] times `cap` are dropped as soon as their partial sum
/// shows it (early exit), and never refined. The result may cost `cap` or more; the caller
/// checks.
pub(super) fn angular_below(
    template: &Template,
    frame: FrameView,
    predicted: &MorphBlock,
    p: &AngularParams,
    prior: &Prior,
    cap: f32,
) -> Found {
    const KEEP: usize = 3;
    let mut top: [Found; KEEP] = [Found {
        block: *predicted,
        cost: f32::INFINITY,
    }; KEEP];
    let coarse_cap = cap * COARSE_SLACK;
    let steps = (p.range_theta / p.step_theta).ceil().max(0.0) as i64;
    let half_m = (p.m_count / 2) as i64;
    for k in -steps..=steps {
        let theta = predicted.theta + k as f64 * p.step_theta;
        for mi in -half_m..=half_m {
            let f = if half_m == 0 {
                1.0
            } else {
                1.0 + p.range_m * mi as f64 / half_m as f64
            };
            let b = MorphBlock {
                theta,
                m: predicted.m * f,
                n: if p.scale_width {
                    predicted.n * f
                } else {
                    predicted.n
                },
                ..*predicted
            };
            let worst = top[KEEP - 1].cost.min(coarse_cap);
            let c = total_cost(template, frame, &b, prior, true, worst);
            if c < worst {
                top[KEEP - 1] = Found { block: b, cost: c };
                top.sort_by(|a, b| a.cost.total_cmp(&b.cost));
            }
        }
    }
    let steps = Steps {
        position: 0.0,
        theta: p.step_theta / 2.0,
        // A length range of 0 holds the length through the refinement too.
        scale: if p.range_m > 0.0 {
            (p.range_m / half_m.max(1) as f64 / 2.0).max(0.01)
        } else {
            0.0
        },
        scale_width: p.scale_width,
        move_origin: false,
        levels: 4,
    };
    let mut best = Found {
        block: *predicted,
        cost: f32::INFINITY,
    };
    for t in top.iter().filter(|t| t.cost.is_finite()) {
        let start = Found {
            block: t.block,
            cost: total_cost(template, frame, &t.block, prior, false, f32::INFINITY),
        };
        let r = refine(template, frame, start, &steps, prior);
        if r.cost < best.cost {
            best = r;
        }
    }
    if !best.cost.is_finite() {
        best.cost = total_cost(template, frame, predicted, prior, false, f32::INFINITY);
    }
    best
}

/// One segment of a two-segment chain (upper arm and forearm, thigh and shank): its colour
/// model, its width and its motion prior.
#[derive(Debug, Clone, Copy)]
pub(super) struct ChainSegment<'a> {
    /// The segment's colour model.
    pub template: &'a Template,
    /// Its width, pixels.
    pub n: f64,
    /// Its motion prior.
    pub prior: &'a Prior,
}

/// Where a two-segment chain hangs from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ChainRoot {
    /// The root joint (shoulder, hip).
    pub at: Point2<f64>,
    /// When the root may move: its rest point and the cost per square pixel of leaving it.
    pub spring: Option<(Point2<f64>, f32)>,
}

/// Beyond the paper: a two-segment chain refined as one figure. The middle joint (elbow, knee)
/// is shared: the segment-by-segment search fixes the upper segment first, so a middle joint a
/// pixel or two off leaves the lower segment anchored wrongly, and on a thin limb it then
/// shortens or turns to fit. Here the middle and end joints (and the root, when it has a
/// spring) move by ± a step in x and y, one joint at a time, while the sum of both segments'
/// costs (plus the spring's) falls; steps start at `step_px` and are halved `levels − 1` times.
/// `allowed` refuses a pair of blocks (a lower segment folded back). Returns the two blocks and
/// their summed cost.
pub(super) fn refine_chain(
    frame: FrameView,
    root: ChainRoot,
    segments: [ChainSegment; 2],
    start: [Point2<f64>; 2],
    step_px: f64,
    levels: usize,
    allowed: impl Fn(&MorphBlock, &MorphBlock) -> bool,
) -> ([MorphBlock; 2], f32) {
    let blocks = |[root, mid, end]: [Point2<f64>; 3]| {
        [
            MorphBlock::along(root, mid, segments[0].n),
            MorphBlock::along(mid, end, segments[1].n),
        ]
    };
    let spring = |r: Point2<f64>| {
        root.spring
            .map_or(0.0, |(rest, k)| k * (r - rest).norm_squared() as f32)
    };
    // Each segment's cost (appearance plus prior) with early exit against `bound`; a
    // refused pair costs infinity.
    let segment_cost = |k: usize, b: &MorphBlock, bound: f32| {
        total_cost(
            segments[k].template,
            frame,
            b,
            segments[k].prior,
            false,
            bound,
        )
    };
    let mut joints = [root.at, start[0], start[1]];
    let [u, l] = blocks(joints);
    // The upper segment's cost carries the root's spring.
    let mut best = if allowed(&u, &l) {
        [
            segment_cost(0, &u, f32::INFINITY) + spring(root.at),
            segment_cost(1, &l, f32::INFINITY),
        ]
    } else {
        [f32::INFINITY; 2]
    };
    let first = if root.spring.is_some() { 0 } else { 1 };
    let mut step = step_px;
    for _ in 0..levels {
        for _ in 0..8 {
            let mut improved = false;
            for which in first..3 {
                for d in [
                    Vector2::new(step, 0.0),
                    Vector2::new(-step, 0.0),
                    Vector2::new(0.0, step),
                    Vector2::new(0.0, -step),
                ] {
                    let mut cand = joints;
                    cand[which] += d;
                    let [u, l] = blocks(cand);
                    if !allowed(&u, &l) {
                        continue;
                    }
                    let total = best[0] + best[1];
                    // Moving the end joint leaves the upper segment as it was; moving the root
                    // leaves the lower one.
                    let cu = if which < 2 {
                        let sp = spring(cand[0]);
                        let rest = if which == 0 { best[1] } else { 0.0 };
                        segment_cost(0, &u, total - rest - sp) + sp
                    } else {
                        best[0]
                    };
                    if !cu.is_finite() {
                        continue;
                    }
                    let cl = if which > 0 {
                        segment_cost(1, &l, total - cu)
                    } else {
                        best[1]
                    };
                    if cu + cl < total {
                        best = [cu, cl];
                        joints = cand;
                        improved = true;
                    }
                }
            }
            if !improved {
                break;
            }
        }
        step /= 2.0;
    }
    (blocks(joints), best[0] + best[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::similarity::{Extent, FloatFrame, SimilarityWeights};
    use image::{Rgb, RgbImage};

    /// A textured bar from `a` to `b` over a differently textured background.
    fn bar(a: Point2<f64>, b: Point2<f64>, width: f64) -> RgbImage {
        let block = MorphBlock::along(a, b, width);
        RgbImage::from_fn(160, 160, |x, y| {
            let p = Point2::new(f64::from(x), f64::from(y));
            let (u, v) = block.to_block(p);
            if (0.0..=1.0).contains(&u) && v.abs() <= 0.5 {
                let s = ((u * 6.0).floor() as i64 + (v * 4.0 + 2.0).floor() as i64) & 1;
                Rgb([180 + 40 * s as u8, 60, 60 + 80 * s as u8])
            } else {
                let s = ((x / 7 + y / 5) & 1) as u8;
                Rgb([70 + 30 * s, 110, 90 + 20 * s])
            }
        })
    }

    /// An arm: an upper bar from `joints[0]` to `joints[1]` and a differently textured lower
    /// bar from `joints[1]` to `joints[2]`, 14 px wide, over the background of [`bar`].
    fn arm(joints: [Point2<f64>; 3]) -> RgbImage {
        let upper = MorphBlock::along(joints[0], joints[1], 14.0);
        let lower = MorphBlock::along(joints[1], joints[2], 14.0);
        let background = bar(joints[0], joints[0], 0.0);
        RgbImage::from_fn(160, 160, |x, y| {
            let p = Point2::new(f64::from(x), f64::from(y));
            let on = |b: &MorphBlock| {
                let (u, v) = b.to_block(p);
                ((0.0..=1.0).contains(&u) && v.abs() <= 0.5).then_some((u, v))
            };
            if let Some((u, v)) = on(&lower) {
                let s = ((u * 5.0).floor() as i64 + (v * 3.0 + 2.0).floor() as i64) & 1;
                Rgb([60 + 120 * s as u8, 200, 40])
            } else if let Some((u, v)) = on(&upper) {
                let s = ((u * 6.0).floor() as i64 + (v * 4.0 + 2.0).floor() as i64) & 1;
                Rgb([180 + 40 * s as u8, 60, 60 + 80 * s as u8])
            } else {
                *background.get_pixel(x, y)
            }
        })
    }

    /// A root that stays put.
    fn fixed(at: Point2<f64>) -> ChainRoot {
        ChainRoot { at, spring: None }
    }

    /// The arm of [`arm`] through `truth` as a frame, with each segment's colour model sampled
    /// on it.
    fn arm_models(truth: [Point2<f64>; 3]) -> (FloatFrame, [Template; 2]) {
        let floats = FloatFrame::new(&arm(truth));
        let model = |a: Point2<f64>, b: Point2<f64>| {
            let block = MorphBlock::along(a, b, 14.0);
            Template::sample(
                floats.view(),
                &block,
                Extent::BLOCK,
                SimilarityWeights::default(),
            )
        };
        let models = [model(truth[0], truth[1]), model(truth[1], truth[2])];
        (floats, models)
    }

    /// The two segments of an arm of [`arm`], without priors.
    fn segments(models: &[Template; 2]) -> [ChainSegment<'_>; 2] {
        [0, 1].map(|k| ChainSegment {
            template: &models[k],
            n: 14.0,
            prior: &Prior::NONE,
        })
    }

    /// Both joints of a bent arm started off (the elbow 2.5 px, the wrist 1.5 px) come back to
    /// within half a pixel, and the cost returned is that of the blocks returned.
    #[test]
    fn the_chain_refinement_moves_both_joints_onto_the_arm() {
        let truth = [
            Point2::new(60.0, 30.0),
            Point2::new(72.0, 85.0),
            Point2::new(115.0, 110.0),
        ];
        let (floats, models) = arm_models(truth);
        let (frame, segments) = (floats.view(), segments(&models));
        let start = [
            truth[1] + Vector2::new(2.0, -1.5),
            truth[2] + Vector2::new(-1.2, 0.9),
        ];
        let ([u, l], cost) =
            refine_chain(frame, fixed(truth[0]), segments, start, 1.0, 3, |_, _| true);
        let elbow = (u.end() - truth[1]).norm();
        let wrist = (l.end() - truth[2]).norm();
        assert!(
            elbow < 0.5 && wrist < 0.5,
            "elbow {elbow:.2} px, wrist {wrist:.2} px off"
        );
        assert_eq!(u.end(), l.origin, "the segments share the elbow");
        let sum = models[0].cost(frame, &u, false, f32::INFINITY)
            + models[1].cost(frame, &l, false, f32::INFINITY);
        assert!((cost - sum).abs() < 1e-4, "cost {cost} against {sum}");
        // A refusal of every move leaves the joints where they started.
        let ([u, l], _) = refine_chain(frame, fixed(truth[0]), segments, start, 1.0, 3, |_, _| {
            false
        });
        assert!((u.end() - start[0]).norm() < 1e-9 && (l.end() - start[1]).norm() < 1e-9);
    }

    /// A shoulder 2.9 px from where the trunk puts it: with a weak spring the refinement moves
    /// the root onto the arm; with a stiff one the root stays.
    #[test]
    fn the_chain_refinement_moves_the_root_only_as_far_as_its_spring_allows() {
        let truth = [
            Point2::new(62.5, 28.5),
            Point2::new(72.0, 85.0),
            Point2::new(115.0, 110.0),
        ];
        let (floats, models) = arm_models(truth);
        let (frame, segments) = (floats.view(), segments(&models));
        let rest = Point2::new(60.0, 30.0);
        let refine = |k: f32| {
            let start = [truth[1], truth[2]];
            let root = ChainRoot {
                at: rest,
                spring: Some((rest, k)),
            };
            let ([u, _], _) = refine_chain(frame, root, segments, start, 1.0, 3, |_, _| true);
            u.origin
        };
        let weak = (refine(0.05) - truth[0]).norm();
        assert!(weak < 0.8, "root {weak:.2} px off with a weak spring");
        let stiff = (refine(100.0) - rest).norm();
        assert!(stiff < 1e-9, "root moved {stiff:.2} px with a stiff spring");
    }

    /// A 70 px limb hanging from (80, 40) that ends at `end` in the next frame, searched with
    /// ±0.7 rad of angle and the given length range; returns the first frame's block and the
    /// result.
    fn search_turned_limb(end: Point2<f64>, range_m: f64, m_count: usize) -> (MorphBlock, Found) {
        search_turned_limb_below(end, range_m, m_count, f32::INFINITY)
    }

    /// [`search_turned_limb`] by [`angular_below`] with `cap`.
    fn search_turned_limb_below(
        end: Point2<f64>,
        range_m: f64,
        m_count: usize,
        cap: f32,
    ) -> (MorphBlock, Found) {
        let shoulder = Point2::new(80.0, 40.0);
        let a = bar(shoulder, Point2::new(80.0, 110.0), 16.0);
        let b = bar(shoulder, end, 16.0);
        let block = MorphBlock::along(shoulder, Point2::new(80.0, 110.0), 16.0);
        let t = Template::sample(
            FloatFrame::new(&a).view(),
            &block,
            Extent::BLOCK,
            SimilarityWeights::default(),
        );
        let found = angular_below(
            &t,
            FloatFrame::new(&b).view(),
            &block,
            &AngularParams {
                range_theta: 0.7,
                step_theta: 0.05,
                range_m,
                m_count,
                scale_width: false,
            },
            &Prior::NONE,
            cap,
        );
        (block, found)
    }

    #[test]
    fn a_capped_angular_search_finds_what_the_full_one_finds_under_its_cap() {
        let truth = Point2::new(80.0 + 50.0 * 0.5f64.sin(), 40.0 + 50.0 * 0.5f64.cos());
        let (_, full) = search_turned_limb(truth, 0.35, 5);
        // A cap well above the best cost changes nothing. (On these sharp edges the nearest
        // coarse candidate costs about five times what the refinement reaches, 15 against 3,
        // so a cap just above the best misses it.)
        let (_, capped) = search_turned_limb_below(truth, 0.35, 5, full.cost * 4.0);
        assert_eq!(capped.block, full.block);
        assert_eq!(capped.cost, full.cost);
        // Under a cap nothing comes near, nothing is refined: the prediction comes back, at
        // its cost.
        let (predicted, none) = search_turned_limb_below(truth, 0.35, 5, full.cost * 0.5);
        assert_eq!(none.block, predicted);
        assert!(none.cost > full.cost * 0.5, "{} under the cap", none.cost);
    }

    #[test]
    fn the_angular_search_finds_a_turned_and_shortened_limb() {
        let truth = Point2::new(80.0 + 50.0 * 0.5f64.sin(), 40.0 + 50.0 * 0.5f64.cos()); // 29° turn, shortened
        let (_, found) = search_turned_limb(truth, 0.35, 5);
        let err = (found.block.end() - truth).norm();
        assert!(err < 2.0, "elbow off by {err} px");
    }

    #[test]
    fn a_length_range_of_zero_holds_the_length() {
        // The limb turned and is shorter in the next frame, but its length is held.
        let (block, found) = search_turned_limb(Point2::new(105.0, 84.0), 0.0, 1);
        assert_eq!(found.block.m, block.m);
        assert!(
            (found.block.theta - block.theta).abs() > 0.3,
            "the angle was searched"
        );
    }

    #[test]
    fn the_spiral_search_follows_a_moved_block() {
        let a = bar(Point2::new(60.0, 50.0), Point2::new(70.0, 100.0), 20.0);
        let b = bar(Point2::new(66.0, 46.0), Point2::new(76.0, 96.0), 20.0);
        let block = MorphBlock::along(Point2::new(60.0, 50.0), Point2::new(70.0, 100.0), 20.0);
        let t = Template::sample(
            FloatFrame::new(&a).view(),
            &block,
            Extent::BLOCK,
            SimilarityWeights::default(),
        );
        let found = spiral(
            &t,
            FloatFrame::new(&b).view(),
            &block,
            &SpiralParams {
                step_px: 2.0,
                d_theta: 0.05,
                d_m: 0.05,
                max_rings: 10,
                m_bounds: (0.0, f64::INFINITY),
            },
        );
        let err = (found.block.origin - Point2::new(66.0, 46.0)).norm();
        assert!(err < 1.0, "origin off by {err} px");
    }

    #[test]
    fn the_spiral_keeps_the_length_within_its_bounds() {
        // The bar shrinks to half its length: unbounded, the spiral's zoom follows it; with a
        // floor, the block stops there, and a start below the floor is lifted to it.
        let (top, bottom) = (Point2::new(60.0, 30.0), Point2::new(70.0, 110.0));
        let a = bar(top, bottom, 20.0);
        let b = bar(top, nalgebra::center(&top, &bottom), 10.0);
        let block = MorphBlock::along(top, bottom, 20.0);
        let t = Template::sample(
            FloatFrame::new(&a).view(),
            &block,
            Extent::BLOCK,
            SimilarityWeights::default(),
        );
        let search = |m_bounds: (f64, f64), start: &MorphBlock| {
            spiral(
                &t,
                FloatFrame::new(&b).view(),
                start,
                &SpiralParams {
                    step_px: 2.0,
                    d_theta: 0.05,
                    d_m: 0.06,
                    max_rings: 10,
                    m_bounds,
                },
            )
        };
        let free = search((0.0, f64::INFINITY), &block);
        assert!(free.block.m < 0.8 * block.m, "unbounded: {}", free.block.m);
        let floor = 0.9 * block.m;
        let held = search((floor, f64::INFINITY), &block);
        assert!(held.block.m >= floor - 1e-9, "bounded: {}", held.block.m);
        let short = MorphBlock {
            m: 0.5 * block.m,
            n: 10.0,
            ..block
        };
        let lifted = search((floor, f64::INFINITY), &short);
        assert!(
            lifted.block.m >= floor - 1e-9,
            "from below: {}",
            lifted.block.m
        );
        assert!(lifted.cost.is_finite());
    }

    /// The spiral's rings walked one point at a time, as Fig. 6 draws them (no threads), then
    /// the same final refinement.
    fn spiral_in_order(
        t: &Template,
        frame: FrameView,
        predicted: &MorphBlock,
        p: &SpiralParams,
    ) -> Found {
        let mut best = Found {
            block: *predicted,
            cost: f32::INFINITY,
        };
        try_point(t, frame, predicted, predicted.origin, p, &mut best);
        for r in 1..=p.max_rings as i64 {
            let mut improved = false;
            for k in 0..(8 * r) {
                let o = ring_point(predicted.origin, r, k, p.step_px);
                improved |= try_point(t, frame, predicted, o, p, &mut best);
            }
            if !improved {
                break;
            }
        }
        spiral_refine(t, frame, best, p)
    }

    #[test]
    fn the_parallel_spiral_finds_what_walking_in_order_finds() {
        let block = MorphBlock::along(Point2::new(60.0, 50.0), Point2::new(70.0, 100.0), 20.0);
        let a = bar(block.origin, block.end(), 20.0);
        let t = Template::sample(
            FloatFrame::new(&a).view(),
            &block,
            Extent::BLOCK,
            SimilarityWeights::default(),
        );
        let p = SpiralParams {
            step_px: 2.0,
            d_theta: 0.05,
            d_m: 0.05,
            max_rings: 10,
            m_bounds: (0.0, f64::INFINITY),
        };
        for (k, shift) in [(3.0, -2.0), (9.0, 7.0), (-13.0, 4.0), (0.5, 0.5)]
            .into_iter()
            .enumerate()
        {
            let d = Vector2::new(shift.0, shift.1);
            let b = bar(block.origin + d, block.end() + d, 20.0);
            let expected = spiral_in_order(&t, FloatFrame::new(&b).view(), &block, &p);
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("a thread pool");
                let found = pool.install(|| spiral(&t, FloatFrame::new(&b).view(), &block, &p));
                assert_eq!(found.block, expected.block, "shift {k}, {threads} threads");
                assert_eq!(found.cost, expected.cost, "shift {k}, {threads} threads");
            }
        }
    }
}
