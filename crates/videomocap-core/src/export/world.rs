//! From camera space (X right, Y down, Z forward) to the Y-up world the exports use: up estimated
//! from the sequence, the floor at height 0, the origin on the floor under the first frame's
//! pelvis, Z pointing back towards the camera and X = Y × Z (the camera's right when it is level).

use super::ExportError;
use crate::skeleton::{Joint, PerJoint};
use nalgebra::{Matrix3, Point3, Rotation3, SymmetricEigen, Unit, Vector3};

/// Height of the ankle joint centre above the floor as a fraction of stature (Winter 2009,
/// Fig. 4.1: 0.039 H), used to put the floor under the ankles.
pub const ANKLE_HEIGHT_FRACTION: f64 = 0.039;

/// Stature from the head_top → ankle chain: head_top 1.000 H down to the ankle at 0.039 H, so
/// the chain of vertical bones spans 0.961 H (same table).
const CHAIN_FRACTION: f64 = 1.0 - ANKLE_HEIGHT_FRACTION;

/// Contact points spread at least this much (standard deviation, metres) along two directions
/// define the floor plane by themselves.
const PLANE_SPREAD_M: f64 = 0.15;

/// Contact points spread at least this much along one direction (a walk) give a horizontal line.
const LINE_SPREAD_M: f64 = 0.30;

/// ... and lie within this fraction of that spread of their plane (a floor is flat; contacts
/// from a noisy reconstruction are not).
const PLANE_FLATNESS: f64 = 0.1;

/// An estimate of "up" further than this from the trunk's mean direction is not trusted.
const MAX_TILT_FROM_TRUNK_DEG: f64 = 30.0;

/// Share of frames whose lowest ankle is taken to be on the floor (the lower quantile of the
/// lowest ankle's height; jumps and noise lie above it).
const FLOOR_QUANTILE: f64 = 0.2;

/// Frames with a planted foot needed before the floor is said to stand on them (two short
/// contacts).
const MIN_PLANTED_FRAMES: usize = 6;

/// What the floor stands on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FloorSource {
    /// The lift found a foot planted on this many frames: the floor under the lowest ankles is
    /// where the feet stood.
    FeetPlanted {
        /// Frames with a planted foot.
        frames: usize,
    },
    /// No foot was found planted (feet never still on the floor, a jump, or the foot lock off):
    /// the floor under the lowest ankles is a guess worth a look.
    NoFootPlanted,
}

impl std::fmt::Display for FloorSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FloorSource::FeetPlanted { frames } => {
                write!(
                    f,
                    "under the lowest ankles (a foot planted on {frames} frames)"
                )
            }
            FloorSource::NoFootPlanted => f.write_str(
                "under the lowest ankles, but no foot was found planted: a guess, check the floor",
            ),
        }
    }
}

/// How "up" was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UpSource {
    /// The plane through the lowest ankle positions (the subject moved over the floor in two
    /// directions).
    AnklePlane,
    /// The trunk's mean direction with its tilt along the walking line removed (the lowest
    /// ankles lie along a horizontal line).
    TrunkAndWalkLine,
    /// The trunk's mean direction (pelvis → neck) alone.
    Trunk,
}

impl std::fmt::Display for UpSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            UpSource::AnklePlane => "plane through the lowest ankles",
            UpSource::TrunkAndWalkLine => "trunk direction levelled along the walking line",
            UpSource::Trunk => "trunk direction",
        })
    }
}

/// The rigid map from camera space to the exports' Y-up world (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct WorldFrame {
    /// Rotation taking camera-space vectors to world vectors (its rows are the world's X, Y and
    /// Z axes in camera space).
    pub rotation: Rotation3<f64>,
    /// The world origin (on the floor under the first frame's pelvis) in camera space.
    pub origin_in_camera: Point3<f64>,
    /// How up was found.
    pub up_source: UpSource,
    /// What the floor stands on.
    pub floor_source: FloorSource,
}

impl WorldFrame {
    /// A camera-space point in world coordinates.
    pub fn to_world(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.rotation * (p - self.origin_in_camera))
    }

    /// A world point back in camera space.
    pub fn to_camera(&self, p: &Point3<f64>) -> Point3<f64> {
        self.origin_in_camera + self.rotation.inverse() * p.coords
    }

    /// The world's up axis in camera space.
    pub fn up_in_camera(&self) -> Vector3<f64> {
        self.rotation.matrix().row(1).transpose()
    }

    /// Estimates up, the floor and the origin from a camera-space sequence; `contacts` (per
    /// frame, the ankles the lift found planted; may be empty) only say whether the floor
    /// stands on anything ([`FloorSource`]):
    /// 1. the trunk's mean direction (pelvis → neck, each frame's unit vector averaged) is a
    ///    first "up";
    /// 2. each frame's lower ankle along it is a floor contact; if the contacts spread over the
    ///    floor in two directions their best-fit plane's normal is up, if they spread along one
    ///    line (a walk) that line is taken as horizontal and removed from the trunk direction,
    ///    otherwise the trunk direction stays (a result tilted more than 30° from the trunk is
    ///    not trusted);
    /// 3. the floor lies [`ANKLE_HEIGHT_FRACTION`] of the stature (from the bone lengths) under
    ///    the lower 20 % quantile of the contacts' heights (a jump shorter than four fifths of
    ///    the clip leaves the floor and lands on it again). Taking the contacts only from the
    ///    frames with a planted foot was tried: worse from the tracker's output on the test
    ///    split (`docs/method.md`, "The floor").
    pub fn estimate(
        frames: &[PerJoint<Point3<f64>>],
        contacts: &[PerJoint<bool>],
    ) -> Result<WorldFrame, ExportError> {
        let first = frames.first().ok_or(ExportError::NoFrames)?;
        let mut trunk = Vector3::zeros();
        for f in frames {
            if let Some(d) = (f[Joint::Neck] - f[Joint::Pelvis]).try_normalize(1e-9) {
                trunk += d;
            }
        }
        let trunk = trunk.try_normalize(1e-9).unwrap_or_else(|| -Vector3::y());
        let lowest_of = |f: &PerJoint<Point3<f64>>| {
            let (l, r) = (f[Joint::LeftAnkle], f[Joint::RightAnkle]);
            if l.coords.dot(&trunk) <= r.coords.dot(&trunk) {
                l
            } else {
                r
            }
        };
        let planted = frames
            .iter()
            .zip(contacts)
            .filter(|(_, c)| c[Joint::LeftAnkle] || c[Joint::RightAnkle])
            .count();
        let floor_source = if planted >= MIN_PLANTED_FRAMES {
            FloorSource::FeetPlanted { frames: planted }
        } else {
            FloorSource::NoFootPlanted
        };
        let points: Vec<Point3<f64>> = frames.iter().map(lowest_of).collect();
        let (up, up_source) = up_from_contacts(&points, trunk);
        let stature = stature_m(frames);
        let mut heights: Vec<f64> = points.iter().map(|c| c.coords.dot(&up)).collect();
        heights.sort_by(f64::total_cmp);
        let k = ((heights.len() - 1) as f64 * FLOOR_QUANTILE).round() as usize;
        let floor = heights[k] - ANKLE_HEIGHT_FRACTION * stature;
        let pelvis = first[Joint::Pelvis];
        let origin_in_camera = pelvis - (pelvis.coords.dot(&up) - floor) * up;
        // Z: back towards the camera, horizontal. When the camera looks straight down, the
        // image's top (camera −Y) made horizontal takes its place.
        let towards_camera = -Vector3::z();
        let z = (towards_camera - towards_camera.dot(&up) * up)
            .try_normalize(1e-6)
            .or_else(|| (Vector3::y() - Vector3::y().dot(&up) * up).try_normalize(1e-6))
            .unwrap_or_else(|| up.cross(&Vector3::x()).normalize());
        let x = up.cross(&z);
        let rows = Matrix3::from_rows(&[x.transpose(), up.transpose(), z.transpose()]);
        Ok(WorldFrame {
            rotation: Rotation3::from_matrix_unchecked(rows),
            origin_in_camera,
            up_source,
            floor_source,
        })
    }
}

/// Up from the floor contacts (see [`WorldFrame::estimate`], step 2).
fn up_from_contacts(contacts: &[Point3<f64>], trunk: Vector3<f64>) -> (Vector3<f64>, UpSource) {
    let n = contacts.len() as f64;
    let mean = contacts.iter().fold(Vector3::zeros(), |a, c| a + c.coords) / n;
    let mut cov = Matrix3::zeros();
    for c in contacts {
        let d = c.coords - mean;
        cov += d * d.transpose();
    }
    cov /= n;
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let spread = |k: usize| eig.eigenvalues[order[k]].max(0.0).sqrt();
    let axis = |k: usize| Unit::new_normalize(eig.eigenvectors.column(order[k]).into_owned());
    let max_tilt = MAX_TILT_FROM_TRUNK_DEG.to_radians().cos();
    if spread(1) >= PLANE_SPREAD_M && spread(2) <= PLANE_FLATNESS * spread(1) {
        let normal = axis(2).into_inner();
        let normal = if normal.dot(&trunk) < 0.0 {
            -normal
        } else {
            normal
        };
        if normal.dot(&trunk) >= max_tilt {
            return (normal, UpSource::AnklePlane);
        }
    }
    if spread(0) >= LINE_SPREAD_M {
        let line = axis(0).into_inner();
        if let Some(up) = (trunk - trunk.dot(&line) * line).try_normalize(1e-6)
            && up.dot(&trunk) >= max_tilt
        {
            return (up, UpSource::TrunkAndWalkLine);
        }
    }
    (trunk, UpSource::Trunk)
}

/// Stature from the median lengths of the vertical chain head_top–neck–chest–pelvis and the
/// longer leg's thigh + shank (see `CHAIN_FRACTION`).
pub fn stature_m(frames: &[PerJoint<Point3<f64>>]) -> f64 {
    let length = |a: Joint, b: Joint| {
        let mut v: Vec<f64> = frames.iter().map(|f| (f[a] - f[b]).norm()).collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let trunk = length(Joint::HeadTop, Joint::Neck)
        + length(Joint::Neck, Joint::Chest)
        + length(Joint::Chest, Joint::Pelvis);
    let left = length(Joint::LeftHip, Joint::LeftKnee) + length(Joint::LeftKnee, Joint::LeftAnkle);
    let right =
        length(Joint::RightHip, Joint::RightKnee) + length(Joint::RightKnee, Joint::RightAnkle);
    (trunk + left.max(right)) / CHAIN_FRACTION
}
