//! Points and poses in the map frame.
//!
//! Map frame (REP-103): x east, y north, heading counter-clockwise from +x, metres and radians.
//! The odometry frame (`odom`) has the same conventions; where a pose is in `odom` rather than
//! `map` the field or function name says so.

use core::f32::consts::{PI, TAU};

use crate::math;

/// A point \[m\].
#[derive(
    Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize, bytemuck::Zeroable,
)]
pub struct Point2 {
    /// East \[m\].
    pub x: f32,
    /// North \[m\].
    pub y: f32,
}

impl Point2 {
    /// The point `(x, y)` \[m\].
    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }

    /// Euclidean distance to `other` \[m\].
    pub fn distance(self, other: Point2) -> f32 {
        math::hypot(other.x - self.x, other.y - self.y)
    }

    /// Bearing from `self` toward `other` \[rad\], counter-clockwise from +x.
    pub fn bearing_to(self, other: Point2) -> f32 {
        math::atan2(other.y - self.y, other.x - self.x)
    }
}

/// A planar pose: position \[m\] and heading \[rad\].
#[derive(
    Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize, bytemuck::Zeroable,
)]
pub struct Pose2 {
    /// East \[m\].
    pub x: f32,
    /// North \[m\].
    pub y: f32,
    /// Heading \[rad\], counter-clockwise from +x, kept in (-pi, pi].
    pub theta: f32,
}

impl Pose2 {
    /// The pose `(x, y, theta)`; `theta` is normalised.
    pub fn new(x: f32, y: f32, theta: f32) -> Self {
        Self {
            x,
            y,
            theta: normalize_angle(theta),
        }
    }

    /// The position part.
    pub const fn position(self) -> Point2 {
        Point2 {
            x: self.x,
            y: self.y,
        }
    }

    /// Transforms a point given in this pose's body frame (x forward, y left) into the frame
    /// this pose is expressed in.
    pub fn transform_point(self, body: Point2) -> Point2 {
        let (s, c) = (math::sin(self.theta), math::cos(self.theta));
        Point2 {
            x: self.x + c * body.x - s * body.y,
            y: self.y + s * body.x + c * body.y,
        }
    }

    /// Composes `self ⊕ rel`: `rel` is a pose in this pose's body frame.
    pub fn compose(self, rel: Pose2) -> Pose2 {
        let p = self.transform_point(rel.position());
        Pose2::new(p.x, p.y, self.theta + rel.theta)
    }

    /// `origin⁻¹ ⊕ self`: this pose in `origin`'s body frame, the inverse of
    /// [`Self::compose`] (`origin.compose(p.in_frame_of(origin))` is `p`). The heading is the
    /// plain difference, not wrapped.
    pub fn in_frame_of(self, origin: Pose2) -> Pose2 {
        let (s, c) = (math::sin(origin.theta), math::cos(origin.theta));
        let (dx, dy) = (self.x - origin.x, self.y - origin.y);
        Pose2::new(c * dx + s * dy, -s * dx + c * dy, self.theta - origin.theta)
    }
}

/// Wraps an angle into (-pi, pi] \[rad\].
pub fn normalize_angle(a: f32) -> f32 {
    if a.is_nan() {
        return a;
    }
    let mut r = a - TAU * math::floor((a + PI) / TAU);
    // floor() maps +pi to -pi; keep +pi, the half-open interval's upper end.
    if r <= -PI {
        r += TAU;
    }
    if r > PI {
        r -= TAU;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_wrap_into_half_open_interval() {
        for &(a, want) in &[
            (0.0, 0.0),
            (PI, PI),
            (-PI, PI),
            (3.0 * PI, PI),
            (TAU + 0.5, 0.5),
            (-TAU - 0.5, -0.5),
        ] {
            assert!(
                (normalize_angle(a) - want).abs() < 1e-5,
                "{a} -> {}",
                normalize_angle(a)
            );
        }
    }

    #[test]
    fn body_points_rotate_with_heading() {
        let pose = Pose2::new(1.0, 2.0, PI / 2.0);
        let p = pose.transform_point(Point2::new(1.0, 0.0));
        assert!((p.x - 1.0).abs() < 1e-6 && (p.y - 3.0).abs() < 1e-6);
    }
}
