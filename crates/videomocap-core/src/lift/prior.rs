//! The pose prior learned from motion capture: how likely each group of bones' directions is in
//! the body's own frames. It is what decides each bone's depth root beside the image
//! (`ambiguity`), in place of hand-fitted ranges of motion.
//!
//! A Gaussian mixture per group of bones (as SMPLify's pose prior fitted on CMU), over the unit
//! directions of the group's bones, each in the body frame it hangs from: the head and neck, the
//! spine and the hips in the key triangle's frame (left, up, forward), each leg's thigh and shank
//! in the pelvis's frame, each arm's upper arm and forearm with its own thigh in the key
//! triangle's frame (so the arms' swing against the legs is learned too). Right limbs are
//! mirrored onto left ones (one model for both sides), and every pose is learned mirrored too.
//! The file (`assets/pose_prior/pose_prior.json`, rebuilt by `videomocap-bench prior`, which
//! lists the takes it read) is bundled and read when first used; a corrupt or missing file is
//! refused by name.
//!
//! A group's cost is its negative log-likelihood relative to the mixture's peak, held under a
//! ceiling (a mixture with a small flat floor): a pose the prior never saw still lifts, it only
//! stops being preferred, and the frame is flagged as an unusual pose.
//!
//! One more mixture learns how the trunk stands against gravity (the key triangle's up and
//! forward directions against the world's up). The lift does not know the world's up, only the
//! camera's, which a raised or lowered camera tilts, so this one never weighs in a depth choice:
//! it only flags a body upside down or lying in the image as an unusual pose.

mod gmm;

pub use gmm::Component;
pub(super) use gmm::{Gmm, fit};

use crate::skeleton::Joint::{self, *};
use crate::skeleton::PerJoint;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The bundled prior's file, as its errors name it.
pub const BUNDLED_PRIOR: &str = "assets/pose_prior/pose_prior.json";

const BUNDLED_TEXT: &str = include_str!("../../../../assets/pose_prior/pose_prior.json");

/// What the file's first field says.
const FORMAT: &str = "videomocap-pose-prior";
/// The version this code reads.
const VERSION: u32 = 1;

/// A prior that cannot be used.
#[derive(Debug, Clone, thiserror::Error)]
pub enum PriorError {
    /// The file cannot be read.
    #[error("{path}: cannot read the pose prior: {reason}")]
    Missing {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// The file is not a pose prior this code can use.
    #[error("{path}: not a usable pose prior: {reason}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// The groups of bones the prior scores, each with its own mixture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PriorGroup {
    /// Chest → neck → head top, in the key triangle's frame.
    Head,
    /// Chest → pelvis, in the key triangle's frame.
    Spine,
    /// Pelvis → each hip, in the key triangle's frame.
    Hips,
    /// Shoulder → elbow → wrist and the same side's hip → knee, in the key triangle's frame.
    Arm(Side),
    /// Hip → knee → ankle, in the pelvis's frame.
    Leg(Side),
}

/// A limb's side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The subject's left.
    Left,
    /// The subject's right (mirrored onto the left in the prior).
    Right,
}

/// The mixtures' names in the file, in the order [`PriorGroup::model`] indexes them, then the
/// trunk's stance against gravity ([`UPRIGHT`]).
const MODEL_NAMES: [&str; 6] = ["head", "spine", "hips", "arm", "leg", "upright"];
/// Each model's dimensions: three per bone direction; the stance two (the key triangle's up
/// and forward directions' components along the world's up).
const MODEL_DIMS: [usize; 6] = [6, 3, 6, 9, 6, 2];
/// The stance's model (flags only; see the module's documentation).
const UPRIGHT: usize = 5;

impl PriorGroup {
    /// Every group scored on a full body, once each.
    pub const ALL: [PriorGroup; 7] = [
        PriorGroup::Head,
        PriorGroup::Spine,
        PriorGroup::Hips,
        PriorGroup::Leg(Side::Left),
        PriorGroup::Leg(Side::Right),
        PriorGroup::Arm(Side::Left),
        PriorGroup::Arm(Side::Right),
    ];

    fn model(self) -> usize {
        match self {
            PriorGroup::Head => 0,
            PriorGroup::Spine => 1,
            PriorGroup::Hips => 2,
            PriorGroup::Arm(_) => 3,
            PriorGroup::Leg(_) => 4,
        }
    }
}

/// The key triangle's directions in one frame: left, up, forward (unit vectors).
#[derive(Debug, Clone)]
pub(crate) struct TrunkFrame {
    pub(crate) left: Vector3<f64>,
    pub(crate) up: Vector3<f64>,
    pub(crate) forward: Vector3<f64>,
}

impl TrunkFrame {
    /// The key triangle's frame: left from the right shoulder to the left, up from the chest
    /// to the shoulders' midpoint made square to it, forward = left × up.
    pub(crate) fn of(points: &PerJoint<Point3<f64>>) -> TrunkFrame {
        let left = (points[LeftShoulder] - points[RightShoulder])
            .try_normalize(f64::EPSILON)
            .unwrap_or_else(Vector3::x);
        let mid = nalgebra::center(&points[LeftShoulder], &points[RightShoulder]);
        let down = points[Chest] - mid;
        let up = -(down - left * left.dot(&down))
            .try_normalize(f64::EPSILON)
            .unwrap_or_else(|| -left.cross(&Vector3::z()));
        // Subject's left × up = forward (right-handed space).
        TrunkFrame {
            left,
            up,
            forward: left.cross(&up),
        }
    }

    /// How far the bone from `from` to `to` points forwards (the sine of its swing from the
    /// trunk's plane; 0 where the joints coincide): a thigh's swing, read by the gait's lag.
    pub(crate) fn forward_sine(&self, from: &Point3<f64>, to: &Point3<f64>) -> f64 {
        (to - from)
            .try_normalize(f64::EPSILON)
            .map_or(0.0, |d| d.dot(&self.forward))
    }

    /// The pelvis's frame: left along the hip line, up the key triangle's up made square to
    /// it (the shoulders turn against the pelvis in a stride; a thigh's lean and its knee's
    /// hinge belong to the pelvis). Where the hips coincide or their line runs along the trunk,
    /// the key triangle's frame stands in.
    pub(crate) fn pelvis(&self, points: &PerJoint<Point3<f64>>) -> TrunkFrame {
        let hip_left = (points[LeftHip] - points[RightHip]).try_normalize(f64::EPSILON);
        let frame = hip_left.and_then(|left| {
            let up = (self.up - left * left.dot(&self.up)).try_normalize(0.1)?;
            Some(TrunkFrame {
                left,
                up,
                forward: left.cross(&up),
            })
        });
        frame.unwrap_or_else(|| self.clone())
    }

    /// The unit direction from `a` to `b` in this frame (left, up, forward), its left part
    /// negated when `mirror` (a right limb read as a left one); zeros where they coincide.
    fn direction(&self, a: &Point3<f64>, b: &Point3<f64>, mirror: bool) -> [f64; 3] {
        let d = (b - a).try_normalize(f64::EPSILON).unwrap_or_default();
        let sign = if mirror { -1.0 } else { 1.0 };
        [
            sign * d.dot(&self.left),
            d.dot(&self.up),
            d.dot(&self.forward),
        ]
    }
}

/// A group's feature vector: its bones' unit directions in the group's frame, written into
/// `out` (its first [`MODEL_DIMS`] entries). `key` is the key triangle's frame of `p`.
fn features(group: PriorGroup, p: &PerJoint<Point3<f64>>, key: &TrunkFrame, out: &mut [f64; 9]) {
    let mut put = |i: usize, d: [f64; 3]| out[3 * i..3 * i + 3].copy_from_slice(&d);
    let limb = |side: Side, left: [Joint; 3], right: [Joint; 3]| match side {
        Side::Left => (left, false),
        Side::Right => (right, true),
    };
    match group {
        PriorGroup::Head => {
            put(0, key.direction(&p[Chest], &p[Neck], false));
            put(1, key.direction(&p[Neck], &p[HeadTop], false));
        }
        PriorGroup::Spine => put(0, key.direction(&p[Chest], &p[Pelvis], false)),
        PriorGroup::Hips => {
            put(0, key.direction(&p[Pelvis], &p[LeftHip], false));
            put(1, key.direction(&p[Pelvis], &p[RightHip], false));
        }
        PriorGroup::Arm(side) => {
            let (j, mirror) = limb(
                side,
                [LeftShoulder, LeftElbow, LeftWrist],
                [RightShoulder, RightElbow, RightWrist],
            );
            let (hip, knee) = if mirror {
                (RightHip, RightKnee)
            } else {
                (LeftHip, LeftKnee)
            };
            put(0, key.direction(&p[j[0]], &p[j[1]], mirror));
            put(1, key.direction(&p[j[1]], &p[j[2]], mirror));
            put(2, key.direction(&p[hip], &p[knee], mirror));
        }
        PriorGroup::Leg(side) => {
            let (j, mirror) = limb(
                side,
                [LeftHip, LeftKnee, LeftAnkle],
                [RightHip, RightKnee, RightAnkle],
            );
            let pelvis = key.pelvis(p);
            put(0, pelvis.direction(&p[j[0]], &p[j[1]], mirror));
            put(1, pelvis.direction(&p[j[1]], &p[j[2]], mirror));
        }
    }
}

/// One group's mixture, its peak and what counts as unusual for it.
#[derive(Debug, Clone)]
struct Model {
    gmm: Gmm,
    peak: f64,
    /// The ceiling of the group's cost (nats): a pose the prior never saw pays this at most.
    ceiling: f64,
    /// The cost beyond which the group's pose is unusual (nats, under the ceiling).
    unusual: f64,
}

impl Model {
    /// The group's cost of the feature `x` (nats, at least 0, under the ceiling).
    fn cost(&self, x: &[f64]) -> f64 {
        let below = (self.peak - self.gmm.log_density(&x[..self.gmm.dims])).max(0.0);
        soft_ceiling(below, self.ceiling)
    }
}

/// The learned pose prior (see the module's documentation).
#[derive(Debug, Clone)]
pub struct PosePrior {
    models: Vec<Model>,
    /// The takes the prior was learned from.
    pub takes: Vec<String>,
}

/// The file's contents.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorFile {
    /// Always `videomocap-pose-prior`.
    pub format: String,
    /// Always 1 (the version this code reads).
    pub version: u32,
    /// What made it and from what (credit line, licence).
    pub source: String,
    /// The takes learned from.
    pub takes: Vec<String>,
    /// How many poses were learned (each also mirrored).
    pub poses: usize,
    /// Per group (`head`, `spine`, `hips`, `arm`, `leg`, `upright`): its mixture, its cost
    /// ceiling and where unusual poses begin.
    pub groups: Vec<GroupFile>,
}

/// One group in the file.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupFile {
    /// Its name: `head`, `spine`, `hips`, `arm`, `leg` or `upright`.
    pub name: String,
    /// Its feature's dimensions.
    pub dims: usize,
    /// The cost's ceiling, nats.
    pub ceiling: f64,
    /// How far below the mixture's peak (nats) a pose is unusual: what only 1 in 1000 learned
    /// poses reach.
    pub unusual: f64,
    /// The mixture's components.
    pub components: Vec<Component>,
}

impl PosePrior {
    /// The prior bundled with the program (read once).
    pub fn bundled() -> Result<&'static PosePrior, PriorError> {
        static BUNDLED: OnceLock<Result<PosePrior, PriorError>> = OnceLock::new();
        BUNDLED
            .get_or_init(|| PosePrior::parse(BUNDLED_TEXT, Path::new(BUNDLED_PRIOR)))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// A prior from a file.
    pub fn load(path: &Path) -> Result<PosePrior, PriorError> {
        let text = std::fs::read_to_string(path).map_err(|e| PriorError::Missing {
            path: path.to_owned(),
            reason: e.to_string(),
        })?;
        PosePrior::parse(&text, path)
    }

    /// A prior from a file's text (`path` names it in errors).
    pub fn parse(text: &str, path: &Path) -> Result<PosePrior, PriorError> {
        let corrupt = |reason: String| PriorError::Corrupt {
            path: path.to_owned(),
            reason,
        };
        let file: PriorFile = serde_json::from_str(text).map_err(|e| corrupt(e.to_string()))?;
        PosePrior::from_file(file).map_err(corrupt)
    }

    /// A prior from a file's parsed contents; `Err` says what is wrong.
    pub fn from_file(file: PriorFile) -> Result<PosePrior, String> {
        if file.format != FORMAT || file.version != VERSION {
            return Err(format!(
                "format {} version {}, expected {FORMAT} version {VERSION}",
                file.format, file.version
            ));
        }
        let mut models = Vec::new();
        for (name, dims) in MODEL_NAMES.iter().zip(MODEL_DIMS) {
            let g = file
                .groups
                .iter()
                .find(|g| g.name == *name)
                .ok_or_else(|| format!("no group \"{name}\""))?;
            if g.dims != dims {
                return Err(format!("group {name}: {} dimensions, not {dims}", g.dims));
            }
            if !(g.ceiling.is_finite() && g.ceiling > 0.0) {
                return Err(format!(
                    "group {name}: ceiling {} is not positive",
                    g.ceiling
                ));
            }
            if !(g.unusual.is_finite() && g.unusual > 0.0 && g.unusual < g.ceiling) {
                return Err(format!(
                    "group {name}: unusual {} is not between 0 and the ceiling",
                    g.unusual
                ));
            }
            let gmm =
                Gmm::new(dims, g.components.clone()).map_err(|e| format!("group {name}: {e}"))?;
            let peak = gmm.peak();
            models.push(Model {
                gmm,
                peak,
                ceiling: g.ceiling,
                unusual: soft_ceiling(g.unusual, g.ceiling),
            });
        }
        Ok(PosePrior {
            models,
            takes: file.takes,
        })
    }

    /// A group's cost for the pose `p` (nats, at least 0): its negative log-likelihood below
    /// the mixture's peak, held softly under the group's ceiling. `key` is `p`'s key triangle
    /// frame ([`TrunkFrame::of`]).
    pub(crate) fn cost(
        &self,
        group: PriorGroup,
        p: &PerJoint<Point3<f64>>,
        key: &TrunkFrame,
    ) -> f64 {
        let mut x = [0.0; 9];
        features(group, p, key, &mut x);
        self.models[group.model()].cost(&x)
    }

    /// Every group's cost summed for a whole pose (nats; the stance against gravity left out).
    pub fn pose_cost(&self, p: &PerJoint<Point3<f64>>) -> f64 {
        let key = TrunkFrame::of(p);
        PriorGroup::ALL.iter().map(|&g| self.cost(g, p, &key)).sum()
    }

    /// Whether the pose `p` is unusual: a limb (an arm with its thigh, a leg), or its trunk's
    /// stance against `up` (the world's up direction, as far as it is known: the camera's for
    /// the lift), lies beyond what 999 in 1000 learned poses reach. The trunk's groups (head,
    /// spine, hips) are left out: their learned spread is the motion capture rig's fixed joint
    /// placement more than a pose, and on the benchmark suite's bodies (their own joint
    /// definitions) the spine alone lay beyond it on most frames.
    pub fn is_unusual(&self, p: &PerJoint<Point3<f64>>, up: &Vector3<f64>) -> bool {
        let key = TrunkFrame::of(p);
        let stance = &self.models[UPRIGHT];
        let limb = |g: &&PriorGroup| matches!(g, PriorGroup::Arm(_) | PriorGroup::Leg(_));
        stance.cost(&stance_features(&key, up)) > stance.unusual
            || PriorGroup::ALL.iter().filter(limb).any(|&g| {
                let model = &self.models[g.model()];
                self.cost(g, p, &key) > model.unusual
            })
    }
}

/// The trunk's stance against gravity: how far the key triangle's up and forward directions
/// point along `up` (the world's up, a unit vector).
fn stance_features(key: &TrunkFrame, up: &Vector3<f64>) -> [f64; 2] {
    [key.up.dot(up), key.forward.dot(up)]
}

/// `x` (nats) held under `ceiling`: −ln(e^−x + e^−ceiling) + ln(1 + e^−ceiling), the cost of a
/// mixture with a flat floor e^−ceiling below its peak: x where x is small, never above ceiling.
fn soft_ceiling(x: f64, ceiling: f64) -> f64 {
    let floor = (-ceiling).exp();
    (-((-x).exp() + floor).ln() + floor.ln_1p()).max(0.0)
}

/// Learns a prior from motion-capture poses (each frame's 16 joints, in right-handed axes
/// whose +Y is the world's up, as BVH files are written): every pose and its mirror image, each
/// group's mixture of `components`; the ceilings and the unusual-pose thresholds from the
/// learned poses' own costs. `takes` and `source` go into the file.
pub fn learn(
    poses: &[PerJoint<Point3<f64>>],
    components: usize,
    takes: Vec<String>,
    source: String,
) -> Result<PriorFile, String> {
    if poses.is_empty() {
        return Err("no poses to learn from".to_owned());
    }
    if components == 0 {
        return Err("a mixture needs at least one component".to_owned());
    }
    let mirrored: Vec<PerJoint<Point3<f64>>> = poses.iter().map(mirror_pose).collect();
    let all: Vec<&PerJoint<Point3<f64>>> = poses.iter().chain(&mirrored).collect();
    let keys: Vec<TrunkFrame> = all.iter().map(|p| TrunkFrame::of(p)).collect();
    let mut groups = Vec::new();
    for (m, (name, dims)) in MODEL_NAMES.iter().zip(MODEL_DIMS).enumerate() {
        let data: Vec<Vec<f64>> = if m == UPRIGHT {
            let up = Vector3::y();
            keys.iter()
                .map(|key| stance_features(key, &up).to_vec())
                .collect()
        } else {
            let members: Vec<PriorGroup> = PriorGroup::ALL
                .into_iter()
                .filter(|g| g.model() == m)
                .collect();
            all.iter()
                .zip(&keys)
                .flat_map(|(p, key)| {
                    members.iter().map(move |&g| {
                        let mut x = [0.0; 9];
                        features(g, p, key, &mut x);
                        x[..dims].to_vec()
                    })
                })
                .collect()
        };
        groups.push(fit_group(name, &data, dims, components)?);
    }
    Ok(PriorFile {
        format: FORMAT.to_owned(),
        version: VERSION,
        source,
        takes,
        poses: poses.len(),
        groups,
    })
}

/// One group's mixture fitted to its features, with its unusual threshold (the
/// [`UNUSUAL_QUANTILE`] of the learned features' costs) and its ceiling above it.
fn fit_group(
    name: &str,
    data: &[Vec<f64>],
    dims: usize,
    components: usize,
) -> Result<GroupFile, String> {
    let gmm = fit(data, dims, components, EM_ITERATIONS, COVARIANCE_FLOOR)?;
    let peak = gmm.peak();
    let mut below: Vec<f64> = data
        .iter()
        .map(|x| (peak - gmm.log_density(x)).max(0.0))
        .collect();
    below.sort_by(f64::total_cmp);
    let at = ((below.len() - 1) as f64 * UNUSUAL_QUANTILE) as usize;
    // At least a nat: a group learned from a handful of identical poses is not a wall either.
    let unusual = below[at].max(1.0);
    Ok(GroupFile {
        name: name.to_owned(),
        dims,
        ceiling: unusual * CEILING_TIMES,
        unusual,
        components: gmm.components,
    })
}

/// EM rounds of the fit (not tuned: enough for the fit to settle from its seeds).
const EM_ITERATIONS: usize = 60;
/// Added to each covariance's diagonal (a spread of 0.1 per direction component, about 6°): the
/// joints' placement itself differs by that much between bodies and skeletons (the takes' rigs,
/// the suite's bodies, a tracker's joints), so the prior is learned as if each learned
/// direction were seen through that uncertainty. At 1e-3 (2°) the trunk's mixtures (the rig's
/// chest → pelvis direction is nearly fixed in the key triangle's frame) were a wall around the
/// rig's own joints: on the lift's procedural test walk the cheapest trunk came from a wrong key
/// triangle, and the key joints' jitter with the steady trunk rose from 0.9 to 7.6 mm.
const COVARIANCE_FLOOR: f64 = 1e-2;
/// A group's pose is unusual beyond this quantile of the learned poses' costs.
const UNUSUAL_QUANTILE: f64 = 0.999;
/// A group's cost's ceiling over its unusual threshold: well beyond every learned pose.
const CEILING_TIMES: f64 = 2.0;

/// A pose seen in a mirror: every joint swapped with its other side's and reflected through
/// the plane through the pelvis square to the hip line (the result is a pose of the same
/// handedness, its left where the right was).
fn mirror_pose(p: &PerJoint<Point3<f64>>) -> PerJoint<Point3<f64>> {
    let normal = (p[LeftHip] - p[RightHip])
        .try_normalize(f64::EPSILON)
        .unwrap_or_else(Vector3::x);
    let origin = p[Pelvis];
    PerJoint::from_fn(|j| {
        let q = p[j.mirrored()];
        q - normal * 2.0 * (q - origin).dot(&normal)
    })
}

#[cfg(test)]
mod tests;
