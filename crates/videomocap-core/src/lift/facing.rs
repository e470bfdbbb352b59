//! The body's facing, decided stretch by stretch over the whole clip: where the key triangle
//! fits with the shoulders in either depth order, the order that explains the whole clip better.

use crate::formats::NetworkBody;
use crate::skeleton::Joint::{LeftShoulder, RightShoulder};
use nalgebra::Point3;
use std::ops::Range;

/// The network's word on the facing counts where it is at least this sure of both shoulders.
const NETWORK_SURE: f32 = 0.5;

/// The shoulders' depth difference (left minus right), metres: which way the body faces.
pub(super) fn facing_m(k: &[Point3<f64>; 3]) -> f64 {
    k[0].z - k[1].z
}

/// A facing shows when the shoulders' depths differ by more than this, metres.
pub(super) const FACING_SHOWS_M: f64 = 0.05;

/// The key path with each stretch of frames where the other facing also fits (a candidate pose
/// of the frame with the shoulders in the other depth order) turned to it when that explains the
/// whole clip better (`score`, lower is better: the fit score of the body built on the path,
/// which weighs the network's facing too). A turn through side-on splits the clip into such
/// stretches, and each is decided by all its frames' evidence rather than by the chain's
/// smoothness at the crossing. Stretches where the pose network (`bodies`) sees the shoulders
/// the other way round are tried first, turned to the mirrored triangle where no candidate
/// faces that way: a mirrored frame often has no candidate of the other facing at all (test
/// split: mirrored 15 → 6 % of frames, `docs/method.md`).
pub(super) fn facing_by_segments(
    mut key: Vec<[Point3<f64>; 3]>,
    candidates: &[(Vec<[Point3<f64>; 3]>, bool)],
    bodies: &[Option<NetworkBody>],
    score: impl Fn(&[[Point3<f64>; 3]]) -> f64,
) -> Vec<[Point3<f64>; 3]> {
    let n = key.len();
    // Each frame's other facing, when one fits: the candidate most like the chosen pose among
    // those facing the other way.
    let other: Vec<Option<[Point3<f64>; 3]>> = (0..n)
        .map(|t| {
            let f = facing_m(&key[t]);
            if f.abs() < FACING_SHOWS_M {
                return None;
            }
            candidates[t]
                .0
                .iter()
                .filter(|c| facing_m(c) * f < 0.0 && facing_m(c).abs() >= FACING_SHOWS_M)
                .min_by(|a, b| {
                    let d = |c: &[Point3<f64>; 3]| {
                        (0..3).map(|i| (c[i] - key[t][i]).norm()).sum::<f64>()
                    };
                    d(a).total_cmp(&d(b))
                })
                .copied()
        })
        .collect();
    let mut segments = Vec::new();
    let mut against: Vec<Range<usize>> = Vec::new();
    let mut t = 0;
    while t < n {
        if other[t].is_some() {
            let start = t;
            while t < n && other[t].is_some() {
                t += 1;
            }
            segments.push(start..t);
        } else {
            t += 1;
        }
    }
    // The stretches where the network sees the shoulders the other way round.
    let disagrees = |t: usize| {
        let f = facing_m(&key[t]);
        bodies.get(t).and_then(|b| b.as_ref()).is_some_and(|b| {
            let net = b.points[LeftShoulder].z - b.points[RightShoulder].z;
            let sure = b.confidence[LeftShoulder].min(b.confidence[RightShoulder]) > NETWORK_SURE;
            sure && f.abs() >= FACING_SHOWS_M && net.abs() >= FACING_SHOWS_M && net * f < 0.0
        })
    };
    let mut t = 0;
    while t < n {
        if disagrees(t) {
            let start = t;
            while t < n && disagrees(t) {
                t += 1;
            }
            against.push(start..t);
        } else {
            t += 1;
        }
    }
    segments.sort_by_key(|s| std::cmp::Reverse(s.len()));
    let mut best = score(&key);
    // First the stretches the network sees facing the other way, each turned to the other
    // facing's candidate or, where none fits, to the mirrored triangle; then the stretches
    // where another facing fits. Longest first; at most a handful each, each one more
    // whole-clip solve.
    against.sort_by_key(|s| std::cmp::Reverse(s.len()));
    for s in against.into_iter().take(8) {
        if s.len() < 3 {
            continue;
        }
        let mut trial = key.clone();
        for t in s.clone() {
            trial[t] = other[t].unwrap_or_else(|| mirrored(&key[t]));
        }
        let v = score(&trial);
        if v < best {
            best = v;
            key = trial;
        }
    }
    for s in segments.into_iter().take(8) {
        if s.len() < 3 {
            continue;
        }
        let mut trial = key.clone();
        for t in s.clone() {
            if let Some(o) = other[t] {
                trial[t] = o;
            }
        }
        let v = score(&trial);
        if v < best {
            best = v;
            key = trial;
        }
    }
    key
}

/// The key triangle turned the other way in depth: each joint's depth reflected about the
/// triangle's mean depth, along its own viewing ray (so the image is unchanged; the sides keep
/// their lengths as far as the view is not too close).
fn mirrored(k: &[Point3<f64>; 3]) -> [Point3<f64>; 3] {
    let mean = (k[0].z + k[1].z + k[2].z) / 3.0;
    k.map(|p| {
        let z = 2.0 * mean - p.z;
        if p.z > 1e-9 && z > 1e-9 {
            Point3::from(p.coords * (z / p.z))
        } else {
            p
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::PerJoint;
    use nalgebra::Vector3;

    /// Shoulders at 4 m, the left one 0.2 m nearer: facing one way.
    fn key() -> [Point3<f64>; 3] {
        [
            Point3::new(0.2, 0.0, 3.9),
            Point3::new(-0.2, 0.0, 4.1),
            Point3::new(0.0, 0.2, 4.0),
        ]
    }

    /// A network body whose shoulders' depth order is `sign` (left minus right).
    fn body(sign: f64) -> NetworkBody {
        let mut points = PerJoint::from_fn(|_| Vector3::zeros());
        points[LeftShoulder].z = 0.1 * sign;
        points[RightShoulder].z = -0.1 * sign;
        NetworkBody {
            points,
            confidence: PerJoint::from_fn(|_| 0.9),
        }
    }

    /// Frames 3–7 face the other way by the network, and no candidate faces that way: the
    /// stretch is tried mirrored and kept when the whole clip then scores better; nothing turns
    /// without the network, or when the score says no.
    #[test]
    fn a_stretch_the_network_sees_turned_is_tried_mirrored() {
        let n = 10;
        let path = vec![key(); n];
        let candidates: Vec<(Vec<[Point3<f64>; 3]>, bool)> = vec![(vec![key()], true); n];
        let bodies: Vec<Option<NetworkBody>> = (0..n)
            .map(|t| Some(body(if (3..8).contains(&t) { 1.0 } else { -1.0 })))
            .collect();
        let turned = |k: &[Point3<f64>; 3]| facing_m(k) > 0.0;
        // The score: frames facing as the network says are cheaper.
        let score = |p: &[[Point3<f64>; 3]]| {
            (0..n)
                .filter(|&t| turned(&p[t]) != (3..8).contains(&t))
                .count() as f64
        };
        let out = facing_by_segments(path.clone(), &candidates, &bodies, score);
        for (t, k) in out.iter().enumerate() {
            assert_eq!(turned(k), (3..8).contains(&t), "frame {t}");
            // Mirrored along the rays: the image is unchanged.
            let (a, b) = (k[0].coords / k[0].z, path[t][0].coords / path[t][0].z);
            assert!((a - b).norm() < 1e-12);
        }
        let none: Vec<Option<NetworkBody>> = vec![None; n];
        assert_eq!(
            facing_by_segments(path.clone(), &candidates, &none, score),
            path
        );
        let against = |_: &[[Point3<f64>; 3]]| 0.0;
        assert_eq!(
            facing_by_segments(path.clone(), &candidates, &bodies, against),
            path
        );
    }
}
