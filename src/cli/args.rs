//! Command-line arguments (clap). `main.rs` parses them and hands over to `cli` or `gui`.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

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
  videomocap synth --motion walk --view side --frames 150 -o synth_walk/
  videomocap synth --motion tests/data/cmu_02_01_walk.bvh --view oblique -o walk/
  videomocap bench lift

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
    /// Second pipeline: point volumes to kinematic motion.
    Volume(VolumeArgs),
    /// Carve voxel grids from calibrated cameras and silhouette masks, for `volume`.
    Carve(CarveArgs),
    /// Render a synthetic clip with ground truth.
    Synth(SynthArgs),
    /// Measure speed and accuracy (decoding, rendering, tracking, correction, lifting, frame
    /// access, point volumes) and print a table.
    Bench(BenchArgs),
    /// (Testing) Save a project and write its exports over and over until killed; the
    /// crash-safety test kills it at random moments and checks every file left behind.
    #[command(hide = true)]
    StressWrite(StressWriteArgs),
}

/// `stress-write`.
#[derive(Debug, Args)]
pub struct StressWriteArgs {
    /// The project to rewrite in place (it must hold a skeleton).
    pub project: PathBuf,
    /// Directory for motion.bvh, joints3d.csv and motion.trc.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Stop after this many rounds (default: until killed).
    #[arg(long)]
    pub rounds: Option<u64>,
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
    /// Worker threads (default: all cores; 1 = decode and track on one thread).
    #[arg(long)]
    pub threads: Option<usize>,
    /// A ground-truth gt.json to score the tracks against (prints PCK and mean error).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Tracker settings as JSON (see docs/formats.md; every field optional, defaults documented).
    #[arg(long)]
    pub tracker_settings: Option<PathBuf>,
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
    #[command(flatten)]
    pub options: LiftOptions,
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
}

/// `carve`.
#[derive(Debug, Args)]
#[command(
    after_help = "Example:\n  videomocap synth --motion wave --frames 30 --fps 15 --volume --views 4 -o out/vol\n  videomocap carve out/vol/carve -o out/carved\n  videomocap volume out/carved --fps 15 --out-dir out/carved-result"
)]
pub struct CarveArgs {
    /// Set-up directory: cameras.json (with bounds_m, the box to carve) and masks/<camera>/
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
    /// X,Y,Z (metres, the set-up's world): keep the blob nearest this point, the person the
    /// carve is for (default: the largest blob). What is dropped is reported.
    #[arg(long)]
    pub person: Option<String>,
}

/// `synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// Motion: walk, treadmill, wave, jumping-jacks, sit-down, bend, march, or a BVH file.
    #[arg(long, default_value = "walk")]
    pub motion: String,
    /// Start time in the BVH, seconds.
    #[arg(long, default_value_t = 0.0)]
    pub start_s: f64,
    /// Number of frames.
    #[arg(long, default_value_t = 100)]
    pub frames: usize,
    /// Frames per second.
    #[arg(long, default_value_t = 30)]
    pub fps: u32,
    /// Image width, pixels.
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Image height, pixels.
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// Camera view: frontal, oblique, side, raised, behind, low.
    #[arg(long, default_value = "oblique")]
    pub view: String,
    /// Focal length, pixels.
    #[arg(long, conflicts_with = "fov_deg")]
    pub focal_px: Option<f64>,
    /// Horizontal field of view, degrees (default 56°).
    #[arg(long)]
    pub fov_deg: Option<f64>,
    /// Stature of the person in the image, pixels (default 0.65 × height).
    #[arg(long)]
    pub person_px: Option<f64>,
    /// Keep the camera at the distance of --person-px even when joints leave the image later
    /// in the clip (default: move back until every joint of every frame is on the image).
    #[arg(long)]
    pub allow_off_frame: bool,
    /// Sensor noise, standard deviation in 8-bit levels.
    #[arg(long, default_value_t = 2.0)]
    pub noise: f64,
    /// Brightness flicker, relative amplitude.
    #[arg(long, default_value_t = 0.02)]
    pub flicker: f64,
    /// Random seed (noise, background).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write a PNG sequence instead of an MP4.
    #[arg(long)]
    pub png: bool,
    /// A photograph to use as background (scaled to fill the frame), e.g.
    /// assets/backgrounds/pose2sim_room.jpg; default a procedural room.
    #[arg(long)]
    pub background: Option<PathBuf>,
    /// Write point volumes instead of video: the body voxelised per frame (frame_NNNN.ply) and
    /// truth.skeleton3d.json, for `videomocap volume`.
    #[arg(long)]
    pub volume: bool,
    /// Voxel size for --volume, millimetres.
    #[arg(long, default_value_t = 40.0)]
    pub voxel_mm: f64,
    /// Spurious voxels per frame for --volume (scattered near the body).
    #[arg(long, default_value_t = 0)]
    pub noise_voxels: usize,
    /// Share of body voxels removed at random for --volume (holes), 0–1.
    #[arg(long, default_value_t = 0.0)]
    pub holes: f64,
    /// With --volume, also write a carving set-up in OUTPUT/carve for `videomocap carve`: this
    /// many cameras (--width × --height) on a ring around the body, cameras.json and each
    /// camera's silhouette masks.
    #[arg(long, default_value_t = 0, requires = "volume")]
    pub views: usize,
    /// With --views, draw the faults of real segmentation into the masks: edges eroded 2 px on
    /// the first view and dilated 2 px on the second, the right forearm missing on the third, a
    /// shadow joined to the feet and a second person 1.2 m to the side (+X).
    #[arg(long, requires = "views")]
    pub faulty_silhouettes: bool,
    /// Output directory.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// What to measure: all (decode and synth), decode, synth, track (tracking accuracy on
    /// suite v3's dev and test splits and the two real clips from clicked marks, beside the
    /// fixed template and OpenCV's trackers when present, and tracking speed), lift (3D
    /// accuracy from true, noisy and tracked 2D with true lengths or a stated height, beside
    /// the flat cut-out; speed), correct (the tracks before and after a simulated user's
    /// corrections, one per 25 frames), scrub (the desktop app's frame access on a long 1080p
    /// clip: open time, random seeks, scrubbing, peak memory), or volume (the point-volume
    /// pipeline: topology, joint error, labels, dev and test takes, carved from clean and faulty
    /// silhouettes, time per frame at
    /// 3k/10k/30k points). The suite renders once into --suite-dir (about 6 minutes).
    #[arg(default_value = "all")]
    pub what: String,
    /// Frames per measured clip (decode).
    #[arg(long, default_value_t = 300)]
    pub frames: usize,
    /// Length of the 1080p clip `bench scrub` makes, minutes.
    #[arg(long, default_value_t = 20.0)]
    pub minutes: f64,
    /// Keyframe interval of the clip `bench scrub` makes, frames (250, x264's default, is 8.3 s
    /// at 30 fps; phone cameras write about one keyframe a second, 30).
    #[arg(long, default_value_t = 250)]
    pub gop: u32,
    /// Where the benchmark suite is rendered (once) and kept.
    #[arg(long, default_value = "out/bench-suite")]
    pub suite_dir: PathBuf,
    /// Tracker settings as JSON for `bench track`.
    #[arg(long)]
    pub tracker_settings: Option<PathBuf>,
    /// Lift settings as JSON for `bench lift`.
    #[arg(long)]
    pub lift_settings: Option<PathBuf>,
    /// Which clips `bench track`, `lift` and `correct` measure: all, dev (the synthetic dev
    /// split and the real clips: the ones to tune on) or test (the synthetic test split);
    /// `bench volume` with dev or test measures only the suite's takes of that split.
    #[arg(long, default_value = "all")]
    pub split: String,
    /// Only the clips (for `bench volume`, the takes) whose name contains this (to look at one
    /// clip of the split).
    #[arg(long)]
    pub clip: Option<String>,
    /// `bench lift` only: leave out input (c), the tracker's output (tracking is most of the
    /// bench's time; for quick looks at the lift from true and noisy 2D).
    #[arg(long)]
    pub no_tracker: bool,
}
