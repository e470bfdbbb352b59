//! Command-line arguments (clap). `main.rs` parses them and hands over to `cli` or the app.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use videomocap_core::export::RigNames;

const EXAMPLES: &str = "\
Examples:
  videomocap                                   open the desktop app
  videomocap gui sample_videos/pose2sim_balancing_cam01/video.mp4
  videomocap info clip.mp4 --json
  videomocap run clip.mp4 --marks marks.json --out-dir out/ --height-m 1.75
  videomocap track clip.mp4 --marks marks.json -o tracks2d.json
  videomocap lift tracks2d.json -o skeleton3d.json --fov-deg 60 --height-m 1.80
  videomocap export skeleton3d.json --bvh motion.bvh --csv joints3d.csv --trc motion.trc
  videomocap export tracks2d.json --csv tracks2d.csv

Exit codes: 0 success, 1 processing failed, 2 bad usage or bad input.";

/// Single-camera video motion capture: mark 16 joints, track them, lift to 3D, export BVH.
#[derive(Debug, Parser)]
#[command(name = "videomocap", version, about, after_help = EXAMPLES)]
pub struct Cli {
    /// What to do; without a command the desktop app opens.
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub global: GlobalArgs,
}

/// Options every command takes.
#[derive(Debug, Clone, Args)]
pub struct GlobalArgs {
    /// No progress bars or messages on stderr.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Print a JSON summary on stdout (for scripts).
    #[arg(long, global = true)]
    pub json: bool,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open the desktop app, optionally on a video or image folder.
    Gui {
        /// Video file or directory of images.
        video: Option<PathBuf>,
    },
    /// Print a video's size, frame rate, frame count, duration and rotation.
    Info {
        /// Video file or directory of images.
        video: PathBuf,
    },
    /// Track the 16 joints from the marks of one frame through the video.
    Track(TrackArgs),
    /// Reconstruct the 3D skeleton from 2D tracks.
    Lift(LiftArgs),
    /// Export a skeleton3d to BVH, CSV or TRC, or tracks2d to CSV.
    Export(ExportArgs),
    /// Every step: track, lift and export into one directory.
    Run(RunArgs),
    /// `run` for every row of a manifest (CSV), resumable, optionally one shard of it.
    Batch(BatchArgs),
    /// Second pipeline: point volumes to kinematic motion.
    Volume(VolumeArgs),
    /// Carve voxel grids from calibrated cameras and silhouette masks, for `volume`.
    Carve(CarveArgs),
}

/// `track`.
#[derive(Debug, Args)]
pub struct TrackArgs {
    /// Video file or directory of images, or a saved project (`.json`: its video is re-tracked
    /// from its keys and settings, and the tracks saved back into it).
    pub video: PathBuf,
    /// The 16 joints marked on one frame (marks.json).
    #[arg(long, conflicts_with = "keys")]
    pub marks: Option<PathBuf>,
    /// Joints placed by hand on any frames (keys.json: the marks and every correction; see
    /// docs/formats.md).
    #[arg(long)]
    pub keys: Option<PathBuf>,
    /// Where to write tracks2d.json (needed unless re-tracking a project).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Worker threads (default: the CPUs this process may use, and no more than Slurm's
    /// SLURM_CPUS_PER_TASK; 1 = decode, track and run the network on one thread).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Tracker settings as JSON (see docs/formats.md; every field optional, defaults documented).
    #[arg(long)]
    pub tracker_settings: Option<PathBuf>,
    /// Track with VBA alone, without the pose network's evidence.
    #[arg(long)]
    pub no_network: bool,
}

/// Camera and subject options shared by `lift` and `run`.
#[derive(Debug, Clone, Args)]
pub struct LiftOptions {
    /// Focal length in pixels.
    #[arg(long, conflicts_with = "fov_deg")]
    pub focal_px: Option<f64>,
    /// Horizontal field of view in degrees (instead of --focal-px).
    #[arg(long, conflicts_with = "focal_px")]
    pub fov_deg: Option<f64>,
    /// Estimate the focal length from the tracks (instead of the default 60° across the
    /// longer image side when neither --focal-px nor --fov-deg is given; experimental).
    #[arg(long, conflicts_with_all = ["focal_px", "fov_deg"])]
    pub estimate_focal: bool,
    /// The subject's height in metres (scales the bone lengths; default 1.70).
    #[arg(long)]
    pub height_m: Option<f64>,
    /// Lift settings as JSON (see docs/formats.md; every field optional, defaults documented).
    #[arg(long)]
    pub lift_settings: Option<PathBuf>,
    /// Bone lengths you know, metres, as JSON (`{"left_knee-left_ankle": 0.42, …}`, any subset;
    /// see docs/formats.md): kept, and they set the scale of the lengths read from the
    /// video instead of the height.
    #[arg(long)]
    pub lengths: Option<PathBuf>,
    /// Leave planted feet where the lift put them (by default a foot found planted on the
    /// floor keeps one depth over its contact and the body follows; overrides the settings
    /// file's `foot_lock`).
    #[arg(long)]
    pub no_foot_lock: bool,
    /// Bone names in the BVH: `cmu` (Hips, LHipJoint, LeftUpLeg, …) or `mixamo`
    /// (mixamorig:Hips, mixamorig:LeftUpLeg, …, for retargeting onto Mixamo characters);
    /// the motion is the same (docs/formats.md).
    #[arg(long, default_value = "cmu", value_parser = parse_rig)]
    pub rig: RigNames,
}

/// `lift`.
#[derive(Debug, Args)]
pub struct LiftArgs {
    /// tracks2d.json from `track`.
    pub tracks: PathBuf,
    /// Where to write skeleton3d.json.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub options: LiftOptions,
    /// Also write a BVH here.
    #[arg(long)]
    pub bvh: Option<PathBuf>,
}

/// `export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// skeleton3d.json (from `lift`) or tracks2d.json (from `track`).
    pub input: PathBuf,
    /// Write a BVH here (skeleton3d input; centimetres, Y up).
    #[arg(long)]
    pub bvh: Option<PathBuf>,
    /// Write a CSV here: the 3D joints (world metres, Y up) for a skeleton3d, the 2D tracks for a
    /// tracks2d.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write an OpenSim marker file (.trc) here (skeleton3d input).
    #[arg(long)]
    pub trc: Option<PathBuf>,
    /// Frames per second, for skeleton3d files that do not record it (or to override it).
    #[arg(long)]
    pub fps: Option<f64>,
    /// Bone names in the BVH: `cmu` (Hips, LHipJoint, LeftUpLeg, …) or `mixamo`
    /// (mixamorig:Hips, mixamorig:LeftUpLeg, …, for retargeting onto Mixamo characters);
    /// the motion is the same (docs/formats.md).
    #[arg(long, default_value = "cmu", value_parser = parse_rig)]
    pub rig: RigNames,
}

/// `run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Video file or directory of images.
    pub video: PathBuf,
    /// The 16 joints marked on one frame (marks.json).
    #[arg(long, conflicts_with = "keys", required_unless_present = "keys")]
    pub marks: Option<PathBuf>,
    /// Joints placed by hand on any frames (keys.json; see docs/formats.md).
    #[arg(long)]
    pub keys: Option<PathBuf>,
    /// Directory for tracks2d.json, skeleton3d.json, motion.bvh, joints3d.csv, tracks2d.csv and
    /// motion.trc.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Track with VBA alone, without the pose network's evidence.
    #[arg(long)]
    pub no_network: bool,
    /// Worker threads (default: the CPUs this process may use, and no more than Slurm's
    /// SLURM_CPUS_PER_TASK).
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub options: LiftOptions,
}

/// `batch`.
#[derive(Debug, Args)]
pub struct BatchArgs {
    /// The manifest: CSV with a header row; columns video (required), keys (a keys or marks
    /// file), height_m, focal_px or fov_deg, lengths, tracker_settings, lift_settings, id
    /// (default: the video's file stem). Paths are relative to the manifest (docs/batch.md).
    pub manifest: PathBuf,
    /// Each row's results go to `DIR/<id>/` (as `run` writes them, plus status.json), and
    /// DIR/summary.csv.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Rows run at once (each gets its share of the threads; never more rows than threads).
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Threads for the whole batch (default: the CPUs this process may use, and no more than
    /// Slurm's SLURM_CPUS_PER_TASK).
    #[arg(long)]
    pub threads: Option<usize>,
    /// K/N: run only shard K of N (rows dealt in manifest order: row i to shard i mod N); or
    /// `slurm`: K and N from the Slurm job array (SLURM_ARRAY_TASK_ID, SLURM_ARRAY_TASK_COUNT).
    #[arg(long)]
    pub shard: Option<String>,
    /// Redo every row, also those complete and unchanged.
    #[arg(long)]
    pub force: bool,
    /// Run nothing: gather the rows' status files (from every shard) into summary.csv.
    #[arg(long)]
    pub summary_only: bool,
    /// Track with VBA alone, without the pose network's evidence.
    #[arg(long)]
    pub no_network: bool,
    /// Bone names in the BVH: `cmu` (Hips, LHipJoint, LeftUpLeg, …) or `mixamo`
    /// (mixamorig:Hips, mixamorig:LeftUpLeg, …, for retargeting onto Mixamo characters);
    /// the motion is the same (docs/formats.md).
    #[arg(long, default_value = "cmu", value_parser = parse_rig)]
    pub rig: RigNames,
}

/// `volume`.
#[derive(Debug, Args)]
pub struct VolumeArgs {
    /// Directory of per-frame point clouds (PLY, XYZ) or voxel grids (.voxels.json), in
    /// natural name order.
    pub input: PathBuf,
    /// Output directory: skeleton3d.json, motion.bvh, joints3d.csv, motion.trc.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Frames per second of the sequence.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Bone names in the BVH: `cmu` (Hips, LHipJoint, LeftUpLeg, …) or `mixamo`
    /// (mixamorig:Hips, mixamorig:LeftUpLeg, …, for retargeting onto Mixamo characters);
    /// the motion is the same (docs/formats.md).
    #[arg(long, default_value = "cmu", value_parser = parse_rig)]
    pub rig: RigNames,
}

/// `carve`.
#[derive(Debug, Args)]
#[command(
    after_help = "Example (the point volumes made by the developer tool, dev/bench):\n  videomocap-bench synth --motion wave --frames 30 --fps 15 --volume --views 4 -o out/vol\n  videomocap carve out/vol/carve -o out/carved\n  videomocap volume out/carved --fps 15 --out-dir out/carved-result"
)]
pub struct CarveArgs {
    /// Set-up directory: cameras.json (with bounds_m, the box to carve) and `masks/<camera>/`
    /// holding one silhouette per frame (PNG or JPEG; grey level ≥ 128 = person).
    pub setup: PathBuf,
    /// Output directory: one .voxels.json grid per frame.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Voxel size, millimetres.
    #[arg(long, default_value_t = 40.0)]
    pub voxel_mm: f64,
    /// Masks that must contain a voxel for it to stay (default: every camera; one fewer keeps a
    /// limb one view's segmentation missed, at the cost of a fatter hull).
    #[arg(long)]
    pub min_votes: Option<usize>,
    /// X,Y,Z (metres, the set-up's world): the person the carve is for: the blob nearest this
    /// point on the frame it comes nearest, followed through the clip (on each frame the blob
    /// continuing the previous frame's); default: the largest blob. What is dropped is reported.
    #[arg(long)]
    pub person: Option<String>,
}

/// `--rig`: one of [`RigNames::ALL`]'s keys.
fn parse_rig(s: &str) -> Result<RigNames, String> {
    RigNames::ALL
        .into_iter()
        .find(|r| r.key().eq_ignore_ascii_case(s))
        .ok_or_else(|| {
            let keys: Vec<&str> = RigNames::ALL.iter().map(|r| r.key()).collect();
            format!("unknown rig `{s}`: choose one of {}", keys.join(", "))
        })
}
