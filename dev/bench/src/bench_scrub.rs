//! `videomocap bench scrub`: what the desktop app's frame access costs on a long 1080p clip made
//! with `ffmpeg -f lavfi`: opening (the frame index), random seeks, stepping through frames,
//! revisiting cached frames (decode cache plus the RGB → RGBA copy the texture upload needs),
//! the seek proxy (its build, and seeks shown from it), tracking a 300-frame span from the
//! middle, and the process's peak memory. The app does the same calls on its frame-loader thread.

use crate::args::{BenchArgs, GlobalArgs};
use crate::{ExitError, say};
use rand::{Rng, SeedableRng};
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use videomocap_core::formats::Marks;
use videomocap_core::track::{TrackJob, TrackerParams, track_video};
use videomocap_core::video::{OpenOptions, Video, VideoError};

/// What scrubbing the long clip measured: opening it, 40 random seeks (sorted, ms), stepping
/// through and revisiting up to 120 frames (frames/s), and the peak memory after.
struct Scrubbing {
    info: videomocap_core::video::VideoInfo,
    open_s: f64,
    targets: Vec<usize>,
    seeks: Vec<f64>,
    step_fps: f64,
    cached_fps: f64,
    rss_scrub: f64,
}

/// Runs the scrubbing benchmark on a long 1080p clip (made once) and prints its table.
pub(crate) fn run(a: &BenchArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    crate::bench::note_debug_build(global);
    let file = long_clip(a, global)?;
    let rss_before = peak_rss_mib();
    let scrubbing = scrub(&file)?;
    let proxy_rows = proxy_rows(&file, &scrubbing.info, &scrubbing.targets, global)?;
    let rss_proxy = peak_rss_mib();
    let (track_label, track_fps) = track_span(&file, scrubbing.info.frame_count)?;
    let s = &scrubbing;
    let n = s.info.frame_count;
    let pct = |q: f64| s.seeks[((s.seeks.len() - 1) as f64 * q).round() as usize];
    let mut rows: Vec<(String, String)> = Vec::new();
    let head = [
        (
            "clip",
            format!(
                "1920×1080, {n} frames ({:.1} min), keyframe every {} frames",
                n as f64 / 30.0 / 60.0,
                a.gop
            ),
        ),
        ("open (reads the frame index)", format!("{:.2} s", s.open_s)),
        ("random seek, median", format!("{:.0} ms", pct(0.5))),
        (
            "random seek, 95th percentile",
            format!("{:.0} ms", pct(0.95)),
        ),
        ("random seek, worst of 40", format!("{:.0} ms", pct(1.0))),
        (
            "random seeks within 150 ms",
            format!("{} of 40", s.seeks.iter().filter(|&&v| v <= 150.0).count()),
        ),
    ];
    rows.extend(head.map(|(k, v)| (k.to_owned(), v)));
    rows.extend(proxy_rows);
    let tail = [
        (
            "step forward one frame at a time",
            format!("{:.0} frames/s", s.step_fps),
        ),
        (
            "revisit cached frames incl. RGBA copy",
            format!("{:.0} frames/s", s.cached_fps),
        ),
        (track_label.as_str(), format!("{track_fps:.0} frames/s")),
        (
            "peak memory (VmHWM) before open",
            format!("{rss_before:.0} MiB"),
        ),
        (
            "peak memory (VmHWM) after scrubbing",
            format!("{:.0} MiB", s.rss_scrub),
        ),
        (
            "peak memory (VmHWM) after the proxy",
            format!("{rss_proxy:.0} MiB"),
        ),
        (
            "peak memory (VmHWM) after tracking",
            format!("{:.0} MiB", peak_rss_mib()),
        ),
    ];
    rows.extend(tail.map(|(k, v)| (k.to_owned(), v)));
    println!("{:<40} value", "measure");
    for (k, v) in rows {
        println!("{k:<40} {v}");
    }
    Ok(())
}

/// The long 1920×1080 clip of `a.minutes` at 30 frames/s in `out/bench-scrub`, made with
/// FFmpeg unless an earlier run left it.
fn long_clip(a: &BenchArgs, global: &GlobalArgs) -> Result<std::path::PathBuf, ExitError> {
    let dir = std::path::Path::new("out/bench-scrub");
    std::fs::create_dir_all(dir).map_err(ExitError::failed)?;
    let frames = (a.minutes * 60.0 * 30.0).round().max(2.0) as usize;
    // Named as before for the default GOP, so clips made earlier are reused.
    let file = if a.gop == 250 {
        dir.join(format!("long_1080p_{frames}.mp4"))
    } else {
        dir.join(format!("long_1080p_{frames}_gop{}.mp4", a.gop))
    };
    if !file.is_file() {
        say(
            global,
            &format!(
                "making a 1920×1080 H.264 clip of {frames} frames ({} min, keyframe every {} frames, kept in {}) …",
                a.minutes,
                a.gop,
                dir.display()
            ),
        );
        crate::bench::make_clip(
            &file,
            1920,
            1080,
            frames,
            crate::bench::ClipKind::Plain,
            a.gop,
        )
        .map_err(ExitError::failed)?;
    }
    Ok(file)
}

/// Opens `file`, seeks to 40 random frames, steps through up to 120 frames from the middle
/// and revisits them five times, as scrubbing back and forth does.
fn scrub(file: &std::path::Path) -> Result<Scrubbing, ExitError> {
    let t0 = Instant::now();
    let mut video = Video::open(file, &OpenOptions::default()).map_err(ExitError::failed)?;
    let open_s = t0.elapsed().as_secs_f64();
    let n = video.info().frame_count;
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let targets: Vec<usize> = (0..40).map(|_| rng.random_range(0..n)).collect();
    let mut seeks: Vec<f64> = Vec::new();
    for &k in &targets {
        let t = Instant::now();
        video.frame(k).map_err(ExitError::failed)?;
        seeks.push(t.elapsed().as_secs_f64() * 1000.0);
    }
    seeks.sort_by(f64::total_cmp);
    let info = video.info().clone();
    let window = n.min(120);
    let start = (n - window) / 2;
    let t = Instant::now();
    for k in start..start + window {
        video.frame(k).map_err(ExitError::failed)?;
    }
    let step_fps = window as f64 / t.elapsed().as_secs_f64();
    let t = Instant::now();
    for _ in 0..5 {
        for k in start..start + window {
            let f = video.frame(k).map_err(ExitError::failed)?;
            std::hint::black_box(texture_copy(&f.image));
        }
    }
    let cached_fps = (5 * window) as f64 / t.elapsed().as_secs_f64();
    Ok(Scrubbing {
        info,
        open_s,
        targets,
        seeks,
        step_fps,
        cached_fps,
        rss_scrub: peak_rss_mib(),
    })
}

/// Tracks a 300-frame span from the middle of `file`'s `n` frames, as a user tracking one
/// stretch of a long clip: (the row's label, frames/s).
fn track_span(file: &std::path::Path, n: usize) -> Result<(String, f64), ExitError> {
    let span_len = n.min(300);
    let span_start = (n - span_len) / 2;
    let mut span = Video::open(file, &OpenOptions::default())
        .and_then(|v| v.into_span(span_start, span_len))
        .map_err(ExitError::failed)?;
    let (w, h) = (span.info().width, span.info().height);
    let job = TrackJob::from_marks(&figure_marks(w, h)?, TrackerParams::default(), 2);
    let t = Instant::now();
    track_video(&mut span, &job, &mut |_| {}, &AtomicBool::new(false))
        .map_err(ExitError::failed)?;
    let track_fps = span_len as f64 / t.elapsed().as_secs_f64();
    let label = format!(
        "track frames {span_start}–{} (2 threads)",
        span_start + span_len - 1
    );
    Ok((label, track_fps))
}

/// The app's seek proxy on this clip: built once (timed unless an earlier run left it), then
/// each seek shows the proxy's frame (decoded and turned into RGBA for the texture) while, as in
/// the app, the full frame decodes on another thread. Clips that the app makes no proxy for get
/// one row saying so.
fn proxy_rows(
    file: &std::path::Path,
    info: &videomocap_core::video::VideoInfo,
    targets: &[usize],
    global: &GlobalArgs,
) -> Result<Vec<(String, String)>, ExitError> {
    use videomocap_core::video::proxy;
    if !proxy::wants_proxy(info) {
        return Ok(vec![(
            "seek proxy".to_owned(),
            format!(
                "not made: keyframes at most {} frames apart (the app makes one above {})",
                info.keyframe_interval,
                proxy::PROXY_MIN_KEYFRAME_INTERVAL
            ),
        )]);
    }
    let proxy_dir = file
        .parent()
        .unwrap_or(std::path::Path::new("."))
        .join("proxies");
    let proxy_file = proxy::proxy_path(&proxy_dir, file).map_err(ExitError::failed)?;
    let proxy_build = if proxy_file.is_file() {
        "reused from an earlier run (delete out/bench-scrub/proxies to time it)".to_owned()
    } else {
        say(global, "building the seek proxy …");
        let t = Instant::now();
        proxy::build(file, &proxy_file, &mut |_, _| true).map_err(ExitError::failed)?;
        format!("{:.0} s", t.elapsed().as_secs_f64())
    };
    let proxy_mib = std::fs::metadata(&proxy_file)
        .map_err(ExitError::failed)?
        .len() as f64
        / (1 << 20) as f64;
    let mut proxy = proxy::open(&proxy_file, info)
        .ok_or_else(|| ExitError::failed(anyhow::anyhow!("the proxy does not fit the clip")))?;
    let (pw, ph) = (proxy.info().width, proxy.info().height);
    let (previews, fulls) = proxy_seeks(&mut proxy, file, targets)?;
    drop(proxy);
    let pct = |v: &[f64], q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    let within = previews.iter().filter(|&&s| s <= 150.0).count();
    Ok(vec![
        ("seek proxy: build time".to_owned(), proxy_build),
        (
            "seek proxy: size".to_owned(),
            format!(
                "{pw}×{ph}, keyframe every {} frames, {proxy_mib:.0} MiB",
                proxy::PROXY_GOP
            ),
        ),
        (
            "seek shown from the proxy, median".to_owned(),
            format!("{:.0} ms", pct(&previews, 0.5)),
        ),
        (
            "seek shown from the proxy, 95th pct".to_owned(),
            format!("{:.0} ms", pct(&previews, 0.95)),
        ),
        (
            "seek shown from the proxy, worst".to_owned(),
            format!("{:.0} ms", pct(&previews, 1.0)),
        ),
        (
            "seeks shown from the proxy within 150 ms".to_owned(),
            format!("{within} of {}", previews.len()),
        ),
        (
            "  full frame meanwhile, median / worst".to_owned(),
            format!("{:.0} ms / {:.0} ms", pct(&fulls, 0.5), pct(&fulls, 1.0)),
        ),
    ])
}

/// Seeks to each of `targets` in the proxy (decoded and turned into RGBA for the texture)
/// while, as in the app, the full frame decodes on another thread: (the previews' times, the
/// full frames' times), each sorted, ms.
fn proxy_seeks(
    proxy: &mut Video,
    file: &std::path::Path,
    targets: &[usize],
) -> Result<(Vec<f64>, Vec<f64>), ExitError> {
    // As in the app, the full frame decodes on another thread while the preview is shown.
    let (ask, asked) = std::sync::mpsc::channel::<usize>();
    let (answer, answers) = std::sync::mpsc::channel::<Result<f64, VideoError>>();
    let full_file = file.to_owned();
    let worker = std::thread::spawn(move || {
        let mut full = match Video::open(&full_file, &OpenOptions::default()) {
            Ok(v) => v,
            Err(e) => return answer.send(Err(e)),
        };
        answer.send(Ok(0.0))?;
        for k in asked {
            let t = Instant::now();
            let r = full.frame(k).map(|_| t.elapsed().as_secs_f64() * 1000.0);
            answer.send(r)?;
        }
        Ok(())
    });
    let recv = || -> Result<f64, ExitError> {
        answers
            .recv()
            .map_err(ExitError::failed)?
            .map_err(ExitError::failed)
    };
    recv()?;
    let (mut previews, mut fulls) = (Vec::new(), Vec::new());
    for &k in targets {
        ask.send(k).map_err(ExitError::failed)?;
        let t = Instant::now();
        let f = proxy.frame(k).map_err(ExitError::failed)?;
        std::hint::black_box(texture_copy(&f.image));
        previews.push(t.elapsed().as_secs_f64() * 1000.0);
        fulls.push(recv()?);
    }
    drop(ask);
    let _ = worker.join();
    previews.sort_by(f64::total_cmp);
    fulls.sort_by(f64::total_cmp);
    Ok((previews, fulls))
}

/// The RGB → RGBA copy the app makes to upload a frame as a texture.
fn texture_copy(image: &image::RgbImage) -> Vec<u8> {
    image
        .as_raw()
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect()
}

/// The synthetic sample's marks (640×480) scaled to a `w`×`h` frame: a figure to track (on
/// the test pattern it measures speed and memory, not accuracy).
fn figure_marks(w: u32, h: u32) -> Result<Marks, ExitError> {
    let mut marks = Marks::load(std::path::Path::new(
        "sample_videos/synth_walk_oblique/marks.json",
    ))
    .map_err(ExitError::failed)?;
    for p in marks.points.0.iter_mut() {
        p.x *= f64::from(w - 1) / 639.0;
        p.y *= f64::from(h - 1) / 479.0;
    }
    Ok(marks)
}

/// The process's peak resident memory, MiB (Linux; 0 elsewhere).
fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}
