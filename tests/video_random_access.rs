//! Frame-accurate random access: on a 300-frame H.264 clip with a 250-frame GOP and B-frames,
//! `frame(i)` in any order equals the i-th frame of a sequential decode.

#![cfg(feature = "ffmpeg")]

use image::{Rgb, RgbImage};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use std::path::Path;
use videomocap::video::{EncodeParams, Mp4Writer, OpenOptions, Video};

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
    let params = EncodeParams {
        fps: 30,
        gop: 250,
        max_b_frames: 3,
        crf: 23,
    };
    let mut w = Mp4Writer::create(path, 160, 120, &params).unwrap();
    for i in 0..frames {
        w.write(&test_frame(i, 160, 120)).unwrap();
    }
    w.finish().unwrap();
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
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sample_videos/pose2sim_balancing_cam01/video.mp4");
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
    }
}
