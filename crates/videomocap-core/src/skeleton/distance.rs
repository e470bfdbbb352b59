//! Distances from a point to a bone, shared by the stages that keep one body part out of
//! another (the lift's contact prior, the volume pipeline's body fitting).
use nalgebra::Point3;

/// Distance from `p` to the segment `a`–`b` (to `a` when the segment has no length).
pub fn segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-18)).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_distance_is_to_the_nearest_point_of_the_segment() {
        let (a, b) = (Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 0.0, 0.0));
        // Beside the middle, beyond each end, and on the segment itself.
        assert!((segment_distance(&Point3::new(1.0, 3.0, 0.0), &a, &b) - 3.0).abs() < 1e-12);
        assert!((segment_distance(&Point3::new(5.0, 4.0, 0.0), &a, &b) - 5.0).abs() < 1e-12);
        assert!((segment_distance(&Point3::new(-3.0, 0.0, 4.0), &a, &b) - 5.0).abs() < 1e-12);
        assert!(segment_distance(&Point3::new(0.5, 0.0, 0.0), &a, &b).abs() < 1e-12);
        // A segment of no length is its point.
        assert!((segment_distance(&Point3::new(0.0, 1.0, 0.0), &a, &a) - 1.0).abs() < 1e-12);
    }
}
