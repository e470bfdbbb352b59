//! What the 3D viewport draws, built from the state: the lifted skeleton of the current frame
//! (or, while a job runs, the last one), the camera's frustum and the bones the lift flagged; in
//! volume mode the frame's points coloured by body, the skeleton curve and the fitted bodies.

use super::frame_view::side_colour;
use super::marking::joint_words;
use super::view3d::{Note, Scene};
use crate::state::State;
use crate::state::volume::VolumeSequence;
use egui::{Color32, Stroke};
use nalgebra::{Point3, Vector3};
use videomocap_core::export::WorldSkeleton;
use videomocap_core::formats::{CONTACT_FLAG, FrameIndex, Skeleton3d};
use videomocap_core::skeleton::{Bone, Joint};
use videomocap_volume::Part;
use videomocap_volume::bodies::Cylinder;

/// Most points drawn per frame (the rest are skipped evenly; drawing stays fast).
const MAX_POINTS: usize = 6000;

/// The scene of the current frame: the skeleton (the last one, marked so, while a job makes the
/// next), the camera's frustum, the bones that can be flipped and those the lift flagged.
pub(crate) fn scene(state: &State) -> Scene {
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
    let camera = frustum(world, skeleton);
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
        scene.notes.push(Note::info(
            "the last 3D result: a new one is on its way".to_owned(),
        ));
    }
    add_flags(&mut scene, state, skeleton, current);
    // Problems first, what is merely so (a planted foot) after.
    scene.notes.sort_by_key(|n| n.kind);
    add_unsure(&mut scene, state, current);
    if let Some(ghost) = state.flip_ghost().filter(|g| g.frame == current) {
        scene.notes.push(Note::info(format!(
            "grey: the pose before you flipped the {} (Ctrl+Z takes the flip back)",
            ghost.bone.plain_name()
        )));
        scene.ghost = Some(ghost.joints);
    }
    scene
}

/// The camera's centre and the corners of its image half a metre in front, in the world.
fn frustum(world: &WorldSkeleton, skeleton: &Skeleton3d) -> (Point3<f64>, [Point3<f64>; 4]) {
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
    (
        world.world.to_world(&Point3::origin()),
        [
            corner(0.0, 0.0),
            corner(w, 0.0),
            corner(w, h),
            corner(0.0, h),
        ],
    )
}

/// The frame's lift flags: bones drawn flagged, planted feet ringed, each flag a note in words.
fn add_flags(scene: &mut Scene, state: &State, skeleton: &Skeleton3d, current: usize) {
    let frame = skeleton
        .frames
        .binary_search_by_key(&FrameIndex(current), |f| f.index)
        .ok()
        .map(|k| &skeleton.frames[k]);
    let marked = |j: Joint| {
        state
            .project()
            .is_some_and(|p| p.keys.is_key(FrameIndex(current), j))
    };
    for flag in frame.map(|f| f.flags.as_slice()).unwrap_or_default() {
        if let Some(bone) = flag.strip_prefix("too_long:").and_then(Bone::from_key) {
            scene.flagged.push(bone);
        }
        if let Some(ankle) = flag.strip_prefix(CONTACT_FLAG).and_then(Joint::from_name) {
            scene.planted.push(ankle);
        }
        scene.notes.push(flag_note(flag, &marked));
    }
}

/// The flippable bones whose depth choice is unsure on the frame, drawn magenta with a note.
fn add_unsure(scene: &mut Scene, state: &State, current: usize) {
    let unsure: Vec<Bone> = state
        .unsure_bones(current)
        .into_iter()
        .filter(|b| scene.flippable.contains(b))
        .collect();
    if !unsure.is_empty() {
        scene.notes.push(Note::warning(format!(
            "depth unsure (magenta): {}. If one points the wrong way, click it (here or in \
             the list above) to flip it",
            unsure
                .iter()
                .map(|b| b.plain_name())
                .collect::<Vec<_>>()
                .join(", ")
        )));
        scene.unsure = unsure;
    }
}

/// A lift flag of the frame in words: what it is, the bone or joint it concerns, and what to
/// do about it. `marked` says which joints the user placed on this frame (their own marks are
/// what to check, not the tracker). A planted foot is information, not a problem.
pub(crate) fn flag_note(flag: &str, marked: &dyn Fn(Joint) -> bool) -> Note {
    use videomocap_core::formats::{
        LOST_FLAG, NO_IMAGE_DEPTH_FLAG, OFF_FRAME_FLAG, UNUSUAL_POSE_FLAG,
    };
    let joint = |prefix: &str| flag.strip_prefix(prefix).and_then(Joint::from_name);
    if let Some(bone) = flag.strip_prefix("too_long:").and_then(Bone::from_key) {
        let (a, b) = (joint_words(bone.parent), joint_words(bone.child));
        let what = format!(
            "The {} ({a} to {b}, red) looks longer in the image than the bone can be",
            bone.plain_name()
        );
        return Note::warning(if marked(bone.parent) && marked(bone.child) {
            format!(
                "{what}. These are your own marks: check the {a} and the {b}, or the subject \
                 height (Parameters)"
            )
        } else {
            format!(
                "{what}: drag the {a} or the {b} to its joint on this frame (it re-tracks from \
                 here), or check the subject height (Parameters)"
            )
        });
    }
    if let Some(ankle) = joint(CONTACT_FLAG) {
        return Note::info(format!(
            "{} planted: the lift holds it still on the floor (brown on the timeline). \
             Nothing to do",
            foot_words(ankle)
        ));
    }
    if let Some(j) = joint(LOST_FLAG) {
        return Note::warning(format!(
            "The {} is lost here: its place is the tracker's guess. Drag it to where it is on \
             this frame (it re-tracks from here)",
            joint_words(j)
        ));
    }
    if let Some(j) = joint(OFF_FRAME_FLAG) {
        return Note::warning(format!(
            "The {} is off the frame: the 3D uses the tracker's estimate of where it is. \
             Nothing to do unless it looks wrong",
            joint_words(j)
        ));
    }
    Note::warning(match flag {
        "key_triangle_not_converged" => "The trunk (both shoulders and the chest) did not fit \
            one rigid shape here: check those three joints on this frame"
            .to_owned(),
        f if f == NO_IMAGE_DEPTH_FLAG => "The pose network saw no body on this frame: which \
            way each limb points in depth rests on the geometry alone. Check the limbs; click \
            one to flip it"
            .to_owned(),
        f if f == UNUSUAL_POSE_FLAG => "A pose the prior has seldom or never seen: which way \
            each limb points in depth rests on the image and the motion. Check the limbs; click \
            one to flip it"
            .to_owned(),
        other => format!("flagged: {other}"),
    })
}

/// An ankle's foot in words: "left foot".
fn foot_words(ankle: Joint) -> &'static str {
    if ankle.name().starts_with("left") {
        "Left foot"
    } else if ankle.name().starts_with("right") {
        "Right foot"
    } else {
        "A foot"
    }
}

/// The scene of frame `index` of a point-volume sequence.
pub(crate) fn volume_scene(v: &VolumeSequence, index: usize) -> Scene {
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
    use super::*;
    use crate::views::view3d::NoteKind;

    /// Each flag names its bone or joint and says what to do; a bone too long on the user's
    /// own marks asks to check those marks; a planted foot is information.
    #[test]
    fn lift_flags_name_the_bone_or_foot_and_say_what_to_do() {
        let none = |_: Joint| false;
        let all = |_: Joint| true;
        let neck = flag_note("too_long:chest-neck", &none);
        assert_eq!(neck.kind, NoteKind::Warning);
        assert!(
            neck.text.contains("The neck (chest to neck, red)")
                && neck.text.contains("drag the chest or the neck"),
            "{}",
            neck.text
        );
        let marked = flag_note("too_long:chest-neck", &all);
        assert!(
            marked
                .text
                .contains("your own marks: check the chest and the neck"),
            "{}",
            marked.text
        );
        let foot = flag_note("contact:left_ankle", &none);
        assert_eq!(foot.kind, NoteKind::Info);
        assert!(
            foot.text.starts_with("Left foot planted") && !foot.text.contains("contact:"),
            "{}",
            foot.text
        );
        let lost = flag_note("lost:left_knee", &none);
        assert!(lost.text.contains("left knee is lost") && lost.text.contains("Drag it"));
        assert!(
            flag_note("off_frame:right_wrist", &none)
                .text
                .contains("right wrist is off")
        );
        assert!(
            flag_note("no_image_depth", &none)
                .text
                .contains("pose network saw no body")
        );
        assert!(
            flag_note("unusual_pose", &none)
                .text
                .contains("prior has seldom or never seen")
        );
        assert_eq!(
            flag_note("a_later_flag", &none).text,
            "flagged: a_later_flag"
        );
    }
}
