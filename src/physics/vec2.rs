//! A plain 2-D vector in the horizontal plane (docs/physics.md section 1), in world units or ups.

use super::real::Real;
use serde::{Deserialize, Serialize};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// A horizontal vector over the scalar `R`: a position in units or a velocity in ups.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct V2<R> {
    /// x component.
    pub x: R,
    /// y component.
    pub y: R,
}

/// The planning vector (f64).
pub type Vec2 = V2<f64>;

impl<R: Real> V2<R> {
    /// The zero vector.
    pub const ZERO: V2<R> = V2 {
        x: R::ZERO,
        y: R::ZERO,
    };

    /// A vector from its components.
    #[inline]
    pub const fn new(x: R, y: R) -> Self {
        V2 { x, y }
    }

    /// Dot product.
    #[inline]
    pub fn dot(self, o: Self) -> R {
        self.x * o.x + self.y * o.y
    }

    /// z component of the 3-D cross product (positive when `o` is anticlockwise of `self`).
    #[inline]
    pub fn cross(self, o: Self) -> R {
        self.x * o.y - self.y * o.x
    }

    /// Euclidean length, computed as the game does: `sqrt(x*x + y*y)`.
    #[inline]
    pub fn length(self) -> R {
        self.x.hypot(self.y)
    }

    /// Squared length.
    #[inline]
    pub fn length_squared(self) -> R {
        self.x * self.x + self.y * self.y
    }

    /// Rotated by +90 degrees (anticlockwise).
    #[inline]
    pub fn perp(self) -> Self {
        V2 {
            x: -self.y,
            y: self.x,
        }
    }

    /// True when both components are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }

    /// The unit vector in this direction, or `None` for a zero (or non-finite) vector.
    #[inline]
    pub fn normalized(self) -> Option<Self> {
        let len = self.length();
        if len > R::ZERO && len.is_finite() {
            Some(self * (R::ONE / len))
        } else {
            None
        }
    }

    /// The same vector in planning precision.
    #[inline]
    pub fn to_f64(self) -> Vec2 {
        V2::new(self.x.to_f64(), self.y.to_f64())
    }

    /// The vector rounded to the scalar `R`.
    #[inline]
    pub fn from_f64(v: Vec2) -> Self {
        V2::new(R::from_f64(v.x), R::from_f64(v.y))
    }
}

impl Vec2 {
    /// The unit vector at `angle_rad` anticlockwise from +x.
    #[inline]
    pub fn from_angle(angle_rad: f64) -> Self {
        let (s, c) = angle_rad.sin_cos();
        V2 { x: c, y: s }
    }

    /// Angle anticlockwise from +x, in radians (`atan2`; zero for the zero vector).
    #[inline]
    pub fn angle(self) -> f64 {
        self.y.atan2(self.x)
    }

    /// Rotated anticlockwise by `angle_rad` (the rotation R(theta) of docs/physics.md section 5; our positive
    /// angles turn left, anticlockwise, the way the game's yaw grows).
    #[inline]
    pub fn rotated(self, angle_rad: f64) -> Self {
        let (s, c) = angle_rad.sin_cos();
        self.rotated_cos_sin(c, s)
    }

    /// Rotated anticlockwise by the angle whose cosine and sine are given (R(theta) of docs/physics.md
    /// section 5 without a trigonometric function; `cos^2 + sin^2 = 1` is the caller's to keep).
    #[inline]
    pub fn rotated_cos_sin(self, cos_angle: f64, sin_angle: f64) -> Self {
        V2 {
            x: cos_angle * self.x - sin_angle * self.y,
            y: sin_angle * self.x + cos_angle * self.y,
        }
    }
}

impl<R: Real> Add for V2<R> {
    type Output = V2<R>;
    #[inline]
    fn add(self, o: V2<R>) -> V2<R> {
        V2::new(self.x + o.x, self.y + o.y)
    }
}

impl<R: Real> AddAssign for V2<R> {
    #[inline]
    fn add_assign(&mut self, o: V2<R>) {
        self.x += o.x;
        self.y += o.y;
    }
}

impl<R: Real> Sub for V2<R> {
    type Output = V2<R>;
    #[inline]
    fn sub(self, o: V2<R>) -> V2<R> {
        V2::new(self.x - o.x, self.y - o.y)
    }
}

impl<R: Real> SubAssign for V2<R> {
    #[inline]
    fn sub_assign(&mut self, o: V2<R>) {
        self.x -= o.x;
        self.y -= o.y;
    }
}

impl<R: Real> Mul<R> for V2<R> {
    type Output = V2<R>;
    #[inline]
    fn mul(self, k: R) -> V2<R> {
        V2::new(self.x * k, self.y * k)
    }
}

impl<R: Real> Neg for V2<R> {
    type Output = V2<R>;
    #[inline]
    fn neg(self) -> V2<R> {
        V2::new(-self.x, -self.y)
    }
}
