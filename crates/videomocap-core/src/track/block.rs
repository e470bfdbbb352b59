//! The morph-block (Pan et al., Fig. 7): `A = {(x, y), m, n, θ}`, a rectangle whose middle line
//! is a bone. `(x, y)` is where the middle line meets one side (the block's anchor), `m` the
//! height along the middle line, `n` the width across it, `θ` the angle of the middle line with
//! the image X axis. Image pixels: x right, y down, pixel centres at integers.

use nalgebra::{Point2, Vector2};

/// A morph-block in image pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct MorphBlock {
    /// Where the middle line meets the anchored side (a joint), pixels.
    pub origin: Point2<f64>,
    /// Height along the middle line, pixels (the bone's image length).
    pub m: f64,
    /// Width across the middle line, pixels.
    pub n: f64,
    /// Angle of the middle line with the image X axis, radians (y down, so positive turns
    /// clockwise on screen).
    pub theta: f64,
}

impl MorphBlock {
    /// The block whose middle line runs from `from` to `to`, `width` pixels wide.
    pub(super) fn along(from: Point2<f64>, to: Point2<f64>, width: f64) -> MorphBlock {
        let d = to - from;
        MorphBlock {
            origin: from,
            m: d.norm(),
            n: width,
            theta: d.y.atan2(d.x),
        }
    }

    /// Unit vector along the middle line.
    pub(super) fn direction(&self) -> Vector2<f64> {
        Vector2::new(self.theta.cos(), self.theta.sin())
    }

    /// Unit vector across the middle line (θ + 90°).
    pub(super) fn across(&self) -> Vector2<f64> {
        Vector2::new(-self.theta.sin(), self.theta.cos())
    }

    /// The far end of the middle line (the other joint).
    pub(super) fn end(&self) -> Point2<f64> {
        self.origin + self.direction() * self.m
    }

    /// Image position of block coordinates `u` (0 at the anchor, 1 at the far end) and `v`
    /// (−0.5 … 0.5 across, positive towards θ + 90°).
    pub(super) fn to_image(self, u: f64, v: f64) -> Point2<f64> {
        self.origin + self.direction() * (u * self.m) + self.across() * (v * self.n)
    }

    /// Block coordinates `(u, v)` of an image point (inverse of [`MorphBlock::to_image`]).
    pub(super) fn to_block(self, p: Point2<f64>) -> (f64, f64) {
        let d = p - self.origin;
        let u = if self.m > 1e-9 {
            d.dot(&self.direction()) / self.m
        } else {
            0.0
        };
        let v = if self.n > 1e-9 {
            d.dot(&self.across()) / self.n
        } else {
            0.0
        };
        (u, v)
    }
}

/// Wraps an angle to (−π, π].
pub(super) fn wrap_angle(a: f64) -> f64 {
    let mut a = a % std::f64::consts::TAU;
    if a <= -std::f64::consts::PI {
        a += std::f64::consts::TAU;
    } else if a > std::f64::consts::PI {
        a -= std::f64::consts::TAU;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_coordinates_round_trip() {
        let b = MorphBlock::along(Point2::new(10.0, 20.0), Point2::new(40.0, 60.0), 12.0);
        assert!((b.m - 50.0).abs() < 1e-12);
        assert!((b.end() - Point2::new(40.0, 60.0)).norm() < 1e-9);
        let p = b.to_image(0.3, -0.25);
        let (u, v) = b.to_block(p);
        assert!((u - 0.3).abs() < 1e-12 && (v + 0.25).abs() < 1e-12);
    }

    #[test]
    fn angles_wrap_into_one_turn() {
        assert!((wrap_angle(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap_angle(-0.5) + 0.5).abs() < 1e-12);
        assert!((wrap_angle(7.0) - (7.0 - std::f64::consts::TAU)).abs() < 1e-12);
    }
}
