//! Seek proxies: a small copy of a video with a keyframe every few frames, for showing any frame
//! at once while the full-size frame decodes.
//!
//! A random seek decodes from the keyframe before the frame. Cameras and phones put a keyframe
//! every second or so, but x264's default (and screen recorders) put one every 250 frames, so a
//! seek into a 1080p video may decode 250 frames. The proxy (at most [`PROXY_MAX_SIDE`] pixels
//! on its long side, a keyframe every [`PROXY_GOP`] frames) shows frame `i` after decoding at
//! most [`PROXY_GOP`] small frames. Proxies are only ever shown, never tracked: tracking reads
//! the video itself. This is what video editors call proxy media.
//!
//! Proxies live in a cache directory chosen by the caller, named by the video's path, size and
//! modification time (an edited video gets a new proxy), written to a temporary file and renamed
//! when complete, so a half-built proxy is never used.

use super::{Video, VideoError, VideoInfo};
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// Longest side of a proxy frame, pixels (a fitted 1080p frame on a laptop screen is about this
/// wide; zooming in shows the full-size frame, which follows within a GOP's decoding).
pub const PROXY_MAX_SIDE: u32 = 960;

/// Keyframe interval of a proxy, frames: the most frames a preview decodes.
pub const PROXY_GOP: u32 = 10;

/// x264 quality of a proxy (23 is x264's default; previews need no more).
pub const PROXY_CRF: u32 = 23;

/// Videos whose keyframes are further apart than this many frames get a proxy. At 1080p a frame
/// decodes in about 1 ms (2 cores; `bench scrub`), so 32 frames keep a seek well within 150 ms
/// without one.
pub const PROXY_MIN_KEYFRAME_INTERVAL: usize = 32;

/// Bytes of proxies the cache directory keeps; the least recently made go first.
pub const PROXY_CACHE_BYTES: u64 = 4 << 30;

/// Frame cache of an open proxy, bytes (about 40 frames at 960×540).
const PROXY_FRAME_CACHE_BYTES: usize = 64 << 20;

/// Bumped when the proxy's encoding changes, so old proxies are not reused.
const PROXY_FORMAT: u32 = 1;

/// Whether a seek into this video is slow enough to be worth a proxy.
pub fn wants_proxy(info: &VideoInfo) -> bool {
    info.keyframe_interval > PROXY_MIN_KEYFRAME_INTERVAL
}

/// Size of the proxy frames for a `width × height` video: fitted within [`PROXY_MAX_SIDE`],
/// sides even (H.264's 4:2:0 needs it), never larger than the video.
pub fn proxy_size(width: u32, height: u32) -> (u32, u32) {
    let long = width.max(height).max(1);
    let scale = (f64::from(PROXY_MAX_SIDE) / f64::from(long)).min(1.0);
    let even = |v: u32| ((f64::from(v) * scale / 2.0).round() as u32 * 2).max(2);
    (even(width), even(height))
}

/// Where the proxy of `video` lives in `cache_dir`. The name comes from the video's full path,
/// size and modification time, so a changed or replaced video does not find an old proxy.
pub fn proxy_path(cache_dir: &Path, video: &Path) -> Result<PathBuf, VideoError> {
    let io = |source| VideoError::Io {
        path: video.to_owned(),
        source,
    };
    let full = std::fs::canonicalize(video).map_err(io)?;
    let meta = std::fs::metadata(&full).map_err(io)?;
    let modified = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(SystemTime::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    // `DefaultHasher::new` is the same in every run of one build; a new Rust may hash
    // differently, which only costs one rebuilt proxy.
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    (&full, meta.len(), modified, PROXY_FORMAT).hash(&mut hasher);
    let stem: String = full
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
        .chars()
        .map(|c| if c.is_alphanumeric() { c } else { '_' })
        .take(40)
        .collect();
    Ok(cache_dir.join(format!("{stem}-{:016x}.mp4", hasher.finish())))
}

/// How [`build`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildOutcome {
    /// The proxy is complete at the path asked for.
    Built,
    /// `progress` asked to stop; nothing was left behind.
    Cancelled,
}

/// Builds the proxy of `video` at `out`: decodes every frame in order, shrunk to
/// [`proxy_size`], and encodes them with a keyframe every [`PROXY_GOP`] frames. Frame `i` of
/// the proxy is frame `i` of the video whatever its timestamps (variable frame rate included);
/// a frame that cannot be decoded repeats the one before, so the numbering holds.
///
/// `progress(done, total)` is called before each frame; returning `false` stops the build.
/// The file appears at `out` only when complete (written beside it, then renamed).
#[cfg(feature = "ffmpeg")]
pub fn build(
    video: &Path,
    out: &Path,
    progress: &mut dyn FnMut(usize, usize) -> bool,
) -> Result<BuildOutcome, VideoError> {
    use super::{EncodeParams, FfmpegSource, Mp4Writer, VideoSource};
    let mut source = FfmpegSource::open(video)?;
    let (w, h) = proxy_size(source.info().width, source.info().height);
    source.shrink_to(w, h);
    let total = source.info().frame_count;
    let fps = source.info().fps.round().clamp(1.0, 240.0) as u32;
    let dir = out.parent().unwrap_or(Path::new("."));
    let io = |source| VideoError::Io {
        path: out.to_owned(),
        source,
    };
    std::fs::create_dir_all(dir).map_err(io)?;
    let partial = tempfile::Builder::new()
        .prefix(".partial-")
        .suffix(".mp4")
        .tempfile_in(dir)
        .map_err(io)?;
    let params = EncodeParams {
        fps,
        gop: PROXY_GOP,
        max_b_frames: 0,
        crf: PROXY_CRF,
    };
    let mut writer = Mp4Writer::create(partial.path(), w, h, &params)?;
    let mut last: Option<image::RgbImage> = None;
    for i in 0..total {
        if !progress(i, total) {
            return Ok(BuildOutcome::Cancelled);
        }
        let image = match source.decode(i) {
            Ok(image) => image,
            Err(VideoError::Decode { .. }) => {
                last.clone().unwrap_or_else(|| image::RgbImage::new(w, h))
            }
            Err(e) => return Err(e),
        };
        writer.write(&image)?;
        last = Some(image);
    }
    writer.finish()?;
    partial.persist(out).map_err(|e| io(e.error))?;
    progress(total, total);
    Ok(BuildOutcome::Built)
}

/// Without FFmpeg there are no video files to make proxies of.
#[cfg(not(feature = "ffmpeg"))]
pub fn build(
    video: &Path,
    _out: &Path,
    _progress: &mut dyn FnMut(usize, usize) -> bool,
) -> Result<BuildOutcome, VideoError> {
    Err(VideoError::FfmpegDisabled {
        path: video.to_owned(),
    })
}

/// Opens the proxy at `path` for the video described by `original`, if there is one and it
/// fits: as many frames and the same shape. A proxy that does not fit (or does not open) is
/// deleted so that it gets rebuilt; `None` then.
pub fn open(path: &Path, original: &VideoInfo) -> Option<Video> {
    if !path.is_file() {
        return None;
    }
    let fits = |v: &Video| {
        let i = v.info();
        i.frame_count == original.frame_count
            && (i.width, i.height) == proxy_size(original.width, original.height)
    };
    match Video::open(
        path,
        &super::OpenOptions {
            cache_bytes: PROXY_FRAME_CACHE_BYTES,
            ..Default::default()
        },
    ) {
        Ok(v) if fits(&v) => Some(v),
        _ => {
            let _ = std::fs::remove_file(path);
            None
        }
    }
}

/// Deletes the least recently made files in `cache_dir` until the rest fit in `keep_bytes`,
/// never `keep` (the proxy just made). Best effort: a file that cannot be removed is left.
pub fn prune(cache_dir: &Path, keep: &Path, keep_bytes: u64) {
    let Ok(entries) = std::fs::read_dir(cache_dir) else {
        return;
    };
    let mut files: Vec<(SystemTime, u64, PathBuf)> = entries
        .filter_map(Result::ok)
        .filter_map(|e| {
            let meta = e.metadata().ok()?;
            let modified = meta.modified().ok()?;
            meta.is_file().then(|| (modified, meta.len(), e.path()))
        })
        .collect();
    let mut total: u64 = files.iter().map(|f| f.1).sum();
    files.sort();
    for (_, len, path) in files {
        if total <= keep_bytes {
            break;
        }
        if path != keep && std::fs::remove_file(&path).is_ok() {
            total = total.saturating_sub(len);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proxy_size_fits_the_long_side_and_keeps_sides_even() {
        assert_eq!(proxy_size(1920, 1080), (960, 540));
        assert_eq!(proxy_size(1080, 1920), (540, 960));
        assert_eq!(proxy_size(640, 480), (640, 480));
        assert_eq!(proxy_size(641, 479), (642, 480));
        let (w, h) = proxy_size(3840, 1634);
        assert_eq!(w, 960);
        assert!(h % 2 == 0 && (h as i32 - 408).abs() <= 1, "{h}");
    }

    #[test]
    fn proxy_path_changes_with_the_video() {
        let dir = tempfile::tempdir().unwrap();
        let video = dir.path().join("clip one.mp4");
        std::fs::write(&video, b"first").unwrap();
        let a = proxy_path(dir.path(), &video).unwrap();
        assert_eq!(a, proxy_path(dir.path(), &video).unwrap());
        assert!(
            a.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("clip_one-")
        );
        std::fs::write(&video, b"second, longer").unwrap();
        assert_ne!(a, proxy_path(dir.path(), &video).unwrap());
        let missing = proxy_path(dir.path(), &dir.path().join("gone.mp4"));
        assert!(missing.unwrap_err().to_string().contains("gone.mp4"));
    }

    #[test]
    fn prune_removes_the_oldest_but_never_the_one_kept() {
        let dir = tempfile::tempdir().unwrap();
        let names = ["a.mp4", "b.mp4", "c.mp4"];
        for (k, n) in names.iter().enumerate() {
            let p = dir.path().join(n);
            std::fs::write(&p, vec![0u8; 100]).unwrap();
            let t = SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_000 + k as u64);
            std::fs::File::options()
                .write(true)
                .open(&p)
                .unwrap()
                .set_modified(t)
                .unwrap();
        }
        // Keep the oldest: the next oldest goes.
        prune(dir.path(), &dir.path().join("a.mp4"), 200);
        assert!(dir.path().join("a.mp4").exists());
        assert!(!dir.path().join("b.mp4").exists());
        assert!(dir.path().join("c.mp4").exists());
    }
}
