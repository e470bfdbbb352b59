//! Decodes frames on a worker thread so the UI never waits for FFmpeg. The UI sends the index
//! it wants; the worker skips stale requests (only the latest matters while scrubbing) and sends
//! back decoded frames, asking egui to repaint.

use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;
use videomocap::video::{Frame, Video, VideoError, VideoInfo};

/// A frame or the error decoding it.
pub type Loaded = Result<Frame, VideoError>;

/// The UI side of the worker.
pub struct FrameLoader {
    requests: Option<Sender<usize>>,
    results: Receiver<Loaded>,
    worker: Option<JoinHandle<()>>,
    info: VideoInfo,
}

impl FrameLoader {
    /// Moves the video to a new worker thread.
    pub fn spawn(mut video: Video, ctx: egui::Context) -> FrameLoader {
        let info = video.info().clone();
        let (req_tx, req_rx) = channel::<usize>();
        let (res_tx, res_rx) = channel::<Loaded>();
        let worker = std::thread::Builder::new()
            .name("frame-loader".into())
            .spawn(move || {
                while let Ok(mut index) = req_rx.recv() {
                    // Only the newest request matters.
                    while let Ok(newer) = req_rx.try_recv() {
                        index = newer;
                    }
                    let result = video.frame(index);
                    if res_tx.send(result).is_err() {
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
            info,
        }
    }

    /// Metadata of the video.
    pub fn info(&self) -> &VideoInfo {
        &self.info
    }

    /// Asks for a frame (answered later through [`FrameLoader::poll`]).
    pub fn request(&self, index: usize) {
        if let Some(tx) = &self.requests {
            let _ = tx.send(index);
        }
    }

    /// The newest finished frame, if any arrived since the last call.
    pub fn poll(&self) -> Option<Loaded> {
        let mut last = None;
        while let Ok(r) = self.results.try_recv() {
            last = Some(r);
        }
        last
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
