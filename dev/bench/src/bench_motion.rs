//! `videomocap bench motion`: what an animator sees in the motion (issue 82): jitter beside the
//! reference motion capture's own, foot sliding over the reference's contact phases beside the
//! reference's own, the root's path after aligning the first frame, and acceleration error
//! ([`videomocap_testkit::eval::motion`]), for the lift and the flat cut-out on the same input.
//!
//! Inputs: (a) the true 2D with the pose network's 3D body (run from the clicked marks, as
//! `bench lift --network` runs it; `--reuse` shares its cache) and, unless `--no-tracker`, (c)
//! the tracker's output with the network (the product's default). User conditions: the height a
//! person would state and the default camera.

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_lift_network::network_on_truth;
use crate::bench_suite::{BenchClip, Merge, Tally, bench_clips};
use crate::{ExitError, say};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use videomocap_core::camera::default_focal;
use videomocap_core::formats::{Marks, Skeleton3d, Tracks2d};
use videomocap_core::lift::{CameraChoice, LiftParams, SubjectChoice, reconstruct};
use videomocap_core::network::PoseNetwork;
use videomocap_core::skeleton::DEFAULT_HEIGHT_M;
use videomocap_core::track::{TrackJob, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::motion::{MotionScore, score_motion};
use videomocap_testkit::eval::pose3d::{cutout, tracks_from_truth};
use videomocap_testkit::eval::suite::{CLICK_NOISE_PX, clicked_marks};
use videomocap_testkit::synth::GroundTruth;

impl Merge for MotionScore {
    fn merge_from(&mut self, other: &Self) {
        self.merge(other);
    }
}

/// Per input, the lift's motion and the cut-out's.
type Scores = [[MotionScore; 2]; 2];

const INPUTS: [&str; 2] = [
    "(a) true 2D with the network's body",
    "(c) the tracker's output (with the network)",
];

/// The lift (stated height, default camera) and the cut-out of one input.
fn score_input(gt: &GroundTruth, tracks: &Tracks2d) -> Result<[MotionScore; 2], ExitError> {
    let mut camera = gt.camera();
    camera.focal_px = default_focal(gt.width, gt.height);
    let subject = SubjectChoice::Height {
        height_m: gt.stated_height_m.unwrap_or(DEFAULT_HEIGHT_M),
        known: Default::default(),
    };
    let lifted: Skeleton3d = reconstruct(
        tracks,
        CameraChoice::Given(camera),
        &subject,
        &LiftParams::default(),
        Default::default(),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .map_err(ExitError::failed)?
    .output
    .skeleton;
    let flat = cutout(gt, tracks, gt.camera());
    Ok([
        score_motion(gt, &lifted).unwrap_or_default(),
        score_motion(gt, &flat).unwrap_or_default(),
    ])
}

fn score_clip(
    clip: &BenchClip,
    network: &Arc<PoseNetwork>,
    a: &BenchArgs,
    threads: usize,
) -> Result<Scores, ExitError> {
    let dir = &clip.dir;
    let gt = GroundTruth::load(&dir.join("gt.json")).map_err(ExitError::failed)?;
    let marks = clicked_marks(
        &Marks::load(&dir.join("marks.json")).map_err(ExitError::failed)?,
        CLICK_NOISE_PX,
        &clip.name,
    );
    let mut video =
        Video::open(&dir.join("video.mp4"), &OpenOptions::default()).map_err(ExitError::failed)?;
    let mut exact = tracks_from_truth(&gt, 0.0, 1);
    let net = network_on_truth(clip, &mut video, &exact, &marks, network, a.reuse)?;
    for (f, seen) in exact.frames.iter_mut().zip(&net) {
        f.body3d = seen.body().map(Box::new);
    }
    let mut scores = Scores::default();
    scores[0] = score_input(&gt, &exact)?;
    if !a.no_tracker {
        let job = TrackJob::from_marks(&marks, TrackerParams::default(), threads)
            .with_network(Some(network.clone()));
        let tracked = track_video(&mut video, &job, &mut |_| {}, &AtomicBool::new(false))
            .map_err(ExitError::failed)?
            .tracks;
        scores[1] = score_input(&gt, &tracked)?;
    }
    Ok(scores)
}

const WIDTH: usize = 44;

fn cell(s: &[MotionScore; 2]) -> String {
    if s[0].jitter_n == 0 {
        return format!("{:>WIDTH$}", "—");
    }
    let (j, rj) = s[0].jitter();
    let (sl, rsl) = s[0].slide_cm();
    let (cut_sl, _) = s[1].slide_cm();
    format!(
        "{:>5.0}/{:<4.0} {:>5.1}/{:<4.1} {:>5.1} {:>6.0} {:>6.1}",
        j,
        rj,
        sl,
        rsl,
        cut_sl,
        s[0].root_mm(),
        s[0].accel()
    )
}

/// Runs the motion benchmark and prints its tables.
pub fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let network = Arc::new(
        PoseNetwork::bundled()
            .map_err(ExitError::failed)?
            .with_threads(threads),
    );
    let clips = bench_clips(&a.suite_dir, &a.split, a.clip.as_deref(), global)?;
    let mut tally: Tally<Scores> = Tally::default();
    for clip in &clips {
        say(global, &format!("motion of {} …", clip.name));
        let s = score_clip(clip, &network, a, threads)?;
        tally.add(clip, &s);
    }
    let columns = format!(
        "{:>10} {:>10} {:>5} {:>6} {:>6}",
        "jitter/ref", "slide/ref", "cut", "root", "accel"
    );
    let mut out = vec![
        "motion of the lift (stated height, default camera): jitter m/s³ (the reference's own after /), foot sliding cm per contact phase (the reference's own after /, the cut-out's), root path error mm (first frame aligned), acceleration error m/s²".to_owned(),
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
