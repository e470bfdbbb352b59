//! `videomocap bench volume`: the second pipeline on synthetic volume sequences (the paper's
//! marching, waving and jumping jacks, plus real motion capture) at several voxel sizes —
//! topology, joint error against the truth, label consistency — the same motions carved from
//! 4 and 8 synthetic silhouettes (and, per split, the suite's takes from clean and faulty ones),
//! and the time per frame at
//! N = 3k, 10k and 30k points on one core with Isomap's share.

use crate::args::{BenchArgs, GlobalArgs};
use crate::bench_suite::Merge;
use crate::bench_suite::{BenchClip, Tally, parse_split};
use crate::{ExitError, say};
use rayon::prelude::*;
use videomocap_core::skeleton::SubjectModel;
use videomocap_testkit::eval::suite::{Split, Suite};
use videomocap_testkit::eval::volume::{CarveCase, VolumeScore, carve_and_score, score_volume};
use videomocap_testkit::repo_root;
use videomocap_testkit::synth::{
    Motion, ProceduralMotion, SilhouetteFaults, Surface, SynthParams, VoxelParams, from_bvh,
    load_motion, procedural, stature_of, subject_stature, volume_truth, voxelise,
};
use videomocap_volume::{
    VolumeParams, assemble_and_fit, clean_clip, five_limb_frames, process_frame_for_fit,
};

/// Frames per sequence (the paper's sequences had about 50).
const FRAMES: usize = 50;
/// Frame rate of the sequences (the paper captured at about 10 Hz).
const FPS: f64 = 15.0;

fn motions() -> Result<Vec<(String, Motion, bool)>, ExitError> {
    let subject = SubjectModel::default();
    let mut out = Vec::new();
    for kind in [
        ProceduralMotion::March,
        ProceduralMotion::Wave,
        ProceduralMotion::JumpingJacks,
    ] {
        out.push((
            kind.name().to_owned(),
            procedural(kind, &subject, FRAMES, FPS),
            true,
        ));
    }
    out.push((
        "walk (procedural)".to_owned(),
        procedural(ProceduralMotion::Walk, &subject, FRAMES, FPS),
        false,
    ));
    let data = repo_root().join("tests/data");
    for (file, start, label) in [
        ("cmu_02_01_walk.bvh", 0.5, "CMU 02_01 walk"),
        ("cmu_02_03_run.bvh", 0.3, "CMU 02_03 run"),
        ("cmu_06_03_dribble.bvh", 1.0, "CMU 06_03 dribble"),
        ("cmu_60_02_dance.bvh", 2.0, "CMU 60_02 dance"),
    ] {
        let m = from_bvh(&data.join(file), start, FRAMES, FPS).map_err(ExitError::failed)?;
        out.push((label.to_owned(), m, false));
    }
    Ok(out)
}

struct Row {
    name: String,
    voxel_mm: f64,
    points: f64,
    /// The subject's body fitted over the clip (the product's output).
    score: VolumeScore,
    /// The paper's skeleton curve alone, same run.
    curve: VolumeScore,
    /// Frames the fit flagged.
    flagged: usize,
    sides: String,
}

/// The curve alone and the fitted body of one or more sequences, and the frames flagged.
#[derive(Debug, Clone, Default)]
struct Both {
    curve: VolumeScore,
    fitted: VolumeScore,
    flagged: usize,
}

impl Merge for Both {
    fn merge_from(&mut self, o: &Self) {
        self.curve.merge(&o.curve);
        self.fitted.merge(&o.fitted);
        self.flagged += o.flagged;
    }
}

fn run_sequence(
    name: &str,
    motion: &Motion,
    stature: f64,
    voxel: VoxelParams,
    params: &VolumeParams,
) -> Row {
    let mut clouds: Vec<_> = motion
        .frames
        .par_iter()
        .enumerate()
        .map(|(i, j)| {
            let mut rng =
                <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(voxel.seed + i as u64);
            voxelise(j, stature, &voxel, &mut rng)
        })
        .collect();
    if let Some(clean) = &params.clean {
        clean_clip(&mut clouds, clean);
    }
    let (results, fit_points): (Vec<_>, Vec<_>) = clouds
        .par_iter()
        .map(|c| process_frame_for_fit(c, params))
        .unzip();
    let names: Vec<String> = (0..results.len()).map(|i| format!("frame {i}")).collect();
    let (assembled, curve, _) = assemble_and_fit(&results, &fit_points, &names, motion.fps, params);
    let ok = five_limb_frames(&results);
    let truth = volume_truth(motion);
    Row {
        name: name.to_owned(),
        voxel_mm: voxel.voxel_m * 1000.0,
        points: clouds.iter().map(Vec::len).sum::<usize>() as f64 / clouds.len().max(1) as f64,
        score: score_volume(&truth, &assembled.skeleton, ok),
        curve: score_volume(&truth, &curve, ok),
        flagged: flagged(&assembled.skeleton),
        sides: format!("{:?}", assembled.sides_from).to_lowercase(),
    }
}

/// Frames of `s` with a flag.
fn flagged(s: &videomocap_core::formats::Skeleton3d) -> usize {
    s.frames.iter().filter(|f| !f.flags.is_empty()).count()
}

/// One split's column of the suite table: the curve alone and the fitted body, each as the
/// error with sides as reported (mm, voxel sizes) and sides right; labels consistent and frames
/// flagged of the fit.
fn suite_cell(b: &Both, voxel_mm: f64) -> String {
    let (c, f) = (&b.curve, &b.fitted);
    format!(
        "{:>6.1} {:>5.1}% | {:>6.1} {:>5.2} {:>5.1}% {:>5.1}%",
        c.mean_reported_mm(),
        100.0 * c.sides_right_share(),
        f.mean_reported_mm(),
        f.mean_reported_mm() / voxel_mm,
        100.0 * f.sides_right_share(),
        100.0 * b.flagged as f64 / f.scored_frames.max(1) as f64,
    )
}

/// A sequence's figures as JSON.
fn take_json(b: &Both) -> serde_json::Value {
    serde_json::json!({
        "curve_reported_mm": b.curve.mean_reported_mm(),
        "curve_sides_right": b.curve.sides_right_share(),
        "curve_topology": b.curve.topology(),
        "reported_mm": b.fitted.mean_reported_mm(),
        "sides_right": b.fitted.sides_right_share(),
        "matched_once_mm": b.fitted.mean_mm(),
        "flagged_share": b.flagged as f64 / b.fitted.scored_frames.max(1) as f64,
    })
}

/// The voxelisations of the suite's takes: 30, 40 and 50 mm clean, and 40 mm with noise voxels
/// and holes.
const SUITE_VOXELS: [(f64, usize, f64); 4] = [
    (0.03, 0, 0.0),
    (0.04, 0, 0.0),
    (0.05, 0, 0.0),
    (0.04, 200, 0.05),
];

/// Which of the suite's takes and tables `bench volume` runs (`None`: all).
#[derive(Debug, Clone, Copy, Default)]
struct Only<'a> {
    /// Takes whose name contains this.
    take: Option<&'a str>,
    /// Tables whose label contains one of these, `;`-separated.
    tables: Option<&'a str>,
}

impl Only<'_> {
    fn table(&self, label: &str) -> bool {
        self.tables
            .is_none_or(|t| t.split(';').any(|w| label.contains(w.trim())))
    }
}

/// The volume pipeline on every take of suite v4 of `split` (`None`: both; its first clip's
/// body and start, [`FRAMES`] frames at [`FPS`] fps) at each of [`SUITE_VOXELS`], dev and test
/// side by side per family; returns the same as JSON.
fn suite_takes(
    params: &VolumeParams,
    split: Option<Split>,
    only: &Only,
    global: &GlobalArgs,
    lines: &mut Vec<String>,
) -> Result<serde_json::Value, ExitError> {
    let takes = suite_bench_takes(split, only)?;
    let mut json = serde_json::Map::new();
    voxel_tables(&takes, params, only, global, lines, &mut json);
    carved_tables(&takes, params, only, global, lines, &mut json)?;
    Ok(serde_json::Value::Object(json))
}

/// One take of the suite: its name, the clip it stands for in the tables, its motion and the
/// subject's stature.
type Take = (String, BenchClip, Motion, f64);

/// The suite v4 takes of `split` (`None`: both) that `only` lets through, each once: its
/// first clip's body and start, [`FRAMES`] frames at [`FPS`] fps.
fn suite_bench_takes(split: Option<Split>, only: &Only) -> Result<Vec<Take>, ExitError> {
    let suite = Suite::load(&repo_root()).map_err(ExitError::failed)?;
    let mut takes = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for clip in &suite.clips {
        if split.is_some_and(|s| s != clip.split)
            || only.take.is_some_and(|o| !clip.take.contains(o))
            || !seen.insert(clip.take.clone())
        {
            continue;
        }
        let synth = SynthParams {
            frames: FRAMES,
            fps: FPS as u32,
            ..clip.params.clone()
        };
        let motion = load_motion(&synth).map_err(ExitError::failed)?;
        let stature = subject_stature(&synth, &motion);
        let bench = BenchClip {
            name: clip.name.clone(),
            family: clip.family,
            split: clip.split,
            dir: Default::default(),
            view: crate::bench_suite::ViewFamily::of(clip.params.view),
        };
        takes.push((clip.take.clone(), bench, motion, stature));
    }
    Ok(takes)
}

/// One take's row of a suite table as JSON: its scores ([`take_json`]), family and split.
fn take_row(bench: &BenchClip, both: &Both) -> serde_json::Value {
    let mut j = take_json(both);
    j["family"] = bench.family.name().into();
    j["split"] = bench.split.name().into();
    j
}

/// The volumes of the takes at each of [`SUITE_VOXELS`]: a table each into `lines` and `json`.
fn voxel_tables(
    takes: &[Take],
    params: &VolumeParams,
    only: &Only,
    global: &GlobalArgs,
    lines: &mut Vec<String>,
    json: &mut serde_json::Map<String, serde_json::Value>,
) {
    for (voxel_m, noise_voxels, hole_fraction) in SUITE_VOXELS {
        let voxel = VoxelParams {
            voxel_m,
            noise_voxels,
            hole_fraction,
            ..VoxelParams::default()
        };
        let voxel_mm = voxel_m * 1000.0;
        let label = if noise_voxels > 0 {
            format!(
                "{voxel_mm:.0} mm, {noise_voxels} noise voxels, {:.0} % holes",
                hole_fraction * 100.0
            )
        } else {
            format!("{voxel_mm:.0} mm")
        };
        if !only.table(&label) {
            continue;
        }
        let mut tally: Tally<Both> = Tally::default();
        let mut per_take = serde_json::Map::new();
        for (take, bench, motion, stature) in takes {
            say(global, &format!("volumes of take {take} at {label} …"));
            let r = run_sequence(take, motion, *stature, voxel, params);
            let both = Both {
                curve: r.curve,
                fitted: r.score,
                flagged: r.flagged,
            };
            tally.add(bench, &both);
            per_take.insert(take.clone(), take_row(bench, &both));
        }
        let title = format!(
            "suite v4 takes at {label} (the bodies of their first clips, {FRAMES} frames at {FPS} fps)"
        );
        push_table(lines, json, &title, &label, &tally, per_take, voxel_mm);
    }
}

/// The takes carved from silhouettes: 4 and 8 clean views, and 4 views with the faults of real
/// segmentation (every mask must hold a voxel, or one may miss it), of the capsule bodies and
/// the MakeHuman mesh; a table each into `lines` and `json`.
fn carved_tables(
    takes: &[Take],
    params: &VolumeParams,
    only: &Only,
    global: &GlobalArgs,
    lines: &mut Vec<String>,
    json: &mut serde_json::Map<String, serde_json::Value>,
) -> Result<(), ExitError> {
    let faulty = CarveCase {
        faults: SilhouetteFaults::typical(),
        ..CarveCase::clean(4, 0.04)
    };
    let mesh = |case: &CarveCase| CarveCase {
        surface: Surface::Mesh,
        ..case.clone()
    };
    let cases = [
        ("4 views", CarveCase::clean(4, 0.04)),
        ("8 views", CarveCase::clean(8, 0.04)),
        ("4 faulty views", faulty.clone()),
        ("mesh bodies, 8 views", mesh(&CarveCase::clean(8, 0.04))),
        ("mesh bodies, 4 views", mesh(&CarveCase::clean(4, 0.04))),
        ("mesh bodies, 4 faulty views", mesh(&faulty)),
    ];
    for (label, case) in cases {
        if !only.table(&format!("carved {label}")) {
            continue;
        }
        let mut tally: Tally<Both> = Tally::default();
        let mut per_take = serde_json::Map::new();
        for (take, bench, motion, _) in takes {
            say(global, &format!("take {take} carved from {label} …"));
            let r = carve_and_score(motion, &case, params).map_err(ExitError::failed)?;
            let both = Both {
                curve: r.curve_score,
                fitted: r.score,
                flagged: r.flagged,
            };
            tally.add(bench, &both);
            let mut j = take_row(bench, &both);
            j["voxels"] = r.voxels.into();
            j["dropped_voxels"] = r.dropped.into();
            per_take.insert(take.clone(), j);
        }
        let what = if case.faults.any() {
            "; faults: edges eroded and dilated 2 px on two views, the right forearm missing on one, a shadow at the feet, a second person 1.2 m away; the person followed over the clip, the floor sheet and points no neighbouring frame has taken off"
        } else {
            ""
        };
        let title = format!(
            "suite v4 takes carved at 40 mm from {label} (640×480 cameras on a ring{what})"
        );
        let key = format!("carved {label}");
        push_table(lines, json, &title, &key, &tally, per_take, 40.0);
    }
    Ok(())
}

/// One table of the suite's takes: `title`, the family rows of `tally` (voxel sizes of
/// `voxel_mm`) into `lines`, and under `key` (and `key` + " takes" for `per_take`) into `json`.
fn push_table(
    lines: &mut Vec<String>,
    json: &mut serde_json::Map<String, serde_json::Value>,
    title: &str,
    key: &str,
    tally: &Tally<Both>,
    per_take: serde_json::Map<String, serde_json::Value>,
    voxel_mm: f64,
) {
    const WIDTH: usize = 44;
    lines.push(format!(
        "{title}: mean error with left and right as reported (mm) and sides right, the paper's curve alone | the fitted body (mm, voxel sizes, sides right, frames flagged)"
    ));
    lines.extend(Tally::<Both>::heading(
        WIDTH,
        " curve  sides |    fit voxel sides  flag",
    ));
    lines.extend(tally.lines(WIDTH, |s| suite_cell(s, voxel_mm)));
    lines.push(String::new());
    json.insert(format!("{key} takes"), serde_json::Value::Object(per_take));
    json.insert(key.to_owned(), tally.json(take_json));
}

/// Runs the volume benchmark and prints its tables.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let params = VolumeParams::default();
    // One split: only the suite's takes (the other tables have no split).
    let split = parse_split(&a.split)?;
    if split.is_some() {
        let mut lines = Vec::new();
        let only = Only {
            take: a.clip.as_deref(),
            tables: a.tables.as_deref(),
        };
        let suite_json = suite_takes(&params, split, &only, global, &mut lines)?;
        let march = procedural(
            ProceduralMotion::March,
            &SubjectModel::default(),
            FRAMES,
            FPS,
        );
        if only.table("speed") {
            crate::bench_volume_speed::speed_table(&march, &params, global, &mut lines);
        }
        print_tables(global, suite_json, &lines);
        return Ok(());
    }
    let motions = motions()?;
    let mut lines = motion_table(&motions, &params, global);
    let suite_json = suite_takes(&params, None, &Only::default(), global, &mut lines)?;
    lines.extend(carved_paper_table(&motions, &params, global)?);
    crate::bench_volume_speed::speed_table(&motions[0].1, &params, global, &mut lines);
    print_tables(global, suite_json, &lines);
    Ok(())
}

/// The paper's motions and others at 30, 40 and 50 mm voxels: a row each, then the paper's
/// three and the others summed up.
fn motion_table(
    motions: &[(String, Motion, bool)],
    params: &VolumeParams,
    global: &GlobalArgs,
) -> Vec<String> {
    let mut lines = Vec::new();
    lines.push(format!(
        "Volume pipeline accuracy ({FRAMES} frames per sequence at {FPS} fps; error: left/right matched once per sequence, and per frame)"
    ));
    lines.push(format!(
        "{:<20} {:>6} {:>7} {:>9} {:>9} {:>9} {:>8} {:>10} {:>9}",
        "sequence",
        "voxel",
        "points",
        "topology",
        "mean mm",
        "voxels",
        "frame mm",
        "labels ok",
        "sides"
    ));
    let mut paper = VolumeScore::default();
    let mut paper_voxels = (0.0, 0usize);
    let mut others = VolumeScore::default();
    for voxel_m in [0.03, 0.04, 0.05] {
        for (name, motion, is_paper) in motions {
            say(
                global,
                &format!("{name}, {:.0} mm voxels …", voxel_m * 1000.0),
            );
            let voxel = VoxelParams {
                voxel_m,
                ..VoxelParams::default()
            };
            let r = run_sequence(name, motion, stature_of(motion), voxel, params);
            let s = &r.score;
            lines.push(format!(
                "{:<20} {:>4.0}mm {:>7.0} {:>8.1}% {:>9.1} {:>9.2} {:>8.1} {:>9.1}% {:>9}",
                r.name,
                r.voxel_mm,
                r.points,
                100.0 * s.topology(),
                s.mean_mm(),
                s.mean_mm() / r.voxel_mm,
                s.mean_frame_matched_mm(),
                100.0 * s.consistency(),
                r.sides
            ));
            if *is_paper {
                paper.merge(s);
                paper_voxels.0 += s.mean_mm() / r.voxel_mm;
                paper_voxels.1 += 1;
            } else {
                others.merge(s);
            }
        }
    }
    lines.push(format!(
        "paper's three motions, all voxel sizes: topology {:.1}%, mean {:.1} mm = {:.2} voxel sizes (mean over sequences), labels consistent {:.1}%",
        100.0 * paper.topology(),
        paper.mean_mm(),
        paper_voxels.0 / paper_voxels.1.max(1) as f64,
        100.0 * paper.consistency()
    ));
    lines.push(format!(
        "other motions, all voxel sizes: topology {:.1}%, mean {:.1} mm, labels consistent {:.1}%",
        100.0 * others.topology(),
        others.mean_mm(),
        100.0 * others.consistency()
    ));
    lines.push(String::new());
    lines
}

/// The paper's motions carved from 4 and 8 clean views (paper §2): the visual hull is fatter
/// than the body and fills gaps a camera cannot see through.
fn carved_paper_table(
    motions: &[(String, Motion, bool)],
    params: &VolumeParams,
    global: &GlobalArgs,
) -> Result<Vec<String>, ExitError> {
    let mut lines = Vec::new();
    lines.push(
        "Carved from silhouettes (40 mm voxels; synthetic 640×480 cameras spread over half a turn, 20° down; a voxel stays when every mask holds it)".to_owned(),
    );
    lines.push(format!(
        "{:<20} {:>6} {:>9} {:>9} {:>9} {:>9} {:>10}",
        "sequence", "views", "voxels", "topology", "mean mm", "voxels", "labels ok"
    ));
    for (name, motion, is_paper) in motions {
        if !*is_paper {
            continue;
        }
        for views in [4, 8] {
            say(global, &format!("{name} carved from {views} views …"));
            let r = carve_and_score(motion, &CarveCase::clean(views, 0.04), params)
                .map_err(ExitError::failed)?;
            let (s, voxels) = (r.score, r.voxels);
            lines.push(format!(
                "{:<20} {:>6} {:>9.0} {:>8.1}% {:>9.1} {:>9.2} {:>9.1}%",
                name,
                views,
                voxels,
                100.0 * s.topology(),
                s.mean_mm(),
                s.mean_mm() / 40.0,
                100.0 * s.consistency()
            ));
        }
    }
    lines.push(String::new());

    Ok(lines)
}

/// Prints the tables, or with `--json` the suite's figures and the tables as JSON.
fn print_tables(global: &GlobalArgs, suite_json: serde_json::Value, lines: &[String]) {
    if global.json {
        println!(
            "{}",
            serde_json::json!({"suite": suite_json, "table": lines})
        );
    } else {
        println!("{}", lines.join("\n"));
    }
}
