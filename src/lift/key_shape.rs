//! Beyond the paper: the key triangle's height read from the tracks.
//!
//! Eqs. 6–11 need the key triangle's shape (both shoulders and the chest) in metres. From the
//! subject's height alone it comes from the proportions table, and the calibration is very
//! sensitive to it: a triangle seen nearly face on turns by several degrees for a 1 % error in
//! a side, and every limb hangs from it. The table's chest lies 0.255 of the trunk (neck to
//! pelvis) below the shoulder line; the real sample's reference has 0.335 and the CMU subjects
//! of the synthetic suite 0.29–0.31 (where the shoulder joints sit is a matter of definition
//! as much as of build).
//!
//! That drop is visible in every frame of an upright body, whichever way it faces: the chest's
//! distance below the midpoint of the shoulders, measured along the image trunk (neck to
//! pelvis), over the trunk's image length. Turning about the vertical foreshortens neither;
//! leaning towards the camera foreshortens both alike. The median over the frames estimated the
//! drop within 0.016 of the truth on all 12 clips of the suite and the real sample, side views
//! included (the shoulder width cannot be read this way: it vanishes in a side view, so it stays
//! the table's).

use crate::formats::{PointSource, Tracks2d};
use crate::skeleton::{Bone, Joint, Proportions, ProportionsError, SubjectModel};

/// A trunk shorter than this in the image (pixels) is not measured.
const MIN_TRUNK_PX: f64 = 10.0;

/// The measured drop is kept within this factor of the proportions' (either way): marks that
/// put the chest level with the shoulders are a marking slip, not a build.
const MAX_FACTOR: f64 = 1.6;

/// Track points below this confidence are not used.
const MIN_CONFIDENCE: f32 = 0.5;

/// The chest's drop below the shoulder line, as a fraction of the trunk (chest–neck plus
/// pelvis–chest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChestDrop {
    /// What the tracks show (the median over frames, clamped to the plausible range).
    pub measured: f64,
    /// What the subject model had.
    pub model: f64,
    /// Frames measured.
    pub frames: usize,
}

/// The chest's perpendicular distance from the shoulder line in the subject model, metres, and
/// its offset along the line from the shoulders' midpoint (towards the left shoulder).
fn model_triangle(subject: &SubjectModel) -> Option<(f64, f64)> {
    let w = subject.shoulder_width_m;
    let a = subject.bone_length(Bone::new(Joint::Chest, Joint::LeftShoulder));
    let b = subject.bone_length(Bone::new(Joint::Chest, Joint::RightShoulder));
    if !(w.is_finite() && w > 0.0) {
        return None;
    }
    // Chest at (x, h) with the left shoulder at (w/2, 0) and the right at (−w/2, 0).
    let x = (b * b - a * a) / (2.0 * w);
    let h2 = a * a - (x - w / 2.0).powi(2);
    (h2 > 0.0).then(|| (h2.sqrt(), x))
}

/// The trunk's length in the subject model: chest–neck plus pelvis–chest (the chest lies on the
/// line between neck and pelvis by its definition).
fn model_trunk(subject: &SubjectModel) -> f64 {
    subject.bone_length(Bone::new(Joint::Chest, Joint::Neck))
        + subject.bone_length(Bone::new(Joint::Pelvis, Joint::Chest))
}

/// The median drop over the frames whose shoulders, chest, neck and pelvis are trusted, and
/// how many frames that was.
pub fn measure(tracks: &Tracks2d) -> Option<(f64, usize)> {
    use Joint::*;
    let mut drops: Vec<f64> = tracks
        .frames
        .iter()
        .filter_map(|f| {
            let p = &f.points;
            let trusted = [LeftShoulder, RightShoulder, Chest, Neck, Pelvis]
                .iter()
                .all(|&j| {
                    p[j].confidence >= MIN_CONFIDENCE
                        && matches!(p[j].source, PointSource::Tracked)
                        && p[j].pos.x.is_finite()
                        && p[j].pos.y.is_finite()
                });
            if !trusted {
                return None;
            }
            let axis = p[Pelvis].pos - p[Neck].pos;
            let trunk = axis.norm();
            if trunk < MIN_TRUNK_PX {
                return None;
            }
            let mid = nalgebra::center(&p[LeftShoulder].pos, &p[RightShoulder].pos);
            Some((p[Chest].pos - mid).dot(&axis) / (trunk * trunk))
        })
        .collect();
    if drops.is_empty() {
        return None;
    }
    drops.sort_by(f64::total_cmp);
    Some((drops[drops.len() / 2], drops.len()))
}

/// The subject with its chest–shoulder bones set so that the key triangle's height is the
/// drop the tracks show (shoulder width and the chest's sideways offset kept), and the
/// measurement; the subject unchanged and `None` when nothing could be measured.
pub fn fit_to_tracks(
    subject: &SubjectModel,
    tracks: &Tracks2d,
) -> (SubjectModel, Option<ChestDrop>) {
    let trunk = model_trunk(subject);
    let (Some((h, x)), Some((drop, frames))) = (model_triangle(subject), measure(tracks)) else {
        return (subject.clone(), None);
    };
    if !(trunk.is_finite() && trunk > 0.0) {
        return (subject.clone(), None);
    }
    let model = h / trunk;
    let measured = drop.clamp(model / MAX_FACTOR, model * MAX_FACTOR);
    let h_new = measured * trunk;
    let w = subject.shoulder_width_m;
    let mut out = subject.clone();
    out.bone_length_m[Bone::new(Joint::Chest, Joint::LeftShoulder).index()] =
        (h_new * h_new + (x - w / 2.0).powi(2)).sqrt();
    out.bone_length_m[Bone::new(Joint::Chest, Joint::RightShoulder).index()] =
        (h_new * h_new + (x + w / 2.0).powi(2)).sqrt();
    (
        out,
        Some(ChestDrop {
            measured,
            model,
            frames,
        }),
    )
}

/// What a user who knows only the subject's height gets: the proportions table scaled to the
/// height, with the key triangle's height read from the tracks ([`fit_to_tracks`]).
pub fn subject_from_height(
    height_m: f64,
    tracks: &Tracks2d,
) -> Result<(SubjectModel, Option<ChestDrop>), ProportionsError> {
    let subject = SubjectModel::from_height(height_m, Proportions::default())?;
    Ok(fit_to_tracks(&subject, tracks))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::PinholeCamera;
    use crate::formats::{FrameTracks, SourceInfo, TrackedPoint};
    use crate::skeleton::{PerJoint, standing_pose};
    use nalgebra::{Point3, Rotation3, Vector3};

    /// The table's subject with its chest `drop` of the trunk below the shoulder line.
    fn subject_with_drop(drop: f64) -> SubjectModel {
        let mut s = SubjectModel::default();
        let h = drop * model_trunk(&s);
        let a = (h * h + (s.shoulder_width_m / 2.0).powi(2)).sqrt();
        s.bone_length_m[Bone::new(Joint::Chest, Joint::LeftShoulder).index()] = a;
        s.bone_length_m[Bone::new(Joint::Chest, Joint::RightShoulder).index()] = a;
        s
    }

    /// The subject standing 4 m in front of a camera, turned by each yaw in turn (a side view
    /// among them) and leaning a little, as tracks; `confidence` for every point.
    fn tracks_of(s: &SubjectModel, yaws: &[f64], confidence: f32) -> Tracks2d {
        let cam = PinholeCamera::centred(800.0, 640, 480);
        let down = -Vector3::y();
        let body = standing_pose(
            |b| s.bone_length(b),
            s.shoulder_width_m,
            Point3::origin(),
            |_| [down; 4],
        );
        let frames = yaws
            .iter()
            .enumerate()
            .map(|(t, &yaw)| {
                // Model Y up → camera Y down; the pelvis 4 m away, 0.2 m below the axis.
                let r = Rotation3::from_axis_angle(&Vector3::y_axis(), yaw)
                    * Rotation3::from_axis_angle(&Vector3::x_axis(), 0.1);
                FrameTracks {
                    index: t,
                    points: PerJoint::from_fn(|j| {
                        let q = r * body[j].coords;
                        let c = Point3::new(q.x, -q.y + 0.2, q.z + 4.0);
                        TrackedPoint {
                            pos: cam.project(&c).unwrap(),
                            confidence,
                            source: PointSource::Tracked,
                        }
                    }),
                }
            })
            .collect();
        Tracks2d {
            source: SourceInfo {
                path: "test".into(),
                width: 640,
                height: 480,
                fps: 30.0,
                frame_count: yaws.len(),
            },
            frames,
        }
    }

    #[test]
    fn the_drop_is_read_in_front_oblique_and_side_views() {
        let truth = subject_with_drop(0.33);
        let table = SubjectModel::default();
        let model = model_triangle(&table).unwrap().0 / model_trunk(&table);
        assert!(
            (model - 0.33).abs() > 0.05,
            "the test needs a different build"
        );
        for yaws in [
            [0.0; 3],
            [0.7; 3],
            [std::f64::consts::FRAC_PI_2; 3],
            [2.5, 0.3, 1.2],
        ] {
            let tracks = tracks_of(&truth, &yaws, 1.0);
            let (drop, frames) = measure(&tracks).unwrap();
            assert_eq!(frames, 3);
            assert!((drop - 0.33).abs() < 0.01, "yaws {yaws:?}: {drop}");
            let (fitted, found) = fit_to_tracks(&table, &tracks);
            assert!(found.is_some_and(|d| (d.model - model).abs() < 1e-9));
            for side in [Joint::LeftShoulder, Joint::RightShoulder] {
                let bone = Bone::new(Joint::Chest, side);
                let (got, want) = (fitted.bone_length(bone), truth.bone_length(bone));
                assert!((got / want - 1.0).abs() < 0.02, "{got} {want}");
            }
            assert_eq!(fitted.shoulder_width_m, table.shoulder_width_m);
        }
    }

    #[test]
    fn untrusted_or_implausible_marks_leave_the_table_or_are_held_to_it() {
        let table = SubjectModel::default();
        // Weak points only: nothing is measured and the subject is unchanged.
        let weak = tracks_of(&subject_with_drop(0.33), &[0.0, 0.5], 0.2);
        let (same, found) = fit_to_tracks(&table, &weak);
        assert!(found.is_none());
        assert_eq!(same, table);
        // A chest marked level with the shoulders: held to the plausible range.
        let flat = tracks_of(&subject_with_drop(0.02), &[0.0], 1.0);
        let (_, found) = fit_to_tracks(&table, &flat);
        let d = found.unwrap();
        assert!((d.measured - d.model / MAX_FACTOR).abs() < 1e-12, "{d:?}");
    }
}
