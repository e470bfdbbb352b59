//! Opens and decodes the video on a worker thread so the UI never waits for FFmpeg (opening an
//! hour-long file reads its whole packet index). The UI sends the index it wants; the worker
//! skips stale requests (only the latest matters while scrubbing) and sends back decoded frames,
//! asking egui to repaint.
//!
//! Videos whose keyframes are far apart (a seek decodes up to hundreds of frames) also get a
//! seek proxy ([`videomocap_core::video::proxy`]): a second worker finds or builds it in the
//! background, then answers each request with the proxy's frame (a preview, in a few
//! milliseconds) while the first worker decodes the full frame.

use std::cell::Cell;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;
use std::time::Duration;
use videomocap_core::video::proxy::{self, BuildOutcome};
use videomocap_core::video::{Frame, OpenOptions, Video, VideoError, VideoInfo};

/// What the worker reports.
pub(crate) enum LoaderEvent {
    /// The video opened (or could not be).
    Opened(Result<VideoInfo, VideoError>),
    /// A decoded frame or the error decoding it.
    Frame(Result<Frame, VideoError>),
    /// A frame from the seek proxy: the right frame, smaller, ahead of the full one.
    Preview(Frame),
    /// How the seek proxy is coming on.
    Proxy(ProxyStatus),
}

/// State of the seek proxy.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum ProxyStatus {
    /// Being built: frames done of total.
    Building(usize, usize),
    /// In use: seeks show its frame first.
    Ready,
    /// Could not be made (seeks still work, at full-decode speed).
    Failed(String),
}

/// The UI side of the workers.
pub(crate) struct FrameLoader {
    requests: Option<Sender<usize>>,
    previews: Option<Sender<usize>>,
    results: Receiver<LoaderEvent>,
    workers: Vec<JoinHandle<()>>,
    info: Option<VideoInfo>,
    proxy: Option<ProxyStatus>,
    /// Pauses the proxy build (set while a tracking job needs the cores).
    pause: Arc<AtomicBool>,
    /// Stops the proxy build (set when the video is closed).
    stop: Arc<AtomicBool>,
    /// The last frame asked for: a request just after it decodes on, with no seek.
    last_request: Cell<Option<usize>>,
}

/// A request at most this many frames after the last one is a step (playing, →), which decodes
/// on quickly: no preview, so playback does not flicker between preview and full frames.
const STEP_FRAMES: usize = 8;

/// How often a paused proxy build looks again.
const PAUSE_POLL: Duration = Duration::from_millis(100);

impl FrameLoader {
    /// Opens `path` on a new worker thread; [`FrameLoader::poll`] reports when it is open.
    /// With a `proxy_dir`, a video with far-apart keyframes gets a seek proxy kept there.
    pub(crate) fn open(
        path: PathBuf,
        ctx: egui::Context,
        proxy_dir: Option<PathBuf>,
    ) -> FrameLoader {
        let (req_tx, req_rx) = channel::<usize>();
        let (pre_tx, pre_rx) = channel::<usize>();
        let (res_tx, res_rx) = channel::<LoaderEvent>();
        let pause = Arc::new(AtomicBool::new(false));
        let stop = Arc::new(AtomicBool::new(false));
        let (worker_pause, worker_stop) = (Arc::clone(&pause), Arc::clone(&stop));
        let worker = std::thread::Builder::new()
            .name("frame-loader".into())
            .spawn(move || {
                let opened = Video::open(&path, &OpenOptions::default());
                let (mut video, info) = match opened {
                    Ok(v) => {
                        let info = v.info().clone();
                        (v, info)
                    }
                    Err(e) => {
                        let _ = res_tx.send(LoaderEvent::Opened(Err(e)));
                        ctx.request_repaint();
                        return;
                    }
                };
                if res_tx.send(LoaderEvent::Opened(Ok(info.clone()))).is_err() {
                    return;
                }
                ctx.request_repaint();
                // The proxy worker lives as long as this one (joined below, after the request
                // channel closes and `stop` is set by the drop).
                let proxy_worker =
                    proxy_dir
                        .filter(|_| proxy::wants_proxy(&info))
                        .and_then(|dir| {
                            let worker = ProxyWorker {
                                path,
                                info,
                                dir,
                                requests: pre_rx,
                                results: res_tx.clone(),
                                ctx: ctx.clone(),
                                pause: worker_pause,
                                stop: worker_stop,
                            };
                            std::thread::Builder::new()
                                .name("seek-proxy".into())
                                .spawn(move || worker.run())
                                .ok()
                        });
                while let Ok(mut index) = req_rx.recv() {
                    // Only the newest request matters.
                    while let Ok(newer) = req_rx.try_recv() {
                        index = newer;
                    }
                    if res_tx.send(LoaderEvent::Frame(video.frame(index))).is_err() {
                        break;
                    }
                    ctx.request_repaint();
                }
                if let Some(w) = proxy_worker {
                    let _ = w.join();
                }
            })
            .ok();
        FrameLoader {
            requests: Some(req_tx),
            previews: Some(pre_tx),
            results: res_rx,
            workers: worker.into_iter().collect(),
            info: None,
            proxy: None,
            pause,
            stop,
            last_request: Cell::new(None),
        }
    }

    /// Metadata of the video, once open.
    pub(crate) fn info(&self) -> Option<&VideoInfo> {
        self.info.as_ref()
    }

    /// The seek proxy's state, if the video gets one.
    pub(crate) fn proxy(&self) -> Option<&ProxyStatus> {
        self.proxy.as_ref()
    }

    /// Holds a running proxy build (while tracking needs the cores) or lets it go on.
    pub(crate) fn pause_background(&self, pause: bool) {
        self.pause.store(pause, Ordering::Relaxed);
    }

    /// Asks for a frame (answered later through [`FrameLoader::poll`]): for a seek, a preview
    /// first when the seek proxy is ready; then the full frame.
    pub(crate) fn request(&self, index: usize) {
        if let Some(tx) = &self.requests {
            let _ = tx.send(index);
        }
        let step = self
            .last_request
            .replace(Some(index))
            .is_some_and(|last| index > last && index - last <= STEP_FRAMES);
        if !step
            && self.proxy == Some(ProxyStatus::Ready)
            && let Some(tx) = &self.previews
        {
            let _ = tx.send(index);
        }
    }

    /// What arrived since the last call: the open result (first), the proxy's state, the
    /// newest preview and the newest frame.
    pub(crate) fn poll(&mut self) -> Vec<LoaderEvent> {
        let mut opened = None;
        let mut frame = None;
        let mut preview = None;
        let mut proxy = None;
        while let Ok(event) = self.results.try_recv() {
            match event {
                LoaderEvent::Opened(r) => {
                    if let Ok(info) = &r {
                        self.info = Some(info.clone());
                    }
                    opened = Some(LoaderEvent::Opened(r));
                }
                f @ LoaderEvent::Frame(_) => frame = Some(f),
                p @ LoaderEvent::Preview(_) => preview = Some(p),
                LoaderEvent::Proxy(s) => {
                    self.proxy = Some(s.clone());
                    proxy = Some(LoaderEvent::Proxy(s));
                }
            }
        }
        opened
            .into_iter()
            .chain(proxy)
            .chain(preview)
            .chain(frame)
            .collect()
    }
}

/// The proxy worker's inputs.
struct ProxyWorker {
    path: PathBuf,
    info: VideoInfo,
    dir: PathBuf,
    requests: Receiver<usize>,
    results: Sender<LoaderEvent>,
    ctx: egui::Context,
    pause: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
}

impl ProxyWorker {
    fn report(&self, s: ProxyStatus) {
        let _ = self.results.send(LoaderEvent::Proxy(s));
        self.ctx.request_repaint();
    }

    /// Opens the proxy or builds it (reporting progress, holding while paused, ending when
    /// stopped), then answers preview requests until the loader goes.
    fn run(self) {
        let Some(mut video) = self.find_or_build() else {
            return;
        };
        self.report(ProxyStatus::Ready);
        while let Ok(mut index) = self.requests.recv() {
            while let Ok(newer) = self.requests.try_recv() {
                index = newer;
            }
            // A preview that fails is simply not shown: the full frame follows anyway.
            if let Ok(frame) = video.frame(index) {
                if self.results.send(LoaderEvent::Preview(frame)).is_err() {
                    break;
                }
                self.ctx.request_repaint();
            }
        }
    }

    fn find_or_build(&self) -> Option<Video> {
        let file = match proxy::proxy_path(&self.dir, &self.path) {
            Ok(f) => f,
            Err(e) => {
                self.report(ProxyStatus::Failed(e.to_string()));
                return None;
            }
        };
        if let Some(v) = proxy::open(&file, &self.info) {
            return Some(v);
        }
        let step = (self.info.frame_count / 200).max(1);
        let built = proxy::build(&self.path, &file, &mut |done, total| {
            while self.pause.load(Ordering::Relaxed) && !self.stop.load(Ordering::Relaxed) {
                std::thread::sleep(PAUSE_POLL);
            }
            if done % step == 0 {
                self.report(ProxyStatus::Building(done, total));
            }
            !self.stop.load(Ordering::Relaxed)
        });
        match built {
            Ok(BuildOutcome::Built) => {}
            Ok(BuildOutcome::Cancelled) => return None,
            Err(e) => {
                self.report(ProxyStatus::Failed(e.to_string()));
                return None;
            }
        }
        proxy::prune(&self.dir, &file, proxy::PROXY_CACHE_BYTES);
        let video = proxy::open(&file, &self.info);
        if video.is_none() {
            self.report(ProxyStatus::Failed(format!(
                "{}: the proxy made does not match the video",
                file.display()
            )));
        }
        video
    }
}

impl Drop for FrameLoader {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        // Closing the channels ends both workers.
        self.requests = None;
        self.previews = None;
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::path::Path;
    use std::time::Instant;
    use videomocap_core::video::{EncodeParams, Mp4Writer};

    /// A 320×240 clip whose only keyframe is its first frame (a long GOP), each frame distinct.
    pub(crate) fn long_gop_clip(path: &Path, frames: usize) {
        let params = EncodeParams {
            fps: 30,
            gop: frames as u32,
            max_b_frames: 2,
            crf: 23,
        };
        let mut w = Mp4Writer::create(path, 320, 240, &params).unwrap();
        for i in 0..frames {
            w.write(&image::RgbImage::from_fn(320, 240, |x, y| {
                image::Rgb([
                    ((x as usize * 2 + i * 6) % 256) as u8,
                    ((y as usize * 3 + i * 2) % 256) as u8,
                    ((x + y) as usize % 256) as u8,
                ])
            }))
            .unwrap();
        }
        w.finish().unwrap();
    }

    /// Polls until `done` says so (or 60 s pass), handing it every event.
    fn poll_until(loader: &mut FrameLoader, mut done: impl FnMut(&LoaderEvent) -> bool) {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(60) {
            for e in loader.poll() {
                if done(&e) {
                    return;
                }
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        panic!("timed out");
    }

    fn proxies(dir: &Path) -> usize {
        std::fs::read_dir(dir).map_or(0, |d| d.count())
    }

    #[test]
    fn a_long_gop_video_gets_a_proxy_and_a_request_brings_its_preview_and_the_full_frame() {
        let dir = tempfile::tempdir().unwrap();
        let clip = dir.path().join("long.mp4");
        long_gop_clip(&clip, 120);
        let cache = dir.path().join("proxies");

        let mut loader =
            FrameLoader::open(clip.clone(), egui::Context::default(), Some(cache.clone()));
        let mut building = 0;
        poll_until(&mut loader, |e| match e {
            LoaderEvent::Proxy(ProxyStatus::Building(..)) => {
                building += 1;
                false
            }
            LoaderEvent::Proxy(s) => {
                assert_eq!(*s, ProxyStatus::Ready);
                true
            }
            _ => false,
        });
        assert!(building > 0, "the first open builds the proxy");
        assert_eq!(proxies(&cache), 1);
        loader.request(90);
        let (mut preview, mut full) = (None, None);
        poll_until(&mut loader, |e| {
            match e {
                LoaderEvent::Preview(f) => preview = Some(f.clone()),
                LoaderEvent::Frame(Ok(f)) => full = Some(f.clone()),
                _ => {}
            }
            preview.is_some() && full.is_some()
        });
        let (preview, full) = (preview.unwrap(), full.unwrap());
        assert_eq!((preview.index, full.index), (90, 90));
        let diff = preview
            .image
            .as_raw()
            .iter()
            .zip(full.image.as_raw())
            .map(|(a, b)| f64::from(a.abs_diff(*b)))
            .sum::<f64>()
            / full.image.as_raw().len() as f64;
        assert!(diff < 8.0, "the preview differs by {diff:.1} on average");
        // A step forward (playing) decodes on: no preview to flicker.
        loader.request(92);
        poll_until(&mut loader, |e| {
            assert!(
                !matches!(e, LoaderEvent::Preview(_)),
                "a preview for a step"
            );
            matches!(e, LoaderEvent::Frame(Ok(f)) if f.index == 92)
        });
        drop(loader);

        // Opened again: the proxy is found, not rebuilt.
        let mut again = FrameLoader::open(clip, egui::Context::default(), Some(cache.clone()));
        poll_until(&mut again, |e| {
            assert!(
                !matches!(e, LoaderEvent::Proxy(ProxyStatus::Building(..))),
                "rebuilt"
            );
            matches!(e, LoaderEvent::Proxy(ProxyStatus::Ready))
        });
    }

    #[test]
    fn a_paused_proxy_build_waits_and_closing_the_video_stops_it_leaving_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let clip = dir.path().join("long.mp4");
        long_gop_clip(&clip, 120);
        let cache = dir.path().join("proxies");
        let mut loader = FrameLoader::open(clip, egui::Context::default(), Some(cache.clone()));
        loader.pause_background(true);
        poll_until(&mut loader, |e| matches!(e, LoaderEvent::Opened(_)));
        std::thread::sleep(Duration::from_millis(500));
        for e in loader.poll() {
            assert!(
                !matches!(e, LoaderEvent::Proxy(ProxyStatus::Ready)),
                "built while paused"
            );
        }
        assert!(loader.proxy() != Some(&ProxyStatus::Ready));
        let t = Instant::now();
        drop(loader);
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "closing waited for the build"
        );
        assert_eq!(proxies(&cache), 0, "a partial proxy was left behind");
    }

    #[test]
    fn short_gop_videos_and_image_folders_get_no_proxy() {
        let dir = tempfile::tempdir().unwrap();
        for i in 0..3 {
            image::RgbImage::new(8, 6)
                .save(dir.path().join(format!("f{i}.png")))
                .unwrap();
        }
        let cache = dir.path().join("proxies");
        let mut loader = FrameLoader::open(
            dir.path().to_owned(),
            egui::Context::default(),
            Some(cache.clone()),
        );
        loader.request(2);
        poll_until(&mut loader, |e| matches!(e, LoaderEvent::Frame(Ok(_))));
        assert_eq!(loader.proxy(), None);
        drop(loader);
        assert!(!cache.exists());
    }
}
