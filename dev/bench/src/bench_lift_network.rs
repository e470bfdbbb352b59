//! `videomocap bench lift --network`: the lift alone, the pose network's 3D body alone and the
//! two together (the network's body as depth evidence in the lift's choice of roots), with the
//! flat cut-out, on the same input and in the same run.
//!
//! Inputs: (a) the true 2D points, the network run on the clip's frames from the clicked marks
//! (as the tracker runs it: each crop the one it proposed on the frame before); (c) unless
//! `--no-tracker`, the tracker's output with the network weighed in (the product's default),
//! which carries the network's body itself. Every lift from the height a person would state
//! and the true focal length.

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_suite::{BenchClip, Merge, OpenedClip, Tally, bench_clips};
use crate::{ExitError, say};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::{Frame3d, Marks, Skeleton3d, Tracks2d, UNUSUAL_POSE_FLAG};
use videomocap_core::lift::{CameraChoice, LiftParams, SubjectChoice, reconstruct};
use videomocap_core::network::PoseNetwork;
use videomocap_core::skeleton::{Bone, DEFAULT_HEIGHT_M, Joint, PerJoint};
use videomocap_core::track::{NetworkFrames, TrackJob, TrackerParams, run_network, track_video};
use videomocap_core::video::Video;
use videomocap_testkit::eval::doubt::{DoubtTally, tally_doubt};
use videomocap_testkit::eval::pose3d::{Pose3dScore, cutout, score_skeleton, tracks_from_truth};
use videomocap_testkit::eval::suite::Split;
use videomocap_testkit::synth::GroundTruth;

/// A bone's depth order counts when the reference's ends differ in depth by more than this,
/// metres (as the probe counted it).
const ORDER_SHOWS_M: f64 = 0.05;

/// How often a 3D body puts a bone's ends in the reference's depth order, over the bone-frames
/// where the reference's ends differ by more than [`ORDER_SHOWS_M`].
#[derive(Debug, Clone, Copy, Default)]
struct Agreement {
    agree: usize,
    total: usize,
}

impl Merge for Agreement {
    fn merge_from(&mut self, o: &Self) {
        self.agree += o.agree;
        self.total += o.total;
    }
}

impl Agreement {
    fn share(&self) -> f64 {
        self.agree as f64 / self.total.max(1) as f64
    }

    /// Adds a frame: `ours` against the reference's points (any origin: differences only).
    fn add(&mut self, ours: &PerJoint<[f64; 3]>, truth: &PerJoint<[f64; 3]>) {
        for b in Bone::ALL {
            let dz = |p: &PerJoint<[f64; 3]>| p[b.child][2] - p[b.parent][2];
            if dz(truth).abs() > ORDER_SHOWS_M {
                self.total += 1;
                self.agree += usize::from(dz(ours) * dz(truth) > 0.0);
            }
        }
    }
}

/// One column's scores: the 3D error and the depth order's agreement.
type Column = (Pose3dScore, Agreement);

/// A clip's columns per input: cut-out, the lift's geometry alone (no prior, no network), the
/// geometry with the pose prior, the network alone, then the lift (with the prior) together
/// with the network at each weight; `None` where the input was not run.
/// And per input, whether the together lift's doubts point at its mistakes.
type Scores = ([Vec<Column>; 2], [DoubtTally; 2]);

const INPUT_NAMES: [&str; 2] = [
    "(a) true 2D, network run from the clicked marks",
    "(c) the tracker's output (with the network)",
];

fn agreement(gt: &GroundTruth, skeleton: &Skeleton3d) -> Agreement {
    let mut a = Agreement::default();
    for f in &skeleton.frames {
        if let Some(t) = gt.frames.get(f.index.get()) {
            let truth = t.points3d().map(|_, p| [p.x, p.y, p.z]);
            a.add(&f.points.map(|_, p| [p.x, p.y, p.z]), &truth);
        }
    }
    a
}

/// The network's 3D body as the answer: each frame's body at the reference pelvis (as the
/// cut-out stands at its depth: scores are pelvis-aligned), the cut-out's frame where it saw
/// no body.
fn network_alone(gt: &GroundTruth, tracks: &Tracks2d, flat: &Skeleton3d) -> Skeleton3d {
    let frames = tracks
        .frames
        .iter()
        .zip(&flat.frames)
        .map(|(f, cut)| match (&f.body3d, gt.frames.get(f.index.get())) {
            (Some(body), Some(t)) => {
                let pelvis = t.points3d()[Joint::Pelvis];
                let origin = body.points[Joint::Pelvis];
                Frame3d {
                    index: f.index,
                    points: body.points.map(|_, p| pelvis + (p - origin)),
                    flags: Vec::new(),
                }
            }
            _ => cut.clone(),
        })
        .collect();
    Skeleton3d {
        frames,
        ..flat.clone()
    }
}

/// `tracks` with the network's bodies taken off (the lift alone).
fn without_bodies(tracks: &Tracks2d) -> Tracks2d {
    let mut t = tracks.clone();
    for f in &mut t.frames {
        f.body3d = None;
    }
    t
}

/// The network's frames on the true 2D, cached in the clip's folder with `--reuse`.
pub(crate) fn network_on_truth(
    clip: &BenchClip,
    video: &mut Video,
    exact: &Tracks2d,
    marks: &Marks,
    network: &PoseNetwork,
    reuse: bool,
) -> Result<NetworkFrames, ExitError> {
    let cache = clip.dir.join("lift-net.json");
    if reuse
        && let Ok(text) = std::fs::read_to_string(&cache)
        && let Ok(net) = serde_json::from_str::<NetworkFrames>(&text)
        && net.len() == exact.frames.len()
    {
        return Ok(net);
    }
    let keys = videomocap_core::track::KeyFrames::from_marks(marks);
    let net = run_network(
        video,
        exact,
        network,
        &keys,
        None,
        &mut || {},
        &AtomicBool::new(false),
    )
    .map_err(ExitError::failed)?;
    if reuse {
        let text = serde_json::to_string(&net).map_err(ExitError::failed)?;
        std::fs::write(&cache, text).map_err(ExitError::failed)?;
    }
    Ok(net)
}

/// What one input of one clip gives: its columns, the first together lift's doubts, the seconds
/// that lift took and its frames flagged as an unusual pose.
type Input = (Vec<Column>, DoubtTally, f64, usize);

/// Scores one input of one clip: cut-out, geometry alone, the prior, network alone, together per
/// weight; the first together lift's doubts against its mistakes; the seconds it took (one
/// thread: the lift runs on the caller's) and its frames flagged as an unusual pose.
fn score_input(
    gt: &GroundTruth,
    tracks: &Tracks2d,
    params: &LiftParams,
    weights: &[f64],
) -> Result<Input, ExitError> {
    let camera = gt.camera();
    let subject = SubjectChoice::Height {
        height_m: gt.stated_height_m.unwrap_or(DEFAULT_HEIGHT_M),
        known: Default::default(),
    };
    let lift = |tracks: &Tracks2d, params: &LiftParams| {
        reconstruct(
            tracks,
            CameraChoice::Given(camera),
            &subject,
            params,
            Default::default(),
            &mut |_| {},
            &AtomicBool::new(false),
        )
        .map(|r| r.output)
        .map_err(ExitError::failed)
    };
    let column = |s: &Skeleton3d| -> Result<Column, ExitError> {
        Ok((
            score_skeleton(gt, s).map_err(ExitError::failed)?,
            agreement(gt, s),
        ))
    };
    let flat = cutout(gt, tracks, camera);
    let geometry = LiftParams {
        pose_prior: 0.0,
        ..*params
    };
    let alone = without_bodies(tracks);
    let mut out = vec![
        column(&flat)?,
        column(&lift(&alone, &geometry)?.skeleton)?,
        column(&lift(&alone, params)?.skeleton)?,
        column(&network_alone(gt, tracks, &flat))?,
    ];
    let mut first: Option<(DoubtTally, f64, usize)> = None;
    for &w in weights {
        let mut p = *params;
        p.image_depth = w;
        let (t0, cpu0) = (std::time::Instant::now(), thread_cpu_s());
        let together = lift(tracks, &p)?;
        let seconds = match (cpu0, thread_cpu_s()) {
            (Some(a), Some(b)) => b - a,
            _ => t0.elapsed().as_secs_f64(),
        };
        if first.is_none() {
            let doubt =
                tally_doubt(gt, &together.skeleton, &together.bones).map_err(ExitError::failed)?;
            let unusual = together
                .skeleton
                .frames
                .iter()
                .filter(|f| f.flags.iter().any(|s| s == UNUSUAL_POSE_FLAG))
                .count();
            first = Some((doubt, seconds, unusual));
        }
        out.push(column(&together.skeleton)?);
    }
    let (doubt, seconds, unusual) = first.unwrap_or_default();
    Ok((out, doubt, seconds, unusual))
}

/// The CPU time this thread has run (seconds, from Linux's `/proc/thread-self/schedstat`):
/// the lift's speed on one thread whatever else the machine runs beside it; `None` elsewhere
/// (the wall clock stands in).
fn thread_cpu_s() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// The clip's true 2D carrying the network's body (run from the clicked marks as the tracker
/// runs it), and, unless `--no-tracker`, the tracker's output with the network.
pub(crate) fn inputs_with_network(
    clip: &BenchClip,
    opened: &mut OpenedClip,
    network: &Arc<PoseNetwork>,
    a: &BenchArgs,
    threads: usize,
) -> Result<(Tracks2d, Option<Tracks2d>), ExitError> {
    let mut exact = tracks_from_truth(&opened.gt, 0.0, 1);
    let net = network_on_truth(
        clip,
        &mut opened.video,
        &exact,
        &opened.marks,
        network,
        a.reuse,
    )?;
    for (f, seen) in exact.frames.iter_mut().zip(&net) {
        f.body3d = seen.body().map(Box::new);
    }
    // With `--reuse`, the tracker's output is kept beside the clip (stale after any change
    // to the tracker or the network: delete the file then).
    let cache = clip.dir.join("tracked-net.json");
    let tracked = if a.no_tracker {
        None
    } else if a.reuse
        && let Ok(t) = Tracks2d::load(&cache)
    {
        Some(t)
    } else {
        let job = TrackJob::from_marks(&opened.marks, TrackerParams::default(), threads)
            .with_network(Some(network.clone()));
        let out = track_video(
            &mut opened.video,
            &job,
            &mut |_| {},
            &AtomicBool::new(false),
        )
        .map_err(ExitError::failed)?;
        if a.reuse {
            out.tracks.save(&cache).map_err(ExitError::failed)?;
        }
        Some(out.tracks)
    };
    Ok((exact, tracked))
}

fn score_clip(
    clip: &BenchClip,
    network: &Arc<PoseNetwork>,
    params: &LiftParams,
    weights: &[f64],
    a: &BenchArgs,
    threads: usize,
) -> Result<(Scores, f64, usize, usize), ExitError> {
    let mut opened = clip.open()?;
    let (exact, tracked) = inputs_with_network(clip, &mut opened, network, a, threads)?;
    let gt = &opened.gt;
    let mut scores: Scores = Default::default();
    let (columns, doubt, seconds, unusual) = score_input(gt, &exact, params, weights)?;
    (scores.0[0], scores.1[0]) = (columns, doubt);
    if let Some(tracked) = tracked {
        let (columns, doubt, _, _) = score_input(gt, &tracked, params, weights)?;
        (scores.0[1], scores.1[1]) = (columns, doubt);
    }
    Ok((scores, seconds, exact.frames.len(), unusual))
}

fn cell(c: Option<&Column>) -> String {
    c.map_or_else(
        || format!("{:>21}", "—"),
        |(s, a)| {
            format!(
                "{:>6.1} {:>5.1} {:>4.0}% {:>3.0}%",
                s.mpjpe_mm(),
                s.pa_mpjpe_mm(),
                100.0 * s.facing_mirrored_share(),
                100.0 * a.share()
            )
        },
    )
}

/// The camera's view a clip's name gives (`real` for the real clips).
fn view_of(name: &str) -> &'static str {
    ["frontal", "oblique", "side", "behind", "raised", "low"]
        .into_iter()
        .find(|v| name.contains(v))
        .unwrap_or("real")
}

/// Per view and split, each column's MPJPE (mm) and its ratio to the cut-out's.
fn view_lines(views: &BTreeMap<(Split, &'static str), Scores>, names: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for (i, input) in INPUT_NAMES.iter().enumerate() {
        out.push(String::new());
        out.push(format!(
            "{input}, per view: MPJPE mm (÷ cut-out) — {}",
            names.join(" | ")
        ));
        for ((split, view), s) in views {
            let Some(cut) = s.0[i].first() else {
                continue;
            };
            let cut = cut.0.mpjpe_mm();
            let cells: Vec<String> = s.0[i]
                .iter()
                .map(|c| format!("{:>6.1} ({:.2})", c.0.mpjpe_mm(), c.0.mpjpe_mm() / cut))
                .collect();
            out.push(format!("{:<5} {view:<8} {}", split.name(), cells.join(" ")));
        }
    }
    out
}

/// The score tables, per input and per part (`names`), and the doubt's tables per input.
fn score_tables(tally: &Tally<Scores>, names: &[String]) -> Vec<String> {
    let mut out = vec![
        "lift alone / network alone / together (the network's 3D body as depth evidence), stated height, true focal: per column MPJPE, PA-MPJPE (mm), frames mirrored, bones in the reference's depth order (where its ends differ by > 5 cm)".to_owned(),
    ];
    for (i, input) in INPUT_NAMES.iter().enumerate() {
        for (c, name) in names.iter().enumerate() {
            out.push(String::new());
            out.push(format!("{input}: {name}"));
            let columns = format!("{:>6} {:>5} {:>5} {:>4}", "mm", "PA", "mirr", "ord");
            out.extend(Tally::<Scores>::heading(21, &columns));
            out.extend(tally.lines(21, |s: &Scores| cell(s.0[i].get(c))));
        }
    }
    out.push(String::new());
    out.push(format!(
        "together: frames with a bone flagged too long; how often a flagged bone's depth choice is wrong against an unflagged one's; per margin, the share shown unsure and how often an unsure / a sure choice is wrong (the product's margin is {})",
        videomocap_core::lift::UNSURE_MARGIN
    ));
    let doubt_columns = crate::bench_lift::doubt_columns();
    let doubt_width = doubt_columns.chars().count();
    for (i, input) in INPUT_NAMES.iter().enumerate() {
        out.push((*input).to_owned());
        out.extend(Tally::<Scores>::heading(doubt_width, &doubt_columns));
        out.extend(tally.lines(doubt_width, |s: &Scores| {
            crate::bench_lift::doubt_cell(&s.1[i])
        }));
    }
    out
}

/// Runs the comparison and prints its tables.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs, weights: &[f64]) -> Result<(), ExitError> {
    let threads = crate::bench_suite::machine_threads();
    let params = crate::bench_suite::lift_settings(a)?;
    let network = crate::bench_suite::bundled_network(threads)?;
    let clips = bench_clips(&a.suite_dir, &a.split, a.clip.as_deref(), global)?;
    let mut tally: Tally<Scores> = Tally::default();
    let mut views: BTreeMap<(Split, &'static str), Scores> = BTreeMap::new();
    let mut names = vec![
        "cut-out".to_owned(),
        "lift alone (geometry)".to_owned(),
        "prior (geometry + pose prior)".to_owned(),
        "network alone".to_owned(),
    ];
    names.extend(weights.iter().map(|w| format!("together ({w})")));
    let mut per_clip = Vec::new();
    let (mut seconds, mut frames, mut unusual) = (0.0, 0, 0);
    for clip in &clips {
        say(global, &format!("lifting {} with the network …", clip.name));
        let (s, t, n, u) = score_clip(clip, &network, &params, weights, a, threads)?;
        seconds += t;
        frames += n;
        unusual += u;
        per_clip.push(format!(
            "{:<26} {:<5} {:>4} {}",
            clip.name,
            clip.split.name(),
            u,
            s.0[0]
                .iter()
                .map(|c| format!("{:>7.1}", c.0.mpjpe_mm()))
                .collect::<Vec<_>>()
                .join(" ")
        ));
        tally.add(clip, &s);
        views
            .entry((clip.split, view_of(&clip.name)))
            .or_default()
            .merge_from(&s);
    }
    let mut out = score_tables(&tally, &names);
    out.extend(view_lines(&views, &names));
    out.push(String::new());
    out.push(format!(
        "per clip, (a): frames flagged {UNUSUAL_POSE_FLAG} (together), MPJPE mm: {}",
        names.join(" | ")
    ));
    out.extend(per_clip);
    out.push(format!(
        "(a) frames flagged {UNUSUAL_POSE_FLAG} (together): {unusual} of {frames}"
    ));
    out.push(String::new());
    out.push(format!(
        "speed: the whole lift together with the network's body (reading the lengths, the per-frame solve with the facing steps, the refinement, the feet) on (a), one thread's CPU time: {:.2} s per 1000 frames",
        1000.0 * seconds / frames.max(1) as f64
    ));
    for l in out {
        println!("{l}");
    }
    Ok(())
}
