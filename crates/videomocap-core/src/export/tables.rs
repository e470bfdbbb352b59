//! Tables: the 2D tracks and the 3D joints as CSV (one row per joint per frame, so every
//! spreadsheet and data-frame library reads them without reshaping), and the 3D joints as an
//! OpenSim marker file (`.trc`, tab-separated, one row per frame).
//!
//! Joints off the frame or lost are estimates: both CSVs say so in `off_frame` and `lost`
//! columns, and the TRC leaves their cells empty (OpenSim's missing marker), so inverse
//! kinematics ignores them.

use super::WorldSkeleton;
use crate::formats::{PointSource, Tracks2d};
use crate::skeleton::Joint;
use std::fmt::Write as _;

/// Tracks CSV: `frame,time_s,joint,x_px,y_px,confidence,interpolated,off_frame,lost`
/// (pixels, y down; time from the video's frame rate; `interpolated` is 1 for points filled in
/// across an occlusion, `off_frame` 1 for the tracker's estimate of a joint outside the image,
/// `lost` 1 for its guess in a weak run too long to fill).
pub fn tracks_csv(tracks: &Tracks2d) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let header = [
        "frame",
        "time_s",
        "joint",
        "x_px",
        "y_px",
        "confidence",
        "interpolated",
        "off_frame",
        "lost",
    ];
    let _ = w.write_record(header);
    for f in &tracks.frames {
        let time = f.index.seconds(tracks.source.fps);
        for j in Joint::ALL {
            let p = f.points[j];
            let flag = |b: bool| if b { "1" } else { "0" }.to_owned();
            let _ = w.write_record([
                f.index.to_string(),
                format!("{time:.6}"),
                j.name().to_owned(),
                format!("{:.3}", p.pos.x),
                format!("{:.3}", p.pos.y),
                format!("{:.3}", p.confidence),
                flag(p.source == PointSource::Interpolated),
                flag(p.source == PointSource::OffFrame),
                flag(p.source == PointSource::Lost),
            ]);
        }
    }
    finish(w)
}

/// 3D CSV: `frame,time_s,joint,x_m,y_m,z_m,off_frame,lost,contact` in the exports' Y-up world
/// (metres); `off_frame` or `lost` is 1 where the joint's 2D track was off the frame or lost
/// (an estimate); `contact` is 1 on an ankle the lift found planted on the floor.
pub fn skeleton_csv(skeleton: &WorldSkeleton) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record([
        "frame",
        "time_s",
        "joint",
        "x_m",
        "y_m",
        "z_m",
        "off_frame",
        "lost",
        "contact",
    ]);
    let flag = |b: bool| if b { "1" } else { "0" }.to_owned();
    for (k, p) in skeleton.frames.iter().enumerate() {
        for j in Joint::ALL {
            let _ = w.write_record([
                skeleton.indices[k].to_string(),
                format!("{:.6}", skeleton.time_s(k)),
                j.name().to_owned(),
                format!("{:.5}", p[j].x),
                format!("{:.5}", p[j].y),
                format!("{:.5}", p[j].z),
                flag(skeleton.off_frame[k][j]),
                flag(skeleton.lost[k][j]),
                flag(skeleton.contact[k][j]),
            ]);
        }
    }
    finish(w)
}

fn finish(w: csv::Writer<Vec<u8>>) -> String {
    // Writing to a Vec<u8> cannot fail and every field is UTF-8.
    w.into_inner()
        .map(|bytes| String::from_utf8_lossy(&bytes).into_owned())
        .unwrap_or_default()
}

/// OpenSim TRC (marker trajectories, `PathFileType 4`): the 16 joints as markers named like the
/// joints, metres, Y up, frames numbered from 1 with times from the video's start. A joint off
/// the frame or lost leaves its three cells empty (a missing marker).
pub fn trc(skeleton: &WorldSkeleton, file_name: &str) -> String {
    let n = skeleton.frames.len();
    let rate = skeleton.fps;
    let mut out = String::new();
    let _ = writeln!(out, "PathFileType\t4\t(X/Y/Z)\t{file_name}");
    let _ = writeln!(
        out,
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames"
    );
    let first = skeleton.indices.first().map_or(1, |i| i.get() + 1);
    let _ = writeln!(
        out,
        "{rate:.4}\t{rate:.4}\t{n}\t{}\tm\t{rate:.4}\t{first}\t{n}",
        Joint::ALL.len()
    );
    let names: Vec<String> = Joint::ALL
        .iter()
        .map(|j| format!("{}\t\t", j.name()))
        .collect();
    let _ = writeln!(out, "Frame#\tTime\t{}", names.concat().trim_end());
    let axes: Vec<String> = (1..=Joint::ALL.len())
        .map(|k| format!("X{k}\tY{k}\tZ{k}"))
        .collect();
    let _ = writeln!(out, "\t\t{}", axes.join("\t"));
    let _ = writeln!(out);
    for (k, p) in skeleton.frames.iter().enumerate() {
        let _ = write!(out, "{}\t{:.6}", k + 1, skeleton.time_s(k));
        for j in Joint::ALL {
            if skeleton.off_frame[k][j] || skeleton.lost[k][j] {
                out.push_str("\t\t\t");
            } else {
                let _ = write!(out, "\t{:.5}\t{:.5}\t{:.5}", p[j].x, p[j].y, p[j].z);
            }
        }
        out.push('\n');
    }
    out
}
