//! The developer tool's arguments (clap): the benchmarks, the synthetic renderer, the scorer
//! and the crash-safety writer. Users never install this tool.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
pub(crate) use videomocap::cli::args::GlobalArgs;

const EXAMPLES: &str = "\
Examples:
  videomocap-bench track --split test          tracking accuracy on suite v3's test split
  videomocap-bench correct --split dev         the tracks before and after a user's corrections
  videomocap-bench lift --split test           3D accuracy beside the flat cut-out
  videomocap-bench volume --split test         the point-volume pipeline
  videomocap-bench scrub                       the app's frame access on a long 1080p clip
  videomocap-bench speed                       decoding and rendering speed
  videomocap-bench speed track --runs 3        track with/without the network beside MediaPipe
  videomocap-bench speed retrack --runs 3      a re-track after one correction, 300 frames of 1080p
  videomocap-bench synth --motion walk --view side --frames 150 -o synth_walk/
  videomocap-bench synth --motion tests/data/cmu_02_01_walk.bvh --view oblique -o walk/
  videomocap-bench score tracks2d.json synth_walk/gt.json

Run from the repository (the suite and the test data are read from it), with --release for
real figures: cargo run --release -p videomocap-bench -- track --split test";

/// videomocap's developer tool: benchmarks, synthetic clips with ground truth, scoring.
#[derive(Debug, Parser)]
#[command(name = "videomocap-bench", version, about, after_help = EXAMPLES)]
pub(crate) struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
    #[command(flatten)]
    pub global: GlobalArgs,
}

/// The developer tool's commands.
#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Tracking accuracy on suite v3's dev and test splits and the two real clips from clicked
    /// marks, beside the fixed template and OpenCV's trackers when present, and tracking speed.
    Track(BenchArgs),
    /// The tracks before and after a simulated user's corrections, one per 25 frames.
    Correct(BenchArgs),
    /// 3D accuracy from true, noisy and tracked 2D with true lengths or a stated height, beside
    /// the flat cut-out; speed.
    Lift(BenchArgs),
    /// Motion an animator sees: jitter, foot sliding, the root's path and acceleration error
    /// of the lift beside the reference's own and the cut-out's.
    Motion(BenchArgs),
    /// The point-volume pipeline: topology, joint error, labels, dev and test takes, carved
    /// from clean and faulty silhouettes, time per frame at 3k/10k/30k points.
    Volume(BenchArgs),
    /// The desktop app's frame access on a long 1080p clip: open time, random seeks,
    /// scrubbing, peak memory.
    Scrub(BenchArgs),
    /// VBA alone, the pose network alone and the two together, from the same clicked marks.
    Learned(BenchArgs),
    /// Decoding (beside the ffmpeg command) and rendering speed; `track`: whole `videomocap
    /// track` processes with and without the pose network beside MediaPipe's (issue 95).
    Speed {
        /// all, decode, synth, track, network (the network's profile per operator) or retrack
        /// (a re-track after one correction on a 300-frame 1080p clip).
        #[arg(default_value = "all")]
        what: String,
        #[command(flatten)]
        args: BenchArgs,
    },
    /// Render a synthetic clip with ground truth.
    Synth(SynthArgs),
    /// Score tracks2d.json against a synthetic clip's gt.json (per joint mean error, PCK, lost).
    Score {
        /// The tracks (tracks2d.json).
        tracks: PathBuf,
        /// The ground truth (gt.json, written by `synth`).
        reference: PathBuf,
    },
    /// Learn the lift's pose prior from motion-capture takes (gzip or plain BVH) and write its
    /// parameter file (`assets/pose_prior/pose_prior.json`), listing the takes it used; the
    /// suite's test takes are refused.
    Prior(PriorArgs),
    /// Write the README's benchmark figures from the outputs committed under `docs/bench/`
    /// (`figures.json` names each), or with `--check` fail when the README differs from them.
    Report {
        /// The README to write or check.
        #[arg(long, default_value = "README.md")]
        readme: PathBuf,
        /// The figures file beside the committed outputs.
        #[arg(long, default_value = "docs/bench/figures.json")]
        figures: PathBuf,
        /// Only compare: exit non-zero naming each figure that differs.
        #[arg(long)]
        check: bool,
    },
    /// Save a project and write its exports over and over until killed; the crash-safety test
    /// kills it at random moments and checks every file left behind.
    StressWrite(StressWriteArgs),
}

/// `prior`: where the takes are and where the parameters go.
#[derive(Debug, Args)]
pub(crate) struct PriorArgs {
    /// The folder of takes (`*.bvh` or `*.bvh.gz`, read recursively).
    pub mocap: PathBuf,
    /// The parameter file to write.
    #[arg(short, long, default_value = "assets/pose_prior/pose_prior.json")]
    pub out: PathBuf,
    /// Mixture components per group of bones.
    #[arg(long, default_value_t = 12)]
    pub components: usize,
    /// Poses learned per second of motion (each take resampled).
    #[arg(long, default_value_t = 15.0)]
    pub per_second: f64,
}

/// `stress-write`: the writer the crash-safety test kills.
#[derive(Debug, Args)]
pub(crate) struct StressWriteArgs {
    /// The project to rewrite in place (it must hold a skeleton).
    pub project: PathBuf,
    /// Directory for motion.bvh, joints3d.csv and motion.trc.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Stop after this many rounds (default: until killed).
    #[arg(long)]
    pub rounds: Option<u64>,
}

/// `synth`.
#[derive(Debug, Args)]
pub(crate) struct SynthArgs {
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
    /// The body drawn: mesh (MakeHuman's skinned mesh, as suite v4) or capsule (the
    /// mannequin of suite v3 and the quick tests).
    #[arg(long, default_value = "mesh")]
    pub body: String,
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

/// The options every benchmark takes.
#[derive(Debug, Args)]
pub(crate) struct BenchArgs {
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
    /// `bench volume` with a split only: the suite tables whose label contains one of these
    /// (`;`-separated, e.g. `40 mm;mesh bodies, 8 views`; the labels hold commas).
    #[arg(long)]
    pub tables: Option<String>,
    /// `learned` only: evidence settings to sweep (dev), `A,B,C,D,E,F;…` = VBA doubt, network
    /// doubt, swap cost, motion, key fade frames, jump cap (torso lengths).
    #[arg(long)]
    pub evidence: Option<String>,
    /// Keep what is slow to make in each clip's folder and read it back when there, for sweeps
    /// of what comes after: `learned`'s VBA tracks and network output (`learned-vba.json`,
    /// `learned-net.json`); `lift --network` and `motion`'s network frames on the true 2D
    /// (`lift-net.json`) and tracker output (`tracked-net.json`). Stale after any change to
    /// the tracker or the network: delete the files then.
    #[arg(long)]
    pub reuse: bool,
    /// `correct`: track as the product does, with the pose network's evidence (without it,
    /// VBA alone). `lift`: the lift alone, the network's 3D body alone and the two together
    /// (with `--reuse`, the network's frames on the true 2D are kept in `lift-net.json`).
    #[arg(long)]
    pub network: bool,
    /// `lift --network` only: the image-depth weights to compare (dev sweeps), comma-separated;
    /// default the lift's own.
    #[arg(long, value_delimiter = ',')]
    pub depth_weights: Option<Vec<f64>>,
    /// `bench lift` only: leave out input (c), the tracker's output (tracking is most of the
    /// bench's time; for quick looks at the lift from true and noisy 2D).
    #[arg(long)]
    pub no_tracker: bool,
    /// `learned` only: write every non-key joint-frame's doubt features and whether it is more
    /// than 0.2 torso off (CSV) to this file, to calibrate the doubt on dev
    /// (`scripts/fit_doubt.py`).
    #[arg(long)]
    pub doubt_dump: Option<PathBuf>,
    /// `speed track`, `speed network` and `speed retrack`: runs of each process, network run
    /// or re-track (medians).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
}
