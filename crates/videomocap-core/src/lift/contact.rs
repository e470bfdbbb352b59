//! The lift's last stage: feet on the floor. A foot is in contact while its ankle is seen, slow
//! in the image and no higher than the other ankle (with hysteresis); over each contact the body is
//! moved as one rigid piece along the planted ankle's viewing ray, so that the ankle keeps one
//! depth and stays on its 2D track, and the moves are blended across the swings between. A single camera sees
//! depth worst: a body that wanders a few centimetres towards and away from the camera per
//! frame slides its planted feet by as much, while the image pins everything else.

use crate::camera::PinholeCamera;
use crate::skeleton::{Joint, PerJoint};
use nalgebra::{Point2, Point3, Vector3};

/// The two ankles, in the order of [`FootContacts`].
pub const FEET: [Joint; 2] = [Joint::LeftAnkle, Joint::RightAnkle];

/// Per frame, whether each foot (left, right) is planted.
pub type FootContacts = Vec<[bool; 2]>;

/// A foot comes into contact below this speed of its ankle (metres per second, its image speed
/// at its depth): loose enough for a tracked ankle's jitter (`docs/method.md`, "Planted feet") ...
const ENTER_SPEED_M_S: f64 = 0.48;

/// ... and leaves it above this one.
const LEAVE_SPEED_M_S: f64 = 0.8;

/// An ankle higher than the other by more than this (metres, along the trunk's mean up
/// direction) is not planted.
const HIGHER_M: f64 = 0.08;

/// Contacts shorter than this many frames are dropped (a foot passing slowly).
const MIN_CONTACT_FRAMES: usize = 3;

/// Frames over which a depth move is blended in and out (a Gaussian of this deviation).
const BLEND_FRAMES: f64 = 1.0;

/// Finds each foot's contacts (see the module's note); `images` are the tracks the lift was
/// solved on, `points` the skeleton in camera space, `seen` per frame whether each ankle's
/// track was seen (not lost, not off the frame): a foot is never planted where it was not seen,
/// and a contact broken by such a span is two contacts.
pub(super) fn foot_contacts(
    cam: &PinholeCamera,
    images: &[PerJoint<Point2<f64>>],
    points: &[PerJoint<Point3<f64>>],
    seen: &[[bool; 2]],
    fps: f64,
) -> FootContacts {
    let n = points.len().min(images.len()).min(seen.len());
    let up = points
        .iter()
        .map(|p| (p[Joint::Neck] - p[Joint::Pelvis]).normalize())
        .fold(Vector3::zeros(), |a, b| a + b)
        .try_normalize(1e-9)
        // Camera Y points down.
        .unwrap_or(-Vector3::y());
    let mut contacts = vec![[false; 2]; n];
    for (k, &ankle) in FEET.iter().enumerate() {
        let other = FEET[1 - k];
        let mut planted = false;
        for t in 0..n {
            let (a, b) = (t.saturating_sub(1), (t + 1).min(n - 1));
            let pixels = (images[b][ankle] - images[a][ankle]).norm() / (b - a).max(1) as f64;
            let speed = pixels * points[t][ankle].z.max(0.1) / cam.focal_px * fps;
            let higher = (points[t][ankle] - points[t][other]).dot(&up);
            planted = seen[t][k]
                && higher < HIGHER_M
                && if planted {
                    speed < LEAVE_SPEED_M_S
                } else {
                    speed < ENTER_SPEED_M_S
                };
            contacts[t][k] = planted;
        }
        // Short contacts dropped.
        let mut t = 0;
        while t < n {
            if contacts[t][k] {
                let from = t;
                while t < n && contacts[t][k] {
                    t += 1;
                }
                if t - from < MIN_CONTACT_FRAMES {
                    (from..t).for_each(|s| contacts[s][k] = false);
                }
            } else {
                t += 1;
            }
        }
    }
    contacts
}

/// Moves each frame's body rigidly so that every planted ankle keeps its contact's median depth
/// along its own viewing ray (it stays on its 2D track; the body follows); between contacts the
/// moves are interpolated, and all are blended over a few frames. Bone lengths and directions
/// are unchanged.
pub(super) fn plant_feet(points: &mut [PerJoint<Point3<f64>>], contacts: &[[bool; 2]]) {
    let n = points.len().min(contacts.len());
    // The move each frame's planted ankles ask for (the mean when both are planted): along the
    // ankle's ray (scaled to unit depth), by the depth it is off its contact's median.
    let mut wanted: Vec<Option<Vector3<f64>>> = vec![None; n];
    for (k, &ankle) in FEET.iter().enumerate() {
        let mut t = 0;
        while t < n {
            if !contacts[t][k] {
                t += 1;
                continue;
            }
            let from = t;
            while t < n && contacts[t][k] {
                t += 1;
            }
            let mut depths: Vec<f64> = (from..t).map(|s| points[s][ankle].z).collect();
            depths.sort_by(f64::total_cmp);
            let target = depths[depths.len() / 2];
            for s in from..t {
                let q = points[s][ankle];
                let step = q.coords / q.z.max(1e-6) * (target - q.z);
                wanted[s] = Some(wanted[s].map_or(step, |w| 0.5 * (w + step)));
            }
        }
    }
    let known: Vec<usize> = (0..n).filter(|&t| wanted[t].is_some()).collect();
    if known.is_empty() {
        return;
    }
    let at = |t: usize| wanted[t].unwrap_or_else(Vector3::zeros);
    // Interpolated across the swings, held at the ends.
    let shift: Vec<Vector3<f64>> = (0..n)
        .map(|t| {
            let after = known.partition_point(|&k| k < t);
            match (after.checked_sub(1).map(|i| known[i]), known.get(after)) {
                _ if wanted[t].is_some() => at(t),
                (Some(a), Some(&b)) => at(a) + (at(b) - at(a)) * ((t - a) as f64 / (b - a) as f64),
                (Some(a), None) => at(a),
                (None, Some(&b)) => at(b),
                (None, None) => Vector3::zeros(),
            }
        })
        .collect();
    let columns: Vec<Vec<f64>> = (0..3)
        .map(|axis| {
            gaussian(
                &shift.iter().map(|v| v[axis]).collect::<Vec<_>>(),
                BLEND_FRAMES,
            )
        })
        .collect();
    let blended = (0..n).map(|t| Vector3::new(columns[0][t], columns[1][t], columns[2][t]));
    for (p, step) in points.iter_mut().zip(blended) {
        *p = p.map(|_, q| q + step);
    }
}

/// `x` smoothed by a Gaussian of deviation `sigma` samples (edges renormalised).
fn gaussian(x: &[f64], sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as isize;
    (0..x.len() as isize)
        .map(|t| {
            let (mut sum, mut weight) = (0.0, 0.0);
            for d in -r..=r {
                if let Some(v) = usize::try_from(t + d).ok().and_then(|i| x.get(i)) {
                    let w = (-(d * d) as f64 / (2.0 * sigma * sigma)).exp();
                    sum += w * v;
                    weight += w;
                }
            }
            sum / weight
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    type Pose = PerJoint<Point3<f64>>;

    /// A standing body, pelvis 4 m away, the left foot still in the image and the right one
    /// swinging; its depth wanders 1 cm a frame.
    fn wandering(n: usize) -> (PinholeCamera, Vec<PerJoint<Point2<f64>>>, Vec<Pose>) {
        let cam = PinholeCamera::centred(500.0, 640, 480);
        let body = |t: usize| {
            let swing = 0.3 * (t as f64 * 0.5).sin();
            PerJoint::from_fn(|j| match j {
                Joint::LeftAnkle => Point3::new(0.1, 0.9, 4.0),
                Joint::RightAnkle => Point3::new(-0.1, 0.75, 4.0 + swing),
                Joint::Neck => Point3::new(0.0, -0.5, 4.0),
                _ => Point3::new(0.0, 0.0, 4.0),
            })
        };
        let truth: Vec<_> = (0..n).map(body).collect();
        let images = truth
            .iter()
            .map(|p| p.map(|_, q| cam.project(q).unwrap_or(Point2::origin())))
            .collect();
        // The lift's depth wanders: each frame scaled along its rays (the image is unchanged).
        let lifted = truth
            .iter()
            .enumerate()
            .map(|(t, p)| p.map(|_, q| Point3::from(q.coords * (1.0 + 0.0025 * t as f64))))
            .collect();
        (cam, images, lifted)
    }

    #[test]
    fn a_still_foot_is_planted_and_the_swinging_one_is_not() {
        let (cam, images, lifted) = wandering(20);
        let c = foot_contacts(&cam, &images, &lifted, &[[true; 2]; 20], 30.0);
        assert!(c.iter().all(|f| f[0]), "the left foot stands");
        assert!(
            c.iter().filter(|f| f[1]).count() < 5,
            "the right foot swings"
        );
    }

    /// A foot lost for a span is not planted there, and the span splits its contact.
    #[test]
    fn a_foot_lost_for_a_span_is_not_planted_there() {
        let (cam, images, lifted) = wandering(20);
        let mut seen = [[true; 2]; 20];
        (8..12).for_each(|t| seen[t][0] = false);
        let c = foot_contacts(&cam, &images, &lifted, &seen, 30.0);
        assert!((8..12).all(|t| !c[t][0]), "not planted while lost");
        assert!((0..8).chain(12..20).all(|t| c[t][0]), "planted either side");
        // Lost on every frame: no contact at all, and planting moves nothing.
        let c = foot_contacts(&cam, &images, &lifted, &[[false; 2]; 20], 30.0);
        assert!(c.iter().all(|f| !f[0] && !f[1]));
        let mut moved = lifted.clone();
        plant_feet(&mut moved, &c);
        assert_eq!(moved, lifted);
    }

    #[test]
    fn planting_holds_the_foots_depth_and_keeps_the_body_rigid() {
        let (cam, images, mut lifted) = wandering(20);
        let before = lifted.clone();
        let c = foot_contacts(&cam, &images, &lifted, &[[true; 2]; 20], 30.0);
        plant_feet(&mut lifted, &c);
        let depth = |p: &[PerJoint<Point3<f64>>]| {
            let z: Vec<f64> = p.iter().map(|q| q[Joint::LeftAnkle].z).collect();
            z.iter().copied().fold(f64::MIN, f64::max) - z.iter().copied().fold(f64::MAX, f64::min)
        };
        assert!(depth(&before) > 0.15, "{}", depth(&before));
        assert!(depth(&lifted) < 0.03, "{}", depth(&lifted));
        for (a, b) in before.iter().zip(&lifted) {
            let d = b[Joint::Neck] - a[Joint::Neck];
            assert!(((b[Joint::LeftAnkle] - a[Joint::LeftAnkle]) - d).norm() < 1e-9);
        }
        // The planted ankle stays on its track (it moves along its own ray).
        for (t, p) in lifted.iter().enumerate() {
            let px = cam.project(&p[Joint::LeftAnkle]).unwrap();
            assert!((px - images[t][Joint::LeftAnkle]).norm() < 0.5, "frame {t}");
        }
    }
}
