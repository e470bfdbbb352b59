//! Synthetic clips with ground truth: a textured person posed by motion capture or a procedural
//! motion, rendered by a pinhole camera from a chosen view, written as an MP4 or a PNG sequence
//! with `gt.json` (2D, 3D, visibility, intrinsics, bone lengths) and `marks.json` for frame 0.
//! This is the ground truth for every accuracy test and benchmark.

mod appearance;
mod body;
mod capsules;
mod clip;
mod faults;
mod ground_truth;
mod mesh;
mod motion;
mod render;
mod volume;

pub use appearance::{Appearance, Cloth, Clothes, Pattern};
pub use body::{BodyShape, JointDefinitions, retarget, shoulder_girdle};
pub use clip::{render_clip, render_small_clip};
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
