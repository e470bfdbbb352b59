//! Z-X-Y Euler angles (the BVH channel order `Zrotation Xrotation Yrotation`, R = Rz·Rx·Ry) kept
//! continuous from frame to frame.

use nalgebra::Matrix3;

/// The Z, X and Y angles (degrees) of `m` = Rz(z)·Rx(x)·Ry(y). Of the two triples that give the
/// same rotation (x and 180° − x) the one nearer `previous` is taken, and each angle is moved
/// by whole turns to lie within 180° of its previous value, so curves have no ±360° jumps or
/// flips; without `previous`, x lies in [−90°, 90°] and z, y in (−180°, 180°]. At gimbal lock
/// (x = ±90°) only z ± y is defined: y keeps its previous value.
pub fn zxy_degrees(m: &Matrix3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    let sx = m[(2, 1)].clamp(-1.0, 1.0);
    // cos x from the other two entries of its row and column: accurate near ±90°, where
    // asin loses half the digits.
    let cx = m[(0, 1)].hypot(m[(1, 1)]);
    let x = sx.atan2(cx);
    let candidates: Vec<[f64; 3]> = if cx > 1e-12 {
        let z = (-m[(0, 1)]).atan2(m[(1, 1)]);
        let y = (-m[(2, 0)]).atan2(m[(2, 2)]);
        let pi = std::f64::consts::PI;
        vec![[z, x, y], [z + pi, pi - x, y + pi]]
    } else {
        let y = previous.map_or(0.0, |p| p[2].to_radians());
        let sum = m[(1, 0)].atan2(m[(0, 0)]);
        let z = if sx > 0.0 { sum - y } else { sum + y };
        vec![[z, x, y]]
    };
    let degrees = candidates.into_iter().map(|c| c.map(f64::to_degrees));
    let Some(prev) = previous else {
        // Invariant: there is always at least one candidate.
        return degrees.map(|c| c.map(wrap)).next().unwrap_or([0.0; 3]);
    };
    degrees
        .map(|c| {
            let mut out = [0.0; 3];
            for k in 0..3 {
                out[k] = c[k] + 360.0 * ((prev[k] - c[k]) / 360.0).round();
            }
            out
        })
        .min_by(|a, b| distance(a, &prev).total_cmp(&distance(b, &prev)))
        .unwrap_or([0.0; 3])
}

fn wrap(a: f64) -> f64 {
    let w = a - 360.0 * (a / 360.0).round();
    if w <= -180.0 { w + 360.0 } else { w }
}

fn distance(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    fn compose(a: [f64; 3]) -> Matrix3<f64> {
        let r = |axis: Vector3<f64>, d: f64| {
            Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), d.to_radians())
                .into_inner()
        };
        r(Vector3::z(), a[0]) * r(Vector3::x(), a[1]) * r(Vector3::y(), a[2])
    }

    #[test]
    fn angles_recompose_to_the_rotation() {
        for a in [
            [10.0, 20.0, 30.0],
            [-170.0, 85.0, 100.0],
            [0.0, -89.0, -179.0],
            [45.0, 90.0, 0.0],
            [30.0, -90.0, 20.0],
            [30.0, 89.9999999, 20.0],
            [30.0, 89.99999, 20.0],
            [30.0, 89.999, 20.0],
            [-68.0, -89.9999999, 120.0],
        ] {
            let m = compose(a);
            let e = zxy_degrees(&m, None);
            assert!((compose(e) - m).abs().max() < 1e-12, "{a:?} → {e:?}");
            let e = zxy_degrees(&m, Some([1.0, 2.0, 3.0]));
            assert!(
                (compose(e) - m).abs().max() < 1e-12,
                "{a:?} → {e:?} after a previous"
            );
        }
    }

    #[test]
    fn a_slow_turn_through_180_degrees_stays_continuous() {
        let mut prev: Option<[f64; 3]> = None;
        for k in 0..=720 {
            let a = [k as f64, 20.0 + 0.1 * k as f64, -(k as f64) * 0.5];
            let m = compose(a);
            let e = zxy_degrees(&m, prev);
            assert!((compose(e) - m).abs().max() < 1e-9);
            if let Some(p) = prev {
                for i in 0..3 {
                    assert!((e[i] - p[i]).abs() < 5.0, "step {k}: {p:?} → {e:?}");
                }
            }
            prev = Some(e);
        }
    }
}
