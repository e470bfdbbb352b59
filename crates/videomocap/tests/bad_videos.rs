//! The bad-video corpus (`scripts/bad_videos.sh`: truncated, zeroed, wrong extension, audio
//! only, 1×1, odd sizes, 0 frames, variable frame rate, rotated, 10-bit, other codecs): every
//! file either opens and tracks, or gives a clear error naming it with exit code 1 or 2. None
//! panics or hangs. Prints the table (`cargo test --test bad_videos -- --nocapture`).

#![allow(clippy::unwrap_used)] // a test's unwrap is its failure, named by the panic
#![cfg(feature = "ffmpeg")]

use assert_cmd::Command;
use std::path::Path;
use std::time::Duration;
use videomocap_core::formats::{Marks, Tracks2d};

/// Longest a command may take on a one-second clip before it counts as a hang.
const HANG: Duration = Duration::from_secs(120);

struct Outcome {
    code: i32,
    first_line: String,
    stdout: String,
}

fn run(args: &[&str], file: &str) -> Outcome {
    let out = Command::cargo_bin("videomocap")
        .unwrap()
        .args(args)
        .timeout(HANG)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    let code = out.status.code().unwrap_or(-1);
    assert!(code != -1, "{args:?} hung (killed after {HANG:?})");
    assert!(
        [0, 1, 2].contains(&code),
        "{args:?}: exit code {code}: {stderr}"
    );
    if code != 0 {
        assert!(
            stderr.contains(file),
            "{args:?}: the error does not name {file}: {stderr}"
        );
    }
    let first_line = if code == 0 { &stdout } else { &stderr }
        .lines()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .to_owned();
    Outcome {
        code,
        first_line,
        stdout: stdout.into_owned(),
    }
}

/// The synthetic sample's marks (640×480) scaled into a `w`×`h` frame.
fn marks_for(w: f64, h: f64, out: &Path) {
    let sample =
        videomocap_testkit::repo_root().join("sample_videos/synth_walk_oblique/marks.json");
    let mut marks = Marks::load(&sample).unwrap();
    for p in marks.points.0.iter_mut() {
        p.x = p.x * (w - 1.0) / 639.0;
        p.y = p.y * (h - 1.0) / 479.0;
    }
    marks.save(out).unwrap();
}

/// (width, height, frames) from `info`'s output.
fn size_of(info: &str) -> Option<(f64, f64, usize)> {
    let field = |name: &str| {
        info.lines()
            .find(|l| l.starts_with(name))
            .map(|l| l[name.len()..].trim().to_owned())
    };
    let size = field("size:")?;
    let (w, rest) = size.split_once('×')?;
    let h = rest.split_whitespace().next()?;
    let frames = field("frames:")?.parse().ok()?;
    Some((w.parse().ok()?, h.parse().ok()?, frames))
}

#[test]
fn every_bad_video_opens_and_tracks_or_is_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let script = videomocap_testkit::repo_root().join("scripts/bad_videos.sh");
    let made = std::process::Command::new("bash")
        .arg(&script)
        .arg(dir.path())
        .output()
        .expect("bash runs scripts/bad_videos.sh (needs the ffmpeg command)");
    assert!(
        made.status.success(),
        "scripts/bad_videos.sh failed: {}",
        String::from_utf8_lossy(&made.stderr)
    );
    let mut files: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(files.len() >= 20, "corpus has {} files", files.len());

    let work = tempfile::tempdir().unwrap();
    let mut table = Vec::new();
    let (mut tracked, mut refused) = (0, 0);
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let path = file.to_str().unwrap();
        let info = run(&["info", path], &name);
        let mut frames = 0;
        let track = if info.code == 0 {
            let (w, h, n) =
                size_of(&info.stdout).unwrap_or_else(|| panic!("info of {name} has no size"));
            frames = n;
            let marks = work.path().join(format!("{name}.marks.json"));
            marks_for(w, h, &marks);
            let tracks = work.path().join(format!("{name}.tracks2d.json"));
            let t = run(
                &[
                    "track",
                    path,
                    "--marks",
                    marks.to_str().unwrap(),
                    "-o",
                    tracks.to_str().unwrap(),
                    "-q",
                ],
                &name,
            );
            assert_eq!(
                t.code == 0,
                SHOULD_TRACK.contains(&name.as_str()),
                "{name}: track exit {}",
                t.code
            );
            if t.code == 0 {
                let read = Tracks2d::load(&tracks).unwrap();
                assert_eq!(read.source.frame_count, frames, "{name}");
                assert_eq!(read.frames.len(), frames, "{name}");
                tracked += 1;
            } else {
                refused += 1;
            }
            Some(t)
        } else {
            assert!(
                !SHOULD_TRACK.contains(&name.as_str()),
                "{name} does not open: {}",
                info.first_line
            );
            refused += 1;
            None
        };
        let cell = |o: &Outcome| match o.code {
            0 => "ok".to_owned(),
            c => format!("exit {c}: {}", o.first_line),
        };
        table.push(format!(
            "| {name} | {} | {} |",
            if info.code == 0 {
                size_of(&info.stdout).map_or(String::new(), |(w, h, n)| {
                    format!("opens: {w}×{h}, {n} frames")
                })
            } else {
                cell(&info)
            },
            track.as_ref().map_or("—".to_owned(), |t| if t.code == 0 {
                format!("tracked all {frames} frames")
            } else {
                cell(t)
            })
        ));
    }
    println!("| file | info | track |\n|---|---|---|");
    for row in &table {
        println!("{row}");
    }
    println!("{tracked} tracked, {refused} refused with a clear error, 0 panics, 0 hangs");
    assert_eq!(tracked, SHOULD_TRACK.len());
}

/// The files that must open and track; the rest must be refused with a clear error. A file
/// damaged in the middle or cut short after its index tracks: its unreadable frames count as
/// lost and are filled like occlusions.
const SHOULD_TRACK: [&str; 14] = [
    "faststart.mp4",
    "good.mp4",
    "h264_10bit.mp4",
    "hevc_10bit.mp4",
    "mjpeg.avi",
    "odd_321x241.mp4",
    "one_pixel.mp4",
    "rotated_90.mp4",
    "tiny_17x9.mp4",
    "truncated_60pct_faststart.mp4",
    "vfr.mp4",
    "vp9.webm",
    "wrong_extension.avi",
    "zeroed_middle.mp4",
];
