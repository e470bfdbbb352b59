//! Frame-accurate random access: on a 300-frame H.264 clip with a 250-frame GOP and B-frames,
//! `frame(i)` in any order equals the i-th frame of a sequential decode.

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic
#![cfg(feature = "ffmpeg")]

use image::{Rgb, RgbImage};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use std::path::Path;
use videomocap_core::video::proxy::{self, BuildOutcome};
use videomocap_core::video::{EncodeParams, Mp4Writer, OpenOptions, Video};

/// A frame whose content changes with `i` everywhere (moving gradient plus a counter bar).
fn test_frame(i: usize, w: u32, h: u32) -> RgbImage {
    RgbImage::from_fn(w, h, |x, y| {
        let bar = (x as usize) < (i * w as usize) / 300 && y < 8;
        if bar {
            Rgb([255, 255, 255])
        } else {
            Rgb([
                ((x as usize * 3 + i * 5) % 256) as u8,
                ((y as usize * 4 + i * 3) % 256) as u8,
                ((x as usize + y as usize + i * 7) % 256) as u8,
            ])
        }
    })
}

fn make_clip(path: &Path, frames: usize) {
    make_clip_sized(path, frames, 160, 120);
}

fn make_clip_sized(path: &Path, frames: usize, width: u32, height: u32) {
    let params = EncodeParams {
        fps: 30,
        gop: 250,
        max_b_frames: 3,
        crf: 23,
    };
    let mut w = Mp4Writer::create(path, width, height, &params).unwrap();
    for i in 0..frames {
        w.write(&test_frame(i, width, height)).unwrap();
    }
    w.finish().unwrap();
}

fn mean_abs_diff(a: &RgbImage, b: &RgbImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    a.as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>()
        / a.as_raw().len() as f64
}

fn no_cache() -> OpenOptions {
    OpenOptions {
        cache_bytes: 0,
        ..OpenOptions::default()
    }
}

#[test]
fn random_access_equals_sequential_decoding_on_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("gop250.mp4");
    make_clip(&path, 300);

    let mut seq = Video::open(&path, &no_cache()).unwrap();
    assert_eq!(seq.info().frame_count, 300);
    assert!((seq.info().fps - 30.0).abs() < 1e-9);
    let sequential: Vec<RgbImage> = (0..300)
        .map(|i| (*seq.frame(i).unwrap().image).clone())
        .collect();
    // The decode follows the source: frame i is closest to test_frame(i) among its neighbours.
    for i in [0usize, 1, 2, 149, 250, 251, 299] {
        let err = |j: usize| -> u64 {
            let t = test_frame(j, 160, 120);
            sequential[i]
                .as_raw()
                .iter()
                .zip(t.as_raw())
                .map(|(a, b)| u64::from(a.abs_diff(*b)))
                .sum()
        };
        let lo = i.saturating_sub(1);
        let hi = (i + 1).min(299);
        assert!(
            err(i) <= err(lo) && err(i) <= err(hi),
            "frame {i} is not in its place"
        );
    }

    let mut order: Vec<usize> = (0..300).collect();
    order.shuffle(&mut rand::rngs::StdRng::seed_from_u64(42));
    let mut random = Video::open(&path, &no_cache()).unwrap();
    for &i in &order {
        let f = random.frame(i).unwrap();
        assert_eq!(f.index, i);
        assert!(
            *f.image == sequential[i],
            "frame {i} differs between random and sequential access"
        );
        assert!(
            (f.time_s - i as f64 / 30.0).abs() < 1e-6,
            "frame {i} time {}",
            f.time_s
        );
    }
    // Backwards, one by one: the worst case for a decoder that only goes forwards.
    for i in (240..260).rev() {
        assert!(
            *random.frame(i).unwrap().image == sequential[i],
            "frame {i} backwards"
        );
    }
}

#[test]
fn the_real_sample_is_portrait_60_fps_100_frames() {
    let path =
        videomocap_testkit::repo_root().join("sample_videos/pose2sim_balancing_cam01/video.mp4");
    let mut v = Video::open(&path, &OpenOptions::default()).unwrap();
    let info = v.info().clone();
    assert_eq!(
        (info.width, info.height, info.frame_count),
        (1080, 1920, 100)
    );
    assert!((info.fps - 60.0).abs() < 1e-9);
    let last = v.frame(99).unwrap();
    assert_eq!(last.image.dimensions(), (1080, 1920));
    assert!(v.frame(100).is_err());
}

#[test]
fn display_rotation_is_applied_as_ffmpeg_itself_applies_it() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.mp4");
    let mut w = Mp4Writer::create(&plain, 64, 32, &EncodeParams::default()).unwrap();
    for _ in 0..5 {
        // Left half dark, right half bright, a grey stripe at the top.
        w.write(&RgbImage::from_fn(64, 32, |x, y| match (x < 32, y < 6) {
            (_, true) => Rgb([128, 128, 128]),
            (true, false) => Rgb([20, 20, 20]),
            (false, false) => Rgb([230, 230, 230]),
        }))
        .unwrap();
    }
    w.finish().unwrap();
    let ffmpeg = |args: &[&str]| {
        let status = std::process::Command::new("ffmpeg")
            .args(["-loglevel", "error", "-y"])
            .args(args)
            .status()
            .expect("the ffmpeg command is needed for this test (scripts/setup.sh installs it)");
        assert!(status.success(), "ffmpeg {args:?}");
    };
    for rotate in ["90", "180", "270"] {
        let rotated = dir.path().join(format!("rotated{rotate}.mp4"));
        let reference = dir.path().join(format!("reference{rotate}.png"));
        let (p, r, f) = (
            plain.to_str().unwrap(),
            rotated.to_str().unwrap(),
            reference.to_str().unwrap(),
        );
        ffmpeg(&[
            "-i",
            p,
            "-c",
            "copy",
            "-metadata:s:v:0",
            &format!("rotate={rotate}"),
            r,
        ]);
        // FFmpeg's own autorotation is the reference for what "displayed" means.
        ffmpeg(&["-i", r, "-frames:v", "1", f]);
        let expected = image::open(&reference).unwrap().to_rgb8();
        let mut v = Video::open(&rotated, &OpenOptions::default()).unwrap();
        assert_ne!(v.info().rotation_deg, 0, "rotate={rotate}");
        assert_eq!(
            (v.info().width, v.info().height),
            expected.dimensions(),
            "rotate={rotate}"
        );
        let ours = v.frame(0).unwrap().image;
        let mean_diff = ours
            .as_raw()
            .iter()
            .zip(expected.as_raw())
            .map(|(a, b)| f64::from(a.abs_diff(*b)))
            .sum::<f64>()
            / ours.as_raw().len() as f64;
        assert!(
            mean_diff < 6.0,
            "rotate={rotate}: mean difference {mean_diff} from ffmpeg's own"
        );
        // The seek proxy is made from the displayed frames: turned the same way.
        let out = dir.path().join(format!("proxy{rotate}.mp4"));
        proxy::build(&rotated, &out, &mut |_, _| true).unwrap();
        let mut p = proxy::open(&out, v.info()).expect("the proxy opens");
        let shown = p.frame(0).unwrap().image;
        let proxy_diff = mean_abs_diff(&shown, &expected);
        assert!(
            proxy_diff < 8.0,
            "rotate={rotate}: proxy differs by {proxy_diff} from ffmpeg's own"
        );
    }
}

#[test]
fn a_seek_proxy_shows_every_frame_in_its_place_from_short_gops() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("wide gop250.mp4");
    // Wider than the proxy's limit, so the proxy is shrunk.
    make_clip_sized(&path, 300, 1200, 160);
    let mut video = Video::open(&path, &no_cache()).unwrap();
    let info = video.info().clone();
    // Keyframes at 0 and 250: the longest run is 250 frames.
    assert_eq!(info.keyframe_interval, 250);
    assert!(proxy::wants_proxy(&info));

    let cache = dir.path().join("proxies");
    let out = proxy::proxy_path(&cache, &path).unwrap();
    let mut calls = Vec::new();
    let outcome = proxy::build(&path, &out, &mut |done, total| {
        calls.push((done, total));
        true
    })
    .unwrap();
    assert_eq!(outcome, BuildOutcome::Built);
    assert_eq!(calls.first(), Some(&(0, 300)));
    assert_eq!(calls.last(), Some(&(300, 300)));
    let mut p = proxy::open(&out, &info).expect("the proxy opens");
    assert_eq!(p.info().frame_count, 300);
    assert_eq!((p.info().width, p.info().height), (960, 128));
    assert!(p.info().keyframe_interval <= proxy::PROXY_GOP as usize);
    assert!(!proxy::wants_proxy(p.info()));
    for i in [0usize, 1, 77, 249, 250, 251, 299] {
        let shown = p.frame(i).unwrap().image;
        let mut small = |j: usize| video_frame_small(&mut video, j);
        let here = mean_abs_diff(&shown, &small(i));
        assert!(
            here < 8.0,
            "frame {i}: proxy differs by {here:.1} on average"
        );
        for j in [i.saturating_sub(1), (i + 1).min(299)] {
            if j != i {
                assert!(
                    here < mean_abs_diff(&shown, &small(j)),
                    "proxy frame {i} looks more like frame {j}"
                );
            }
        }
    }
}

/// Frame `j` of `video` shrunk to the proxy's size.
fn video_frame_small(video: &mut Video, j: usize) -> RgbImage {
    let (w, h) = proxy::proxy_size(video.info().width, video.info().height);
    image::imageops::resize(
        &*video.frame(j).unwrap().image,
        w,
        h,
        image::imageops::FilterType::Triangle,
    )
}

#[test]
fn a_cancelled_proxy_leaves_nothing_and_a_proxy_that_does_not_fit_is_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("gop250.mp4");
    make_clip(&path, 300);
    let cache = dir.path().join("proxies");
    let out = proxy::proxy_path(&cache, &path).unwrap();
    let outcome = proxy::build(&path, &out, &mut |done, _| done < 40).unwrap();
    assert_eq!(outcome, BuildOutcome::Cancelled);
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(&cache).unwrap().count(),
        0,
        "partial file left"
    );

    assert_eq!(
        proxy::build(&path, &out, &mut |_, _| true).unwrap(),
        BuildOutcome::Built
    );
    let mut info = Video::open(&path, &no_cache()).unwrap().info().clone();
    assert!(proxy::open(&out, &info).is_some());
    // A proxy of another length (say, of the file before it was re-encoded) is not used.
    info.frame_count = 299;
    assert!(proxy::open(&out, &info).is_none());
    assert!(!out.exists(), "the proxy that did not fit was not removed");
    // A cache folder that cannot be made is an error naming the proxy, not a panic.
    let unwritable = Path::new("/proc/videomocap-no-such-dir/proxy.mp4");
    let err = proxy::build(&path, unwritable, &mut |_, _| true).unwrap_err();
    assert!(err.to_string().contains("proxy.mp4"), "{err}");
    // A video that is not one gives the usual error, naming it.
    let bad = dir.path().join("notes.txt");
    std::fs::write(&bad, "not a video").unwrap();
    let err = proxy::build(&bad, &cache.join("x.mp4"), &mut |_, _| true).unwrap_err();
    assert!(err.to_string().contains("notes.txt"), "{err}");
}

#[test]
fn a_video_can_deliver_shrunk_frames_and_full_ones_again() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("clip.mp4");
    make_clip_sized(&path, 12, 320, 240);
    let mut video = Video::open(&path, &OpenOptions::default()).unwrap();
    let full = video.frame(5).unwrap().image;
    assert!(video.output_size(Some((160, 120))));
    assert_eq!((video.info().width, video.info().height), (160, 120));
    let small = video.frame(5).unwrap().image;
    assert_eq!(small.dimensions(), (160, 120));
    // The same picture as shrinking the full frame (the cache did not hand back the old size).
    let reference = image::imageops::thumbnail(&*full, 160, 120);
    let diff = mean_abs_diff(&small, &reference);
    assert!(diff < 12.0, "{diff}");
    assert!(video.output_size(None));
    assert_eq!(video.frame(5).unwrap().image.dimensions(), (320, 240));
    assert_eq!(video.frame(11).unwrap().image.dimensions(), (320, 240));
}
