//! Biovision BVH motion files: a reader (any channel order, End Sites, one root) with forward
//! kinematics, and the table-driven mapping of a rig's joints onto the 16-joint model.
//!
//! Shared by `synth` (motion capture drives the synthetic clips) and the round-trip checks
//! of the BVH writer in `export`.

mod mapping;
mod parse;

pub use mapping::{MappedMotion, map_to_model};
pub use parse::{Bvh, BvhError, BvhJoint, Channel};

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

impl Bvh {
    /// Local transform of joint `j` in frame `f`: translation (offset plus position channels),
    /// then the rotation channels applied in the order listed (`Zrotation Xrotation Yrotation`
    /// means R = Rz·Rx·Ry), angles in degrees in the file.
    pub fn local_transform(&self, j: usize, f: usize) -> Isometry3<f64> {
        let joint = &self.joints[j];
        let row = self.frame(f);
        let mut t = joint.offset;
        let mut r = UnitQuaternion::identity();
        for (k, ch) in joint.channels.iter().enumerate() {
            let v = row.get(joint.first_channel + k).copied().unwrap_or(0.0);
            match ch {
                Channel::Xposition => t.x += v,
                Channel::Yposition => t.y += v,
                Channel::Zposition => t.z += v,
                Channel::Xrotation => r *= rot(Vector3::x_axis(), v),
                Channel::Yrotation => r *= rot(Vector3::y_axis(), v),
                Channel::Zrotation => r *= rot(Vector3::z_axis(), v),
            }
        }
        Isometry3::from_parts(Translation3::from(t), r)
    }

    /// Global transforms of all joints in frame `f` (parents come before children).
    pub fn global_transforms(&self, f: usize) -> Vec<Isometry3<f64>> {
        let mut out: Vec<Isometry3<f64>> = Vec::with_capacity(self.joints.len());
        for (j, joint) in self.joints.iter().enumerate() {
            let local = self.local_transform(j, f);
            let global = match joint.parent {
                Some(p) => out[p] * local,
                None => local,
            };
            out.push(global);
        }
        out
    }

    /// Global positions of all joints in frame `f`, in file units.
    pub fn positions(&self, f: usize) -> Vec<Point3<f64>> {
        self.global_transforms(f)
            .iter()
            .map(|t| t.translation.vector.into())
            .collect()
    }

    /// Global positions of all joints with every channel at zero (the rest pose).
    pub fn rest_positions(&self) -> Vec<Point3<f64>> {
        let mut out: Vec<Point3<f64>> = Vec::with_capacity(self.joints.len());
        for joint in &self.joints {
            let p = match joint.parent {
                Some(parent) => out[parent] + joint.offset,
                None => Point3::from(joint.offset),
            };
            out.push(p);
        }
        out
    }
}

fn rot(axis: nalgebra::Unit<Vector3<f64>>, degrees: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_axis_angle(&axis, degrees.to_radians()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const TWO_BONES: &str = "HIERARCHY
ROOT hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT knee
  {
    OFFSET 0 -1 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    End Site
    {
      OFFSET 0 -1 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.5
0 0 0 0 0 0 0 0 0
1 2 3 90 0 0 90 0 0
";

    #[test]
    fn forward_kinematics_applies_offsets_positions_and_rotations() {
        let bvh = Bvh::parse(TWO_BONES, Path::new("t.bvh")).unwrap();
        assert_eq!(bvh.frame_count(), 2);
        assert_eq!(bvh.joints.len(), 3); // hips, knee, its End Site
        let p0 = bvh.positions(0);
        assert!((p0[2] - Point3::new(0.0, -2.0, 0.0)).norm() < 1e-12);
        // Frame 1: root moved to (1,2,3) and turned 90° about Z: the leg's -Y becomes +X.
        // The knee then bends 90° about X: the shank's -Y becomes -Z in the knee frame,
        // which the root's Z turn leaves as -Z.
        let p1 = bvh.positions(1);
        assert!(
            (p1[1] - Point3::new(2.0, 2.0, 3.0)).norm() < 1e-9,
            "{:?}",
            p1[1]
        );
        assert!(
            (p1[2] - Point3::new(2.0, 2.0, 2.0)).norm() < 1e-9,
            "{:?}",
            p1[2]
        );
    }
}
