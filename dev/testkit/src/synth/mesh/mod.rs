//! A person that looks like one: MakeHuman's skinned base mesh (MPFB2, CC0) posed from the 16
//! joints by linear blend skinning and rasterised with a z-buffer.
//!
//! Posing: the trunk below and above the chest, and the head, each take the frame their joints
//! span (up from the joints, left from the hips or shoulders: swing and twist); each limb bone
//! turns from its parent by the shortest arc onto its joints (swing, the twist carried from the
//! parent); hands and feet ride rigidly on the forearms and shins (the motion has none). Each
//! bone is stretched along itself to the clip's segment length and across by the subject's
//! stature (so the suite's varied bodies keep their lengths). Rasterising: triangles with
//! perspective-correct depth, colour and per-vertex normals, Lambert and ambient as the
//! mannequin; clothes by region (a shirt to the elbows or wrists, trousers or shorts, shoes).

mod raster;
mod rest;

use super::appearance::{Appearance, Material};
use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};
use rest::{BoneAxes, Region, RestMesh};
use std::collections::HashMap;
use std::sync::OnceLock;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::skeleton::{Joint, PerJoint};

pub use rest::MeshError;

/// The rig's bones as the posing moves them (fingers ride on the hand, toes on the foot).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Bone {
    Hips,
    LeftHipJoint,
    RightHipJoint,
    LowerBack,
    Spine,
    Chest,
    Neck,
    Head,
    LeftClavicle,
    LeftArm,
    LeftForeArm,
    LeftHand,
    RightClavicle,
    RightArm,
    RightForeArm,
    RightHand,
    LeftUpLeg,
    LeftLeg,
    LeftFoot,
    RightUpLeg,
    RightLeg,
    RightFoot,
}

impl Bone {
    /// Our bone for a bone of the CMU-named rig.
    fn from_rig(name: &str) -> Option<Bone> {
        use Bone::*;
        Some(match name {
            "Hips" => Hips,
            "LHipJoint" => LeftHipJoint,
            "RHipJoint" => RightHipJoint,
            "LowerBack" => LowerBack,
            "Spine" => Spine,
            "Spine1" => Chest,
            "Neck" | "Neck1" => Neck,
            "Head" => Head,
            "LeftShoulder" => LeftClavicle,
            "LeftArm" => LeftArm,
            "LeftForeArm" => LeftForeArm,
            "RightShoulder" => RightClavicle,
            "RightArm" => RightArm,
            "RightForeArm" => RightForeArm,
            "LeftUpLeg" => LeftUpLeg,
            "LeftLeg" => LeftLeg,
            "LeftFoot" | "LeftToeBase" => LeftFoot,
            "RightUpLeg" => RightUpLeg,
            "RightLeg" => RightLeg,
            "RightFoot" | "RightToeBase" => RightFoot,
            n if n.starts_with("Left") || n.starts_with("LThumb") => LeftHand,
            n if n.starts_with("Right") || n.starts_with("RThumb") => RightHand,
            _ => return None,
        })
    }
}

/// The rest mesh, read once.
fn rest_mesh() -> Result<&'static RestMesh, MeshError> {
    static MESH: OnceLock<Result<RestMesh, String>> = OnceLock::new();
    MESH.get_or_init(|| RestMesh::load().map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| MeshError::new(e))
}

/// One bone's pose: `v' = anchor_posed + linear · (v − anchor_rest)`.
#[derive(Debug, Clone, Copy)]
struct BonePose {
    linear: Matrix3<f64>,
    rotation: Matrix3<f64>,
    anchor_rest: Vector3<f64>,
    anchor_posed: Vector3<f64>,
}

/// An orthonormal frame: `y` along `up`, `x` along `left` made square to it, `z = x × y`.
fn frame(up: Vector3<f64>, left: Vector3<f64>) -> Matrix3<f64> {
    let y = up.try_normalize(1e-9).unwrap_or(Vector3::y());
    let x = (left - y * left.dot(&y))
        .try_normalize(1e-9)
        .unwrap_or_else(|| y.cross(&Vector3::z()).normalize());
    Matrix3::from_columns(&[x, y, x.cross(&y)])
}

/// The shortest rotation taking direction `a` onto `b`.
fn swing(a: &Vector3<f64>, b: &Vector3<f64>) -> Matrix3<f64> {
    UnitQuaternion::rotation_between(a, b)
        .unwrap_or_else(|| {
            let perp = a
                .cross(&Vector3::x())
                .try_normalize(1e-9)
                .unwrap_or(Vector3::y());
            UnitQuaternion::from_axis_angle(
                &nalgebra::Unit::new_normalize(perp),
                std::f64::consts::PI,
            )
        })
        .to_rotation_matrix()
        .into_inner()
}

/// A scale of `along` on direction `axis` (unit) and `across` square to it.
fn stretch(axis: &Vector3<f64>, along: f64, across: f64) -> Matrix3<f64> {
    Matrix3::identity() * across + axis * axis.transpose() * (along - across)
}

/// Every bone's pose for joints `p` (camera space) of a subject `width` times as wide as the
/// rest mesh.
fn bone_poses(rest: &RestMesh, p: &PerJoint<Point3<f64>>, width: f64) -> HashMap<Bone, BonePose> {
    use Joint::*;
    let fit = Fit { rest, p, width };
    let mut poses = HashMap::new();
    let hips_scale = ratio(
        (fit.q(LeftHip) - fit.q(RightHip)).norm(),
        (rest.joints[LeftHip] - rest.joints[RightHip]).norm(),
    );
    let lower = fit.trunk(Pelvis, Chest, LeftHip, RightHip, Some(hips_scale));
    let upper = fit.trunk(Chest, Neck, LeftShoulder, RightShoulder, None);
    for b in [
        Bone::Hips,
        Bone::LeftHipJoint,
        Bone::RightHipJoint,
        Bone::LowerBack,
    ] {
        poses.insert(b, lower);
    }
    for b in [Bone::Spine, Bone::Chest] {
        poses.insert(b, upper);
    }
    let head = fit.head(&upper);
    poses.insert(Bone::Neck, head);
    poses.insert(Bone::Head, head);
    fit.arms(&upper, &mut poses);
    fit.legs(&lower, &mut poses);
    poses
}

/// `a / b` held within 0.3–3 (1 when `b` is nothing).
fn ratio(a: f64, b: f64) -> f64 {
    if b > 1e-9 {
        (a / b).clamp(0.3, 3.0)
    } else {
        1.0
    }
}

/// The rest mesh's joints fitted onto posed joints `p` for a subject `width` times as wide.
struct Fit<'a> {
    rest: &'a RestMesh,
    p: &'a PerJoint<Point3<f64>>,
    width: f64,
}

impl Fit<'_> {
    fn q(&self, j: Joint) -> Vector3<f64> {
        self.p[j].coords
    }

    /// A trunk part: up `lo` → `hi`, left from `left_b` → `left_a`, scaled across by
    /// `side_scale` (else the width).
    fn trunk(
        &self,
        lo: Joint,
        hi: Joint,
        left_a: Joint,
        left_b: Joint,
        side_scale: Option<f64>,
    ) -> BonePose {
        let (r, width) = (&self.rest.joints, self.width);
        let q = |j: Joint| self.q(j);
        let fr = frame(r[hi] - r[lo], r[left_a] - r[left_b]);
        let fp = frame(q(hi) - q(lo), q(left_a) - q(left_b));
        let rot = fp * fr.transpose();
        let sy = ratio((q(hi) - q(lo)).norm(), (r[hi] - r[lo]).norm());
        let sx = side_scale.unwrap_or(width);
        let s = fr * Matrix3::from_diagonal(&Vector3::new(sx, sy, width)) * fr.transpose();
        BonePose {
            linear: rot * s,
            rotation: rot,
            anchor_rest: r[lo],
            anchor_posed: q(lo),
        }
    }

    /// The head: up neck → head top, left carried from the chest (`upper`).
    fn head(&self, upper: &BonePose) -> BonePose {
        use Joint::*;
        let (r, width) = (&self.rest.joints, self.width);
        let q = |j: Joint| self.q(j);
        let fr = frame(r[HeadTop] - r[Neck], Vector3::x());
        let fp = frame(q(HeadTop) - q(Neck), upper.rotation * Vector3::x());
        let rot = fp * fr.transpose();
        let sy = ratio((q(HeadTop) - q(Neck)).norm(), (r[HeadTop] - r[Neck]).norm());
        let s = fr * Matrix3::from_diagonal(&Vector3::new(width, sy, width)) * fr.transpose();
        BonePose {
            linear: rot * s,
            rotation: rot,
            anchor_rest: r[Neck],
            anchor_posed: q(Neck),
        }
    }

    /// A limb bone from `head_rest` to `tail_rest` onto `head_posed` → `tail_posed`, turned from
    /// its parent's rotation by the shortest arc.
    fn limb(
        &self,
        parent: &BonePose,
        head_rest: Vector3<f64>,
        tail_rest: Vector3<f64>,
        head_posed: Vector3<f64>,
        tail_posed: Vector3<f64>,
    ) -> BonePose {
        let dr = tail_rest - head_rest;
        let dp = tail_posed - head_posed;
        let rot = swing(&(parent.rotation * dr), &dp) * parent.rotation;
        let axis = dr.try_normalize(1e-9).unwrap_or(Vector3::y());
        BonePose {
            linear: rot * stretch(&axis, ratio(dp.norm(), dr.norm()), self.width),
            rotation: rot,
            anchor_rest: head_rest,
            anchor_posed: head_posed,
        }
    }

    /// A bone carried rigidly by its parent (hands, feet).
    fn rigid(&self, parent: &BonePose, at_rest: Vector3<f64>, at_posed: Vector3<f64>) -> BonePose {
        BonePose {
            linear: parent.rotation * self.width,
            rotation: parent.rotation,
            anchor_rest: at_rest,
            anchor_posed: at_posed,
        }
    }

    /// Each arm from its clavicle (carried by the chest, `upper`) to its hand.
    fn arms(&self, upper: &BonePose, poses: &mut HashMap<Bone, BonePose>) {
        use Joint::*;
        let r = &self.rest.joints;
        let q = |j: Joint| self.q(j);
        for (k, [clav, arm, fore, hand], [sh, el, wr]) in [
            (
                0,
                [
                    Bone::LeftClavicle,
                    Bone::LeftArm,
                    Bone::LeftForeArm,
                    Bone::LeftHand,
                ],
                [LeftShoulder, LeftElbow, LeftWrist],
            ),
            (
                1,
                [
                    Bone::RightClavicle,
                    Bone::RightArm,
                    Bone::RightForeArm,
                    Bone::RightHand,
                ],
                [RightShoulder, RightElbow, RightWrist],
            ),
        ] {
            let clav_rest = self.rest.clavicles[k];
            let clav_posed = upper.anchor_posed + upper.linear * (clav_rest - upper.anchor_rest);
            let c = self.limb(upper, clav_rest, r[sh], clav_posed, q(sh));
            let a = self.limb(&c, r[sh], r[el], q(sh), q(el));
            let f = self.limb(&a, r[el], r[wr], q(el), q(wr));
            poses.insert(hand, self.rigid(&f, r[wr], q(wr)));
            poses.insert(clav, c);
            poses.insert(arm, a);
            poses.insert(fore, f);
        }
    }

    /// Each leg from the hips (`lower`) to its foot.
    fn legs(&self, lower: &BonePose, poses: &mut HashMap<Bone, BonePose>) {
        use Joint::*;
        let r = &self.rest.joints;
        let q = |j: Joint| self.q(j);
        for ([up, leg, foot], [hip, knee, ankle]) in [
            (
                [Bone::LeftUpLeg, Bone::LeftLeg, Bone::LeftFoot],
                [LeftHip, LeftKnee, LeftAnkle],
            ),
            (
                [Bone::RightUpLeg, Bone::RightLeg, Bone::RightFoot],
                [RightHip, RightKnee, RightAnkle],
            ),
        ] {
            let u = self.limb(lower, r[hip], r[knee], q(hip), q(knee));
            let l = self.limb(&u, r[knee], r[ankle], q(knee), q(ankle));
            poses.insert(foot, self.rigid(&l, r[ankle], q(ankle)));
            poses.insert(up, u);
            poses.insert(leg, l);
        }
    }
}

/// The mesh posed on joints `points` (camera space, metres) for a subject of `stature_m`:
/// vertices in camera space.
fn posed_vertices(
    rest: &RestMesh,
    points: &PerJoint<Point3<f64>>,
    stature_m: f64,
) -> Vec<Vector3<f64>> {
    let width = stature_m / rest.stature_m;
    let poses = bone_poses(rest, points, width);
    rest.positions
        .iter()
        .zip(&rest.weights)
        .map(|(v, w)| {
            let mut out = Vector3::zeros();
            for &(bone, weight) in w {
                if weight <= 0.0 {
                    continue;
                }
                if let Some(b) = poses.get(&bone) {
                    out += (b.anchor_posed + b.linear * (v - b.anchor_rest)) * f64::from(weight);
                }
            }
            out
        })
        .collect()
}

/// The colour `appearance` gives the rest point `p` of a triangle whose first vertex sits in
/// `region` on a bone with `axes`.
fn colour_at(
    appearance: &Appearance,
    region: Region,
    axes: &BoneAxes,
    p: &Vector3<f64>,
) -> [f64; 3] {
    const SHOES: [f64; 3] = [48.0, 42.0, 40.0];
    let (along, angle) = axes.pattern_coordinates(p);
    let cloth = |m: Material, seed: f64| appearance.colour(m, along, angle, seed);
    match region {
        Region::Face => appearance.face,
        Region::Hair => {
            let streak = 0.85 + 0.15 * (angle * 9.0 + along * 40.0).sin();
            appearance.hair.map(|c| c * streak)
        }
        Region::Neck | Region::Hand => cloth(Material::Skin, 0.0),
        Region::Trunk => cloth(Material::Shirt, 0.0),
        Region::UpperArm => cloth(Material::Shirt, 1.0),
        Region::Forearm if appearance.long_sleeves => cloth(Material::Shirt, 2.0),
        Region::Forearm => cloth(Material::Skin, 2.0),
        Region::Seat => cloth(Material::Trousers, 0.0),
        Region::Thigh => cloth(Material::Trousers, 1.0),
        Region::Shin if appearance.shorts => cloth(Material::Skin, 3.0),
        Region::Shin => cloth(Material::Trousers, 2.0),
        Region::Foot => SHOES,
    }
}

/// Draws the person with joints `points` (camera space) over `image`, z-buffered against itself,
/// and returns its depth per pixel (infinite where it is not).
pub(crate) fn paint(
    camera: &PinholeCamera,
    points: &PerJoint<Point3<f64>>,
    stature_m: f64,
    appearance: &Appearance,
    image: &mut image::RgbImage,
) -> Result<Vec<f64>, MeshError> {
    let rest = rest_mesh()?;
    let vertices = posed_vertices(rest, points, stature_m);
    let colour = |triangle: usize, p: &Vector3<f64>| {
        let first = rest.triangles[triangle][0] as usize;
        let (region, axes) = &rest.regions[first];
        colour_at(appearance, *region, axes, p)
    };
    Ok(raster::draw(
        camera,
        &vertices,
        &rest.positions,
        &rest.triangles,
        &colour,
        image,
    ))
}

#[cfg(test)]
mod tests;
