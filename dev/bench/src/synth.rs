//! `videomocap-bench synth`: render a synthetic clip with ground truth.

use crate::args::{GlobalArgs, SynthArgs};
use crate::{ExitError, progress_bar, say};
use anyhow::anyhow;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use videomocap_core::camera::PinholeCamera;
use videomocap_testkit::synth::{
    MotionSource, ProceduralMotion, SensorEffects, SilhouetteFaults, Surface, SynthError,
    SynthParams, VideoOutput, View, VoxelParams, load_motion, render_clip, write_carving_setup,
    write_volume_sequence,
};

/// Horizontal field of view of the synthetic camera when none is given (a phone's main camera
/// in video mode is about 55–65°).
const DEFAULT_FOV_DEG: f64 = 56.0;

/// Builds the library's parameters from the command line.
pub(crate) fn params_from_args(a: &SynthArgs) -> Result<SynthParams, ExitError> {
    let motion = match ProceduralMotion::from_name(&a.motion) {
        Some(kind) => MotionSource::Procedural(kind),
        None => {
            let path = PathBuf::from(&a.motion);
            if !path.is_file() {
                return Err(ExitError::bad_input(anyhow!(
                    "--motion {}: neither walk, treadmill, wave, jumping-jacks, sit-down, bend, march nor an existing BVH file",
                    a.motion
                )));
            }
            MotionSource::Bvh {
                path,
                start_s: a.start_s,
            }
        }
    };
    let view = View::from_name(&a.view).ok_or_else(|| {
        ExitError::bad_input(anyhow!(
            "--view {}: expected frontal, oblique, side, raised, behind or low",
            a.view
        ))
    })?;
    let focal_px = match (a.focal_px, a.fov_deg) {
        (Some(f), _) => f,
        (None, Some(d)) => PinholeCamera::focal_from_horizontal_fov(d, a.width),
        (None, None) => PinholeCamera::focal_from_horizontal_fov(DEFAULT_FOV_DEG, a.width),
    };
    if !(focal_px.is_finite() && focal_px > 0.0) {
        return Err(ExitError::bad_input(anyhow!(
            "focal length must be positive, got {focal_px}"
        )));
    }
    if !a.png && (!a.width.is_multiple_of(2) || !a.height.is_multiple_of(2)) {
        return Err(ExitError::bad_input(anyhow!(
            "MP4 needs even sides, got {}×{} (use --png for odd sizes)",
            a.width,
            a.height
        )));
    }
    Ok(SynthParams {
        motion,
        frames: a.frames,
        fps: a.fps,
        width: a.width,
        height: a.height,
        view,
        focal_px,
        person_px: a.person_px.unwrap_or(0.65 * f64::from(a.height)),
        allow_off_frame: a.allow_off_frame,
        effects: SensorEffects {
            noise_sigma: a.noise.max(0.0),
            flicker: a.flicker.max(0.0),
            seed: a.seed,
        },
        background_seed: a.seed.wrapping_add(6),
        background_image: a.background.clone(),
        output: if a.png {
            VideoOutput::PngSequence
        } else {
            VideoOutput::Mp4
        },
        surface: match a.body.as_str() {
            "mesh" => Surface::Mesh,
            "capsule" => Surface::Capsules,
            other => {
                return Err(ExitError::bad_input(anyhow!(
                    "--body {other}: expected mesh or capsule"
                )));
            }
        },
        ..SynthParams::default()
    })
}

pub(crate) fn run(a: &SynthArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let params = params_from_args(a)?;
    if a.volume {
        return volume(a, &params, global);
    }
    let bar = progress_bar(global, a.frames as u64, "rendering");
    let cancel = AtomicBool::new(false);
    let result = render_clip(
        &params,
        &a.output,
        &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
        &cancel,
    )
    .map_err(|e| match e {
        SynthError::Motion(_) | SynthError::Params(_) => ExitError::bad_input(e),
        _ => ExitError::failed(e),
    })?;
    bar.finish_and_clear();
    if global.json {
        let summary = serde_json::json!({
            "video": result.video,
            "ground_truth": result.ground_truth,
            "marks": result.marks,
            "frames": result.frames,
            "focal_px": result.camera.focal_px,
            "render_ms_per_frame": result.render_s_per_frame * 1e3,
            "person_px": [result.framing.stature_px.0, result.framing.stature_px.1],
        });
        println!("{summary}");
    } else {
        say(
            global,
            &format!(
                "wrote {} frames: {}, {}, {} ({:.1} ms per frame to render; the person {:.0}–{:.0} px tall)",
                result.frames,
                result.video.display(),
                result.ground_truth.display(),
                result.marks.display(),
                result.render_s_per_frame * 1e3,
                result.framing.stature_px.0,
                result.framing.stature_px.1
            ),
        );
    }
    Ok(())
}

/// `synth --volume`: the posed body voxelised per frame.
fn volume(a: &SynthArgs, params: &SynthParams, global: &GlobalArgs) -> Result<(), ExitError> {
    if !(a.voxel_mm.is_finite() && a.voxel_mm >= 5.0) {
        return Err(ExitError::bad_input(anyhow!(
            "--voxel-mm must be at least 5, got {}",
            a.voxel_mm
        )));
    }
    if !(0.0..1.0).contains(&a.holes) {
        return Err(ExitError::bad_input(anyhow!(
            "--holes must be in [0, 1), got {}",
            a.holes
        )));
    }
    let motion = load_motion(params).map_err(ExitError::bad_input)?;
    let voxel = VoxelParams {
        voxel_m: a.voxel_mm / 1000.0,
        noise_voxels: a.noise_voxels,
        hole_fraction: a.holes,
        seed: a.seed,
    };
    let bar = progress_bar(global, motion.frames.len() as u64, "voxelising");
    let points = write_volume_sequence(&motion, &a.output, &voxel, |done, _| {
        bar.set_position(done as u64)
    })
    .map_err(ExitError::failed)?;
    bar.finish_and_clear();
    if a.views > 0 {
        let dir = a.output.join("carve");
        let bar = progress_bar(global, motion.frames.len() as u64, "silhouettes");
        let faults = if a.faulty_silhouettes {
            SilhouetteFaults::typical()
        } else {
            SilhouetteFaults::default()
        };
        write_carving_setup(
            &motion,
            &dir,
            a.views,
            (a.width, a.height),
            &faults,
            &|done, _| bar.set_position(done as u64),
        )
        .map_err(ExitError::failed)?;
        bar.finish_and_clear();
        say(
            global,
            &format!(
                "wrote a carving set-up of {} cameras to {} (videomocap carve {} -o DIR)",
                a.views,
                dir.display(),
                dir.display()
            ),
        );
    }
    say(
        global,
        &format!(
            "wrote {} frames ({:.0} points per frame) and truth.skeleton3d.json to {}",
            motion.frames.len(),
            points as f64 / motion.frames.len().max(1) as f64,
            a.output.display()
        ),
    );
    Ok(())
}
