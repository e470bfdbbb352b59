//! videomocap: single-camera video motion capture.
//!
//! Data flows one way: [`video`] (frame sources) → [`track`] (2D: marks → tracks) → [`lift`]
//! (calibration, 3D skeleton) → [`export`] (BVH, CSV), with [`skeleton`] (joints, bones,
//! proportions) shared by all and [`volume`] (the second pipeline, point volumes → kinematics)
//! beside tracking and lifting. [`synth`] renders clips with known joints for tests and
//! benchmarks. The GUI and the CLI live in the binary and only call this library.

pub mod bvh;
pub mod camera;
pub mod eval;
pub mod formats;
pub mod skeleton;
pub mod synth;
pub mod video;

pub mod export;
pub mod lift;
pub mod project;
mod setting_range;
pub mod track;
pub mod volume;
