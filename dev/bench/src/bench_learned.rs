//! `videomocap-bench learned`: VBA alone, the pose network alone and the two together, from the
//! same clicked marks, on the suite's clips and the real ones; PCK@0.2 and lost share of the 13
//! limb joints and of all 16, and the network's time per frame.
//!
//! - VBA alone: the tracker from the clicked marks.
//! - The network alone: each frame cropped where the network proposed on the frame before (its
//!   tracking region; the clicked marks on the first frame), its joints as it maps them
//!   (`network`), no VBA.
//! - Together: what the product tracks, `track_video` with the network (VBA's passes, the
//!   network's evidence weighed in, then weak runs filled); with `--evidence`, each setting of
//!   the weighing (`track::weigh`) applied to VBA's finished tracks besides.
//!
//! `--evidence A,B,C,D,E,F[;…]` (dev only, for sweeps) weighs with other settings
//! (`EvidenceParams`: VBA doubt, network doubt, swap cost, motion, key fade frames, jump cap).

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_suite::{BenchClip, Tally, bench_clips};
use crate::bench_track::{threads_and_settings, track_opened};
use crate::{ExitError, say};
use anyhow::anyhow;
use nalgebra::Point2;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_core::formats::{KeyFrames, Marks, PointSource, Tracks2d};
use videomocap_core::network::{Crop, PoseNetwork};
use videomocap_core::skeleton::{Joint, PerJoint};
use videomocap_core::track::{
    EvidenceParams, NetworkFrames, TrackJob, run_network, track_video, weigh,
};
use videomocap_core::video::{OpenOptions, Video};
use videomocap_testkit::eval::suite::{CLICK_NOISE_PX, clicked_marks};
use videomocap_testkit::eval::{Accuracy, ClipScore, score_positions, score_tracks};
use videomocap_testkit::synth::GroundTruth;

/// Limb joints and all 16 of one method.
type Pair = [Accuracy; 2];

/// One clip's scores (VBA alone, the network alone, together, then each setting swept) and
/// how well VBA's and together's reliabilities point at their errors.
type Scores = (Vec<Pair>, [Pointing; 2]);

/// Joint-frames (keys left out) more than 0.2 torso off, shown weak (reliability under the
/// tracker's weak threshold, or not tracked: interpolated, lost, off the frame), and both.
#[derive(Debug, Clone, Copy, Default)]
struct Pointing {
    off: usize,
    shown: usize,
    both: usize,
}

impl crate::bench_suite::Merge for Pointing {
    fn merge_from(&mut self, o: &Self) {
        self.off += o.off;
        self.shown += o.shown;
        self.both += o.both;
    }
}

impl Pointing {
    fn of(gt: &GroundTruth, tracks: &Tracks2d, keys: &KeyFrames, weak: f32) -> Pointing {
        let mut p = Pointing::default();
        for (g, f) in gt.frames.iter().zip(&tracks.frames) {
            let at = |j: Joint| Point2::new(g.points2d[j.index()][0], g.points2d[j.index()][1]);
            let torso = (at(Joint::Neck) - at(Joint::Pelvis)).norm().max(1.0);
            for j in Joint::ALL.into_iter().filter(|&j| !keys.is_key(f.index, j)) {
                let q = f.points[j];
                let off = (q.pos - at(j)).norm() > 0.2 * torso;
                let shown = q.source != PointSource::Tracked || q.confidence < weak;
                p.off += usize::from(off);
                p.shown += usize::from(shown);
                p.both += usize::from(off && shown);
            }
        }
        p
    }

    /// Recall and precision.
    fn cell(&self) -> String {
        let share = |a: usize, b: usize| a as f64 / b.max(1) as f64;
        format!(
            "{:>6.2} {:>9.2}",
            share(self.both, self.off),
            share(self.both, self.shown)
        )
    }
}

fn pair(s: &ClipScore) -> Pair {
    [s.limbs(), s.overall]
}

/// Reads `--evidence`.
fn sweep(text: Option<&str>) -> Result<Vec<EvidenceParams>, ExitError> {
    let Some(text) = text else {
        return Ok(vec![EvidenceParams::default()]);
    };
    text.split(';')
        .map(|set| {
            let v: Vec<f64> = set
                .split(',')
                .map(|x| x.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| ExitError::bad_input(anyhow!("--evidence {set}: {e}")))?;
            let [
                vba_doubt,
                net_doubt,
                swap_cost,
                motion,
                key_fade_frames,
                jump_cap_torso,
            ] = v[..]
            else {
                return Err(ExitError::bad_input(anyhow!(
                    "--evidence {set}: expected six numbers"
                )));
            };
            Ok(EvidenceParams {
                vba_doubt,
                net_doubt,
                swap_cost,
                motion,
                key_fade_frames,
                jump_cap_torso,
            })
        })
        .collect()
}

/// One frame's joints: (frame, positions).
type Positions = (usize, PerJoint<Point2<f64>>);

/// The network alone: crops where it proposed on the frame before, from the clicked marks.
fn network_alone(
    video: &mut Video,
    marks: &Marks,
    network: &PoseNetwork,
) -> Result<Vec<Positions>, ExitError> {
    let mut crop = Crop::around(&marks.points);
    let mut out = Vec::new();
    for index in 0..video.info().frame_count {
        let frame = video.frame(index).map_err(ExitError::failed)?;
        let Some(c) = crop else {
            break;
        };
        let pose = network.run(&frame.image, &c).map_err(ExitError::failed)?;
        if pose.presence >= 0.5 {
            out.push((index, pose.joints.map(|_, j| j.pos)));
            crop = pose.next_crop.or(crop);
        } else {
            // No person: every joint lost on this frame; the crop stays where it was.
            out.push((index, PerJoint::from_fn(|_| Point2::new(-1.0e4, -1.0e4))));
        }
    }
    Ok(out)
}

/// The per-view table: VBA, the network and the two together per clip (`clip_scores`), and
/// MediaPipe when it ran.
fn view_table(
    clips: &[BenchClip],
    clip_scores: &[[ClipScore; 3]],
    mediapipe: Option<&[ClipScore]>,
) -> crate::bench_views::ViewTable {
    let mut views = crate::bench_views::ViewTable::new(if mediapipe.is_some() {
        &["VBA", "net", "together", "MediaPipe"]
    } else {
        &["VBA", "net", "together"]
    });
    for (k, (clip, full)) in clips.iter().zip(clip_scores).enumerate() {
        let mut row: Vec<&ClipScore> = full.iter().collect();
        if let Some(mp) = mediapipe {
            row.push(&mp[k]);
        }
        views.add(clip, &row);
    }
    views
}

/// Runs the comparison and prints its tables.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let (threads, params) = threads_and_settings(a)?;
    let settings = sweep(a.evidence.as_deref())?;
    let clips = bench_clips(&a.suite_dir, &a.split, a.clip.as_deref(), global)?;
    let network = crate::bench_suite::bundled_network(threads)?;
    let mut tally: Tally<Scores> = Tally::default();
    let mut lines = vec![format!(
        "{:<26} {:<5} limbs PCK@0.2: {:>6} {:>6} {:>9}",
        "clip", "split", "VBA", "net", "together"
    )];
    let (mut net_seconds, mut net_frames) = (0.0, 0usize);
    // The product's frames the network's chain left out, of all its frames.
    let mut product_frames = [0.0; 2];
    let mut clip_scores = Vec::with_capacity(clips.len());
    let mut dump = vec![format!(
        "clip,frame,joint,{},off",
        videomocap_core::track::DOUBT_FEATURES.join(",")
    )];
    for clip in &clips {
        say(global, &format!("{} …", clip.name));
        let (s, full, [seconds, skipped, frames]) = score_clip(
            clip,
            threads,
            params,
            network.clone(),
            &settings,
            a.reuse,
            a.doubt_dump.is_some().then_some(&mut dump),
        )?;
        net_seconds += seconds;
        product_frames[0] += skipped;
        product_frames[1] += frames;
        net_frames += count_frames(clip)?;
        lines.push(format!(
            "{:<26} {:<5}               {:>6.3} {:>6.3} {:>9.3}",
            clip.name,
            clip.split.name(),
            s.0[0][0].pck02(),
            s.0[1][0].pck02(),
            s.0[2][0].pck02()
        ));
        tally.add(clip, &s);
        clip_scores.push(full);
    }
    if let Some(path) = &a.doubt_dump {
        std::fs::write(path, dump.join("\n") + "\n").map_err(ExitError::failed)?;
    }
    let mediapipe = crate::bench_baselines::mediapipe_scores(&clips, &a.suite_dir, global)?;
    let views = view_table(&clips, &clip_scores, mediapipe.as_deref());
    lines.extend(tables(&tally, a.reuse, mediapipe.is_some(), &views));
    lines.push(String::new());
    lines.extend(opencv_table(&clips, a, global)?);
    if settings.len() > 1 {
        lines.push(String::new());
        lines.push("together, each setting swept (13 limb joints, PCK@0.2 / lost)".to_owned());
        for (k, p) in settings.iter().enumerate() {
            lines.push(format!("{p:?}"));
            lines.extend(tally.lines(WIDTH, |s| cell(&s.0, 0, 3 + k)));
        }
    }
    lines.push(String::new());
    lines.push(format!(
        "the network (crops following the subject, one after the other): {:.1} ms a frame ({:.1} frames/s), crops 256×256",
        1000.0 * net_seconds / net_frames.max(1) as f64,
        net_frames as f64 / net_seconds.max(1e-9)
    ));
    if product_frames[1] > 0.0 {
        lines.push(format!(
            "together: the network left out on {:.0} of {:.0} frames ({:.1} %)",
            product_frames[0],
            product_frames[1],
            100.0 * product_frames[0] / product_frames[1]
        ));
    }
    for l in lines {
        println!("{l}");
    }
    Ok(())
}

/// OpenCV's trackers from the same clicked marks (all 16 joints), as a table.
fn opencv_table(
    clips: &[BenchClip],
    a: &BenchArgs,
    global: &GlobalArgs,
) -> Result<Vec<String>, ExitError> {
    let clicked = clips
        .iter()
        .map(|clip| {
            let marks = Marks::load(&clip.dir.join("marks.json")).map_err(ExitError::failed)?;
            Ok(clicked_marks(&marks, CLICK_NOISE_PX, &clip.name))
        })
        .collect::<Result<Vec<_>, ExitError>>()?;
    let opencv = crate::bench_baselines::opencv(clips, &clicked, &a.suite_dir, global)?;
    Ok(crate::bench_baselines::opencv_lines(opencv.as_ref()))
}

/// The split and family tables: limbs, all joints, reliability, per view.
fn tables(
    tally: &Tally<Scores>,
    reuse: bool,
    mediapipe: bool,
    views: &crate::bench_views::ViewTable,
) -> Vec<String> {
    let mut lines = Vec::new();
    lines.push(String::new());
    lines.push(format!(
        "13 limb joints, PCK@0.2 / lost; marks clicked with {CLICK_NOISE_PX} px of noise; together: {}",
        if reuse {
            "the default weighing of the cached tracks"
        } else {
            "track_video with the network (the product)"
        }
    ));
    lines.extend(Tally::<Scores>::heading(WIDTH, COLUMNS));
    lines.extend(tally.lines(WIDTH, |s| cell(&s.0, 0, 2)));
    lines.push(String::new());
    lines.push("all 16 joints, PCK@0.2 / lost".to_owned());
    lines.extend(Tally::<Scores>::heading(WIDTH, COLUMNS));
    lines.extend(tally.lines(WIDTH, |s| cell(&s.0, 1, 2)));
    lines.push(String::new());
    lines.push(
        "reliability: of the joint-frames over 0.2 torso off (keys left out), the share shown weak (recall), and of those shown weak, the share off (precision); all 16 joints"
            .to_owned(),
    );
    lines.extend(Tally::<Scores>::heading(
        WIDTH,
        "VBA recall precision  together recall precision",
    ));
    lines.extend(tally.lines(WIDTH, |s| {
        format!("{}  {}   ", s.1[0].cell(), s.1[1].cell())
    }));
    lines.push(String::new());
    lines.push(format!(
        "per view (clicked marks; MediaPipe Pose 0.10.21 with its own detector, no marks{})",
        if mediapipe { "" } else { ": not found" }
    ));
    lines.extend(views.lines());
    lines
}

/// Width of [`cell`].
const WIDTH: usize = 57;
/// The columns of [`cell`].
const COLUMNS: &str = "  VBA   lost    net   lost together     @0.1 V/n/t";

/// One split's column: VBA, the network and together (`k`-th setting), accuracy `which`
/// (0 limbs, 1 all).
fn cell(s: &[Pair], which: usize, together: usize) -> String {
    let t = s.get(together).map_or(Accuracy::default(), |p| p[which]);
    format!(
        "{:>5.3} {:>5.1}% {:>6.3} {:>5.1}% {:>5.3} {:>3.0}%  {:.3}/{:.3}/{:.3}",
        s[0][which].pck02(),
        100.0 * s[0][which].lost(),
        s[1][which].pck02(),
        100.0 * s[1][which].lost(),
        t.pck02(),
        100.0 * t.lost(),
        s[0][which].pck01(),
        s[1][which].pck01(),
        t.pck01()
    )
}

/// What `--reuse` keeps of a clip beside VBA's tracks: the network beside them, the network
/// alone.
#[derive(serde::Serialize, serde::Deserialize)]
struct Cached {
    net: NetworkFrames,
    alone: Vec<Positions>,
}

fn count_frames(clip: &BenchClip) -> Result<usize, ExitError> {
    Ok(GroundTruth::load(&clip.dir.join("gt.json"))
        .map_err(ExitError::failed)?
        .frames
        .len())
}

/// VBA's tracks, the network beside them and the network alone for a clip (from the clip's
/// caches with `--reuse` when there, kept there when made), and the seconds the network ran.
fn vba_and_network(
    clip: &BenchClip,
    threads: usize,
    params: videomocap_core::track::TrackerParams,
    network: &Arc<PoseNetwork>,
    clicked: &Marks,
    keys: &KeyFrames,
    reuse: bool,
) -> Result<(Tracks2d, Cached, f64), ExitError> {
    let (vba_path, net_path) = (
        clip.dir.join("learned-vba.json"),
        clip.dir.join("learned-net.json"),
    );
    let cached = reuse
        .then(|| {
            let vba = Tracks2d::load(&vba_path).ok()?;
            let bytes = std::fs::read(&net_path).ok()?;
            let c: Cached = serde_json::from_slice(&bytes).ok()?;
            Some((vba, c))
        })
        .flatten();
    let mut net_seconds = 0.0;
    let (vba, cached) = match cached {
        Some(c) => c,
        None => {
            let mut video = Video::open(&clip.dir.join("video.mp4"), &OpenOptions::default())
                .map_err(ExitError::failed)?;
            let vba: Tracks2d = track_opened(&mut video, clicked, threads, params)?;
            let t0 = Instant::now();
            let net = run_network(
                &mut video,
                &vba,
                network,
                keys,
                None,
                &mut || {},
                &AtomicBool::new(false),
            )
            .map_err(ExitError::failed)?;
            net_seconds += t0.elapsed().as_secs_f64();
            let alone = network_alone(&mut video, clicked, network)?;
            let c = Cached { net, alone };
            if reuse {
                vba.save(&vba_path).map_err(ExitError::failed)?;
                let bytes = serde_json::to_vec(&c).map_err(|e| ExitError::failed(anyhow!(e)))?;
                std::fs::write(&net_path, bytes).map_err(ExitError::failed)?;
            }
            (vba, c)
        }
    };
    Ok((vba, cached, net_seconds))
}

/// Each non-key joint-frame's doubt features and whether it is over 0.2 torso off, as CSV rows
/// (`--doubt-dump`, for `scripts/fit_doubt.py`).
fn dump_doubt(
    dump: &mut Vec<String>,
    clip: &BenchClip,
    gt: &GroundTruth,
    vba: &Tracks2d,
    net: &NetworkFrames,
    keys: &KeyFrames,
    product: &Tracks2d,
) {
    let x = videomocap_core::track::doubt_features(vba, net, keys, product);
    let derived = gt.derived();
    for ((g, f), row) in gt.frames.iter().zip(&product.frames).zip(&x) {
        let at = |j: Joint| Point2::new(g.points2d[j.index()][0], g.points2d[j.index()][1]);
        let torso = (at(Joint::Neck) - at(Joint::Pelvis)).norm().max(1.0);
        for j in Joint::ALL {
            if keys.is_key(f.index, j) || derived.contains(&j) {
                continue;
            }
            let off = (f.points[j].pos - at(j)).norm() > 0.2 * torso;
            let values: Vec<String> = row[j].iter().map(|v| format!("{v:.4}")).collect();
            dump.push(format!(
                "{},{},{},{},{}",
                clip.name,
                f.index.get(),
                j.name(),
                values.join(","),
                u8::from(off)
            ));
        }
    }
}

fn score_clip(
    clip: &BenchClip,
    threads: usize,
    params: videomocap_core::track::TrackerParams,
    network: Arc<PoseNetwork>,
    settings: &[EvidenceParams],
    reuse: bool,
    dump: Option<&mut Vec<String>>,
) -> Result<(Scores, [ClipScore; 3], [f64; 3]), ExitError> {
    let gt = GroundTruth::load(&clip.dir.join("gt.json")).map_err(ExitError::failed)?;
    let marks = Marks::load(&clip.dir.join("marks.json")).map_err(ExitError::failed)?;
    let clicked = clicked_marks(&marks, CLICK_NOISE_PX, &clip.name);
    let keys = KeyFrames::from_marks(&clicked);
    let (vba, Cached { net, alone }, net_seconds) =
        vba_and_network(clip, threads, params, &network, &clicked, &keys, reuse)?;
    // Together as the product tracks (`track_video` with the network), unless only the
    // weighing is swept from the caches.
    let (mut skipped, mut frames) = (0, 0);
    let product = if reuse {
        weigh(&vba, &net, &keys, &EvidenceParams::default())
    } else {
        let mut video = Video::open(&clip.dir.join("video.mp4"), &OpenOptions::default())
            .map_err(ExitError::failed)?;
        let job = TrackJob::from_marks(&clicked, params, threads).with_network(Some(network));
        let out = track_video(&mut video, &job, &mut |_| {}, &AtomicBool::new(false))
            .map_err(ExitError::failed)?;
        let seen = out.network.unwrap_or_default();
        (skipped, frames) = (seen.iter().filter(|f| f.skipped).count(), seen.len());
        out.tracks
    };
    if let Some(dump) = dump {
        dump_doubt(dump, clip, &gt, &vba, &net, &keys, &product);
    }
    let weak = params.weak_reliability;
    let pointing = [
        Pointing::of(&gt, &vba, &keys, weak),
        Pointing::of(&gt, &product, &keys, weak),
    ];
    let full = [
        score_tracks(&gt, &vba).map_err(ExitError::failed)?,
        score_positions(&gt, alone).map_err(ExitError::failed)?,
        score_tracks(&gt, &product).map_err(ExitError::failed)?,
    ];
    let mut scores: Vec<Pair> = full.iter().map(pair).collect();
    for (k, p) in settings.iter().enumerate() {
        let together = weigh(&vba, &net, &keys, p);
        if reuse && k == 0 {
            // For looking at the first setting's choices beside the caches.
            together
                .save(&clip.dir.join("learned-together.json"))
                .map_err(ExitError::failed)?;
        }
        scores.push(pair(
            &score_tracks(&gt, &together).map_err(ExitError::failed)?,
        ));
    }
    Ok((
        (scores, pointing),
        full,
        [net_seconds, skipped as f64, frames as f64],
    ))
}
