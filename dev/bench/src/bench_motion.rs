//! `videomocap bench motion`: what an animator sees in the motion (issue 82): jitter beside the
//! reference motion capture's own, foot sliding over the reference's contact phases beside the
//! reference's own, the root's path after aligning the first frame, the root's height over the
//! floor (each in its export world), and acceleration error
//! ([`videomocap_testkit::eval::motion`]), for the lift and the flat cut-out on the same input.
//!
//! Inputs: (a) the true 2D with the pose network's 3D body (run from the clicked marks, as
//! `bench lift --network` runs it; `--reuse` shares its cache) and, unless `--no-tracker`, (c)
//! the tracker's output with the network (the product's default). User conditions: the height a
//! person would state and the default camera.

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_lift_network::inputs_with_network;
use crate::bench_suite::{BenchClip, Merge, Tally, bench_clips};
use crate::{ExitError, say};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use videomocap_core::camera::default_focal;
use videomocap_core::formats::{Skeleton3d, Tracks2d};
use videomocap_core::lift::{CameraChoice, FEET, LiftParams, SubjectChoice, reconstruct};
use videomocap_core::network::PoseNetwork;
use videomocap_core::skeleton::DEFAULT_HEIGHT_M;
use videomocap_testkit::eval::motion::{MotionScore, score_motion};
use videomocap_testkit::eval::pose3d::cutout;
use videomocap_testkit::synth::GroundTruth;

impl Merge for MotionScore {
    fn merge_from(&mut self, other: &Self) {
        self.merge(other);
    }
}

/// How far the foot lock moved the ankles in the image on the frames it held them, pixels.
#[derive(Debug, Clone, Copy, Default)]
struct LockShift {
    sum_px: f64,
    max_px: f64,
    n: usize,
}

impl Merge for LockShift {
    fn merge_from(&mut self, o: &Self) {
        self.sum_px += o.sum_px;
        self.max_px = self.max_px.max(o.max_px);
        self.n += o.n;
    }
}

/// Per input: the lift without the foot lock, with it, the cut-out; the lock's image shift.
type Scores = [([MotionScore; 3], LockShift); 2];

const INPUTS: [&str; 2] = [
    "(a) true 2D with the network's body",
    "(c) the tracker's output (with the network)",
];

/// The lift (stated height, default camera) without and with the foot lock, and the cut-out,
/// of one input.
fn score_input(
    gt: &GroundTruth,
    tracks: &Tracks2d,
) -> Result<([MotionScore; 3], LockShift), ExitError> {
    let mut camera = gt.camera();
    camera.focal_px = default_focal(gt.width, gt.height);
    let subject = SubjectChoice::Height {
        height_m: gt.stated_height_m.unwrap_or(DEFAULT_HEIGHT_M),
        known: Default::default(),
    };
    let lift = |foot_lock: bool| {
        let params = LiftParams {
            foot_lock,
            ..LiftParams::default()
        };
        reconstruct(
            tracks,
            CameraChoice::Given(camera),
            &subject,
            &params,
            Default::default(),
            &mut |_| {},
            &AtomicBool::new(false),
        )
        .map_err(ExitError::failed)
        .map(|r| r.output)
    };
    let free = lift(false)?.skeleton;
    let locked = lift(true)?;
    let mut shift = LockShift::default();
    for ((a, b), c) in free
        .frames
        .iter()
        .zip(&locked.skeleton.frames)
        .zip(&locked.contacts)
    {
        for (k, ankle) in FEET.iter().enumerate() {
            if c[k]
                && let (Some(p), Some(q)) = (
                    camera.project(&a.points[*ankle]),
                    camera.project(&b.points[*ankle]),
                )
            {
                let d = (p - q).norm();
                shift.sum_px += d;
                shift.max_px = shift.max_px.max(d);
                shift.n += 1;
            }
        }
    }
    let flat = cutout(gt, tracks, gt.camera());
    let score = |s: &Skeleton3d| score_motion(gt, s).unwrap_or_default();
    Ok(([score(&free), score(&locked.skeleton), score(&flat)], shift))
}

fn score_clip(
    clip: &BenchClip,
    network: &Arc<PoseNetwork>,
    a: &BenchArgs,
    threads: usize,
) -> Result<Scores, ExitError> {
    let mut opened = clip.open()?;
    let (exact, tracked) = inputs_with_network(clip, &mut opened, network, a, threads)?;
    let gt = &opened.gt;
    let mut scores = Scores::default();
    scores[0] = score_input(gt, &exact)?;
    if let Some(tracked) = tracked {
        scores[1] = score_input(gt, &tracked)?;
    }
    Ok(scores)
}

const WIDTH: usize = 60;

fn cell(s: &([MotionScore; 3], LockShift)) -> String {
    let [free, locked, flat] = &s.0;
    if free.jitter_n == 0 {
        return format!("{:>WIDTH$}", "—");
    }
    let (_, rj) = free.jitter();
    let (_, rsl) = free.slide_cm();
    format!(
        "{:>4.0}/{:<4.0} {:>4.1}>{:<4.1}/{:<3.1} {:>4.1} {:>4.0}>{:<4.0} {:>5.0} {:>5.1} {:>3.1}/{:<4.1}",
        locked.jitter().0,
        rj,
        free.slide_cm().0,
        locked.slide_cm().0,
        rsl,
        flat.slide_cm().0,
        free.root_mm(),
        locked.root_mm(),
        locked.root_height_mm(),
        locked.accel(),
        s.1.sum_px / s.1.n.max(1) as f64,
        s.1.max_px
    )
}

/// Runs the motion benchmark and prints its tables.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let threads = crate::bench_suite::machine_threads();
    let network = crate::bench_suite::bundled_network(threads)?;
    let clips = bench_clips(&a.suite_dir, &a.split, a.clip.as_deref(), global)?;
    let mut tally: Tally<Scores> = Tally::default();
    for clip in &clips {
        say(global, &format!("motion of {} …", clip.name));
        let s = score_clip(clip, &network, a, threads)?;
        tally.add(clip, &s);
    }
    let columns = format!(
        "{:>9} {:>14} {:>4} {:>9} {:>5} {:>5} {:>8}",
        "jitter/ref", "slide>lock/ref", "cut", "root>lock", "height", "accel", "px m/max"
    );
    let mut out = vec![
        "motion of the lift (stated height, default camera): jitter m/s³ with the foot lock (the reference's own after /); foot sliding, cm per reference contact phase, without > with the lock (the reference's own after /), the cut-out's; root path error mm (first frame aligned) without > with; the root's height over the floor, error mm, with the lock; acceleration error m/s²; how far the lock moved a held ankle in the image, px mean / max".to_owned(),
    ];
    for (i, input) in INPUTS.iter().enumerate() {
        out.push(String::new());
        out.push((*input).to_owned());
        out.extend(Tally::<Scores>::heading(WIDTH, &columns));
        out.extend(tally.lines(WIDTH, |s: &Scores| cell(&s[i])));
    }
    for l in out {
        println!("{l}");
    }
    Ok(())
}
