//! `videomocap lift`: from tracks2d.json to skeleton3d.json (the lift step of `run` too).

use super::args::{GlobalArgs, LiftArgs, LiftOptions};
use super::{ExitError, progress_bar, say};
use anyhow::anyhow;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::{KnownLengths, Tracks2d};
use videomocap_core::lift::{
    CameraChoice, FrameFlag, LiftError, LiftOutput, LiftParams, SubjectChoice, reconstruct,
};
use videomocap_core::skeleton::DEFAULT_HEIGHT_M;

/// Checks the camera and subject options before any work, and reads the lift settings (the
/// defaults without `--lift-settings`) and the known lengths (none without `--lengths`) they
/// name.
pub fn check_options(o: &LiftOptions) -> Result<(LiftParams, KnownLengths), ExitError> {
    if let Some(f) = o.focal_px
        && !(f.is_finite() && f > 0.0)
    {
        return Err(ExitError::bad_input(anyhow!(
            "--focal-px must be positive, got {f}"
        )));
    }
    if let Some(d) = o.fov_deg
        && !(d.is_finite() && d > 0.0 && d < 180.0)
    {
        return Err(ExitError::bad_input(anyhow!(
            "--fov-deg must be between 0 and 180, got {d}"
        )));
    }
    if let Some(h) = o.height_m
        && !(h.is_finite() && h > 0.3 && h < 3.0)
    {
        return Err(ExitError::bad_input(anyhow!(
            "--height-m must be a person's height in metres (0.3 to 3), got {h}"
        )));
    }
    let mut params = match &o.lift_settings {
        Some(p) => load_settings(p)?,
        None => LiftParams::default(),
    };
    if o.no_foot_lock {
        params.foot_lock = false;
    }
    let known = match &o.lengths {
        Some(p) => KnownLengths::load(p).map_err(ExitError::bad_input)?,
        None => KnownLengths::default(),
    };
    Ok((params, known))
}

/// Reads lift settings from a JSON file; an older file's retired settings are named on stderr
/// (they no longer change anything).
pub fn load_settings(path: &Path) -> Result<LiftParams, ExitError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| ExitError::bad_input(anyhow!("{}: cannot read: {e}", path.display())))?;
    let bad = |e: serde_json::Error| {
        ExitError::bad_input(anyhow!("{}: bad lift settings: {e}", path.display()))
    };
    let json: serde_json::Value = serde_json::from_str(&text).map_err(bad)?;
    let retired = videomocap_core::lift::retired_lift_settings(&json);
    if !retired.is_empty() {
        eprintln!(
            "note: {}: settings retired in 2026-11 are ignored (now fixed in the lift): {}",
            path.display(),
            retired.join(", ")
        );
    }
    let params: LiftParams = serde_json::from_value(json).map_err(bad)?;
    params
        .validate()
        .map_err(|e| ExitError::bad_input(anyhow!("{}: {e}", path.display())))?;
    Ok(params)
}

/// A lift error naming the input it came from.
fn lift_error(source: &Path, e: LiftError) -> ExitError {
    let named = anyhow!("{}: {e}", source.display());
    match e {
        LiftError::Cancelled | LiftError::CalibrationFailed { .. } => ExitError::failed(named),
        _ => ExitError::bad_input(named),
    }
}

/// Lifts tracks with the options' camera and subject and the lift settings `params` (from
/// [`check_options`]) through [`reconstruct`], with progress; shared by `lift` and `run`.
/// `source` names the tracks (or the video they came from) in errors.
pub fn lift_with_progress(
    tracks: &Tracks2d,
    source: &Path,
    o: &LiftOptions,
    params: LiftParams,
    known: &KnownLengths,
    global: &GlobalArgs,
) -> Result<LiftOutput, ExitError> {
    let camera = match (o.focal_px, o.fov_deg) {
        (Some(f), _) => CameraChoice::FocalPx(f),
        (None, Some(fov)) => CameraChoice::FovDeg(fov),
        (None, None) if o.estimate_focal => CameraChoice::Estimate,
        (None, None) => CameraChoice::Default,
    };
    let subject = SubjectChoice::Height {
        height_m: o.height_m.unwrap_or(DEFAULT_HEIGHT_M),
        known: known.clone(),
    };
    let bar = progress_bar(global, 1, "lifting");
    let cancel = AtomicBool::new(false);
    let done = reconstruct(
        tracks,
        camera,
        &subject,
        &params,
        Default::default(),
        &mut |p| {
            bar.set_message(p.stage.to_string());
            bar.set_length(p.total as u64);
            bar.set_position(p.done as u64);
        },
        &cancel,
    )
    .map_err(|e| lift_error(source, e))?;
    bar.finish_and_clear();
    say(global, &done.camera_line());
    if let Some(fit) = &done.fit {
        say(global, &fit.to_string());
    }
    Ok(done.output)
}

/// Prints what the lift found (`foot_lock`: whether the lift was asked to hold planted feet).
pub fn report(out: &LiftOutput, foot_lock: bool, global: &GlobalArgs) {
    let n = out.reports.len();
    let count = |pred: &dyn Fn(&FrameFlag) -> bool| {
        out.reports
            .iter()
            .filter(|r| r.flags.iter().any(pred))
            .count()
    };
    say(
        global,
        &format!(
            "lifted {n} frames with focal length {:.0} px; camera calibrated on frame {}",
            out.skeleton.camera.focal_px, out.reports[out.calibration_frame].index
        ),
    );
    say(
        global,
        &format!(
            "frames with a bone too long for its 2D image: {}; with no key-triangle pose that fits: {}",
            count(&|f| matches!(f, FrameFlag::TooLong(_))),
            count(&|f| matches!(f, FrameFlag::KeyTriangleNotConverged)),
        ),
    );
    let blind = count(&|f| matches!(f, FrameFlag::NoImageDepth));
    if blind > 0 {
        say(
            global,
            &format!(
                "frames where the pose network saw no body (depth from the geometry alone): {blind}"
            ),
        );
    }
    let unusual = count(&|f| matches!(f, FrameFlag::UnusualPose));
    if unusual > 0 {
        say(
            global,
            &format!(
                "frames whose pose the learned prior has seen seldom or never (depth from the image and motion): {unusual}"
            ),
        );
    }
    if let Some(r) = &out.refinement {
        say(
            global,
            &format!(
                "global refinement: {} iterations, reprojection RMS {:.2} → {:.2} px",
                r.iterations, r.reprojection_px_before, r.reprojection_px_after
            ),
        );
    }
    if foot_lock {
        say(global, &feet_report(&out.contacts));
    } else {
        say(global, "planted feet: left as lifted (--no-foot-lock)");
    }
}

/// What the foot lock did, in a line: the frames each foot was held planted, or that no
/// planted foot was found (the feet never seen still on the floor: a jump, a swim, feet out of
/// the picture) and nothing was held.
fn feet_report(contacts: &[[bool; 2]]) -> String {
    let held = |k: usize| contacts.iter().filter(|c| c[k]).count();
    let (left, right) = (held(0), held(1));
    if left + right == 0 {
        "planted feet: none found (no foot seen still on the floor), nothing held".to_owned()
    } else {
        format!(
            "planted feet held still: left on {left} frames, right on {right} (--no-foot-lock \
             leaves them as lifted)"
        )
    }
}

/// `lift`.
pub fn run(a: &LiftArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let (params, known) = check_options(&a.options)?;
    let tracks = Tracks2d::load(&a.tracks).map_err(ExitError::bad_input)?;
    let out = lift_with_progress(&tracks, &a.tracks, &a.options, params, &known, global)?;
    out.skeleton.save(&a.output).map_err(ExitError::failed)?;
    report(&out, params.foot_lock, global);
    say(global, &format!("wrote {}", a.output.display()));
    if let Some(bvh) = &a.bvh {
        let outputs = super::export::Outputs3d {
            bvh: Some(bvh.clone()),
            rig: a.options.rig,
            ..Default::default()
        };
        let written = super::export::write_3d(&out.skeleton, &a.output, None, &outputs)?;
        super::export::report_3d(&written, global);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_feet_line_says_when_nothing_was_held() {
        assert!(feet_report(&[[false; 2]; 5]).contains("none found"));
        let line = feet_report(&[[true, false], [true, true], [false, false]]);
        assert!(line.contains("left on 2 frames, right on 1"), "{line}");
    }
}
