//! MakeHuman's base mesh at rest (MPFB2, CC0; `assets/mpfb2/`): the skin's vertices and
//! triangles, the CMU-named rig's bones from the mesh's joint cubes, four skinning weights per
//! vertex, our 16 joints on the mesh, and what each vertex wears.

use super::Bone;
use flate2::read::GzDecoder;
use nalgebra::Vector3;
use serde::Deserialize;
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use videomocap_core::skeleton::{Joint, PerJoint};

const OBJ_GZ: &[u8] = include_bytes!("../../../../../assets/mpfb2/base.obj.gz");
const WEIGHTS_GZ: &[u8] = include_bytes!("../../../../../assets/mpfb2/weights.cmu_mb.json.gz");
const RIG: &str = include_str!("../../../../../assets/mpfb2/rig.cmu_mb.json");
const GROUPS: &str = include_str!("../../../../../assets/mpfb2/basemesh_vertex_groups.json");

/// The OBJ is in decimetres.
const OBJ_UNIT_M: f64 = 0.1;

/// What a vertex wears, by the bone that moves it most (and, on the head, where it sits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Region {
    Face,
    Hair,
    Neck,
    Trunk,
    /// Hips and belly below the waist.
    Seat,
    UpperArm,
    Forearm,
    Hand,
    Thigh,
    Shin,
    Foot,
}

/// A bone at rest: where it starts, its direction, and two directions square to it.
#[derive(Debug, Clone, Copy)]
pub(super) struct BoneAxes {
    head: Vector3<f64>,
    axis: Vector3<f64>,
    across: Vector3<f64>,
    other: Vector3<f64>,
}

impl BoneAxes {
    /// Metres along the bone and angle around it (radians) of the rest point `p`.
    pub(super) fn pattern_coordinates(&self, p: &Vector3<f64>) -> (f64, f64) {
        let d = p - self.head;
        (
            d.dot(&self.axis),
            d.dot(&self.other).atan2(d.dot(&self.across)),
        )
    }
}

/// The mesh at rest, in its own frame (metres, Y up, +X the subject's left, +Z the front).
pub(super) struct RestMesh {
    /// Skin vertices.
    pub positions: Vec<Vector3<f64>>,
    /// Triangles of the skin (the OBJ's quads split).
    pub triangles: Vec<[u32; 3]>,
    /// Up to four (bone, weight) per vertex, weights summing to 1.
    pub weights: Vec<[(Bone, f32); 4]>,
    /// Each vertex's region and the axes of the bone that moves it most (for the cloth's
    /// pattern: metres along the bone, angle around it).
    pub regions: Vec<(Region, BoneAxes)>,
    /// Our 16 joints on the rest mesh.
    pub joints: PerJoint<Vector3<f64>>,
    /// The clavicles' inner ends (left, right), which none of our joints marks.
    pub clavicles: [Vector3<f64>; 2],
    /// Stature at rest, metres.
    pub stature_m: f64,
}

#[derive(Deserialize)]
struct Weights {
    /// By bone name, read in name order: a vertex's bones of equal weight then keep one order,
    /// so the same clip renders the same pixels on every run (a hash map's order changed from
    /// process to process and with it a few grey levels on a couple of hundred pixels a frame).
    weights: BTreeMap<String, Vec<(usize, f32)>>,
}

#[derive(Deserialize)]
struct RigBone {
    head: RigEnd,
    tail: RigEnd,
}

#[derive(Deserialize)]
struct RigEnd {
    cube_name: Option<String>,
}

/// A mesh that cannot be read (a corrupt asset: the test kit's own files).
#[derive(Debug, thiserror::Error)]
#[error("assets/mpfb2: {0}")]
pub struct MeshError(String);

impl MeshError {
    /// An error saying `message`.
    pub(super) fn new(message: &str) -> MeshError {
        MeshError(message.to_owned())
    }
}

fn bad(what: impl std::fmt::Display) -> MeshError {
    MeshError(what.to_string())
}

impl RestMesh {
    /// Reads the bundled mesh, rig and weights.
    pub(super) fn load() -> Result<RestMesh, MeshError> {
        let mut obj = String::new();
        GzDecoder::new(OBJ_GZ)
            .read_to_string(&mut obj)
            .map_err(|e| bad(format!("base.obj.gz: {e}")))?;
        let groups: HashMap<String, serde_json::Value> =
            serde_json::from_str(GROUPS).map_err(|e| bad(format!("vertex groups: {e}")))?;
        let range = |name: &str| -> Result<Vec<(usize, usize)>, MeshError> {
            serde_json::from_value(groups.get(name).cloned().ok_or_else(|| bad(name))?)
                .map_err(|e| bad(format!("vertex group {name}: {e}")))
        };
        let skin_end = range("body")?.first().map_or(0, |r| r.1 + 1);
        let (all, triangles) = parse_obj(&obj, skin_end)?;
        if all.len() < skin_end || triangles.is_empty() {
            return Err(bad("base.obj.gz holds no skin"));
        }
        let cube = |name: &str| -> Result<Vector3<f64>, MeshError> {
            let mut sum = Vector3::zeros();
            let mut n = 0.0f64;
            for (a, b) in range(name)? {
                for p in all.get(a..=b).ok_or_else(|| bad(name))? {
                    sum += p;
                    n += 1.0;
                }
            }
            Ok(sum / n.max(1.0))
        };
        let positions = all[..skin_end].to_vec();
        let top = positions.iter().map(|p| p.y).fold(f64::MIN, f64::max);
        let sole = positions.iter().map(|p| p.y).fold(f64::MAX, f64::min);
        let head = cube("joint-head")?;
        let joints = PerJoint::from_fn(|j| match joint_cube(j) {
            None => Ok(Vector3::new(head.x, top, head.z)),
            Some(name) => cube(name),
        });
        let mut js = PerJoint::from_fn(|_| Vector3::zeros());
        for (j, p) in joints.iter() {
            js[j] = p.as_ref().map_err(bad)?.to_owned();
        }
        let clavicles = [cube("joint-l-clavicle")?, cube("joint-r-clavicle")?];
        let eye = cube("joint-l-eye")?;
        let weights = read_weights(skin_end)?;
        let bone_ends = bone_ends(&cube)?;
        let regions = positions
            .iter()
            .zip(&weights)
            .map(|(p, w)| region(p, w[0].0, &js, eye, &bone_ends))
            .collect();
        Ok(RestMesh {
            positions,
            triangles,
            weights,
            regions,
            joints: js,
            clavicles,
            stature_m: top - sole,
        })
    }
}

/// An OBJ's vertices (metres) and its skin's triangles.
type ObjMesh = (Vec<Vector3<f64>>, Vec<[u32; 3]>);

/// The OBJ's vertices (metres) and the skin's triangles (faces whose vertices all lie below
/// `skin_end`, quads and polygons fanned).
fn parse_obj(obj: &str, skin_end: usize) -> Result<ObjMesh, MeshError> {
    let mut all = Vec::new();
    let mut triangles = Vec::new();
    for line in obj.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.filter_map(|t| t.parse().ok()).collect();
                if c.len() < 3 {
                    return Err(bad(format!("vertex line {line:?}")));
                }
                all.push(Vector3::new(c[0], c[1], c[2]) * OBJ_UNIT_M);
            }
            Some("f") => {
                let idx: Vec<u32> = it
                    .filter_map(|t| t.split('/').next()?.parse::<u32>().ok())
                    .map(|i| i - 1)
                    .collect();
                if idx.iter().all(|&i| (i as usize) < skin_end) {
                    for k in 1..idx.len().saturating_sub(1) {
                        triangles.push([idx[0], idx[k], idx[k + 1]]);
                    }
                }
            }
            _ => {}
        }
    }
    Ok((all, triangles))
}

/// The rig's joint cube that places each of our joints (`None`: the head top, on the top of the
/// head above the head's cube).
fn joint_cube(j: Joint) -> Option<&'static str> {
    use Joint::*;
    Some(match j {
        HeadTop => return None,
        Neck => "joint-neck",
        Chest => "joint-spine-1",
        Pelvis => "joint-pelvis",
        LeftShoulder => "joint-l-shoulder",
        LeftElbow => "joint-l-elbow",
        LeftWrist => "joint-l-hand",
        RightShoulder => "joint-r-shoulder",
        RightElbow => "joint-r-elbow",
        RightWrist => "joint-r-hand",
        LeftHip => "joint-l-upper-leg",
        LeftKnee => "joint-l-knee",
        LeftAnkle => "joint-l-ankle",
        RightHip => "joint-r-upper-leg",
        RightKnee => "joint-r-knee",
        RightAnkle => "joint-r-ankle",
    })
}

/// Each vertex's four strongest bones (ours), normalised.
fn read_weights(n: usize) -> Result<Vec<[(Bone, f32); 4]>, MeshError> {
    let mut text = String::new();
    GzDecoder::new(WEIGHTS_GZ)
        .read_to_string(&mut text)
        .map_err(|e| bad(format!("weights: {e}")))?;
    let file: Weights = serde_json::from_str(&text).map_err(|e| bad(format!("weights: {e}")))?;
    let mut per_vertex: Vec<Vec<(Bone, f32)>> = vec![Vec::new(); n];
    for (name, list) in &file.weights {
        let Some(bone) = Bone::from_rig(name) else {
            return Err(bad(format!("weights name an unknown bone {name}")));
        };
        for &(v, w) in list {
            if let Some(slot) = per_vertex.get_mut(v) {
                match slot.iter_mut().find(|(b, _)| *b == bone) {
                    Some(e) => e.1 += w,
                    None => slot.push((bone, w)),
                }
            }
        }
    }
    Ok(per_vertex
        .into_iter()
        .map(|mut list| {
            list.sort_by(|a, b| b.1.total_cmp(&a.1));
            list.truncate(4);
            let total: f32 = list.iter().map(|e| e.1).sum();
            let mut out = [(Bone::Hips, 0.0); 4];
            if total <= 0.0 {
                out[0] = (Bone::Hips, 1.0);
                return out;
            }
            for (o, (b, w)) in out.iter_mut().zip(list) {
                *o = (b, w / total);
            }
            out
        })
        .collect())
}

/// Each bone's rest head and tail.
type BoneEnds = HashMap<Bone, (Vector3<f64>, Vector3<f64>)>;

/// Rest head and tail of each of our bones, from the rig's joint cubes.
fn bone_ends(
    cube: &dyn Fn(&str) -> Result<Vector3<f64>, MeshError>,
) -> Result<BoneEnds, MeshError> {
    // In name order: where two of the rig's bones map onto one of ours, the same one is kept
    // on every run (see `Weights`).
    let rig: BTreeMap<String, RigBone> =
        serde_json::from_str(RIG).map_err(|e| bad(format!("rig: {e}")))?;
    let mut ends = HashMap::new();
    for (name, b) in &rig {
        let (Some(bone), Some(h), Some(t)) = (
            Bone::from_rig(name),
            b.head.cube_name.as_deref(),
            b.tail.cube_name.as_deref(),
        ) else {
            continue;
        };
        ends.entry(bone).or_insert((cube(h)?, cube(t)?));
    }
    Ok(ends)
}

/// What a vertex at `p` moved mostly by `bone` wears, and where it sits on that bone.
fn region(
    p: &Vector3<f64>,
    bone: Bone,
    joints: &PerJoint<Vector3<f64>>,
    eye: Vector3<f64>,
    ends: &BoneEnds,
) -> (Region, BoneAxes) {
    use Bone::*;
    let r = match bone {
        Head => {
            let above = p.y - eye.y;
            let behind = eye.z - p.z;
            if above > 0.035 || (behind > 0.07 && above > -0.07) {
                Region::Hair
            } else {
                Region::Face
            }
        }
        Neck => Region::Neck,
        Hips | LeftHipJoint | RightHipJoint => {
            if p.y > joints[Joint::Pelvis].y + 0.07 {
                Region::Trunk
            } else {
                Region::Seat
            }
        }
        LowerBack | Spine | Chest | LeftClavicle | RightClavicle => Region::Trunk,
        LeftArm | RightArm => Region::UpperArm,
        LeftForeArm | RightForeArm => Region::Forearm,
        LeftHand | RightHand => Region::Hand,
        LeftUpLeg | RightUpLeg => Region::Thigh,
        LeftLeg | RightLeg => Region::Shin,
        LeftFoot | RightFoot => Region::Foot,
    };
    let (h, t) = ends
        .get(&bone)
        .copied()
        .unwrap_or((joints[Joint::Pelvis], joints[Joint::Neck]));
    let axis = (t - h).try_normalize(1e-9).unwrap_or(Vector3::y());
    let across = (Vector3::x() - axis * axis.x)
        .try_normalize(1e-9)
        .unwrap_or(Vector3::z());
    let other = axis.cross(&across);
    (
        r,
        BoneAxes {
            head: h,
            axis,
            across,
            other,
        },
    )
}
