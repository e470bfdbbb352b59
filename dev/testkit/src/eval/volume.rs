//! Accuracy of the volume pipeline against the true joints of a synthetic volume sequence:
//! topology (share of frames whose skeleton curve had five limbs), joint position error in
//! millimetres with left and right matched once per sequence (the paper labels limbs arm1/arm2,
//! leg1/leg2, never left/right), the same per frame, and limb-label consistency (share of frames
//! whose best per-frame matching equals the sequence's); and, as a user gets them, the error with
//! left and right as reported (nothing forgiven) and the share of frames whose sides are right.

use nalgebra::Point3;
use serde::Serialize;
use videomocap_core::formats::Skeleton3d;
use videomocap_core::skeleton::{Joint, PerJoint};

/// Scores of one sequence.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct VolumeScore {
    /// Input frames.
    pub frames: usize,
    /// Frames whose skeleton curve had the right five-limb topology.
    pub topology_ok: usize,

    /// Joint samples scored (16 per output frame).
    pub samples: usize,
    /// Sum of joint errors with one left/right matching for the sequence, metres.
    pub sum_m: f64,
    /// Sum of joint errors with the best matching per frame, metres.
    pub sum_frame_matched_m: f64,
    /// Sum of joint errors with left and right as reported, metres.
    pub sum_reported_m: f64,
    /// Output frames whose reported sides are the best matching (arms and legs).
    pub sides_right: usize,
    /// Output frames whose best per-frame matching equals the sequence's.
    pub consistent: usize,
    /// Output frames scored.
    pub scored_frames: usize,
}

impl VolumeScore {
    /// Adds another sequence's counts.
    pub fn merge(&mut self, o: &VolumeScore) {
        self.frames += o.frames;
        self.topology_ok += o.topology_ok;

        self.samples += o.samples;
        self.sum_m += o.sum_m;
        self.sum_frame_matched_m += o.sum_frame_matched_m;
        self.sum_reported_m += o.sum_reported_m;
        self.sides_right += o.sides_right;
        self.consistent += o.consistent;
        self.scored_frames += o.scored_frames;
    }
    /// Share of frames with the right topology.
    pub fn topology(&self) -> f64 {
        self.topology_ok as f64 / self.frames.max(1) as f64
    }
    /// Mean joint error, millimetres (sequence matching).
    pub fn mean_mm(&self) -> f64 {
        1000.0 * self.sum_m / self.samples.max(1) as f64
    }
    /// Mean joint error, millimetres (per-frame matching).
    pub fn mean_frame_matched_mm(&self) -> f64 {
        1000.0 * self.sum_frame_matched_m / self.samples.max(1) as f64
    }
    /// Mean joint error with left and right as reported, millimetres.
    pub fn mean_reported_mm(&self) -> f64 {
        1000.0 * self.sum_reported_m / self.samples.max(1) as f64
    }
    /// Share of output frames whose reported left and right are the best matching.
    pub fn sides_right_share(&self) -> f64 {
        self.sides_right as f64 / self.scored_frames.max(1) as f64
    }
    /// Share of frames whose labels agree with the sequence's matching.
    pub fn consistency(&self) -> f64 {
        self.consistent as f64 / self.scored_frames.max(1) as f64
    }
}

/// The joints with arms and/or legs swapped.
fn swapped(p: &PerJoint<Point3<f64>>, arms: bool, legs: bool) -> PerJoint<Point3<f64>> {
    use Joint::*;
    PerJoint::from_fn(|j| {
        let arm = matches!(
            j,
            LeftShoulder | LeftElbow | LeftWrist | RightShoulder | RightElbow | RightWrist
        );
        let leg = matches!(
            j,
            LeftHip | LeftKnee | LeftAnkle | RightHip | RightKnee | RightAnkle
        );
        if (arm && arms) || (leg && legs) {
            p[j.mirrored()]
        } else {
            p[j]
        }
    })
}

/// Summed joint errors of one frame: [head, trunk and arms; legs] (a swap of arms changes
/// only the first, a swap of legs only the second).
fn frame_errors(a: &PerJoint<Point3<f64>>, b: &PerJoint<Point3<f64>>) -> [f64; 2] {
    let mut e = [0.0; 2];
    for (j, p) in a.iter() {
        let d = (p - b[j]).norm();
        if j.index() >= Joint::LeftHip.index() {
            e[1] += d;
        } else {
            e[0] += d;
        }
    }
    e
}

/// Scores `result` (the pipeline's skeleton) against `truth`; `topology_ok` counts frames whose
/// skeleton curve showed all five limbs.
pub fn score_volume(truth: &Skeleton3d, result: &Skeleton3d, topology_ok: usize) -> VolumeScore {
    let mut s = VolumeScore {
        frames: truth.frames.len(),
        topology_ok,
        ..Default::default()
    };
    type Pose = PerJoint<Point3<f64>>;
    let pairs: Vec<(&Pose, &Pose)> = result
        .frames
        .iter()
        .filter_map(|f| {
            truth
                .frames
                .iter()
                .find(|t| t.index == f.index)
                .map(|t| (&f.points, &t.points))
        })
        .collect();
    // [no swap, swap] totals for arms and legs; "upper" holds head/trunk/arms, "lower" legs.
    let mut totals = [[0.0; 2]; 2]; // [swap?][arms-part, legs-part]
    let mut per_frame = Vec::new();
    for (r, t) in &pairs {
        let plain = frame_errors(r, t);
        let both = frame_errors(&swapped(r, true, true), t);
        for k in 0..2 {
            totals[0][k] += plain[k];
            totals[1][k] += both[k];
        }
        per_frame.push((plain, both));
    }
    let swap_arms = totals[1][0] < totals[0][0];
    let swap_legs = totals[1][1] < totals[0][1];
    for (plain, both) in per_frame {
        let seq = [
            if swap_arms { both[0] } else { plain[0] },
            if swap_legs { both[1] } else { plain[1] },
        ];
        let best = [plain[0].min(both[0]), plain[1].min(both[1])];
        s.sum_m += seq[0] + seq[1];
        s.sum_frame_matched_m += best[0] + best[1];
        s.sum_reported_m += plain[0] + plain[1];
        if plain[0] <= both[0] && plain[1] <= both[1] {
            s.sides_right += 1;
        }
        s.samples += 16;
        s.scored_frames += 1;
        let agrees = (swap_arms == (both[0] < plain[0])) && (swap_legs == (both[1] < plain[1]));
        if agrees {
            s.consistent += 1;
        }
    }
    s
}

/// How `carve_and_score` carves: views, voxel size, the faults drawn into the silhouettes and
/// how many masks must hold a voxel (`None`: every one).
#[derive(Debug, Clone, PartialEq)]
pub struct CarveCase {
    /// Cameras on the ring.
    pub views: usize,
    /// Voxel edge, metres.
    pub voxel_m: f64,
    /// Faults drawn into the masks.
    pub faults: crate::synth::SilhouetteFaults,
    /// Masks that must contain a voxel.
    pub min_votes: Option<usize>,
    /// What the person is drawn as: the capsule body, or MakeHuman's mesh (suite v4's people).
    pub surface: crate::synth::Surface,
}

impl CarveCase {
    /// `views` cameras with clean silhouettes, every mask holding each voxel, at `voxel_m`.
    pub fn clean(views: usize, voxel_m: f64) -> CarveCase {
        CarveCase {
            views,
            voxel_m,
            faults: crate::synth::SilhouetteFaults::default(),
            min_votes: None,
            surface: crate::synth::Surface::Capsules,
        }
    }
}

/// What one carved sequence gave: its score, the mean voxels kept per frame, and the mean
/// voxels the carve dropped per frame (other components: a second person, fragments).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarveResult {
    /// Accuracy against the truth: the subject's body fitted over the clip (the product's
    /// output; the curve's when the fit could not run).
    pub score: VolumeScore,
    /// The paper's skeleton curve alone.
    pub curve_score: VolumeScore,
    /// Mean voxels kept per frame.
    pub voxels: f64,
    /// Mean voxels dropped per frame.
    pub dropped: f64,
    /// Frames the fit flagged.
    pub flagged: usize,
}

/// Carves `motion` as `case` says (640×480 cameras around the body, see
/// [`crate::synth::write_carving_setup`]), keeping the component nearest the body's mean
/// pelvis (the person a user points at), runs the volume pipeline on the grids and scores it
/// against the truth. Every file lives in a temporary directory. What the carving test and
/// `bench volume` measure.
pub fn carve_and_score(
    motion: &crate::synth::Motion,
    case: &CarveCase,
    params: &videomocap_volume::VolumeParams,
) -> Result<CarveResult, videomocap_volume::SequenceError> {
    use std::sync::atomic::AtomicBool;
    use videomocap_volume::carve::{carve_sequence, open_setup};
    use videomocap_volume::{VolumeError, process_directory};
    let dir = tempfile::tempdir().map_err(VolumeError::io(&std::env::temp_dir()))?;
    let (setup_dir, grids) = (dir.path().join("setup"), dir.path().join("grids"));
    crate::synth::write_carving_setup_of(
        motion,
        &setup_dir,
        case.views,
        (640, 480),
        &case.faults,
        case.surface,
        &|_, _| {},
    )?;
    let setup = open_setup(&setup_dir)?;
    let never = AtomicBool::new(false);
    let pelvis = motion
        .frames
        .iter()
        .map(|f| f[videomocap_core::skeleton::Joint::Pelvis].coords)
        .sum::<nalgebra::Vector3<f64>>()
        / motion.frames.len().max(1) as f64;
    let kept = carve_sequence(
        &setup,
        case.voxel_m,
        case.min_votes,
        Some(nalgebra::Point3::from(pelvis)),
        &grids,
        &|_, _| {},
        &never,
    )?;
    let p = process_directory(&grids, params, motion.fps, &|_, _| {}, &never)?;
    let n = kept.len().max(1) as f64;
    let truth = crate::synth::volume_truth(motion);
    Ok(CarveResult {
        score: score_volume(&truth, &p.assembled.skeleton, p.five_limb_frames()),
        curve_score: score_volume(&truth, &p.curve_skeleton, p.five_limb_frames()),
        voxels: kept.iter().map(|k| k.voxels).sum::<usize>() as f64 / n,
        dropped: kept.iter().map(|k| k.dropped_voxels).sum::<usize>() as f64 / n,
        flagged: p
            .assembled
            .skeleton
            .frames
            .iter()
            .filter(|f| !f.flags.is_empty())
            .count(),
    })
}
