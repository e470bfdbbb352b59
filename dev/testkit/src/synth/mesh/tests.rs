//! The mesh figure as rendered: joints on the mesh, the trunk closed.
use super::*;
use crate::synth::{
    Figure, ProceduralMotion, SensorEffects, Surface, procedural, render_frame, stature_of,
};
use image::{Rgb, RgbImage};
use videomocap_core::skeleton::SubjectModel;

const GREEN: [u8; 3] = [0, 255, 0];

/// Frames of a walk seen from the front, 4 m away, on a green screen.
fn walk_frames(frames: &[usize]) -> Vec<(crate::synth::Rendered, PerJoint<Point3<f64>>)> {
    let motion = procedural(ProceduralMotion::Walk, &SubjectModel::default(), 20, 30.0);
    let camera = PinholeCamera::centred(600.0, 320, 400);
    let screen = RgbImage::from_pixel(320, 400, Rgb(GREEN));
    let still = SensorEffects {
        noise_sigma: 0.0,
        flicker: 0.0,
        seed: 0,
    };
    frames
        .iter()
        .map(|&i| {
            // World (Y up, facing +Z) to a camera 4 m in front, 1 m up, looking back at it.
            let points = motion.frames[i].map(|_, p| Point3::new(p.x, 1.0 - p.y, 4.0 - p.z));
            let figure = Figure {
                points: &points,
                stature_m: stature_of(&motion),
                appearance: Appearance::default(),
                surface: Surface::Mesh,
            };
            let r = render_frame(&camera, &figure, &[], &screen, &still, i).unwrap();
            (r, points)
        })
        .collect()
}

#[test]
fn every_visible_joint_falls_on_the_mesh_and_no_background_shows_through_the_trunk() {
    for (r, _) in walk_frames(&[0, 7, 14]) {
        let on_body = |x: f64, y: f64| {
            let (x, y) = (x.round() as i64, y.round() as i64);
            (x >= 0 && y >= 0 && x < 320 && y < 400)
                && r.image.get_pixel(x as u32, y as u32).0 != GREEN
        };
        let seen = Joint::ALL.iter().filter(|&&j| r.visible[j]).count();
        assert!(seen >= 12, "only {seen} joints visible");
        for j in Joint::ALL {
            if !r.visible[j] {
                continue;
            }
            let p = r.points2d[j];
            let near = (-2..=2)
                .flat_map(|dy| (-2..=2).map(move |dx| (dx, dy)))
                .any(|(dx, dy)| on_body(p.x + f64::from(dx), p.y + f64::from(dy)));
            assert!(near, "{} at {p} is off the mesh", j.name());
        }
        // The trunk's quad (shoulders, hips) shrunk to 70 % about its centre: all body.
        use Joint::*;
        let q = [LeftShoulder, RightShoulder, RightHip, LeftHip].map(|j| r.points2d[j]);
        let centre = (q[0].coords + q[1].coords + q[2].coords + q[3].coords) / 4.0;
        for a in 0..=10 {
            for b in 0..=10 {
                let (s, t) = (f64::from(a) / 10.0, f64::from(b) / 10.0);
                let top = q[0].coords * (1.0 - s) + q[1].coords * s;
                let bottom = q[3].coords * (1.0 - s) + q[2].coords * s;
                let p = centre + ((top * (1.0 - t) + bottom * t) - centre) * 0.7;
                assert!(
                    on_body(p.x, p.y),
                    "background shows at {p} inside the trunk"
                );
            }
        }
    }
}

#[test]
fn the_posed_mesh_keeps_the_clips_stature_and_its_joints() {
    let rest = rest_mesh().unwrap();
    assert!(
        (1.5..1.9).contains(&rest.stature_m),
        "rest stature {} m",
        rest.stature_m
    );
    // Posed on its own rest joints the mesh does not move.
    let points = rest.joints.map(|_, p| Point3::from(*p));
    let same = posed_vertices(rest, &points, rest.stature_m);
    let worst = same
        .iter()
        .zip(&rest.positions)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "moved {worst} m");
}

/// The rest mesh reads the same every time (skinning weights and bone axes): two loads, each
/// with its own hash maps inside, give identical weights and regions, so a clip renders the same
/// pixels on every run.
#[test]
fn the_rest_mesh_reads_the_same_every_time() {
    let a = RestMesh::load().unwrap();
    for _ in 0..3 {
        let b = RestMesh::load().unwrap();
        assert!(
            a.weights == b.weights,
            "skinning weights differ between loads"
        );
        let axes = |m: &RestMesh| -> Vec<(f64, f64)> {
            let p = Vector3::new(0.1, 0.9, 0.05);
            m.regions
                .iter()
                .map(|(_, x)| x.pattern_coordinates(&p))
                .collect()
        };
        assert!(axes(&a) == axes(&b), "bone axes differ between loads");
    }
}
