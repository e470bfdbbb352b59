//! The pose network: BlazePose GHUM "full" (Google, Apache-2.0; `assets/blazepose/`, converted
//! from MediaPipe's TFLite file by `scripts/convert_blazepose.sh`), run in pure Rust with
//! `tract`. It is evidence beside the VBA tracker, never the answer: given a crop made from the
//! body the user marked ([`Crop::around`]), it returns where it sees each of our 16 joints, how
//! sure it is, and a 3D body.
//!
//! Our joints from its 33 landmarks: shoulders, elbows, wrists, hips, knees and ankles are its
//! landmarks 11–16 and 23–28 (left before right, the subject's own sides); the neck is the
//! shoulders' midpoint, the pelvis the hips'; the chest lies on neck → pelvis at 0.40 of the way
//! (the stature fractions neck → chest 0.125 and chest → pelvis 0.19); the head top is the neck
//! plus 1.7 times neck → the ears' midpoint. Its hips and shoulders sit elsewhere than a user
//! marks them: callers carry the offset the key frames show.

mod crop;
mod graph;
mod profile;

pub use crop::{Crop, INPUT_PX};
pub use profile::{NetworkProfile, OpTime};

use crate::skeleton::{Joint, PerJoint};
use image::RgbImage;
use nalgebra::{Point2, Vector3};
use std::path::{Path, PathBuf};
use tract_linalg::multithread::{Executor, multithread_tract_scope};
use tract_onnx::prelude::*;

/// The bundled model (12.8 MB; sha256 in `assets/blazepose/SOURCE.md`).
const BUNDLED: &[u8] = include_bytes!("../../../../assets/blazepose/pose_landmark_full.onnx");

/// Landmarks the network reports (BlazePose's 33 and 6 for its region of interest).
const LANDMARKS: usize = 39;

/// Where the chest lies on neck → pelvis (stature fractions 0.125 / (0.125 + 0.19)).
const CHEST_ALONG: f64 = 0.125 / (0.125 + 0.19);

/// Head top = neck + this × (ears' midpoint − neck) (ears about 0.09 of stature above the
/// neck, the head top 0.155).
const HEAD_TOP_OVER_EARS: f64 = 1.7;

/// A network that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum NetworkError {
    /// The model file is missing, truncated or not a model this code can run.
    #[error("{path}: not a usable pose network: {reason}")]
    Model {
        /// The model file (`bundled` for the one built in).
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// Running the network failed.
    #[error("the pose network failed: {0}")]
    Run(String),
}

/// One joint as the network sees it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NetJoint {
    /// Position, image pixels.
    pub pos: Point2<f64>,
    /// How sure the network is that the joint is there and seen, 0–1.
    pub confidence: f64,
}

/// What the network sees in one crop.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkPose {
    /// Our 16 joints, image pixels.
    pub joints: PerJoint<NetJoint>,
    /// How sure the network is that a person fills the crop, 0–1.
    pub presence: f64,
    /// Our 16 joints in the network's 3D body (metres, origin between the hips, y down).
    pub world: PerJoint<Vector3<f64>>,
    /// The crop the network itself proposes for the next frame (its landmarks 33 and 34: the
    /// hips' centre and a point beyond the head, MediaPipe's tracking region).
    pub next_crop: Option<Crop>,
}

/// The loaded network (shareable between threads).
pub struct PoseNetwork {
    plan: std::sync::Arc<TypedRunnableModel>,
    /// Threads for the network's matrix products (`None`: the calling thread alone).
    pool: Option<Executor>,
}

impl std::fmt::Debug for PoseNetwork {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PoseNetwork")
            .field("threads", &self.pool.is_some())
            .finish_non_exhaustive()
    }
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

impl PoseNetwork {
    /// The network built into the program.
    pub fn bundled() -> Result<PoseNetwork, NetworkError> {
        Self::from_reader(&mut std::io::Cursor::new(BUNDLED), Path::new("bundled"))
    }

    /// The bundled network on `threads` threads, loaded once per process and thread count
    /// (loading parses and optimises the model, about a second): the one loader the command
    /// line, the app and the benchmarks share. An error says why it cannot be used; the
    /// callers then track with VBA alone and say so.
    pub fn shared(threads: usize) -> Result<std::sync::Arc<PoseNetwork>, NetworkError> {
        type Loaded = Vec<(usize, std::sync::Arc<PoseNetwork>)>;
        static LOADED: std::sync::Mutex<Loaded> = std::sync::Mutex::new(Vec::new());
        // A panic while loading leaves the list as it was: nothing half-made is kept.
        let mut loaded = LOADED
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some((_, n)) = loaded.iter().find(|(t, _)| *t == threads) {
            return Ok(n.clone());
        }
        let n = std::sync::Arc::new(Self::bundled()?.with_threads(threads));
        loaded.push((threads, n.clone()));
        Ok(n)
    }

    /// A network from an ONNX file (the same model, converted anew).
    pub fn load(path: &Path) -> Result<PoseNetwork, NetworkError> {
        let bytes = std::fs::read(path).map_err(|e| NetworkError::Model {
            path: path.to_owned(),
            reason: e.to_string(),
        })?;
        Self::from_reader(&mut std::io::Cursor::new(bytes), path)
    }

    /// The same network running its matrix products on `threads` threads (1: the calling
    /// thread alone). Falls back to one thread when the system gives no more.
    pub fn with_threads(mut self, threads: usize) -> PoseNetwork {
        self.pool = (threads > 1)
            .then(|| {
                rayon::ThreadPoolBuilder::new()
                    .thread_name(|k| format!("pose-network-{k}"))
                    .num_threads(threads)
                    .build()
                    .ok()
            })
            .flatten()
            .map(|pool| Executor::MultiThread(std::sync::Arc::new(pool)));
        self
    }

    fn from_reader(
        reader: &mut dyn std::io::Read,
        path: &Path,
    ) -> Result<PoseNetwork, NetworkError> {
        let bad = |e: &dyn std::fmt::Display| NetworkError::Model {
            path: path.to_owned(),
            reason: e.to_string(),
        };
        let input = [1, INPUT_PX, INPUT_PX, 3];
        let mut model = tract_onnx::onnx()
            .model_for_read(reader)
            .map_err(|e| bad(&e))?
            .with_input_fact(0, f32::fact(input).into())
            .map_err(|e| bad(&e))?
            .into_typed()
            .map_err(|e| bad(&e))?;
        graph::keep_read_outputs(&mut model, &[LANDMARKS * 5, 1, LANDMARKS * 3])
            .map_err(|e| bad(&e))?;
        let mut model = model.into_decluttered().map_err(|e| bad(&e))?;
        graph::channels_last(&mut model).map_err(|e| bad(&e))?;
        let plan = model
            .into_optimized()
            .map_err(|e| bad(&e))?
            .into_runnable()
            .map_err(|e| bad(&e))?;
        let network = PoseNetwork { plan, pool: None };
        // The outputs this code reads must be there, with their sizes.
        let probe = network.raw(&mut |_: &mut [f32]| {}).map_err(|e| bad(&e))?;
        drop(probe);
        Ok(network)
    }

    /// The landmarks (39 × 5), the pose flag and the world coordinates (39 × 3) of the input
    /// `fill` writes (into zeros, 256 × 256 × 3 values, in place in the network's input).
    fn raw(
        &self,
        fill: &mut dyn FnMut(&mut [f32]),
    ) -> Result<(Vec<f32>, f32, Vec<f32>), NetworkError> {
        let run = |e: &dyn std::fmt::Display| NetworkError::Run(e.to_string());
        let mut tensor = Tensor::zero::<f32>(&[1, INPUT_PX, INPUT_PX, 3]).map_err(|e| run(&e))?;
        {
            let mut view = tensor.try_as_plain_ram_mut().map_err(|e| run(&e))?;
            fill(view.as_slice_mut::<f32>().map_err(|e| run(&e))?);
        }
        let input = tvec!(tensor.into());
        let outputs = match &self.pool {
            Some(pool) => multithread_tract_scope(pool.clone(), || self.plan.run(input)),
            None => self.plan.run(input),
        }
        .map_err(|e| run(&e))?;
        let mut landmarks = None;
        let mut flag = None;
        let mut world = None;
        for o in &outputs {
            // The mask and the heatmaps are not read.
            let n: usize = o.shape().iter().product();
            if ![LANDMARKS * 5, 1, LANDMARKS * 3].contains(&n) {
                continue;
            }
            let view = o.to_plain_array_view::<f32>().map_err(|e| run(&e))?;
            let values: Vec<f32> = view.iter().copied().collect();
            match n {
                1 => flag = values.first().copied(),
                n if n == LANDMARKS * 5 => landmarks = Some(values),
                _ => world = Some(values),
            }
        }
        match (landmarks, flag, world) {
            (Some(l), Some(f), Some(w)) => Ok((l, f, w)),
            _ => Err(NetworkError::Run(format!(
                "expected outputs of 195, 1 and 117 values, got {:?}",
                outputs
                    .iter()
                    .map(|o| o.shape().to_vec())
                    .collect::<Vec<_>>()
            ))),
        }
    }

    /// Runs the network on `crop` of `frame`.
    pub fn run(&self, frame: &RgbImage, crop: &Crop) -> Result<NetworkPose, NetworkError> {
        let (landmarks, flag, world) = self.raw(&mut |input| crop.sample_into(frame, input))?;
        let lm = |i: usize| {
            let r = &landmarks[i * 5..i * 5 + 5];
            NetJoint {
                pos: crop.to_image(f64::from(r[0]), f64::from(r[1])),
                confidence: sigmoid(f64::from(r[3])) * sigmoid(f64::from(r[4])),
            }
        };
        let w = |i: usize| {
            Vector3::new(
                f64::from(world[i * 3]),
                f64::from(world[i * 3 + 1]),
                f64::from(world[i * 3 + 2]),
            )
        };
        Ok(NetworkPose {
            joints: ours(&lm),
            presence: sigmoid(f64::from(flag)),
            world: ours_3d(&w),
            next_crop: Crop::aligned(lm(33).pos, lm(34).pos),
        })
    }
}

/// Our 16 joints from the network's landmarks (see the module's text).
fn ours(lm: &dyn Fn(usize) -> NetJoint) -> PerJoint<NetJoint> {
    let mid = |a: NetJoint, b: NetJoint| NetJoint {
        pos: nalgebra::center(&a.pos, &b.pos),
        confidence: a.confidence.min(b.confidence),
    };
    let neck = mid(lm(11), lm(12));
    let pelvis = mid(lm(23), lm(24));
    let ears = mid(lm(7), lm(8));
    PerJoint::from_fn(|j| match j {
        Joint::HeadTop => NetJoint {
            pos: neck.pos + (ears.pos - neck.pos) * HEAD_TOP_OVER_EARS,
            confidence: neck.confidence.min(ears.confidence),
        },
        Joint::Neck => neck,
        Joint::Chest => NetJoint {
            pos: neck.pos + (pelvis.pos - neck.pos) * CHEST_ALONG,
            confidence: neck.confidence.min(pelvis.confidence),
        },
        Joint::Pelvis => pelvis,
        _ => lm(landmark_of(j)),
    })
}

/// Our 16 joints in the network's 3D body.
fn ours_3d(w: &dyn Fn(usize) -> Vector3<f64>) -> PerJoint<Vector3<f64>> {
    let neck = (w(11) + w(12)) / 2.0;
    let pelvis = (w(23) + w(24)) / 2.0;
    let ears = (w(7) + w(8)) / 2.0;
    PerJoint::from_fn(|j| match j {
        Joint::HeadTop => neck + (ears - neck) * HEAD_TOP_OVER_EARS,
        Joint::Neck => neck,
        Joint::Chest => neck + (pelvis - neck) * CHEST_ALONG,
        Joint::Pelvis => pelvis,
        _ => w(landmark_of(j)),
    })
}

/// BlazePose's landmark for one of our limb joints.
fn landmark_of(j: Joint) -> usize {
    match j {
        Joint::LeftShoulder => 11,
        Joint::RightShoulder => 12,
        Joint::LeftElbow => 13,
        Joint::RightElbow => 14,
        Joint::LeftWrist => 15,
        Joint::RightWrist => 16,
        Joint::LeftHip => 23,
        Joint::RightHip => 24,
        Joint::LeftKnee => 25,
        Joint::RightKnee => 26,
        Joint::LeftAnkle => 27,
        Joint::RightAnkle => 28,
        // Derived joints (head top, neck, chest, pelvis) never ask.
        Joint::HeadTop | Joint::Neck | Joint::Chest | Joint::Pelvis => 0,
    }
}
