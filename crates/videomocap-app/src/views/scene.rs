//! What the 3D viewport draws, built from the state: the lifted skeleton of the current frame
//! (or, while a job runs, the last one), the camera's frustum and the bones the lift flagged; in
//! volume mode the frame's points coloured by body, the skeleton curve and the fitted bodies.

use super::frame_view::side_colour;
use super::view3d::Scene;
use crate::state::State;
use crate::state::volume::VolumeSequence;
use egui::{Color32, Stroke};
use nalgebra::{Point3, Vector3};
use videomocap_core::formats::FrameIndex;
use videomocap_core::skeleton::{Bone, Joint};
use videomocap_volume::Part;
use videomocap_volume::bodies::Cylinder;

/// Most points drawn per frame (the rest are skipped evenly; drawing stays fast).
const MAX_POINTS: usize = 6000;

/// The scene of the current frame: the skeleton (the last one, marked so, while a job makes the
/// next), the camera's frustum, the bones that can be flipped and those the lift flagged.
pub fn scene(state: &State) -> Scene {
    let current = state.current_frame();
    if let Some(v) = state.volume() {
        return volume_scene(v, current);
    }
    let Some((world, skeleton)) = state.shown_world() else {
        return Scene::default();
    };
    let joints = world
        .indices
        .binary_search(&FrameIndex(current))
        .ok()
        .map(|k| world.frames[k]);
    let cam = &skeleton.camera;
    let corner = |x: f64, y: f64| {
        let depth = 0.5;
        world.world.to_world(&Point3::new(
            (x - cam.cx) / cam.focal_px * depth,
            (y - cam.cy) / cam.focal_px * depth,
            depth,
        ))
    };
    let (w, h) = (f64::from(cam.width), f64::from(cam.height));
    let camera = (
        world.world.to_world(&Point3::origin()),
        [
            corner(0.0, 0.0),
            corner(w, 0.0),
            corner(w, h),
            corner(0.0, h),
        ],
    );
    let key = videomocap_core::lift::KEY_JOINTS;
    let mut scene = Scene {
        joints,
        camera: Some(camera),
        flippable: Bone::ALL
            .into_iter()
            .filter(|b| !(key.contains(&b.parent) && key.contains(&b.child)))
            .collect(),
        ..Scene::default()
    };
    if state.world_is_stale() {
        scene
            .notes
            .push("the last 3D result: a new one is on its way".to_owned());
    }
    let flags = skeleton
        .frames
        .binary_search_by_key(&FrameIndex(current), |f| f.index)
        .ok()
        .map(|k| &skeleton.frames[k].flags);
    let mut too_long = Vec::new();
    for flag in flags.into_iter().flatten() {
        match flag.strip_prefix("too_long:").and_then(Bone::from_key) {
            Some(bone) => too_long.push(bone),
            None => scene.notes.push(format!("flagged: {}", plain_flag(flag))),
        }
    }
    if !too_long.is_empty() {
        let what = if too_long.len() == 1 {
            "1 bone (red) looks longer in the image than it can be".to_owned()
        } else {
            format!(
                "{} bones (red) look longer in the image than they can be",
                too_long.len()
            )
        };
        scene.notes.insert(0, format!("flagged: {what}"));
        scene.flagged = too_long;
    }
    let unsure: Vec<Bone> = state
        .unsure_bones(current)
        .into_iter()
        .filter(|b| scene.flippable.contains(b))
        .collect();
    if !unsure.is_empty() {
        let names: Vec<String> = unsure.iter().map(|b| b.plain_name()).collect();
        scene.notes.push(format!(
            "depth unsure (amber): {}: if one points the wrong way, click it to flip",
            names.join(", ")
        ));
        scene.unsure = unsure;
    }
    scene
}

/// A lift flag in words.
fn plain_flag(flag: &str) -> String {
    if flag == "key_triangle_not_converged" {
        "the trunk's pose did not fit its three points".to_owned()
    } else if let Some(j) = flag.strip_prefix(videomocap_core::formats::OFF_FRAME_FLAG) {
        format!("{j} off the frame")
    } else if let Some(j) = flag.strip_prefix(videomocap_core::formats::LOST_FLAG) {
        format!("{j} lost: a guess")
    } else if flag == videomocap_core::formats::NO_IMAGE_DEPTH_FLAG {
        "the pose network saw no body here: depth from the geometry alone".to_owned()
    } else {
        flag.to_owned()
    }
}

/// The scene of frame `index` of a point-volume sequence.
pub fn volume_scene(v: &VolumeSequence, index: usize) -> Scene {
    let mut scene = Scene::default();
    let (Some(p), Some(world)) = (&v.processed, &v.world) else {
        scene.empty_text = Some(v.failed.clone().unwrap_or_else(|| {
            if v.processed.is_some() {
                "no frame of these point volumes gave a skeleton".to_owned()
            } else {
                "reading the point volumes… (progress below)".to_owned()
            }
        }));
        return scene;
    };
    let to_world = |q: &Point3<f64>| world.world.to_world(q);
    scene.joints = world
        .indices
        .binary_search(&FrameIndex(index))
        .ok()
        .map(|k| world.frames[k]);
    let Some(Ok(frame)) = p.results.get(index) else {
        return scene;
    };
    // Fitted limb k sits in slot s (0 left arm, 1 right arm, 2 left leg, 3 right leg).
    let slot_of = |k: u8| {
        p.assembled
            .slots
            .get(index)
            .copied()
            .flatten()
            .and_then(|s| s.iter().position(|&x| x == Some(usize::from(k))))
            .unwrap_or(usize::from(k))
    };
    let limb_colour = |k: u8, lower: bool| {
        let c = side_colour(if slot_of(k) % 2 == 0 {
            Joint::LeftElbow
        } else {
            Joint::RightElbow
        });
        if lower { c.gamma_multiply(0.6) } else { c }
    };
    if v.layers.points {
        let step = frame.points.len().div_ceil(MAX_POINTS).max(1);
        for (q, part) in frame.points.iter().zip(&frame.fit.parts).step_by(step) {
            let colour = match part {
                Part::Head => Color32::from_rgb(230, 200, 120),
                Part::Torso => Color32::from_gray(150),
                Part::Upper(k) => limb_colour(*k, false),
                Part::Lower(k) => limb_colour(*k, true),
            };
            scene.cloud.push((to_world(q), colour));
        }
    }
    if v.layers.curve {
        let stroke = Stroke::new(1.5, Color32::from_rgb(120, 230, 120));
        let c = &frame.curve;
        for (i, parent) in c.parents.iter().enumerate() {
            if let Some(j) = parent {
                scene
                    .segments
                    .push((to_world(&c.points[*j]), to_world(&c.points[i]), stroke));
            }
        }
    }
    if v.layers.bodies {
        let stroke = Stroke::new(1.0, Color32::from_rgba_unmultiplied(200, 200, 255, 140));
        let f = &frame.fit;
        let mut push = |a: Point3<f64>, b: Point3<f64>| {
            scene.segments.push((to_world(&a), to_world(&b), stroke));
        };
        sphere(f.head_centre, f.head_radius, &mut push);
        cylinder(&f.torso, &mut push);
        for l in f.limbs.iter().flatten() {
            let knee = l.split.unwrap_or_else(|| nalgebra::center(&l.root, &l.end));
            for (a, b, r) in [(l.root, knee, l.radii[0]), (knee, l.end, l.radii[1])] {
                cylinder(&Cylinder { a, b, radius: r }, &mut push);
            }
        }
    }
    scene
}

/// Two unit vectors across `axis`.
fn across(axis: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if axis.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = axis.cross(&helper).normalize();
    (u, axis.cross(&u))
}

/// A wire cylinder: rings at both ends and four lines along it.
fn cylinder(c: &Cylinder, push: &mut impl FnMut(Point3<f64>, Point3<f64>)) {
    let Some(axis) = (c.b - c.a).try_normalize(1e-9) else {
        return;
    };
    let (u, v) = across(&axis);
    let at = |centre: &Point3<f64>, t: f64| centre + (u * t.cos() + v * t.sin()) * c.radius;
    let n = 12;
    for k in 0..n {
        let (t0, t1) = (
            std::f64::consts::TAU * f64::from(k) / f64::from(n),
            std::f64::consts::TAU * f64::from(k + 1) / f64::from(n),
        );
        push(at(&c.a, t0), at(&c.a, t1));
        push(at(&c.b, t0), at(&c.b, t1));
        if k % 3 == 0 {
            push(at(&c.a, t0), at(&c.b, t0));
        }
    }
}

/// A wire sphere: three great circles.
fn sphere(centre: Point3<f64>, r: f64, push: &mut impl FnMut(Point3<f64>, Point3<f64>)) {
    let n = 16;
    for (a, b) in [
        (Vector3::x(), Vector3::y()),
        (Vector3::y(), Vector3::z()),
        (Vector3::z(), Vector3::x()),
    ] {
        for k in 0..n {
            let t0 = std::f64::consts::TAU * f64::from(k) / f64::from(n);
            let t1 = std::f64::consts::TAU * f64::from(k + 1) / f64::from(n);
            push(
                centre + (a * t0.cos() + b * t0.sin()) * r,
                centre + (a * t1.cos() + b * t1.sin()) * r,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::plain_flag;

    #[test]
    fn lift_flags_read_in_words_and_unknown_ones_pass_through() {
        assert!(plain_flag("no_image_depth").contains("pose network saw no body"));
        assert_eq!(plain_flag("lost:left_knee"), "left_knee lost: a guess");
        assert_eq!(
            plain_flag("off_frame:right_wrist"),
            "right_wrist off the frame"
        );
        assert_eq!(plain_flag("a_later_flag"), "a_later_flag");
    }
}
