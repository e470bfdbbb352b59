//! `videomocap track`: follow the 16 marked joints through the video and write tracks2d.json.

use super::args::{GlobalArgs, TrackArgs};
use super::{ExitError, progress_bar, say};
use anyhow::anyhow;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use videomocap_core::formats::{KeyFrames, Marks};
use videomocap_core::network::PoseNetwork;
use videomocap_core::project::Project;
use videomocap_core::track::{
    SpanKind, TrackError, TrackJob, TrackOutput, TrackerParams, track_video,
};
use videomocap_core::video::{OpenOptions, Video};

/// Opens the video (its decoder on `threads` threads) and the hand-placed joints (a marks file
/// or a keys file) and checks that they fit together.
pub fn open_checked(
    video: &Path,
    marks: Option<&Path>,
    keys: Option<&Path>,
    threads: usize,
) -> Result<(Video, KeyFrames), ExitError> {
    let (path, keys) = match (marks, keys) {
        (_, Some(k)) => (k, KeyFrames::load(k).map_err(ExitError::bad_input)?),
        (Some(m), None) => (
            m,
            KeyFrames::from_marks(&Marks::load(m).map_err(ExitError::bad_input)?),
        ),
        (None, None) => {
            return Err(ExitError::bad_input(anyhow!(
                "give the joints placed by hand: --marks marks.json or --keys keys.json"
            )));
        }
    };
    let v = Video::open(video, &decoding_on(threads)).map_err(ExitError::bad_input)?;
    check_keys(&v, &keys, path)?;
    Ok((v, keys))
}

/// Video options with the decoder on `threads` threads.
fn decoding_on(threads: usize) -> OpenOptions {
    OpenOptions {
        decoder_threads: Some(threads),
        ..OpenOptions::default()
    }
}

/// Checks keys against the video (frames in range, points on the image, one full key); the
/// error names the file the keys came from and the video.
fn check_keys(video: &Video, keys: &KeyFrames, path: &Path) -> Result<(), ExitError> {
    let info = video.info();
    keys.check_in_video(path, info.width, info.height, info.frame_count)
        .map_err(|e| ExitError::bad_input(anyhow!("{e} (video {})", info.path.display())))
}

/// The bundled pose network on `threads` threads ([`PoseNetwork::shared`]), unless `off`; when
/// it cannot be loaded, says why and tracks with VBA alone (never a failure).
pub fn load_network(off: bool, threads: usize) -> Option<Arc<PoseNetwork>> {
    if off {
        return None;
    }
    match PoseNetwork::shared(threads) {
        Ok(n) => Some(n),
        Err(e) => {
            eprintln!("warning: {e}; tracking with VBA alone");
            None
        }
    }
}

/// Runs the tracker on `threads` threads (its pool and the pose network's) with a progress
/// bar, with the pose network when `params.network` (the one switch: `--no-network` turns it
/// off); shared by `track` and `run`.
pub fn track_with_progress(
    video: &mut Video,
    keys: &KeyFrames,
    threads: usize,
    params: TrackerParams,
    global: &GlobalArgs,
) -> Result<TrackOutput, ExitError> {
    let threads = threads.max(1);
    let network = load_network(!params.network, threads);
    let job = TrackJob {
        keys: keys.clone(),
        params,
        threads,
        background: None,
        network,
        previous_network: None,
        previous_passes: None,
    };
    let bar = progress_bar(global, video.info().frame_count as u64, "tracking");
    let cancel = AtomicBool::new(false);
    let mut on_progress = |p: &videomocap_core::track::TrackProgress| {
        bar.set_length(p.total as u64);
        bar.set_position(p.done as u64);
    };
    let out = track_video(video, &job, &mut on_progress, &cancel).map_err(|e| match e {
        TrackError::Video(_) | TrackError::Cancelled => ExitError::failed(e),
        _ => ExitError::bad_input(e),
    })?;
    bar.finish_and_clear();
    Ok(out)
}

/// Reads tracker settings from a JSON file.
pub fn load_settings(path: &Path) -> Result<TrackerParams, ExitError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| ExitError::bad_input(anyhow!("{}: cannot read: {e}", path.display())))?;
    let params: TrackerParams = serde_json::from_str(&text).map_err(|e| {
        ExitError::bad_input(anyhow!("{}: bad tracker settings: {e}", path.display()))
    })?;
    params
        .validate()
        .map_err(|e| ExitError::bad_input(anyhow!("{}: {e}", path.display())))?;
    Ok(params)
}

/// Prints the weak spans (the tracking report).
pub fn report(out: &TrackOutput, global: &GlobalArgs) {
    let interpolated = out
        .spans
        .iter()
        .filter(|s| s.kind == SpanKind::Interpolated)
        .count();
    let weak: Vec<_> = out
        .spans
        .iter()
        .filter(|s| s.kind != SpanKind::Interpolated)
        .collect();
    let count = |kind| weak.iter().filter(|s| s.kind == kind).count();
    say(
        global,
        &format!(
            "{} frames tracked (working scale 1/{:.2}); {} short weak runs interpolated, {} weak spans left for review ({} of them off the frame)",
            out.tracks.frames.len(),
            out.shrink,
            interpolated,
            weak.len(),
            count(SpanKind::OffFrame),
        ),
    );
    if let (Some(first), Some(last)) = (out.damaged.first(), out.damaged.last()) {
        let place = if first == last {
            format!("frame {first}")
        } else {
            format!("between frames {first} and {last}")
        };
        say(
            global,
            &format!(
                "  {} frame(s) could not be decoded (damaged file, {place}): tracked as lost and filled like occlusions",
                out.damaged.len()
            ),
        );
    }
    for s in weak.iter().take(20) {
        say(
            global,
            &format!(
                "  {:<14}  {:<15} frames {}–{} (lowest reliability {:.2})",
                format!("{}:", s.kind),
                s.joint,
                s.start,
                s.end,
                s.min_reliability
            ),
        );
    }
    if weak.len() > 20 {
        say(global, &format!("  … and {} more", weak.len() - 20));
    }
}

/// Whether a `track` input is a saved project rather than a video.
fn is_project(path: &Path) -> bool {
    path.is_file()
        && path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// `track`.
pub fn run(a: &TrackArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let mut project = load_project(a)?;
    let threads = super::cpus::thread_budget(a.threads)?.threads;
    super::cpus::limit_global_pool(threads);
    let (mut video, keys, settings) = open_input(a, project.as_ref(), threads)?;
    let mut params = match (&a.tracker_settings, settings) {
        (Some(p), _) => load_settings(p)?,
        (None, Some(s)) => s,
        (None, None) => TrackerParams::default(),
    };
    // `--no-network` is the settings' switch turned off.
    params.network &= !a.no_network;
    let t0 = std::time::Instant::now();
    let out = track_with_progress(&mut video, &keys, threads, params, global)?;
    let seconds = t0.elapsed().as_secs_f64();
    let written = write_outputs(a, project.as_mut(), &out)?;
    report(&out, global);
    say(
        global,
        &format!(
            "wrote {} ({:.1} frames/s including decoding)",
            written.join(" and "),
            out.tracks.frames.len() as f64 / seconds
        ),
    );
    if global.json {
        let summary = serde_json::json!({
            "output": a.output.as_ref().map_or_else(|| a.video.clone(), |o| o.clone()),
            "frames": out.tracks.frames.len(),
            "seconds": seconds,
            "shrink": out.shrink,
            "spans": out.spans,
            "damaged_frames": out.damaged,
        });
        println!("{summary:#}");
    }
    Ok(())
}

/// The project `track PROJECT.json` names (which brings its own keys), or `None` for a video.
fn load_project(a: &TrackArgs) -> Result<Option<Project>, ExitError> {
    if !is_project(&a.video) {
        return Ok(None);
    }
    if a.marks.is_some() || a.keys.is_some() {
        return Err(ExitError::bad_input(anyhow!(
            "{}: a project brings its own keys; leave out --marks and --keys",
            a.video.display()
        )));
    }
    Ok(Some(Project::load(&a.video).map_err(ExitError::bad_input)?))
}

/// The video, its keys checked against it, and the project's tracker settings if a project
/// named it (a relative video path is relative to the project's folder).
fn open_input(
    a: &TrackArgs,
    project: Option<&Project>,
    threads: usize,
) -> Result<(Video, KeyFrames, Option<TrackerParams>), ExitError> {
    match project {
        Some(p) => {
            let video_path = match a.video.parent() {
                Some(dir) if p.video.is_relative() => dir.join(&p.video),
                _ => p.video.clone(),
            };
            let v =
                Video::open(&video_path, &decoding_on(threads)).map_err(ExitError::bad_input)?;
            check_keys(&v, &p.keys, &a.video)?;
            Ok((v, p.keys.clone(), Some(p.settings.tracker)))
        }
        None => {
            if a.output.is_none() {
                return Err(ExitError::bad_input(anyhow!(
                    "give --output tracks2d.json (only a project keeps its tracks itself)"
                )));
            }
            let (v, k) = open_checked(&a.video, a.marks.as_deref(), a.keys.as_deref(), threads)?;
            Ok((v, k, None))
        }
    }
}

/// Saves the tracks to `--output` and into the project (whose old 3D goes); returns what was
/// written, for the user.
fn write_outputs(
    a: &TrackArgs,
    project: Option<&mut Project>,
    out: &TrackOutput,
) -> Result<Vec<String>, ExitError> {
    let mut written = Vec::new();
    if let Some(output) = &a.output {
        out.tracks.save(output).map_err(ExitError::failed)?;
        written.push(output.display().to_string());
    }
    if let Some(p) = project {
        // The new tracks replace the old, and the 3D lifted from the old ones goes.
        p.tracks = Some(Arc::new(out.tracks.clone()));
        p.skeleton = None;
        p.save(&a.video).map_err(ExitError::failed)?;
        written.push(format!(
            "{} (its tracks; lift again for 3D)",
            a.video.display()
        ));
    }
    Ok(written)
}
