//! Rigid bodies from the skeleton curve (paper §4, Fig. 6–9): a head sphere, a torso cylinder
//! between the chest and pelvis nodes grown to the head and hips, and two cylinders per limb
//! split at the curve point farthest from the root–leaf segment; points reassigned to the body
//! that contains them.

use super::curve::SkeletonCurve;
use nalgebra::{Point3, Vector3};
use videomocap_core::skeleton::{Joint, SubjectModel, segment_distance};

/// Body fitting settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyParams {
    /// A limb whose farthest curve point lies closer than this fraction of the root–leaf
    /// distance to that segment is straight (no articulation, §4).
    pub straight_fraction: f64,
    /// Share of the root torso's points the initial cylinder radius bounds (the rest are
    /// shoulders and hips poking out).
    pub torso_quantile: f64,
}

impl Default for BodyParams {
    fn default() -> Self {
        BodyParams {
            straight_fraction: 0.08,
            torso_quantile: 0.9,
        }
    }
}

/// A cylinder from `a` to `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Start of the axis.
    pub a: Point3<f64>,
    /// End of the axis.
    pub b: Point3<f64>,
    /// Radius, metres.
    pub radius: f64,
}

/// One limb's fitted bodies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimbFit {
    /// Shoulder or hip: the last curve point inside the torso cylinder.
    pub root: Point3<f64>,
    /// Elbow or knee: the separating curve point, `None` when the limb is straight.
    pub split: Option<Point3<f64>>,
    /// Wrist or ankle: one lower-limb radius in from the limb's tip along its axis.
    pub end: Point3<f64>,
    /// Upper and lower radii (average distance of surface points to the axes).
    pub radii: [f64; 2],
}

/// Which body a point ends up in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Head,
    Torso,
    /// Limb k (0, 1 arms; 2, 3 legs), upper segment.
    Upper(u8),
    /// Limb k, lower segment.
    Lower(u8),
}

/// The bodies of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyFit {
    /// Head sphere centre and radius.
    pub head_centre: Point3<f64>,
    /// See `head_centre`.
    pub head_radius: f64,
    /// Top of the head along the head's axis.
    pub head_top: Point3<f64>,
    /// Torso cylinder, from the bottom (hips) to the top (neck).
    pub torso: Cylinder,
    /// Chest and pelvis branch nodes (input space).
    pub chest: Point3<f64>,
    /// See `chest`.
    pub pelvis: Point3<f64>,
    /// arm1, arm2, leg1, leg2; `None` for an arm the skeleton curve does not show (it lies
    /// against the trunk; see [`SkeletonCurve::arms`]).
    pub limbs: [Option<LimbFit>; 4],
    /// Part of each point (same indexing as the input).
    pub parts: Vec<Part>,
}

fn centroid(points: impl Iterator<Item = Point3<f64>>) -> Option<Point3<f64>> {
    let (mut s, mut n) = (Vector3::zeros(), 0usize);
    for p in points {
        s += p.coords;
        n += 1;
    }
    (n > 0).then(|| Point3::from(s / n as f64))
}

fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Distance from `p` to the infinite line through `a` along unit `u`.
fn axis_distance(p: &Point3<f64>, a: &Point3<f64>, u: &Vector3<f64>) -> f64 {
    let d = p - a;
    (d - u * d.dot(u)).norm()
}

/// Fits the bodies. `input` are the embedded points' input positions, `surface[i]` says whether
/// point i lies on the volume's surface.
pub fn fit(
    curve: &SkeletonCurve,
    input: &[Point3<f64>],
    surface: &[bool],
    params: &BodyParams,
) -> BodyFit {
    let head = Head::new(curve, input);
    let (chest, pelvis) = trunk_ends(curve, input);
    let trunk = Trunk::new(curve, input, params, &head, chest, pelvis);
    let head_top = head.top(input, trunk.cylinder().b, trunk.u);
    let mut parts: Vec<Part> = vec![Part::Torso; input.len()];
    for &i in &head.points {
        parts[i] = Part::Head;
    }
    let limbs: [Option<LimbFit>; 4] =
        std::array::from_fn(|k| fit_limb(curve, input, surface, params, &trunk, k, &mut parts));
    // Reassociation: points inside the head sphere belong to the head, inside the torso
    // cylinder to the torso, whatever they were before.
    for (i, p) in input.iter().enumerate() {
        if (p - head.centre).norm() <= head.radius {
            parts[i] = Part::Head;
        } else if trunk.contains(p) {
            parts[i] = Part::Torso;
        }
    }
    BodyFit {
        head_centre: head.centre,
        head_radius: head.radius,
        head_top,
        torso: trunk.cylinder(),
        chest,
        pelvis,
        limbs,
        parts,
    }
}

/// The input points of the curve's `nodes`.
fn points_of(curve: &SkeletonCurve, nodes: &[usize]) -> Vec<usize> {
    nodes
        .iter()
        .flat_map(|&k| curve.members[k].iter().copied())
        .collect()
}

/// The head sphere (Fig. 6): centre = the merged head curve points, radius = the farthest head
/// point.
struct Head {
    points: Vec<usize>,
    centre: Point3<f64>,
    radius: f64,
}

impl Head {
    /// The head sphere of the curve's head branch.
    fn new(curve: &SkeletonCurve, input: &[Point3<f64>]) -> Head {
        let points = points_of(curve, &curve.head);
        let centre =
            centroid(points.iter().map(|&i| input[i])).unwrap_or(curve.points[curve.head[0]]);
        let radius = points
            .iter()
            .map(|&i| (input[i] - centre).norm())
            .fold(0.0, f64::max);
        Head {
            points,
            centre,
            radius,
        }
    }

    /// The top of the head along its axis from the `neck` (`up`, the trunk's axis, when the
    /// centre is at the neck).
    fn top(&self, input: &[Point3<f64>], neck: Point3<f64>, up: Vector3<f64>) -> Point3<f64> {
        let axis = (self.centre - neck).try_normalize(1e-12).unwrap_or(up);
        let t = self
            .points
            .iter()
            .map(|&i| (input[i] - neck).dot(&axis))
            .fold((self.centre - neck).norm(), f64::max);
        neck + axis * t
    }
}

/// The chest and pelvis nodes (input space); when both limb groups leave from the same node,
/// that node's points split by the head–legs direction.
fn trunk_ends(curve: &SkeletonCurve, input: &[Point3<f64>]) -> (Point3<f64>, Point3<f64>) {
    let chest = curve.points[curve.chest];
    let pelvis = curve.points[curve.pelvis];
    if !(curve.chest == curve.pelvis || (chest - pelvis).norm() < 1e-6) {
        return (chest, pelvis);
    }
    let up = (curve.points[curve.head[0]]
        - nalgebra::center(
            &curve.points[curve.legs[0][0]],
            &curve.points[curve.legs[1][0]],
        ))
    .try_normalize(1e-12)
    .unwrap_or(Vector3::y());
    let c = curve.points[curve.chest];
    let m = &curve.members[curve.chest];
    let side = |above: bool| {
        centroid(
            m.iter()
                .map(|&i| input[i])
                .filter(|p| ((p - c).dot(&up) >= 0.0) == above),
        )
    };
    (
        side(true).unwrap_or(c + up * 0.1),
        side(false).unwrap_or(c - up * 0.1),
    )
}

/// The torso cylinder (Fig. 7), axis pelvis → chest, and the shoulder and hip geometry the
/// limbs' roots are placed by.
struct Trunk {
    pelvis: Point3<f64>,
    /// The axis's direction, pelvis → chest.
    u: Vector3<f64>,
    /// The cylinder's ends along `u` from the pelvis.
    bottom: f64,
    top: f64,
    radius: f64,
    /// Shoulder level below the neck, from the proportions scaled to this trunk.
    shoulder_drop: f64,
    /// Half the shoulder and hip widths, likewise.
    half_widths: (f64, f64),
}

impl Trunk {
    /// The cylinder through the root torso's points (radius: `params.torso_quantile` of them),
    /// grown to meet the head sphere and to bound the pelvis node's points.
    fn new(
        curve: &SkeletonCurve,
        input: &[Point3<f64>],
        params: &BodyParams,
        head: &Head,
        chest: Point3<f64>,
        pelvis: Point3<f64>,
    ) -> Trunk {
        let u = (chest - pelvis)
            .try_normalize(1e-12)
            .unwrap_or(Vector3::y());
        let mut torso_nodes = vec![curve.root, curve.chest, curve.pelvis];
        torso_nodes.dedup();
        let along = |p: &Point3<f64>| (p - pelvis).dot(&u);
        let radius = quantile(
            points_of(curve, &torso_nodes)
                .iter()
                .map(|&i| axis_distance(&input[i], &pelvis, &u))
                .collect(),
            params.torso_quantile,
        );
        let root_points = points_of(curve, &[curve.root]);
        let mut bottom = root_points
            .iter()
            .map(|&i| along(&input[i]))
            .fold(f64::INFINITY, f64::min);
        let mut top = root_points
            .iter()
            .map(|&i| along(&input[i]))
            .fold(f64::NEG_INFINITY, f64::max);
        top = top.max(along(&head.centre) - head.radius);
        bottom = points_of(curve, &[curve.pelvis])
            .iter()
            .map(|&i| along(&input[i]))
            .fold(bottom, f64::min);
        if !bottom.is_finite() || !top.is_finite() {
            bottom = -0.1;
            top = 0.1;
        }
        let m = SubjectModel::default();
        let scale = top / (m.length_to(Joint::Chest) + m.length_to(Joint::Neck));
        let half_widths = (
            m.shoulder_width_m / 2.0 * scale,
            m.length_to(Joint::LeftHip) * scale,
        );
        let shoulder_drop = {
            let across = m.shoulder_width_m / 2.0;
            let up = m.length_to(Joint::LeftShoulder);
            let rise = (up * up - across * across).max(0.0).sqrt();
            (m.length_to(Joint::Neck) - rise).max(0.0) * scale
        };
        Trunk {
            pelvis,
            u,
            bottom,
            top,
            radius,
            shoulder_drop,
            half_widths,
        }
    }

    /// How far along the axis from the pelvis `p` lies.
    fn along(&self, p: &Point3<f64>) -> f64 {
        (p - self.pelvis).dot(&self.u)
    }

    /// Whether `p` lies inside the cylinder.
    fn contains(&self, p: &Point3<f64>) -> bool {
        let t = self.along(p);
        t >= self.bottom && t <= self.top && axis_distance(p, &self.pelvis, &self.u) <= self.radius
    }

    /// The cylinder, from the bottom (hips) to the top (neck).
    fn cylinder(&self) -> Cylinder {
        Cylinder {
            a: self.pelvis + self.u * self.bottom,
            b: self.pelvis + self.u * self.top,
            radius: self.radius,
        }
    }
}

/// Limb `k` (Fig. 8): the curve inside the torso ignored, split at the farthest curve point,
/// its points given their parts in `parts`; `None` for an arm the curve does not show.
fn fit_limb(
    curve: &SkeletonCurve,
    input: &[Point3<f64>],
    surface: &[bool],
    params: &BodyParams,
    trunk: &Trunk,
    k: usize,
    parts: &mut [Part],
) -> Option<LimbFit> {
    let (chain, attach) = match k {
        0 | 1 => (&curve.arms[k], curve.chest),
        _ => (&curve.legs[k - 2], curve.pelvis),
    };
    if chain.is_empty() {
        return None;
    }
    let mut path = vec![curve.points[attach]];
    path.extend(chain.iter().map(|&n| curve.points[n]));
    let (exit, last_in) = exit_point(&path, trunk);
    let leaf = path[path.len() - 1];
    let between = &path[last_in + 1..path.len() - 1];
    // Split candidates lie in the middle 60 % of the root–leaf segment: the curve bends where
    // it leaves the trunk too, and an elbow or knee is never there.
    let farthest_from = |root: &Point3<f64>| {
        let axis = leaf - root;
        between
            .iter()
            .filter(|p| {
                let t = (*p - root).dot(&axis) / axis.norm_squared().max(1e-18);
                (0.2..=0.8).contains(&t)
            })
            .map(|p| (segment_distance(p, root, &leaf), *p))
            .max_by(|a, b| a.0.total_cmp(&b.0))
    };
    let reach = (leaf - exit).norm();
    let split = farthest_from(&exit)
        .filter(|(d, _)| *d >= params.straight_fraction * reach)
        .map(|(_, p)| p);
    // The upper segment's axis: through the elbow or knee (the leaf of a straight limb) and
    // the first curve point outside the trunk (the exit point cuts the corner).
    let toward = split.unwrap_or(leaf);
    let from = between
        .first()
        .filter(|p| (toward - **p).norm() > 0.25 * (toward - exit).norm())
        .copied()
        .unwrap_or(exit);
    let root = joint_root(trunk, k, exit, from, toward);
    let limb = Segments {
        root,
        knee: split.unwrap_or_else(|| nalgebra::center(&root, &leaf)),
        leaf,
        fallback: trunk.u,
    };
    let (radii, end) = limb.assign(&points_of(curve, chain), input, surface, k, parts);
    Some(LimbFit {
        root,
        split,
        end,
        radii,
    })
}

/// Where the limb's `path` (attachment first) leaves the torso cylinder: between the last
/// curve point inside it and the next one, found by bisection; and that last point's index.
fn exit_point(path: &[Point3<f64>], trunk: &Trunk) -> (Point3<f64>, usize) {
    let last_in = path
        .iter()
        .rposition(|p| trunk.contains(p))
        .map_or(0, |i| i.min(path.len() - 2));
    let (mut lo, mut hi) = (path[last_in], path[last_in + 1]);
    if trunk.contains(&lo) {
        for _ in 0..20 {
            let mid = nalgebra::center(&lo, &hi);
            if trunk.contains(&mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }
    (lo, last_in)
}

/// Beyond the paper: the shoulder and hip joints lie inside the trunk, not where the curve
/// leaves it (`exit`). The joint is on the upper segment's axis (`from` → `toward`, the elbow
/// or knee), where it crosses the shoulder level (the subject's proportions below the neck) or
/// the pelvis level; when the segment lies nearly across the trunk (an arm held out in front,
/// a thigh raised), the axis point nearest the trunk axis at that level, but no nearer than
/// half the shoulder (hip) width: a horizontal arm's axis passes through the trunk's middle.
fn joint_root(
    trunk: &Trunk,
    k: usize,
    exit: Point3<f64>,
    from: Point3<f64>,
    toward: Point3<f64>,
) -> Point3<f64> {
    let u = trunk.u;
    let level = if k < 2 {
        trunk.top - trunk.shoulder_drop
    } else {
        0.0
    };
    let centre = trunk.pelvis + u * level;
    match (toward - from).try_normalize(1e-9) {
        Some(d) if d.dot(&u).abs() >= 0.5 => {
            toward + d * ((level - trunk.along(&toward)) / d.dot(&u))
        }
        Some(d) => {
            let mut p = toward + d * (centre - toward).dot(&d);
            let half = if k < 2 {
                trunk.half_widths.0
            } else {
                trunk.half_widths.1
            };
            let off = |q: &Point3<f64>| axis_distance(q, &trunk.pelvis, &u);
            if off(&p) < half {
                let (mut a, mut b) = (0.0, (toward - p).norm());
                for _ in 0..30 {
                    let m = 0.5 * (a + b);
                    if off(&(p + d * m)) < half {
                        a = m;
                    } else {
                        b = m;
                    }
                }
                p += d * b;
            }
            p
        }
        None => exit + u * (level - trunk.along(&exit)),
    }
}

/// A limb's two segments: root → knee (elbow) → leaf; `fallback` is the direction of a
/// segment of no length.
struct Segments {
    root: Point3<f64>,
    knee: Point3<f64>,
    leaf: Point3<f64>,
    fallback: Vector3<f64>,
}

impl Segments {
    /// Gives each of the limb's `points` its part (`Upper(k)` or `Lower(k)`) by the
    /// separating plane at the knee, bisecting the angle between the two axes; returns the
    /// upper and lower radii (mean distance of the surface points to the axes) and the wrist
    /// or ankle: the leaf sits inside the end cap, and the joint is one radius in from the tip.
    fn assign(
        &self,
        points: &[usize],
        input: &[Point3<f64>],
        surface: &[bool],
        k: usize,
        parts: &mut [Part],
    ) -> ([f64; 2], Point3<f64>) {
        let (root, knee, leaf) = (self.root, self.knee, self.leaf);
        let d_up = (knee - root).try_normalize(1e-12).unwrap_or(self.fallback);
        let d_low = (leaf - knee).try_normalize(1e-12).unwrap_or(d_up);
        let normal = (d_up + d_low).try_normalize(1e-12).unwrap_or(d_low);
        let (mut upper_r, mut lower_r) = (Vec::new(), Vec::new());
        let mut tip = 0.0f64;
        for &i in points {
            let p = &input[i];
            let lower = (p - knee).dot(&normal) >= 0.0;
            parts[i] = if lower {
                Part::Lower(k as u8)
            } else {
                Part::Upper(k as u8)
            };
            if lower {
                tip = tip.max((p - knee).dot(&d_low));
            }
            if surface[i] {
                if lower {
                    lower_r.push(axis_distance(p, &knee, &d_low));
                } else {
                    upper_r.push(axis_distance(p, &root, &d_up));
                }
            }
        }
        let mean = |v: &[f64]| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let radii = [mean(&upper_r), mean(&lower_r)];
        let tip = tip.max((leaf - knee).dot(&d_low));
        let end = knee + d_low * (tip - radii[1]).max((leaf - knee).dot(&d_low) * 0.5);
        (radii, end)
    }
}
