//! Consistent limb labels, with left and right, over the whole clip. The paper (§4) keeps labels
//! from frame to frame by the least sum of squared distances between neighbouring frames;
//! decided greedily, one wrongly named frame (an arm taken for the head) hands its mistake to
//! every frame after it. Here the labelling of every frame is chosen at once, by dynamic
//! programming over the clip: a path visits the frames in order, each with one of its four
//! labellings (which arm is the left one, which leg), and may step over a frame at a fixed
//! price. A step costs how far the frame's labelled points (head, neck, pelvis, each limb's
//! root, bend and end) lie from where the previous two frames' points go at constant velocity
//! (the path's first step: how far they moved), in units of the clip's own typical departure;
//! each frame adds its own left/right cues' price for the labelling (the caller's `cue`). The
//! frames the cheapest path steps over do not follow from the frames around them under any
//! labelling: they are left out.

use super::FrameResult;
use super::bodies::LimbFit;
use nalgebra::Point3;

/// Price of stepping over a frame, in squared typical motions per frame: a frame is left out
/// when keeping it costs more than a 3-σ jump would.
const SKIP_COST: f64 = 9.0;
/// The path looks this many posed frames back (so it can step over up to this many minus one
/// in a row).
const REACH: usize = 5;
/// The typical motion per frame is no less than this, metres (a still clip).
const MIN_MOTION_M: f64 = 0.01;

/// The labels of a clip.
#[derive(Debug, Clone, PartialEq)]
pub struct Labels {
    /// Per frame, which fitted limb carries each label (labels 0 and 1 are the arms, 2 and 3 the
    /// legs; left and right are decided afterwards); `None` for frames without a pose or left
    /// out, and a label's `None` for an arm the frame does not show.
    pub order: Vec<Option<[Option<usize>; 4]>>,
    /// Frames that had a pose but were left out (their limbs do not follow from the frames
    /// around them).
    pub left_out: Vec<usize>,
}

/// The four labellings: limb index per label (arms swapped or not, legs swapped or not).
const LABELLINGS: [[usize; 4]; 4] = [[0, 1, 2, 3], [1, 0, 2, 3], [0, 1, 3, 2], [1, 0, 3, 2]];

/// The points of a frame under a labelling that a step compares: head, neck, pelvis, then per
/// label its root, bend and end (`None` where the frame has no such point).
fn labelled_points(f: &FrameResult, labelling: &[usize; 4]) -> Vec<Option<Point3<f64>>> {
    let mut v = vec![
        Some(f.fit.head_centre),
        Some(f.fit.torso.b),
        Some(f.fit.pelvis),
    ];
    for &k in labelling {
        let l: Option<&LimbFit> = f.fit.limbs[k].as_ref();
        v.push(l.map(|l| l.root));
        v.push(l.and_then(|l| l.split));
        v.push(l.map(|l| l.end));
    }
    v
}

/// Mean over the points two frames both have of the squared distance in units of `scale2` (a
/// squared distance).
fn mean_squared(a: &[Option<Point3<f64>>], b: &[Option<Point3<f64>>], scale2: f64) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (p, q) in a.iter().zip(b) {
        if let (Some(p), Some(q)) = (p, q) {
            sum += (p - q).norm_squared() / scale2;
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

/// The points of `a` carried on to the time of `m` at their velocity from `p` to `a` (gaps in
/// frames `g_pa`, `g_am`).
fn predicted(
    p: &[Option<Point3<f64>>],
    a: &[Option<Point3<f64>>],
    g_pa: f64,
    g_am: f64,
) -> Vec<Option<Point3<f64>>> {
    p.iter()
        .zip(a)
        .map(|(p, a)| match (p, a) {
            (Some(p), Some(a)) => Some(a + (a - p) * (g_am / g_pa)),
            _ => None,
        })
        .collect()
}

/// The median of `v`, no less than `floor`.
fn median_at_least(mut v: Vec<f64>, floor: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0).max(floor)
}

/// Labels every frame of `frames` (`None`: no pose) by the cheapest path over the clip. A step
/// from frame a to frame m is priced by how far m's points lie from where a's points go at
/// their velocity from the frame before a on the path (limbs that pass each other, such as
/// legs in a stride, keep their labels); the path's first step, with no velocity yet, by how
/// far they moved.
pub fn label(frames: &[Option<&FrameResult>], cue: &dyn Fn(usize, &[usize; 4]) -> f64) -> Labels {
    let prices = StepPrices::new(frames, cue);
    let n = prices.posed.len();
    let (cost, from) = prices.cheapest_paths();
    let path = trace_back(&cost, &from, n);
    let mut order = vec![None; frames.len()];
    let mut on_path = vec![false; n];
    for (m, l) in path {
        on_path[m] = true;
        if let Some(f) = frames[prices.posed[m]] {
            order[prices.posed[m]] =
                Some(LABELLINGS[l].map(|k| f.fit.limbs[k].is_some().then_some(k)));
        }
    }
    let left_out = (0..n)
        .filter(|&m| !on_path[m])
        .map(|m| prices.posed[m])
        .collect();
    Labels { order, left_out }
}

/// Per posed frame and labelling, the cheapest path whose last step comes from `back` posed
/// frames before with a given labelling: `cost[m][lb][back - 1][la]`.
type Costs = Vec<[[[f64; 4]; REACH]; 4]>;
/// Per entry of [`Costs`], the step before the last (how far back, which labelling); `None`
/// where the path starts at the last step's first frame.
type Froms = Vec<[[[Option<(usize, usize)>; 4]; REACH]; 4]>;

/// What a path's steps are priced from: the posed frames, their points and cues per
/// labelling, and the clip's typical motion and departure from constant velocity.
struct StepPrices {
    /// The frames with a pose.
    posed: Vec<usize>,
    /// Points per posed frame per labelling.
    points: Vec<[Vec<Option<Point3<f64>>>; 4]>,
    /// The caller's left/right cue per posed frame per labelling.
    cues: Vec<[f64; 4]>,
    sigma_moved: f64,
    sigma_residual: f64,
}

impl StepPrices {
    /// Reads the posed frames; the clip's typical motion per frame and typical departure from
    /// constant velocity are medians over neighbouring posed frames of the least under any
    /// relabelling (squared metres).
    fn new(frames: &[Option<&FrameResult>], cue: &dyn Fn(usize, &[usize; 4]) -> f64) -> Self {
        let posed: Vec<usize> = (0..frames.len()).filter(|&i| frames[i].is_some()).collect();
        let points = posed
            .iter()
            .filter_map(|&i| frames[i])
            .map(|f| LABELLINGS.map(|l| labelled_points(f, &l)))
            .collect();
        let cues = posed
            .iter()
            .map(|&i| LABELLINGS.map(|l| cue(i, &l)))
            .collect();
        let mut prices = StepPrices {
            posed,
            points,
            cues,
            sigma_moved: 1.0,
            sigma_residual: 1.0,
        };
        let n = prices.posed.len();
        let floor = MIN_MOTION_M * MIN_MOTION_M;
        prices.sigma_moved = median_at_least(
            (1..n)
                .map(|m| {
                    (0..4)
                        .map(|lb| prices.moved(m - 1, 0, m, lb, 1.0))
                        .fold(f64::INFINITY, f64::min)
                })
                .collect(),
            floor,
        );
        prices.sigma_residual = median_at_least(
            (2..n)
                .map(|m| {
                    let mut best = f64::INFINITY;
                    for la in 0..4 {
                        for lb in 0..4 {
                            best = best.min(prices.residual((m - 2, 0), (m - 1, la), (m, lb), 1.0));
                        }
                    }
                    best
                })
                .collect(),
            floor,
        );
        prices
    }

    /// Frames between posed frames `a` and `b`.
    fn gap(&self, a: usize, b: usize) -> f64 {
        (self.posed[b] - self.posed[a]) as f64
    }

    /// How far posed frame `m`'s points (labelling `lb`) lie from `a`'s (labelling `la`):
    /// squared distances per frame of gap, in units of `scale2`.
    fn moved(&self, a: usize, la: usize, m: usize, lb: usize, scale2: f64) -> f64 {
        let g2 = self.gap(a, m) * self.gap(a, m);
        mean_squared(&self.points[a][la], &self.points[m][lb], scale2 * g2)
    }

    /// How far `m`'s points lie from where `a`'s go at their velocity from `p` (each a posed
    /// frame with its labelling), in units of `scale2`.
    fn residual(
        &self,
        (p, lp): (usize, usize),
        (a, la): (usize, usize),
        (m, lb): (usize, usize),
        scale2: f64,
    ) -> f64 {
        let pred = predicted(
            &self.points[p][lp],
            &self.points[a][la],
            self.gap(p, a),
            self.gap(a, m),
        );
        mean_squared(
            &pred,
            &self.points[m][lb],
            scale2 * self.gap(a, m).max(1.0).powi(2),
        )
    }

    /// The dynamic programme: per posed frame m, labelling lb and step back, the cheapest path
    /// ending there ([`Costs`]) and its step before ([`Froms`]).
    fn cheapest_paths(&self) -> (Costs, Froms) {
        let n = self.posed.len();
        let mut cost: Costs = vec![[[[f64::INFINITY; 4]; REACH]; 4]; n];
        let mut from: Froms = vec![[[[None; 4]; REACH]; 4]; n];
        for m in 0..n {
            for lb in 0..4 {
                for back in 1..=REACH.min(m) {
                    let a = m - back;
                    let over = SKIP_COST * (back - 1) as f64;
                    for la in 0..4 {
                        // The path starts at a (stepping over every frame before it) …
                        let mut best = (
                            SKIP_COST * a as f64
                                + self.cues[a][la]
                                + self.moved(a, la, m, lb, self.sigma_moved)
                                + over
                                + self.cues[m][lb],
                            None,
                        );
                        // … or comes to a from p.
                        for back2 in 1..=REACH.min(a) {
                            let p = a - back2;
                            for (lp, &before) in cost[a][la][back2 - 1].iter().enumerate() {
                                if !before.is_finite() {
                                    continue;
                                }
                                let c = before
                                    + self.residual((p, lp), (a, la), (m, lb), self.sigma_residual)
                                    + over
                                    + self.cues[m][lb];
                                if c < best.0 {
                                    best = (c, Some((back2, lp)));
                                }
                            }
                        }
                        cost[m][lb][back - 1][la] = best.0;
                        from[m][lb][back - 1][la] = best.1;
                    }
                }
            }
        }
        (cost, from)
    }
}

/// The cheapest path's (posed frame, labelling) pairs, last first: its cheapest end (stepping
/// over every frame after it; a path of one frame steps over all the others), followed back.
fn trace_back(cost: &Costs, from: &Froms, n: usize) -> Vec<(usize, usize)> {
    let mut best = (SKIP_COST * n.saturating_sub(1) as f64, None);
    for (m, by_label) in cost.iter().enumerate() {
        for (lb, by_back) in by_label.iter().enumerate() {
            for (back, by_la) in by_back.iter().enumerate().take(REACH.min(m)) {
                for (la, c) in by_la.iter().enumerate() {
                    let c = c + SKIP_COST * (n - 1 - m) as f64;
                    if c < best.0 {
                        best = (c, Some((m, lb, back + 1, la)));
                    }
                }
            }
        }
    }
    let mut path: Vec<(usize, usize)> = Vec::new();
    match best.1 {
        Some((mut m, mut lb, mut back, mut la)) => loop {
            path.push((m, lb));
            let a = m - back;
            match from[m][lb][back - 1][la] {
                Some((back2, lp)) => {
                    (m, lb, back, la) = (a, la, back2, lp);
                }
                None => {
                    path.push((a, la));
                    break;
                }
            }
        },
        None if n > 0 => {
            // One frame (or a path of one): the middle posed frame, as fitted.
            path.push((n / 2, 0));
        }
        None => {}
    }
    path
}
