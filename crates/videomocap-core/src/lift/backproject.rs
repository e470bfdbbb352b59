//! One joint from its known parent: the point on the joint's viewing ray at the bone's length
//! from the parent (Pan et al., "Reconstruction…", the step after eq. 9: "with the order from
//! center to fringe … we can get all the 3D feature points").

use nalgebra::{Point3, Vector3};

/// Which of the two intersections of the ray with the bone-length sphere a joint takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Root {
    /// The intersection nearer the camera (the bone points towards the camera).
    #[default]
    Near,
    /// The intersection farther from the camera.
    Far,
}

impl Root {
    /// The other root.
    pub fn flipped(self) -> Root {
        match self {
            Root::Near => Root::Far,
            Root::Far => Root::Near,
        }
    }
}

/// The two candidate positions of a joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Roots {
    /// Nearer the camera.
    pub near: Point3<f64>,
    /// Farther from the camera.
    pub far: Point3<f64>,
    /// The ray passes farther from the parent than the bone's length (the 2D bone is too long
    /// for its 3D length): both roots are the point at the bone's length from the parent towards
    /// the ray's closest point, off the ray.
    pub too_long: bool,
}

impl Roots {
    /// The candidate for a choice.
    pub fn get(&self, root: Root) -> Point3<f64> {
        match root {
            Root::Near => self.near,
            Root::Far => self.far,
        }
    }
}

/// Intersects the ray `s·ray` (`ray` a unit vector from the camera centre) with the sphere of
/// radius `length` around `parent`: `s² − 2s(r·P) + |P|² − L² = 0`.
pub fn bone_roots(parent: &Point3<f64>, ray: &Vector3<f64>, length: f64) -> Roots {
    let p = parent.coords;
    let along = ray.dot(&p);
    let disc = along * along - p.norm_squared() + length * length;
    if disc >= 0.0 {
        let h = disc.sqrt();
        // Never behind the camera: a root at s ≤ 0 is replaced by the other one.
        let far = (along + h).max(1e-6);
        let near = if along - h > 1e-6 { along - h } else { far };
        Roots {
            near: Point3::from(ray * near),
            far: Point3::from(ray * far),
            too_long: false,
        }
    } else {
        let closest = ray * along.max(1e-6);
        let towards = closest - p;
        let norm = towards.norm();
        let point = if norm > 0.0 {
            Point3::from(p + towards * (length / norm))
        } else {
            Point3::from(closest)
        };
        Roots {
            near: point,
            far: point,
            too_long: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_roots_lie_on_the_ray_at_the_bone_length() {
        let parent = Point3::new(0.1, -0.2, 3.0);
        let child = Point3::new(0.3, 0.1, 3.2);
        let ray = child.coords.normalize();
        let len = (child - parent).norm();
        let r = bone_roots(&parent, &ray, len);
        assert!(!r.too_long);
        for p in [r.near, r.far] {
            assert!(((p - parent).norm() - len).abs() < 1e-12);
            assert!(p.coords.normalize().dot(&ray) > 1.0 - 1e-12);
        }
        // The true child is one of them.
        assert!((r.near - child).norm().min((r.far - child).norm()) < 1e-9);
        assert!(r.near.z < r.far.z);
    }

    #[test]
    fn a_bone_too_short_for_its_ray_keeps_its_length_and_is_flagged() {
        let parent = Point3::new(0.0, 0.0, 3.0);
        let ray = Vector3::new(1.0, 0.0, 3.0).normalize();
        let r = bone_roots(&parent, &ray, 0.2);
        assert!(r.too_long);
        assert!(((r.near - parent).norm() - 0.2).abs() < 1e-12);
        assert_eq!(r.near, r.far);
    }
}
