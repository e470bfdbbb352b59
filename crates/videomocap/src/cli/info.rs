//! `videomocap info VIDEO`: what the video is.

use super::ExitError;
use super::args::GlobalArgs;
use std::path::Path;
use videomocap_core::video::{OpenOptions, Video};

pub(super) fn run(path: &Path, global: &GlobalArgs) -> Result<(), ExitError> {
    let video = Video::open(path, &OpenOptions::default()).map_err(ExitError::bad_input)?;
    let info = video.info();
    if global.json {
        let text = serde_json::to_string_pretty(info).map_err(ExitError::failed)?;
        println!("{text}");
        return Ok(());
    }
    println!("file:        {}", info.path.display());
    println!(
        "size:        {}×{} ({})",
        info.width,
        info.height,
        orientation(info.width, info.height)
    );
    println!(
        "frame rate:  {:.3} fps{}",
        info.fps,
        if info.variable_frame_rate {
            " (variable)"
        } else {
            ""
        }
    );
    println!("frames:      {}", info.frame_count);
    println!("duration:    {:.3} s", info.duration_s);
    println!("rotation:    {}°", info.rotation_deg);
    println!("codec:       {}", info.codec);
    println!(
        "keyframes:   at most {} frames apart{}",
        info.keyframe_interval,
        if videomocap_core::video::proxy::wants_proxy(info) {
            " (the app makes a seek proxy)"
        } else {
            ""
        }
    );
    Ok(())
}

fn orientation(w: u32, h: u32) -> &'static str {
    match w.cmp(&h) {
        std::cmp::Ordering::Less => "portrait",
        std::cmp::Ordering::Greater => "landscape",
        std::cmp::Ordering::Equal => "square",
    }
}
