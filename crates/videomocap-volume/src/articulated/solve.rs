//! Levenberg–Marquardt over the pose (the root, the ball joints' rotations, the hinges' bends;
//! 28 degrees of freedom) and, when the body is being read, the body's lengths, widths and radii
//! too. Two kinds of residual: every point's distance to the nearest capsule's surface (robust:
//! Cauchy, so points no body explains — a floor sheet, ghost voxels — weigh little), and every
//! capsule's coverage (three points on its axis each want a data point within one radius).
//! Each residual moves with the part it lies on; its derivative by a rotation about pivot `o` is
//! `−((c − o) × n)`, by a hinge about axis `a` that dotted with `a`, by the root's translation
//! `−n` (`c` the point on the axis, `n` the unit direction from it to the data point).

use super::model::{Part, Pose, Posed, RADII, SEGMENTS, SubjectBody, side_joints};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{DMatrix, DVector, Point3, Rotation3, Vector3};
use videomocap_core::skeleton::Joint;

/// Degrees of freedom of the pose.
pub(crate) const POSE_DOF: usize = 28;
/// Degrees of freedom of the body: three spine lengths, four limb lengths, shoulder and hip
/// half-widths, the foot's length, and the radii.
pub(crate) const BODY_DOF: usize = RADIUS_COL + RADII;
/// The body's column of the foot's length (after [`POSE_DOF`]).
const FOOT_COL: usize = 9;
/// The body's first radius column (after [`POSE_DOF`]).
const RADIUS_COL: usize = 10;
/// Where each coverage sample sits along its capsule's axis.
const COVER_AT: [f64; 3] = [0.15, 0.5, 0.85];

/// One frame's points as the fit uses them.
pub(crate) struct FrameData {
    /// The points (surface points, thinned).
    pub points: Vec<Point3<f64>>,
    tree: ImmutableKdTree<f64, 3>,
    /// Scale of the robust loss, metres.
    pub sigma_m: f64,
}

impl FrameData {
    /// The fit's view of `points` with the robust loss's scale `sigma_m`.
    pub(crate) fn new(points: Vec<Point3<f64>>, sigma_m: f64) -> FrameData {
        let coords: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        FrameData {
            tree: ImmutableKdTree::new_from_slice(&coords),
            points,
            sigma_m,
        }
    }
    fn nearest(&self, q: &Point3<f64>) -> Option<Point3<f64>> {
        if self.points.is_empty() {
            return None;
        }
        let n = self.tree.nearest_one::<SquaredEuclidean>(&[q.x, q.y, q.z]);
        self.points.get(n.item as usize).copied()
    }
}

/// How well a pose explains a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Quality {
    /// The robust cost (lower is better).
    pub cost: f64,
    /// Share of the points farther than two robust scales from every capsule's surface.
    pub unexplained: f64,
    /// The segment with the worst coverage and its gap beyond its radius, metres.
    pub worst_gap: (usize, f64),
}

/// A capsule in space, with what the nearest-capsule search reuses for every point: its axis
/// `ab`, that squared, and its bounding sphere (centre `mid`, radius `reach`).
struct Capsule {
    a: Point3<f64>,
    b: Point3<f64>,
    r: f64,
    ab: Vector3<f64>,
    l2: f64,
    mid: Point3<f64>,
    reach: f64,
}

impl Capsule {
    fn new(a: Point3<f64>, b: Point3<f64>, r: f64) -> Capsule {
        let ab = b - a;
        let l2 = ab.norm_squared();
        Capsule {
            a,
            b,
            r,
            ab,
            l2,
            mid: a + ab * 0.5,
            reach: 0.5 * l2.sqrt() + r,
        }
    }

    /// The point of the capsule's axis nearest `p` and its parameter along it.
    fn closest(&self, p: &Point3<f64>) -> (Point3<f64>, f64) {
        let t = if self.l2 > 1e-18 {
            ((p - self.a).dot(&self.ab) / self.l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (self.a + self.ab * t, t)
    }

    /// Whether every point of this capsule's surface lies farther than `d` from `p` (then it
    /// cannot be the nearest): the bounding sphere's surface is farther, with a margin.
    fn beyond(&self, p: &Point3<f64>, d: f64) -> bool {
        let bound = d + self.reach + 1e-9;
        bound < 0.0 || (p - self.mid).norm_squared() > bound * bound
    }
}

fn capsules(posed: &Posed, body: &SubjectBody) -> Vec<Capsule> {
    SEGMENTS
        .iter()
        .map(|s| {
            let a = posed.joints[s.a];
            let mut b = posed.end(s);
            let r = body.radius_m[s.radius].max(1e-3);
            if s.cap {
                let d = b - a;
                let len = d.norm();
                if len > 1e-9 {
                    b = a + d * ((len - r).max(0.3 * len) / len);
                }
            }
            Capsule::new(a, b, r)
        })
        .collect()
}

/// A sparse Jacobian row.
struct Row {
    idx: [usize; 24],
    val: [f64; 24],
    n: usize,
}

impl Row {
    fn new() -> Row {
        Row {
            idx: [0; 24],
            val: [0.0; 24],
            n: 0,
        }
    }
    fn push(&mut self, i: usize, v: f64) {
        if self.n < 24 {
            self.idx[self.n] = i;
            self.val[self.n] = v;
            self.n += 1;
        }
    }
    fn rot(&mut self, first: usize, lever: Vector3<f64>, n: &Vector3<f64>) {
        let g = -lever.cross(n);
        for k in 0..3 {
            self.push(first + k, g[k]);
        }
    }
}

/// The Jacobian row of a residual at axis point `c` (parameter `t` on segment `seg`) whose value
/// falls as `c` moves along `n`; body columns when `with_body`.
fn row(
    seg: usize,
    c: &Point3<f64>,
    t: f64,
    n: &Vector3<f64>,
    posed: &Posed,
    with_body: bool,
) -> Row {
    let j = &posed.joints;
    let root = j[Joint::Pelvis];
    let mut r = Row::new();
    for k in 0..3 {
        r.push(k, -n[k]);
    }
    r.rot(3, c - root, n);
    let part = SEGMENTS[seg].part;
    match part {
        Part::Pelvis | Part::Thigh(_) | Part::Shank(_) | Part::Foot(_) => {}
        _ => r.rot(6, c - root, n),
    }
    match part {
        Part::Head => r.rot(9, c - j[Joint::Neck], n),
        Part::UpperArm(k) | Part::Forearm(k) => {
            let [sh, el, ..] = side_joints(k);
            r.rot(12 + 3 * k, c - j[sh], n);
            if let Part::Forearm(_) = part {
                let axis = -(posed.upper_arm[k] * Vector3::x());
                r.push(18 + k, -axis.dot(&(c - j[el]).cross(n)));
            }
        }
        Part::Thigh(k) | Part::Shank(k) | Part::Foot(k) => {
            let [.., hp, kn, _] = side_joints(k);
            r.rot(20 + 3 * k, c - j[hp], n);
            // The foot turns with the shank about the knee.
            if let Part::Shank(_) | Part::Foot(_) = part {
                let axis = posed.thigh[k] * Vector3::x();
                r.push(26 + k, -axis.dot(&(c - j[kn]).cross(n)));
            }
        }
        _ => {}
    }
    if with_body {
        body_columns(&mut r, seg, t, n, posed);
    }
    r
}

/// The body's columns of a row (see [`row`]): lengths move the bone's far end (`t` of it on the
/// bone itself) and everything beyond; widths move the shoulders or hips apart; the radius
/// moves the surface.
fn body_columns(r: &mut Row, seg: usize, t: f64, n: &Vector3<f64>, posed: &Posed) {
    let j = &posed.joints;
    let s = SEGMENTS[seg];
    let dir = |a: Joint, b: Joint| (j[b] - j[a]).try_normalize(1e-9).unwrap_or(Vector3::y());
    let mut length = |col: usize, u: Vector3<f64>, share: f64| {
        r.push(POSE_DOF + col, -share * n.dot(&u));
    };
    use Joint::*;
    let spine = dir(Pelvis, Chest);
    let upper = dir(Chest, Neck);
    match s.part {
        Part::Chest if s.a == Pelvis => length(0, spine, t),
        Part::Chest if s.a == Chest => {
            length(0, spine, 1.0);
            length(1, upper, t);
        }
        Part::Chest | Part::Head | Part::UpperArm(_) | Part::Forearm(_) => {
            length(0, spine, 1.0);
            if s.part == Part::Head {
                length(1, upper, 1.0);
                length(2, dir(Neck, HeadTop), t);
            }
        }
        _ => {}
    }
    let across = |m: &nalgebra::Matrix3<f64>, k: usize| {
        let x = m * Vector3::x();
        if k == 0 { x } else { -x }
    };
    match s.part {
        Part::Chest if s.a == LeftShoulder => {
            length(7, posed.chest * Vector3::x(), 1.0 - 2.0 * t);
        }
        Part::UpperArm(k) | Part::Forearm(k) => {
            let [sh, el, wr, ..] = side_joints(k);
            length(7, across(&posed.chest, k), 1.0);
            if let Part::UpperArm(_) = s.part {
                length(3, dir(sh, el), t);
            } else {
                length(3, dir(sh, el), 1.0);
                length(4, dir(el, wr), t);
            }
        }
        Part::Pelvis => {
            let x = (j[LeftHip] - j[RightHip])
                .try_normalize(1e-9)
                .unwrap_or(Vector3::x());
            length(8, x, 1.0 - 2.0 * t);
        }
        Part::Thigh(k) | Part::Shank(k) | Part::Foot(k) => {
            let [.., hp, kn, an] = side_joints(k);
            let x = (j[LeftHip] - j[RightHip])
                .try_normalize(1e-9)
                .unwrap_or(Vector3::x());
            length(8, if k == 0 { x } else { -x }, 1.0);
            match s.part {
                Part::Thigh(_) => length(5, dir(hp, kn), t),
                Part::Shank(_) => {
                    length(5, dir(hp, kn), 1.0);
                    length(6, dir(kn, an), t);
                }
                _ => {
                    length(5, dir(hp, kn), 1.0);
                    length(6, dir(kn, an), 1.0);
                    let u = (posed.toe[k] - j[an])
                        .try_normalize(1e-9)
                        .unwrap_or(Vector3::z());
                    length(FOOT_COL, u, t);
                }
            }
        }
        _ => {}
    }
    r.push(POSE_DOF + RADIUS_COL + s.radius, -1.0);
}

/// The normal equations of one pose.
struct Normal {
    h: DMatrix<f64>,
    g: DVector<f64>,
}

/// Weight of the coverage residuals against the points': all coverage together weighs this
/// share of all points.
const COVER_SHARE: f64 = 0.5;

/// One residual: its value `r` at axis point `c` (parameter `t` on segment `seg`), falling as
/// `c` moves along `n`, with its weight `w`.
struct Residual {
    seg: usize,
    c: Point3<f64>,
    t: f64,
    n: Vector3<f64>,
    r: f64,
    w: f64,
}

/// A pose's residuals and quality: a Levenberg–Marquardt trial needs only the quality; the
/// normal equations ([`Evaluated::normal`]) are built only for a step that is kept.
struct Evaluated {
    posed: Posed,
    residuals: Vec<Residual>,
    quality: Quality,
}

/// The capsule whose surface is nearest `p`: its signed distance, index, axis point and
/// parameter. `guess` (the previous point's, as the points run along the surface) is tried
/// first, then the others unless their bounding sphere is farther; ties go to the lower
/// index, as a plain scan in order gives them (the same result, fewer capsules measured).
fn nearest_capsule(
    p: &Point3<f64>,
    caps: &[Capsule],
    guess: usize,
) -> (f64, usize, Point3<f64>, f64) {
    let mut best = (f64::INFINITY, 0, Point3::origin(), 0.0);
    for s in std::iter::once(guess).chain((0..caps.len()).filter(|&s| s != guess)) {
        let Some(c) = caps.get(s) else { continue };
        if c.beyond(p, best.0) {
            continue;
        }
        let (q, t) = c.closest(p);
        let d = (p - q).norm() - c.r;
        if d < best.0 || (d == best.0 && s < best.1) {
            best = (d, s, q, t);
        }
    }
    best
}

/// Every point's distance to the nearest capsule's surface (Cauchy-weighted) and every capsule's
/// coverage, at `pose`.
fn evaluate(pose: &Pose, body: &SubjectBody, data: &FrameData) -> Evaluated {
    let posed = pose.posed(body);
    let caps = capsules(&posed, body);
    let sigma2 = data.sigma_m * data.sigma_m;
    let mut cost = 0.0;
    let mut far = 0usize;
    let mut residuals = Vec::with_capacity(data.points.len() + caps.len() * COVER_AT.len());
    let mut guess = 0;
    for p in &data.points {
        let (d, seg, c, t) = nearest_capsule(p, &caps, guess);
        guess = seg;
        let Some(n) = (p - c).try_normalize(1e-9) else {
            continue;
        };
        let w = 1.0 / (1.0 + d * d / sigma2);
        cost += 0.5 * sigma2 * (1.0 + d * d / sigma2).ln();
        if d.abs() > 2.0 * data.sigma_m {
            far += 1;
        }
        residuals.push(Residual {
            seg,
            c,
            t,
            n,
            r: d,
            w,
        });
    }
    let samples = (caps.len() * COVER_AT.len()) as f64;
    let w_cover = COVER_SHARE * data.points.len() as f64 / samples;
    let mut worst_gap = (0, 0.0f64);
    for (seg, cap) in caps.iter().enumerate() {
        for t in COVER_AT {
            let at = cap.a + (cap.b - cap.a) * t;
            let Some(q) = data.nearest(&at) else { continue };
            let gap = (q - at).norm() - cap.r;
            if gap > worst_gap.1 {
                worst_gap = (seg, gap);
            }
            if gap <= 0.0 {
                continue;
            }
            let Some(n) = (q - at).try_normalize(1e-9) else {
                continue;
            };
            cost += 0.5 * w_cover * gap * gap;
            residuals.push(Residual {
                seg,
                c: at,
                t,
                n,
                r: gap,
                w: w_cover,
            });
        }
    }
    Evaluated {
        posed,
        residuals,
        quality: Quality {
            cost,
            unexplained: far as f64 / data.points.len().max(1) as f64,
            worst_gap,
        },
    }
}

impl Evaluated {
    /// The normal equations `JᵀWJ`, `JᵀWr` of the residuals; of `JᵀWJ` only the lower triangle,
    /// which is all the Cholesky factorisation reads.
    fn normal(&self, with_body: bool) -> Normal {
        let dof = POSE_DOF + if with_body { BODY_DOF } else { 0 };
        let mut h = DMatrix::zeros(dof, dof);
        let mut g = DVector::zeros(dof);
        let hs = h.as_mut_slice();
        for e in &self.residuals {
            let row = row(e.seg, &e.c, e.t, &e.n, &self.posed, with_body);
            let (idx, val) = (&row.idx[..row.n], &row.val[..row.n]);
            for (k, (&ia, &a)) in idx.iter().zip(val).enumerate() {
                let va = a * e.w;
                g[ia] += va * e.r;
                // A pose's row lists its columns in increasing order (see [`row`]): the lower
                // triangle is the entries up to this one.
                let upto = if with_body { idx.len() } else { k + 1 };
                for (&ib, &b) in idx[..upto].iter().zip(&val[..upto]) {
                    // Column-major: entry (ia, ib), lower triangle only.
                    if ia >= ib {
                        hs[ib * dof + ia] += va * b;
                    }
                }
            }
        }
        Normal { h, g }
    }
}

/// The pose (and body) moved by the step `d`, within the joints' limits.
fn step(pose: &Pose, body: &SubjectBody, d: &DVector<f64>) -> (Pose, SubjectBody) {
    let v = |i: usize| Vector3::new(d[i], d[i + 1], d[i + 2]);
    let mut p = *pose;
    let rp = pose.pelvis;
    let rc = pose.pelvis * pose.chest;
    p.root += v(0);
    p.pelvis = Rotation3::from_scaled_axis(v(3)) * pose.pelvis;
    // A global turn ω of a part whose parent's frame is R becomes exp(Rᵀω) on its local frame.
    let local = |parent: &Rotation3<f64>, w: Vector3<f64>, r: &Rotation3<f64>| {
        Rotation3::from_scaled_axis(parent.inverse() * w) * r
    };
    p.chest = local(&rp, v(6), &pose.chest);
    p.head = local(&rc, v(9), &pose.head);
    for k in 0..2 {
        p.upper_arm[k] = local(&rc, v(12 + 3 * k), &pose.upper_arm[k]);
        p.thigh[k] = local(&rp, v(20 + 3 * k), &pose.thigh[k]);
        p.elbow[k] += d[18 + k];
        p.knee[k] += d[26 + k];
    }
    p.limit();
    let mut b = body.clone();
    if d.len() > POSE_DOF {
        let e = |i: usize| d[POSE_DOF + i];
        for k in 0..3 {
            b.spine_m[k] = (b.spine_m[k] + e(k)).max(0.02);
        }
        for k in 0..4 {
            b.limb_m[k] = (b.limb_m[k] + e(3 + k)).max(0.05);
        }
        b.shoulder.x = (b.shoulder.x + e(7)).max(0.03);
        b.hip.x = (b.hip.x + e(8)).max(0.02);
        b.foot_m = (b.foot_m + e(FOOT_COL)).clamp(FOOT_MIN_M, 0.35);
        for k in 0..RADII {
            b.radius_m[k] = (b.radius_m[k] + e(RADIUS_COL + k)).clamp(0.01, 0.3);
        }
    }
    (p, b)
}

/// The shortest foot (a body without feet, as the capsule volumes have, keeps one this long,
/// inside its shank's round end).
const FOOT_MIN_M: f64 = 0.01;

/// A fit's result.
#[derive(Debug, Clone)]
pub(crate) struct Fit {
    pub pose: Pose,
    pub body: SubjectBody,
    pub quality: Quality,
}

/// Levenberg–Marquardt from `pose` for at most `iterations` steps; the body too when
/// `with_body`.
pub(crate) fn fit(
    pose: &Pose,
    body: &SubjectBody,
    data: &FrameData,
    iterations: usize,
    with_body: bool,
) -> Fit {
    let first = evaluate(pose, body, data);
    let mut eq = first.normal(with_body);
    let mut cur = Fit {
        pose: *pose,
        body: body.clone(),
        quality: first.quality,
    };
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        let mut a = eq.h.clone();
        for i in 0..a.nrows() {
            a[(i, i)] += lambda * a[(i, i)] + 1e-9;
        }
        let Some(chol) = a.cholesky() else {
            lambda *= 10.0;
            continue;
        };
        let d = -chol.solve(&eq.g);
        let (p, b) = step(&cur.pose, &cur.body, &d);
        let next = evaluate(&p, &b, data);
        if next.quality.cost < cur.quality.cost {
            let gain = (cur.quality.cost - next.quality.cost) / cur.quality.cost.max(1e-12);
            cur = Fit {
                pose: p,
                body: b,
                quality: next.quality,
            };
            eq = next.normal(with_body);
            lambda = (lambda * 0.3).max(1e-7);
            if gain < 1e-4 {
                break;
            }
        } else {
            lambda *= 10.0;
            if lambda > 1e4 {
                break;
            }
        }
    }
    cur
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::articulated::model::RADII;

    fn body() -> SubjectBody {
        SubjectBody {
            spine_m: [0.25, 0.25, 0.25],
            limb_m: [0.3, 0.25, 0.42, 0.4],
            shoulder: Vector3::new(0.18, 0.2, 0.0),
            hip: Vector3::new(0.1, -0.02, 0.0),
            foot_m: 0.14,
            radius_m: [0.13, 0.12, 0.06, 0.08, 0.1, 0.05, 0.04, 0.07, 0.05, 0.04],
        }
    }

    /// Points on the capsules' surfaces of `pose`, spaced about 2 cm.
    fn surface(pose: &Pose, b: &SubjectBody) -> Vec<Point3<f64>> {
        let caps = capsules(&pose.posed(b), b);
        let mut out = Vec::new();
        for c in &caps {
            let u = (c.b - c.a).normalize();
            let e1 = u
                .cross(&Vector3::x())
                .try_normalize(1e-6)
                .unwrap_or(Vector3::z());
            let e2 = u.cross(&e1);
            let steps = ((c.b - c.a).norm() / 0.02).ceil() as usize;
            let mut ring = |at: Point3<f64>, along: f64| {
                let r = c.r * (1.0 - along * along).max(0.0).sqrt();
                for k in 0..12 {
                    let a = k as f64 / 12.0 * std::f64::consts::TAU;
                    let p = at + u * (along * c.r) + (e1 * a.cos() + e2 * a.sin()) * r;
                    // Inside another capsule: not on the body's surface.
                    if caps.iter().all(|o| {
                        let (q, _) = o.closest(&p);
                        (p - q).norm() >= o.r - 1e-6
                    }) {
                        out.push(p);
                    }
                }
            };
            for s in 0..=steps {
                ring(c.a + (c.b - c.a) * (s as f64 / steps as f64), 0.0);
            }
            // The round ends.
            for along in [0.4, 0.7, 0.92, 1.0] {
                ring(c.b, along);
                ring(c.a, -along);
            }
        }
        out
    }

    #[test]
    fn the_pruned_nearest_capsule_search_is_the_plain_scan() {
        let b = body();
        let mut pose = Pose::default_standing();
        pose.knee = [0.7, 0.2];
        pose.elbow = [1.1, 0.3];
        let caps = capsules(&pose.posed(&b), &b);
        let mut guess = 0;
        // Points on a grid through and around the body, some on the shared joints.
        for i in 0..4000 {
            let (x, y, z) = (i % 16, (i / 16) % 25, i / 400);
            let p = Point3::new(
                -0.6 + 0.08 * x as f64,
                -0.1 + 0.08 * y as f64,
                -0.4 + 0.09 * z as f64,
            );
            let mut plain = (f64::INFINITY, 0, Point3::origin(), 0.0);
            for (s, c) in caps.iter().enumerate() {
                let (q, t) = c.closest(&p);
                let d = (p - q).norm() - c.r;
                if d < plain.0 {
                    plain = (d, s, q, t);
                }
            }
            let pruned = nearest_capsule(&p, &caps, guess);
            assert_eq!(pruned, plain, "at {p:?}");
            guess = (guess + 7) % caps.len();
        }
    }

    #[test]
    fn the_fit_finds_a_pose_from_a_start_a_quarter_radian_off() {
        let b = body();
        let mut truth = Pose::default_standing();
        truth.root = Point3::new(0.1, 1.0, 0.3);
        truth.pelvis = Rotation3::from_euler_angles(0.0, 0.6, 0.0);
        truth.upper_arm[0] = Rotation3::from_euler_angles(0.0, 0.0, 1.2);
        truth.elbow = [0.9, 0.2];
        truth.knee = [0.6, 0.1];
        truth.thigh[0] = Rotation3::from_euler_angles(-0.5, 0.0, 0.0);
        let data = FrameData::new(surface(&truth, &b), 0.03);
        let mut start = truth;
        start.root += Vector3::new(0.05, -0.04, 0.03);
        start.pelvis = Rotation3::from_euler_angles(0.0, 0.35, 0.1);
        start.upper_arm[0] = Rotation3::from_euler_angles(0.2, 0.0, 0.9);
        start.elbow = [0.5, 0.4];
        let f = fit(&start, &b, &data, 40, false);
        let (a, t) = (f.pose.posed(&b).joints, truth.posed(&b).joints);
        for (j, p) in a.iter() {
            let d = (p - t[j]).norm();
            assert!(d < 0.02, "{} is {d} m off", j.name());
        }
        assert!(f.quality.unexplained < 0.01);
    }

    #[test]
    fn the_body_fit_reads_lengths_and_radii_from_the_points() {
        let truth_body = body();
        let mut pose = Pose::default_standing();
        pose.elbow = [1.2, 1.0];
        pose.knee = [0.8, 0.9];
        pose.upper_arm[1] = Rotation3::from_euler_angles(0.0, 0.0, -0.8);
        let data = FrameData::new(surface(&pose, &truth_body), 0.03);
        let mut start = truth_body.clone();
        start.limb_m = start.limb_m.map(|l| l * 1.12);
        start.foot_m = 0.09;
        start.radius_m = [0.09; RADII];
        let f = fit(&pose, &start, &data, 60, true);
        assert!(
            (f.body.foot_m - truth_body.foot_m).abs() < 0.03,
            "foot {}",
            f.body.foot_m
        );
        for k in 0..4 {
            let d = (f.body.limb_m[k] - truth_body.limb_m[k]).abs();
            assert!(
                d < 0.02,
                "limb {k}: {} vs {}",
                f.body.limb_m[k],
                truth_body.limb_m[k]
            );
        }
        let d = (f.body.radius_m[7] - truth_body.radius_m[7]).abs();
        assert!(d < 0.01, "thigh radius {}", f.body.radius_m[7]);
    }

    #[test]
    fn a_body_without_feet_is_read_with_its_feet_shrunk() {
        let mut truth_body = body();
        truth_body.foot_m = FOOT_MIN_M;
        let mut pose = Pose::default_standing();
        pose.knee = [0.4, 0.2];
        let data = FrameData::new(surface(&pose, &truth_body), 0.03);
        // Started with long feet: they come back within the shanks' round ends and the radius
        // beyond (a shorter foot is buried in the shank and costs nothing either way).
        let mut start = body();
        start.foot_m = 0.2;
        let f = fit(&pose, &start, &data, 60, true);
        assert!(f.body.foot_m < 0.1, "foot {}", f.body.foot_m);
    }

    #[test]
    fn the_feet_tell_the_front_from_the_back() {
        // Nearly straight legs: without feet, a body turned round explains the points almost
        // as well (only the slight bends differ); the feet make it clearly worse.
        let b = body();
        let mut truth = Pose::default_standing();
        truth.root = Point3::new(0.0, 1.0, 0.0);
        truth.knee = [0.15, 0.05];
        let data = FrameData::new(surface(&truth, &b), 0.03);
        let mut turned = truth;
        turned.pelvis = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
        let (right, wrong) = (
            fit(&truth, &b, &data, 20, false),
            fit(&turned, &b, &data, 20, false),
        );
        assert!(
            wrong.quality.cost > 2.0 * right.quality.cost,
            "{} vs {}",
            wrong.quality.cost,
            right.quality.cost
        );
    }
}
