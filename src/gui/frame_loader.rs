//! Opens and decodes the video on a worker thread so the UI never waits for FFmpeg (opening an
//! hour-long file reads its whole packet index). The UI sends the index it wants; the worker
//! skips stale requests (only the latest matters while scrubbing) and sends back decoded frames,
//! asking egui to repaint.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;
use videomocap::video::{Frame, OpenOptions, Video, VideoError, VideoInfo};

/// What the worker reports.
pub enum LoaderEvent {
    /// The video opened (or could not be).
    Opened(Result<VideoInfo, VideoError>),
    /// A decoded frame or the error decoding it.
    Frame(Result<Frame, VideoError>),
}

/// The UI side of the worker.
pub struct FrameLoader {
    requests: Option<Sender<usize>>,
    results: Receiver<LoaderEvent>,
    worker: Option<JoinHandle<()>>,
    info: Option<VideoInfo>,
}

impl FrameLoader {
    /// Opens `path` on a new worker thread; [`FrameLoader::poll`] reports when it is open.
    pub fn open(path: PathBuf, ctx: egui::Context) -> FrameLoader {
        let (req_tx, req_rx) = channel::<usize>();
        let (res_tx, res_rx) = channel::<LoaderEvent>();
        let worker_path = path;
        let worker = std::thread::Builder::new()
            .name("frame-loader".into())
            .spawn(move || {
                let opened = Video::open(&worker_path, &OpenOptions::default());
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
                if res_tx.send(LoaderEvent::Opened(Ok(info))).is_err() {
                    return;
                }
                ctx.request_repaint();
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
            })
            .ok();
        FrameLoader {
            requests: Some(req_tx),
            results: res_rx,
            worker,
            info: None,
        }
    }

    /// Metadata of the video, once open.
    pub fn info(&self) -> Option<&VideoInfo> {
        self.info.as_ref()
    }

    /// Asks for a frame (answered later through [`FrameLoader::poll`]).
    pub fn request(&self, index: usize) {
        if let Some(tx) = &self.requests {
            let _ = tx.send(index);
        }
    }

    /// What arrived since the last call: the open result (first) and the newest frame.
    pub fn poll(&mut self) -> Vec<LoaderEvent> {
        let mut opened = None;
        let mut frame = None;
        while let Ok(event) = self.results.try_recv() {
            match event {
                LoaderEvent::Opened(r) => {
                    if let Ok(info) = &r {
                        self.info = Some(info.clone());
                    }
                    opened = Some(LoaderEvent::Opened(r));
                }
                f @ LoaderEvent::Frame(_) => frame = Some(f),
            }
        }
        opened.into_iter().chain(frame).collect()
    }
}

impl Drop for FrameLoader {
    fn drop(&mut self) {
        self.requests = None; // closes the channel: the worker ends
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}
