//! videomocap's stages: single-camera video motion capture.
//!
//! Data flows one way: [`video`] (frame sources) → [`track`] (2D: marks → tracks) → [`lift`]
//! (calibration, 3D skeleton) → [`export`] (BVH, CSV, TRC), with [`skeleton`] (joints, bones,
//! proportions), [`camera`], [`formats`] (the versioned files) and [`bvh`] (the BVH reader)
//! shared by all, and [`project`] (a user's saved work). [`network`] runs the pose network
//! whose joints the tracker weighs as evidence beside its own. The point-volume pipeline is the
//! `videomocap-volume` crate beside this one; the desktop app and the command line sit on top
//! and only call these functions.

pub mod bvh;
pub mod camera;
pub mod formats;
pub mod skeleton;
pub mod video;

pub mod export;
pub mod lift;
pub mod network;
pub mod project;
mod setting_range;
pub mod track;
