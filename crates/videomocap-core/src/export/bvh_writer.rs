//! The BVH writer: the rig of [`super::rig::RIG`] as HIERARCHY (root `Hips` with six channels,
//! every other joint three, Z-X-Y rotation order, End Sites at head top, fingertips and toes,
//! bone names from a [`RigNames`] set),
//! then MOTION with one line per frame. Lengths in centimetres, angles in degrees, every number
//! with four decimals, so the same input always gives the same bytes.

use super::euler::zxy_degrees;
use super::kinematics::RigMotion;
use super::rig::{RIG, RigNames};
use std::fmt::Write as _;

/// BVH lengths are written in centimetres: Blender's importer (scale 1.0) then gives a
/// character about 1.7 units tall in a scene in centimetres, or import with scale 0.01 for
/// metres.
pub const BVH_UNITS_PER_METRE: f64 = 100.0;

/// The channels of non-root joints, in order.
pub const ROTATION_CHANNELS: &str = "Zrotation Xrotation Yrotation";

/// The BVH text of a rig motion with the bone names of `names`, and the Euler angles written
/// (per frame, per non-End-Site joint in rig order, Z X Y in degrees).
pub fn bvh_text(motion: &RigMotion, names: RigNames) -> (String, Vec<Vec<[f64; 3]>>) {
    let mut out = String::from("HIERARCHY\n");
    write_joint(&mut out, motion, names, 0, 0);
    let _ = writeln!(out, "MOTION");
    let _ = writeln!(out, "Frames: {}", motion.frames.len());
    let _ = writeln!(out, "Frame Time: {:.8}", motion.frame_time_s);
    let rotating: Vec<usize> = (0..RIG.len()).filter(|&i| !RIG[i].is_end()).collect();
    let mut previous: Vec<Option<[f64; 3]>> = vec![None; rotating.len()];
    let mut angles = Vec::with_capacity(motion.frames.len());
    for pose in &motion.frames {
        let mut line: Vec<String> = pose
            .root
            .iter()
            .map(|v| number(v * BVH_UNITS_PER_METRE))
            .collect();
        let mut row = Vec::with_capacity(rotating.len());
        for (k, &i) in rotating.iter().enumerate() {
            let a = zxy_degrees(pose.local[i].matrix(), previous[k]);
            previous[k] = Some(a);
            line.extend(a.iter().map(|v| number(*v)));
            row.push(a);
        }
        angles.push(row);
        out.push_str(&line.join(" "));
        out.push('\n');
    }
    (out, angles)
}

fn write_joint(out: &mut String, motion: &RigMotion, names: RigNames, i: usize, depth: usize) {
    let indent = "\t".repeat(depth);
    let r = &RIG[i];
    let o = motion.offsets[i] * BVH_UNITS_PER_METRE;
    let offset = format!("{} {} {}", number(o.x), number(o.y), number(o.z));
    if r.is_end() {
        let _ = writeln!(out, "{indent}End Site\n{indent}{{");
        let _ = writeln!(out, "{indent}\tOFFSET {offset}\n{indent}}}");
        return;
    }
    let keyword = if r.parent.is_none() { "ROOT" } else { "JOINT" };
    let _ = writeln!(out, "{indent}{keyword} {}\n{indent}{{", names.name(i));
    let _ = writeln!(out, "{indent}\tOFFSET {offset}");
    if r.parent.is_none() {
        let _ = writeln!(
            out,
            "{indent}\tCHANNELS 6 Xposition Yposition Zposition {ROTATION_CHANNELS}"
        );
    } else {
        let _ = writeln!(out, "{indent}\tCHANNELS 3 {ROTATION_CHANNELS}");
    }
    for (c, child) in RIG.iter().enumerate() {
        if child.parent == Some(i) {
            write_joint(out, motion, names, c, depth + 1);
        }
    }
    let _ = writeln!(out, "{indent}}}");
}

/// Four decimals, and never "-0.0000".
fn number(v: f64) -> String {
    let s = format!("{v:.4}");
    if s.trim_start_matches('-')
        .bytes()
        .all(|b| b == b'0' || b == b'.')
    {
        s.trim_start_matches('-').to_owned()
    } else {
        s
    }
}
