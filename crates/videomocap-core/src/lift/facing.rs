//! The body's facing, decided stretch by stretch over the whole clip: where the key triangle
//! fits with the shoulders in either depth order, the order that explains the whole clip better.

use nalgebra::Point3;

/// The shoulders' depth difference (left minus right), metres: which way the body faces.
pub(super) fn facing_m(k: &[Point3<f64>; 3]) -> f64 {
    k[0].z - k[1].z
}

/// A facing shows when the shoulders' depths differ by more than this, metres.
pub(super) const FACING_SHOWS_M: f64 = 0.05;

/// The key path with each stretch of frames where the other facing also fits (a candidate pose
/// of the frame with the shoulders in the other depth order) turned to it when that explains the
/// whole clip better (`score`, lower is better: [`fit_score`] of the body built on the path).
/// A turn through side-on splits the clip into such stretches, and each is decided by all its
/// frames' evidence rather than by the chain's smoothness at the crossing.
pub(super) fn facing_by_segments(
    mut key: Vec<[Point3<f64>; 3]>,
    candidates: &[(Vec<[Point3<f64>; 3]>, bool)],
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
    // Longest first; at most a handful, each one more whole-clip solve.
    segments.sort_by_key(|s| std::cmp::Reverse(s.len()));
    let mut best = score(&key);
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
