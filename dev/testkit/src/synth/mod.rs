//! Synthetic clips with ground truth: a textured person posed by motion capture or a procedural
//! motion, rendered by a pinhole camera from a chosen view, written as an MP4 or a PNG sequence
//! with `gt.json` (2D, 3D, visibility, intrinsics, bone lengths) and `marks.json` for frame 0.
//! This is the ground truth for every accuracy test and benchmark.

mod appearance;
mod body;
mod faults;
mod ground_truth;
mod mesh;
mod motion;
mod render;
mod volume;

pub use appearance::{Appearance, Cloth, Clothes, Pattern};
pub use body::{BodyShape, JointDefinitions, retarget, shoulder_girdle};
pub use faults::SilhouetteFaults;
pub use ground_truth::{GroundTruth, GroundTruthFrame};
pub use mesh::MeshError;
pub use motion::{
    Motion, ProceduralMotion, from_bvh, normalise_orientation, procedural, stature_of,
};
pub use render::{Figure, Rendered, SensorEffects, Surface, background, render_frame};
pub use volume::{
    VoxelParams, ring_cameras, silhouette, truth as volume_truth, voxelise, write_carving_setup,
    write_carving_setup_of, write_volume_sequence,
};

use nalgebra::{Matrix3, Point2, Point3, Rotation3, Vector3};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use videomocap_core::bvh::BvhError;
use videomocap_core::camera::PinholeCamera;
use videomocap_core::formats::{FormatError, FrameIndex, Marks};
use videomocap_core::skeleton::{Bone, Joint, PerJoint, SubjectModel};
use videomocap_core::video::VideoError;

/// Where the camera stands relative to the subject's facing at the first frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// In front, at chest height.
    Frontal,
    /// 45° to the subject's left, at chest height.
    Oblique,
    /// 90° to the subject's left (profile).
    Side,
    /// 30° to the left and 30° above (a camera on a shelf).
    Raised,
    /// From behind, at chest height.
    Behind,
    /// 30° to the right and 15° below chest height (a camera on the floor or a low tripod).
    Low,
}

impl View {
    /// Parses `frontal`, `oblique`, `side`, `raised`, `behind` or `low`.
    pub fn from_name(name: &str) -> Option<View> {
        match name {
            "frontal" => Some(View::Frontal),
            "oblique" => Some(View::Oblique),
            "side" => Some(View::Side),
            "raised" => Some(View::Raised),
            "behind" => Some(View::Behind),
            "low" => Some(View::Low),
            _ => None,
        }
    }

    /// Azimuth (towards the subject's left) and elevation, degrees.
    fn angles_deg(self) -> (f64, f64) {
        match self {
            View::Frontal => (0.0, 0.0),
            View::Oblique => (45.0, 0.0),
            View::Side => (90.0, 0.0),
            View::Raised => (30.0, 30.0),
            View::Behind => (180.0, 0.0),
            View::Low => (-30.0, -15.0),
        }
    }
}

/// Where a clip's motion comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionSource {
    /// A procedural motion.
    Procedural(ProceduralMotion),
    /// A BVH file from `start_s` seconds.
    Bvh { path: PathBuf, start_s: f64 },
}

/// How to write the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VideoOutput {
    /// `video.mp4` (H.264 through FFmpeg).
    Mp4,
    /// `frames/000000.png` …
    PngSequence,
}

/// Everything that defines a synthetic clip.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// The motion.
    pub motion: MotionSource,
    /// Number of frames.
    pub frames: usize,
    /// Frames per second.
    pub fps: u32,
    /// Image width, pixels (even for MP4).
    pub width: u32,
    /// Image height, pixels (even for MP4).
    pub height: u32,
    /// Camera placement.
    pub view: View,
    /// Focal length, pixels.
    pub focal_px: f64,
    /// Wanted stature of the person in the image, pixels (the camera distance follows; it grows
    /// further if some frame would leave the image, unless `allow_off_frame`).
    pub person_px: f64,
    /// Keep the camera at the distance of `person_px` even when joints leave the image in some
    /// frames (clips with off-frame joints); the first frame must still show every joint.
    pub allow_off_frame: bool,
    /// Sensor noise and flicker.
    pub effects: SensorEffects,
    /// Background texture seed (procedural background).
    pub background_seed: u64,
    /// A photograph to use as background instead (scaled to the frame), e.g.
    /// `assets/backgrounds/*.jpg`.
    pub background_image: Option<PathBuf>,
    /// Output kind.
    pub output: VideoOutput,
    /// The subject's body: the motion is carried onto it ([`retarget`]); `None` keeps the
    /// motion's own.
    pub body: Option<BodyShape>,
    /// Shoulders that ride with the arms ([`shoulder_girdle`]), so the key triangle flexes.
    pub shoulder_girdle: bool,
    /// Where the ground truth puts the joints relative to the rendered body (an annotator's
    /// definitions; [`JointDefinitions::exact`] for the model's own).
    pub joint_definitions: JointDefinitions,
    /// The subject's clothes.
    pub appearance: Appearance,
    /// A second person walking across behind the subject, drawn from this seed.
    pub distractor: Option<u64>,
    /// Motion blur: each frame the mean of three instants a third of a frame apart.
    pub motion_blur: bool,
    /// The subject's body (and the second person's): the mannequin or the skinned mesh.
    pub surface: Surface,
}

impl Default for SynthParams {
    /// 100 frames of walking, 640×480 at 30 fps, oblique view, person 300 px tall, light noise.
    fn default() -> Self {
        SynthParams {
            motion: MotionSource::Procedural(ProceduralMotion::Walk),
            frames: 100,
            fps: 30,
            width: 640,
            height: 480,
            view: View::Oblique,
            focal_px: 600.0,
            person_px: 300.0,
            allow_off_frame: false,
            effects: SensorEffects {
                noise_sigma: 2.0,
                flicker: 0.02,
                seed: 1,
            },
            background_seed: 7,
            background_image: None,
            output: VideoOutput::Mp4,
            body: None,
            shoulder_girdle: false,
            joint_definitions: JointDefinitions::exact(),
            appearance: Appearance::default(),
            distractor: None,
            motion_blur: false,
            surface: Surface::Capsules,
        }
    }
}

/// A synthetic clip could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    #[error(transparent)]
    Motion(#[from] BvhError),
    #[error(transparent)]
    Video(#[from] VideoError),
    #[error(transparent)]
    Write(#[from] FormatError),
    #[error("{path}: cannot create: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot use as background: {message}")]
    Background { path: PathBuf, message: String },
    #[error("bad parameters: {0}")]
    Params(String),
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error("cancelled")]
    Cancelled,
}

/// What was written.
#[derive(Debug, Clone)]
pub struct SynthResult {
    /// The video file or the PNG directory.
    pub video: PathBuf,
    /// The ground truth file.
    pub ground_truth: PathBuf,
    /// The marks of frame 0.
    pub marks: PathBuf,
    /// Frames written.
    pub frames: usize,
    /// The camera used.
    pub camera: PinholeCamera,
    /// Mean seconds to render one frame (excluding encoding).
    pub render_s_per_frame: f64,
    /// How the clip frames its subject ([`framing`]).
    pub framing: Framing,
}

/// Places the camera: looking at the clip's mean pelvis from the view's direction, at the distance
/// that gives the wanted stature in pixels, moved back until every joint of every frame (of the
/// first frame only, with `allow_off_frame`) is on the image with a 3% margin. Returns the
/// world→camera rotation and the camera centre.
fn place_camera(
    motion: &Motion,
    params: &SynthParams,
    camera: &PinholeCamera,
) -> (Matrix3<f64>, Vector3<f64>) {
    let target = mean_pelvis(motion) + Vector3::y() * 0.05;
    let (az, el) = params.view.angles_deg();
    // Facing +Z; azimuth turns towards the subject's left (+X), elevation upwards.
    let dir = Rotation3::from_axis_angle(&Vector3::y_axis(), az.to_radians())
        * Rotation3::from_axis_angle(&(-Vector3::x_axis()), el.to_radians())
        * Vector3::z();
    let stature = subject_stature(params, motion);
    let mut distance = camera.focal_px * stature / params.person_px.max(1.0);
    let z = -dir; // camera looks back at the subject
    let down = -(Vector3::y() - z * z.dot(&Vector3::y())).normalize();
    let x = down.cross(&z);
    let r = Matrix3::from_rows(&[x.transpose(), down.transpose(), z.transpose()]);
    let margin = 0.03 * f64::from(camera.width.min(camera.height));
    // Back off in 2 % steps (the person ends at most 2 % smaller than fits), for up to ~50×.
    for _ in 0..200 {
        let centre = target + dir * distance;
        let checked = if params.allow_off_frame {
            &motion.frames[..motion.frames.len().min(1)]
        } else {
            &motion.frames[..]
        };
        let fits = checked.iter().all(|p| {
            p.0.iter().all(|q| {
                let c = Point3::from(r * (q.coords - centre));
                camera.project(&c).is_some_and(|uv| {
                    uv.x >= margin
                        && uv.y >= margin
                        && uv.x <= f64::from(camera.width) - 1.0 - margin
                        && uv.y <= f64::from(camera.height) - 1.0 - margin
                        && c.z > 0.3
                })
            })
        });
        if fits {
            break;
        }
        distance *= 1.02;
    }
    (r, target + dir * distance)
}

/// How a clip frames its subject, over its frames: the stature in the image, pixels, and the
/// pelvis's depth from the camera, metres, each as (smallest, largest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Framing {
    /// `f · stature / depth of the pelvis`, pixels (a person walking in depth grows and
    /// shrinks).
    pub stature_px: (f64, f64),
    /// The pelvis's depth, metres.
    pub depth_m: (f64, f64),
}

/// The framing of a clip without rendering it.
pub fn framing(params: &SynthParams) -> Result<Framing, SynthError> {
    check_params(params)?;
    let motion = load_motion(params)?;
    let camera = PinholeCamera::centred(params.focal_px, params.width, params.height);
    let (camera_from_world, centre) = place_camera(&motion, params, &camera);
    let stature = subject_stature(params, &motion);
    Ok(framing_of(
        &motion,
        stature,
        &camera,
        &camera_from_world,
        &centre,
    ))
}

/// Refuses parameters no clip can be made from: no frames, under 16×16 pixels, 0 fps, or a
/// focal length that is not positive.
fn check_params(params: &SynthParams) -> Result<(), SynthError> {
    if params.frames == 0 || params.width < 16 || params.height < 16 || params.fps == 0 {
        return Err(SynthError::Params(format!(
            "{} frames of {}×{} at {} fps: need at least 1 frame, 16×16 pixels and 1 fps",
            params.frames, params.width, params.height, params.fps
        )));
    }
    if !(params.focal_px.is_finite() && params.focal_px > 0.0) {
        return Err(SynthError::Params(format!(
            "focal length {} px must be positive",
            params.focal_px
        )));
    }
    Ok(())
}

/// [`framing`] for a motion seen by a placed camera.
fn framing_of(
    motion: &Motion,
    stature: f64,
    camera: &PinholeCamera,
    camera_from_world: &Matrix3<f64>,
    centre: &Vector3<f64>,
) -> Framing {
    let range = |v: &mut dyn Iterator<Item = f64>| {
        v.fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
            (lo.min(s), hi.max(s))
        })
    };
    let depths: Vec<f64> = motion
        .frames
        .iter()
        .map(|p| (camera_from_world * (p[Joint::Pelvis].coords - centre)).z)
        .collect();
    Framing {
        stature_px: range(
            &mut depths
                .iter()
                .map(|d| camera.focal_px * stature / d.max(1e-6)),
        ),
        depth_m: range(&mut depths.iter().copied()),
    }
}

/// Loads or builds the motion of a clip, carried onto the clip's body ([`SynthParams::body`])
/// with its shoulder girdle when asked.
pub fn load_motion(params: &SynthParams) -> Result<Motion, SynthError> {
    let fps = f64::from(params.fps);
    let mut motion = match &params.motion {
        MotionSource::Procedural(kind) => {
            procedural(*kind, &SubjectModel::default(), params.frames, fps)
        }
        MotionSource::Bvh { path, start_s } => from_bvh(path, *start_s, params.frames, fps)?,
    };
    if let Some(body) = &params.body {
        motion = retarget(&motion, body);
    }
    if params.shoulder_girdle {
        let stature = subject_stature(params, &motion);
        shoulder_girdle(&mut motion, stature);
    }
    Ok(motion)
}

/// The subject's stature, sole to vertex: the body's when the clip has one, else the motion's
/// ([`stature_of`]).
pub fn subject_stature(params: &SynthParams, motion: &Motion) -> f64 {
    params
        .body
        .as_ref()
        .map_or_else(|| stature_of(motion), BodyShape::stature_m)
}

/// The second person of a clip ([`SynthParams::distractor`]), in camera space per frame: a
/// procedural walk on a body drawn from `seed`, crossing the view 2.5 m behind the subject's
/// mean position, from the camera's left to its right (or back, by the seed).
fn distractor_frames(
    seed: u64,
    params: &SynthParams,
    target: &Vector3<f64>,
    placement: &Placement,
) -> (Vec<PerJoint<Point3<f64>>>, f64, Appearance) {
    let body = BodyShape::drawn(seed, 0.12);
    let fps = f64::from(params.fps);
    let walk = retarget(
        &procedural(
            ProceduralMotion::Walk,
            &SubjectModel::default(),
            params.frames,
            fps,
        ),
        &body,
    );
    let horizontal = |v: Vector3<f64>| {
        Vector3::new(v.x, 0.0, v.z)
            .try_normalize(1e-9)
            .unwrap_or_else(Vector3::z)
    };
    let forward = horizontal(placement.camera_from_world.row(2).transpose());
    let sign = if seed.is_multiple_of(2) { 1.0 } else { -1.0 };
    let across = horizontal(placement.camera_from_world.row(0).transpose()) * sign;
    let duration = params.frames as f64 / fps;
    let start = Vector3::new(target.x, 0.0, target.z) + forward * 2.5 - across * (0.6 * duration);
    // The walk goes along +Z: turn +Z onto `across`.
    let yaw = across.x.atan2(across.z);
    let turn = Rotation3::from_axis_angle(&Vector3::y_axis(), yaw);
    let frames = walk
        .frames
        .iter()
        .map(|p| placement.to_camera(&p.map(|_, q| Point3::from(start + turn * q.coords))))
        .collect();
    let appearance = Appearance::drawn(Clothes::Print, false, &image::RgbImage::new(1, 1), seed);
    (frames, body.stature_m(), appearance)
}

/// Renders a clip into `out_dir`, calling `progress(done, total)` after each frame; stops with
/// [`SynthError::Cancelled`] when `cancel` becomes true.
pub fn render_clip(
    params: &SynthParams,
    out_dir: &Path,
    progress: &mut dyn FnMut(usize, usize),
    cancel: &AtomicBool,
) -> Result<SynthResult, SynthError> {
    check_params(params)?;
    std::fs::create_dir_all(out_dir).map_err(|source| SynthError::Io {
        path: out_dir.to_owned(),
        source,
    })?;
    let motion = load_motion(params)?;
    let camera = PinholeCamera::centred(params.focal_px, params.width, params.height);
    let (camera_from_world, centre) = place_camera(&motion, params, &camera);
    let stature = subject_stature(params, &motion);
    let bg = match &params.background_image {
        Some(path) => image::open(path)
            .map_err(|e| SynthError::Background {
                path: path.clone(),
                message: e.to_string(),
            })?
            .resize_to_fill(
                params.width,
                params.height,
                image::imageops::FilterType::Triangle,
            )
            .to_rgb8(),
        None => background(params.width, params.height, params.background_seed),
    };
    let placement = Placement {
        camera_from_world,
        centre,
    };
    let distractor = params
        .distractor
        .map(|seed| distractor_frames(seed, params, &mean_pelvis(&motion), &placement));

    let video_path = match params.output {
        VideoOutput::Mp4 => out_dir.join("video.mp4"),
        VideoOutput::PngSequence => out_dir.join("frames"),
    };
    let mut sink = FrameSink::open(params, &video_path)?;
    let mut gt_frames = Vec::with_capacity(motion.frames.len());
    let mut bone_sums = vec![0.0; Bone::ALL.len()];
    let mut render_s = 0.0;
    let total = motion.frames.len();
    let mut first_points2d = None;
    let to_camera = |p: &PerJoint<Point3<f64>>| placement.to_camera(p);
    for (i, world) in motion.frames.iter().enumerate() {
        if cancel.load(Ordering::Relaxed) {
            return Err(SynthError::Cancelled);
        }
        let cam_pts = to_camera(world);
        let others: Vec<Figure> = distractor
            .iter()
            .filter_map(|(frames, stature, appearance)| {
                frames.get(i).map(|points| Figure {
                    points,
                    stature_m: *stature,
                    appearance: *appearance,
                    surface: params.surface,
                })
            })
            .collect();
        let subject = Figure {
            points: &cam_pts,
            stature_m: stature,
            appearance: params.appearance,
            surface: params.surface,
        };
        let t0 = std::time::Instant::now();
        let r = if params.motion_blur {
            blurred_frame(
                &camera, &motion, i, &placement, subject, &others, &bg, params,
            )?
        } else {
            render_frame(&camera, &subject, &others, &bg, &params.effects, i)?
        };
        render_s += t0.elapsed().as_secs_f64();
        sink.write(i, &r.image)?;
        // The ground truth's joints as the clip's annotator defines them.
        let truth = to_camera(&params.joint_definitions.apply(world));
        let points2d = truth.map(|_, p| camera.project(p).unwrap_or(Point2::new(-1e6, -1e6)));
        for (k, b) in Bone::ALL.iter().enumerate() {
            bone_sums[k] += (truth[b.child] - truth[b.parent]).norm();
        }
        if i == 0 {
            first_points2d = Some(points2d);
        }
        gt_frames.push(GroundTruthFrame {
            index: i,
            points2d: points2d
                .0
                .iter()
                .map(|p| [round4(p.x), round4(p.y)])
                .collect(),
            points3d: truth
                .0
                .iter()
                .map(|p| [round6(p.x), round6(p.y), round6(p.z)])
                .collect(),
            visible: r.visible.0.to_vec(),
        });
        progress(i + 1, total);
    }
    sink.finish()?;
    let gt = GroundTruth {
        source: format!(
            "videomocap synth: motion {}, view {:?}, {} frames at {} fps",
            motion.origin, params.view, total, params.fps
        ),
        fps: f64::from(params.fps),
        width: params.width,
        height: params.height,
        focal_px: camera.focal_px,
        cx: camera.cx,
        cy: camera.cy,
        joints: Joint::ALL.iter().map(|j| j.name().to_owned()).collect(),
        derived_joints: Vec::new(),
        stated_height_m: Some(round4(stature)),
        bone_lengths_m: Bone::ALL
            .iter()
            .enumerate()
            .map(|(k, b)| (b.key(), round6(bone_sums[k] / total as f64)))
            .collect(),
        frames: gt_frames,
    };
    let gt_path = out_dir.join("gt.json");
    gt.save(&gt_path)?;
    let marks_path = out_dir.join("marks.json");
    if let Some(points) = first_points2d {
        Marks {
            frame: FrameIndex(0),
            points: points.map(|_, p| nalgebra::Point2::new(round4(p.x), round4(p.y))),
        }
        .save(&marks_path)?;
    }
    Ok(SynthResult {
        video: video_path,
        ground_truth: gt_path,
        marks: marks_path,
        frames: total,
        camera,
        render_s_per_frame: render_s / total.max(1) as f64,
        framing: framing_of(&motion, stature, &camera, &camera_from_world, &centre),
    })
}

/// Where the camera stands: world → camera rotation and the camera's centre in the world.
struct Placement {
    camera_from_world: Matrix3<f64>,
    centre: Vector3<f64>,
}

impl Placement {
    /// A pose in camera space.
    fn to_camera(&self, p: &PerJoint<Point3<f64>>) -> PerJoint<Point3<f64>> {
        p.map(|_, q| Point3::from(self.camera_from_world * (q.coords - self.centre)))
    }
}

/// The mean position of the pelvis over a motion.
fn mean_pelvis(motion: &Motion) -> Vector3<f64> {
    let n = motion.frames.len().max(1) as f64;
    motion
        .frames
        .iter()
        .map(|p| p[Joint::Pelvis].coords)
        .sum::<Vector3<f64>>()
        / n
}

/// Frame `i` with motion blur: the mean of the frame rendered at three instants a third of a
/// frame apart (poses interpolated between frames), then the sensor's effects; the ground truth
/// is the middle instant's.
#[allow(clippy::too_many_arguments)]
fn blurred_frame(
    camera: &PinholeCamera,
    motion: &Motion,
    i: usize,
    placement: &Placement,
    subject: Figure,
    others: &[Figure],
    bg: &image::RgbImage,
    params: &SynthParams,
) -> Result<Rendered, SynthError> {
    let still = SensorEffects {
        noise_sigma: 0.0,
        flicker: 0.0,
        seed: 0,
    };
    let last = motion.frames.len() - 1;
    let at = |t: f64| -> PerJoint<Point3<f64>> {
        let t = t.clamp(0.0, last as f64);
        let (a, b) = (t.floor() as usize, (t.floor() as usize + 1).min(last));
        let k = t - t.floor();
        placement.to_camera(&PerJoint::from_fn(|j| {
            motion.frames[a][j] + (motion.frames[b][j] - motion.frames[a][j]) * k
        }))
    };
    let mut middle = render_frame(camera, &subject, others, bg, &still, i)?;
    let mut sum: Vec<u32> = middle
        .image
        .as_raw()
        .iter()
        .map(|&v| u32::from(v))
        .collect();
    for dt in [-1.0 / 3.0, 1.0 / 3.0] {
        let points = at(i as f64 + dt);
        let shifted = Figure {
            points: &points,
            ..subject
        };
        let r = render_frame(camera, &shifted, others, bg, &still, i)?;
        for (s, &v) in sum.iter_mut().zip(r.image.as_raw()) {
            *s += u32::from(v);
        }
    }
    for (p, s) in middle.image.iter_mut().zip(sum) {
        *p = ((s + 1) / 3) as u8;
    }
    render::apply_effects(&mut middle.image, &params.effects, i);
    Ok(middle)
}

fn round4(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

fn round6(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// A quick test's clip in `dir`: `frames` frames of `motion` seen from `view`, 320×240 PNGs,
/// focal 300 px, the person 200 px tall, the mannequin (with `gt.json` and `marks.json`).
pub fn render_small_clip(
    dir: &Path,
    motion: ProceduralMotion,
    frames: usize,
    view: View,
) -> Result<SynthResult, SynthError> {
    let params = SynthParams {
        motion: MotionSource::Procedural(motion),
        frames,
        view,
        width: 320,
        height: 240,
        focal_px: 300.0,
        person_px: 200.0,
        output: VideoOutput::PngSequence,
        ..SynthParams::default()
    };
    render_clip(&params, dir, &mut |_, _| {}, &AtomicBool::new(false))
}

/// Writes frames to an MP4 or a PNG directory.
enum FrameSink {
    Mp4(videomocap_core::video::Mp4Writer),
    Png(PathBuf),
}

impl FrameSink {
    fn open(params: &SynthParams, path: &Path) -> Result<FrameSink, SynthError> {
        match params.output {
            VideoOutput::Mp4 => {
                let enc = videomocap_core::video::EncodeParams {
                    fps: params.fps,
                    gop: params.fps * 2,
                    max_b_frames: 2,
                    crf: 18,
                };
                Ok(FrameSink::Mp4(videomocap_core::video::Mp4Writer::create(
                    path,
                    params.width,
                    params.height,
                    &enc,
                )?))
            }
            VideoOutput::PngSequence => {
                std::fs::create_dir_all(path).map_err(|source| SynthError::Io {
                    path: path.to_owned(),
                    source,
                })?;
                Ok(FrameSink::Png(path.to_owned()))
            }
        }
    }

    fn write(&mut self, index: usize, image: &image::RgbImage) -> Result<(), SynthError> {
        match self {
            FrameSink::Mp4(w) => Ok(w.write(image)?),
            FrameSink::Png(dir) => {
                let path = dir.join(format!("{index:06}.png"));
                image.save(&path).map_err(|e| {
                    SynthError::Video(VideoError::Image {
                        path,
                        reason: e.to_string(),
                    })
                })
            }
        }
    }

    fn finish(self) -> Result<(), SynthError> {
        match self {
            FrameSink::Mp4(w) => Ok(w.finish()?),
            FrameSink::Png(_) => Ok(()),
        }
    }
}
