//! Exports of a reconstruction: BVH (with the local frames and joint angles of Chu et al. §4),
//! CSV of the 2D tracks and of the 3D joints, and OpenSim's TRC. Camera space is first turned
//! into a Y-up world ([`world`]); every file here is in that world.
//!
//! The BVH reader lives in [`crate::bvh`]; [`bvh`] reads its own output back with it and
//! reports how far forward kinematics lands from the input.

mod bvh_writer;
mod euler;
pub mod kinematics;
pub mod rig;
mod tables;
pub mod world;

pub use bvh_writer::{BVH_UNITS_PER_METRE, ROTATION_CHANNELS, bvh_text};
pub use euler::zxy_degrees;
pub use rig::RigNames;
pub use tables::{skeleton_csv, tracks_csv, trc};
pub use world::{FloorSource, UpSource, WorldFrame};

use crate::formats::{
    CONTACT_FLAG, FormatError, FrameIndex, LOST_FLAG, OFF_FRAME_FLAG, Skeleton3d, write_atomically,
};
use crate::skeleton::{Joint, PerJoint};
use nalgebra::Point3;
use std::path::{Path, PathBuf};

/// Why an export could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("the skeleton has no frames")]
    NoFrames,
    #[error(
        "the skeleton does not record its frame rate (written by an older version); give it with --fps"
    )]
    NoFps,
    #[error("frame rate {0} is not a positive number")]
    BadFps(f64),
    #[error("bone {0} has zero length in most frames")]
    ZeroBone(String),
    #[error(
        "frames are not consecutive (frame {next} follows frame {previous}); BVH needs one pose per frame"
    )]
    Gap {
        previous: FrameIndex,
        next: FrameIndex,
    },
    #[error(transparent)]
    Write(#[from] FormatError),
}

/// A skeleton sequence moved into the exports' world: the frame indices, their times and the
/// world-space joints (metres, Y up).
#[derive(Debug, Clone, PartialEq)]
pub struct WorldSkeleton {
    /// The map from camera space.
    pub world: WorldFrame,
    /// Frames per second of the source.
    pub fps: f64,
    /// Frame indices in the video.
    pub indices: Vec<FrameIndex>,
    /// Joints per frame, world metres.
    pub frames: Vec<PerJoint<Point3<f64>>>,
    /// Per frame, the joints whose 2D track was off the frame (from the `off_frame:` flags):
    /// estimates, written as gaps where a format has them (TRC) and flagged in the CSV.
    pub off_frame: Vec<PerJoint<bool>>,
    /// Per frame, the joints whose 2D track was lost (from the `lost:` flags): guesses,
    /// handled like `off_frame`.
    pub lost: Vec<PerJoint<bool>>,
    /// Per frame, the ankles the lift found planted on the floor (from the `contact:` flags).
    pub contact: Vec<PerJoint<bool>>,
}

impl WorldSkeleton {
    /// Moves a skeleton3d into the world of [`WorldFrame::estimate`]; `fps` overrides (or
    /// supplies) the skeleton's frame rate.
    pub fn new(skeleton: &Skeleton3d, fps: Option<f64>) -> Result<WorldSkeleton, ExportError> {
        let fps = fps.or(skeleton.fps).ok_or(ExportError::NoFps)?;
        if !(fps.is_finite() && fps > 0.0) {
            return Err(ExportError::BadFps(fps));
        }
        let camera: Vec<PerJoint<Point3<f64>>> = skeleton.frames.iter().map(|f| f.points).collect();
        let contact: Vec<PerJoint<bool>> = skeleton
            .frames
            .iter()
            .map(|f| f.joint_flags(CONTACT_FLAG))
            .collect();
        let world = WorldFrame::estimate(&camera, &contact)?;
        let frames = camera
            .iter()
            .map(|p| p.map(|_, q| world.to_world(q)))
            .collect();
        Ok(WorldSkeleton {
            world,
            fps,
            indices: skeleton.frames.iter().map(|f| f.index).collect(),
            frames,
            off_frame: skeleton
                .frames
                .iter()
                .map(|f| f.joint_flags(OFF_FRAME_FLAG))
                .collect(),
            lost: skeleton
                .frames
                .iter()
                .map(|f| f.joint_flags(LOST_FLAG))
                .collect(),
            contact,
        })
    }

    /// Time of the `k`-th frame, seconds from the video's start.
    pub fn time_s(&self, k: usize) -> f64 {
        self.indices[k].seconds(self.fps)
    }
}

/// A BVH ready to save, with what checking it found.
#[derive(Debug, Clone)]
pub struct BvhExport {
    /// The file's text.
    pub text: String,
    /// Number of frames.
    pub frames: usize,
    /// Largest distance, over all joints and frames, between the input and forward kinematics
    /// of the written file as read back by [`crate::bvh::Bvh`] (metres). Zero up to rounding
    /// when the bone lengths are constant; otherwise about their variation.
    pub max_round_trip_m: f64,
    /// Largest change of any Euler angle between neighbouring frames, degrees.
    pub max_angle_step_deg: f64,
}

/// Builds the BVH of a world skeleton with the bone names of `names` and checks it by reading
/// it back.
pub fn bvh(skeleton: &WorldSkeleton, names: RigNames) -> Result<BvhExport, ExportError> {
    for w in skeleton.indices.windows(2) {
        if w[1] != w[0] + 1 {
            return Err(ExportError::Gap {
                previous: w[0],
                next: w[1],
            });
        }
    }
    let motion = kinematics::solve(&skeleton.frames, 1.0 / skeleton.fps)?;
    let (text, angles) = bvh_text(&motion, names);
    let max_angle_step_deg = angles
        .windows(2)
        .flat_map(|w| {
            w[0].iter()
                .zip(&w[1])
                .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        })
        .fold(0.0, f64::max);
    let max_round_trip_m = round_trip_error(&text, &skeleton.frames);
    Ok(BvhExport {
        text,
        frames: skeleton.frames.len(),
        max_round_trip_m,
        max_angle_step_deg,
    })
}

/// Reads BVH text with [`crate::bvh::Bvh`] and returns the largest distance between its forward
/// kinematics (converted to metres) and `frames`; infinite when the text does not read back.
pub fn round_trip_error(text: &str, frames: &[PerJoint<Point3<f64>>]) -> f64 {
    let Ok(read) = crate::bvh::Bvh::parse(text, Path::new("<written BVH>")) else {
        return f64::INFINITY;
    };
    if read.frame_count() != frames.len() {
        return f64::INFINITY;
    }
    let mut worst: f64 = 0.0;
    for (f, truth) in frames.iter().enumerate() {
        let got = read.positions(f);
        for j in Joint::ALL {
            let p = got[rig::rig_index_of(j)] / BVH_UNITS_PER_METRE;
            worst = worst.max((p - truth[j]).norm());
        }
    }
    worst
}

/// Writes `text` to `path` atomically.
pub fn save_text(path: &Path, text: &str) -> Result<PathBuf, ExportError> {
    write_atomically(path, text.as_bytes())?;
    Ok(path.to_owned())
}
