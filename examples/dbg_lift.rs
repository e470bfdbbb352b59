use std::path::Path;
use videomocap::camera::PinholeCamera;
use videomocap::eval::pose3d::*;
use videomocap::lift::*;
use videomocap::skeleton::*;
use videomocap::synth::GroundTruth;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = Path::new(&args[1]);
    let gt = GroundTruth::load(&dir.join("gt.json")).unwrap();
    let tracks = tracks_from_truth(&gt, 0.0, 1);
    let cam = PinholeCamera {
        focal_px: gt.focal_px,
        cx: gt.cx,
        cy: gt.cy,
        width: gt.width,
        height: gt.height,
    };
    let subject = subject_from_truth(&gt);
    let mut params = LiftParams::default();
    params.refine = args.get(2).is_some();
    if let Some(j) = args.get(3) {
        params.refinement = serde_json::from_str(j).unwrap();
    }
    let job = LiftJob {
        tracks: &tracks,
        camera: cam,
        subject: subject.clone(),
        params,
        overrides: Default::default(),
    };
    let out = lift(&job, &mut |_| {}, &Default::default()).unwrap();
    println!("calib frame {}", out.calibration_frame);
    for t in [0usize, 1, 30, 60, 90, 119] {
        let Some(f) = out.per_frame.frames.get(t) else {
            continue;
        };
        let g = gt.frames[t].points3d();
        let errs: Vec<String> = Joint::ALL
            .iter()
            .map(|&j| {
                format!(
                    "{}:{:.0}",
                    &j.name()[..5.min(j.name().len())],
                    1000.0 * (f.points[j] - g[j]).norm()
                )
            })
            .collect();
        println!(
            "t{t} key rms {:.4} flags {:?}\n   {}",
            out.reports[t].key_rms_m,
            out.reports[t]
                .flags
                .iter()
                .map(|f| f.to_string())
                .collect::<Vec<_>>(),
            errs.join(" ")
        );
    }
    for t in [0usize, 60] {
        let f = &out.skeleton.frames[t];
        let g = gt.frames[t].points3d();
        let errs: Vec<String> = Joint::ALL
            .iter()
            .map(|&j| format!("{:.0}", 1000.0 * (f.points[j] - g[j]).norm()))
            .collect();
        println!("refined t{t} {}", errs.join(" "));
        println!(
            "  pelvis ours {:?} gt {:?}",
            f.points[Joint::Pelvis],
            g[Joint::Pelvis]
        );
    }
    println!("lengths {:?}", out.skeleton.bone_lengths_m);
    let s = score_skeleton(&gt, &out.per_frame).unwrap();
    println!(
        "per-frame mpjpe {:.1} wrong {:.3}",
        s.mpjpe_mm(),
        s.wrong_share()
    );
    let s = score_skeleton(&gt, &out.skeleton).unwrap();
    println!(
        "final mpjpe {:.1} wrong {:.3} {:?}",
        s.mpjpe_mm(),
        s.wrong_share(),
        out.refinement
    );
    // bone length truth variation
    for b in Bone::ALL {
        let v: Vec<f64> = gt
            .frames
            .iter()
            .map(|f| {
                let p = f.points3d();
                (p[b.child] - p[b.parent]).norm()
            })
            .collect();
        let mn = v.iter().cloned().fold(f64::MAX, f64::min);
        let mx = v.iter().cloned().fold(0.0, f64::max);
        if mx - mn > 0.005 {
            println!("gt bone {} varies {:.3}..{:.3}", b.key(), mn, mx);
        }
    }
}
