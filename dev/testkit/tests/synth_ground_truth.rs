//! The synthetic clips are trustworthy ground truth: 2D points are the projections of the 3D
//! points, bones keep their lengths, the person is drawn where the joints are, self-occlusion
//! is seen, and the marks are frame 0.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic

use std::path::Path;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::Marks;
use videomocap_core::skeleton::{Bone, Joint};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::synth::{
    GroundTruth, MotionSource, ProceduralMotion, SynthParams, VideoOutput, View, render_clip,
};

fn render(dir: &Path, motion: MotionSource, view: View, frames: usize) -> GroundTruth {
    let params = SynthParams {
        motion,
        frames,
        width: 320,
        height: 240,
        focal_px: 300.0,
        person_px: 180.0,
        view,
        output: VideoOutput::PngSequence,
        ..SynthParams::default()
    };
    let r = render_clip(&params, dir, &mut |_, _| {}, &AtomicBool::new(false)).unwrap();
    assert_eq!(r.frames, frames);
    GroundTruth::load(&r.ground_truth).unwrap()
}

#[test]
fn points2d_are_the_projections_of_points3d_and_bones_are_rigid() {
    let dir = tempfile::tempdir().unwrap();
    let gt = render(
        dir.path(),
        MotionSource::Procedural(ProceduralMotion::JumpingJacks),
        View::Frontal,
        12,
    );
    let cam = gt.camera();
    for f in &gt.frames {
        let p3 = f.points3d();
        let p2 = f.points2d();
        for j in Joint::ALL {
            let proj = cam.project(&p3[j]).unwrap();
            assert!((proj - p2[j]).norm() < 1e-3, "frame {} {j}", f.index);
            assert!(cam.contains(&p2[j]), "frame {} {j} off the image", f.index);
        }
        for b in Bone::ALL {
            let len = (p3[b.child] - p3[b.parent]).norm();
            let truth = gt.bone_lengths_m[&b.key()];
            assert!((len - truth).abs() < 1e-5, "frame {} {}", f.index, b.key());
        }
    }
    // Marks are frame 0.
    let marks = Marks::load(&dir.path().join("marks.json")).unwrap();
    for j in Joint::ALL {
        assert!((marks.points[j] - gt.frames[0].points2d()[j]).norm() < 1e-3);
    }
}

#[test]
fn the_person_is_drawn_at_the_visible_joints_and_the_side_view_hides_some() {
    let dir = tempfile::tempdir().unwrap();
    let gt = render(
        dir.path(),
        MotionSource::Procedural(ProceduralMotion::Walk),
        View::Side,
        6,
    );
    let mut v = Video::open(&dir.path().join("frames"), &OpenOptions::default()).unwrap();
    assert_eq!(v.info().frame_count, 6);
    let bg =
        videomocap_testkit::synth::background(320, 240, SynthParams::default().background_seed);
    let mut hidden = 0;
    for f in &gt.frames {
        let img = v.frame(f.index).unwrap().image;
        for j in Joint::ALL {
            let p = f.points2d()[j];
            let (x, y) = (p.x.round() as u32, p.y.round() as u32);
            if j == Joint::HeadTop {
                continue; // on the outline: half background by definition
            }
            let a = img.get_pixel(x, y);
            let b = bg.get_pixel(x, y);
            let diff: u32 = (0..3).map(|c| u32::from(a[c].abs_diff(b[c]))).sum();
            assert!(
                diff > 30,
                "frame {} {j}: the body is not drawn there",
                f.index
            );
        }
        hidden += f.visible.iter().filter(|v| !**v).count();
    }
    // In profile the far arm and leg are behind the body for part of the time.
    assert!(hidden > 0, "no joint is ever hidden in a side view");
}

#[test]
fn motion_capture_clips_render_with_both_rigs() {
    for file in [
        "tests/data/cmu_02_01_walk.bvh",
        "tests/data/cmu_61_05_dance.bvh",
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = videomocap_testkit::repo_root().join(file);
        let gt = render(
            dir.path(),
            MotionSource::Bvh { path, start_s: 0.5 },
            View::Oblique,
            4,
        );
        let h = gt.frames[0].points2d();
        // Head above ankles in the image (y down), person between 100 and 240 px tall.
        let height = h[Joint::LeftAnkle].y.max(h[Joint::RightAnkle].y) - h[Joint::HeadTop].y;
        assert!((100.0..240.0).contains(&height), "{file}: {height}");
    }
}
