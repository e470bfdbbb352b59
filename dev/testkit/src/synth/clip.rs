//! Rendering a whole clip: the subject (and a second person when asked) posed frame by frame,
//! drawn by the camera the parameters place, written as video or PNGs with `gt.json` and
//! `marks.json`.

use super::*;

/// The second person: their joints per frame in the camera's space, stature and clothes.
type Distractor = (Vec<PerJoint<Point3<f64>>>, f64, Appearance);

/// The second person of a clip ([`SynthParams::distractor`]), in camera space per frame: a
/// procedural walk on a body drawn from `seed`, crossing the view 2.5 m behind the subject's
/// mean position, from the camera's left to its right (or back, by the seed).
fn distractor_frames(
    seed: u64,
    params: &SynthParams,
    target: &Vector3<f64>,
    placement: &Placement,
) -> Distractor {
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
    let bg = load_background(params)?;
    let placement = Placement {
        camera_from_world,
        centre,
    };
    let distractor = params
        .distractor
        .map(|seed| distractor_frames(seed, params, &mean_pelvis(&motion), &placement));

    let video_path = video_path_in(out_dir, params.output);
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
        let others = distractor_figures(distractor.as_ref(), i, params);
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
        add_bone_lengths(&mut bone_sums, &truth);
        if i == 0 {
            first_points2d = Some(points2d);
        }
        gt_frames.push(truth_frame(i, &points2d, &truth, &r.visible.0));
        progress(i + 1, total);
    }
    sink.finish()?;
    let gt = ground_truth(params, &motion, &camera, stature, &bone_sums, gt_frames);
    let gt_path = out_dir.join("gt.json");
    gt.save(&gt_path)?;
    let marks_path = write_marks(out_dir, first_points2d)?;
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

/// Where the video goes: `video.mp4`, or a `frames/` folder of PNGs.
fn video_path_in(out_dir: &Path, output: VideoOutput) -> std::path::PathBuf {
    match output {
        VideoOutput::Mp4 => out_dir.join("video.mp4"),
        VideoOutput::PngSequence => out_dir.join("frames"),
    }
}

/// Adds each bone's length on this frame to its running sum.
fn add_bone_lengths(bone_sums: &mut [f64], truth: &PerJoint<Point3<f64>>) {
    for (k, b) in Bone::ALL.iter().enumerate() {
        bone_sums[k] += (truth[b.child] - truth[b.parent]).norm();
    }
}

/// The second person on frame `i`, when the clip has one walking behind.
fn distractor_figures<'a>(
    distractor: Option<&'a Distractor>,
    i: usize,
    params: &SynthParams,
) -> Vec<Figure<'a>> {
    distractor
        .iter()
        .filter_map(|(frames, stature, appearance)| {
            frames.get(i).map(|points| Figure {
                points,
                stature_m: *stature,
                appearance: *appearance,
                surface: params.surface,
            })
        })
        .collect()
}

/// The first frame's true joints as the user's marks (`marks.json`), rounded as a file keeps
/// them.
fn write_marks(
    out_dir: &Path,
    first_points2d: Option<PerJoint<Point2<f64>>>,
) -> Result<std::path::PathBuf, SynthError> {
    let marks_path = out_dir.join("marks.json");
    if let Some(points) = first_points2d {
        Marks {
            frame: FrameIndex(0),
            points: points.map(|_, p| nalgebra::Point2::new(round4(p.x), round4(p.y))),
        }
        .save(&marks_path)?;
    }
    Ok(marks_path)
}

/// The background: the clip's photograph resized to fill the frame, or a generated one.
fn load_background(params: &SynthParams) -> Result<image::RgbImage, SynthError> {
    Ok(match &params.background_image {
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
    })
}

/// One frame of the ground truth, rounded as the file keeps it.
fn truth_frame(
    index: usize,
    points2d: &PerJoint<Point2<f64>>,
    truth: &PerJoint<Point3<f64>>,
    visible: &[bool],
) -> GroundTruthFrame {
    GroundTruthFrame {
        index,
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
        visible: visible.to_vec(),
    }
}

/// The clip's ground truth: the camera, the stated height, each bone's mean length over the
/// clip (`bone_sums` over its frames) and the frames.
fn ground_truth(
    params: &SynthParams,
    motion: &Motion,
    camera: &PinholeCamera,
    stature: f64,
    bone_sums: &[f64],
    frames: Vec<GroundTruthFrame>,
) -> GroundTruth {
    let total = motion.frames.len();
    GroundTruth {
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
        frames,
    }
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
