//! Unit quaternions for the body-to-world attitude: uniform random draws on SO(3), rotation vectors,
//! shortest-path interpolation.

use super::noise::Rng;
use super::vec3::{V3, cross, dot, norm, scale};

/// A unit quaternion `w + x i + y j + z k`, rotating body vectors into the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quat {
    /// Scalar part.
    pub w: f64,
    /// Vector part.
    pub v: V3,
}

impl Quat {
    /// No rotation.
    pub const IDENTITY: Self = Self { w: 1.0, v: [0.0; 3] };

    /// Uniform on SO(3) (Shoemake's method).
    pub fn random(rng: &mut Rng) -> Self {
        let (u1, u2, u3) = (rng.uniform(), rng.uniform(), rng.uniform());
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let (t2, t3) = (core::f64::consts::TAU * u2, core::f64::consts::TAU * u3);
        Self { w: b * t3.cos(), v: [a * t2.sin(), a * t2.cos(), b * t3.sin()] }
    }

    /// The rotation by `|r|` radians about `r`.
    pub fn from_rotvec(r: V3) -> Self {
        let angle = norm(r);
        if angle < 1e-12 {
            return Self { w: 1.0, v: scale(r, 0.5) }.normalised();
        }
        let half = 0.5 * angle;
        Self { w: half.cos(), v: scale(r, half.sin() / angle) }
    }

    /// Hamilton product `self * other`: the rotation `other` followed by `self`.
    pub fn then_after(self, o: Self) -> Self {
        let c = cross(self.v, o.v);
        Self {
            w: self.w * o.w - dot(self.v, o.v),
            v: [
                self.w * o.v[0] + o.w * self.v[0] + c[0],
                self.w * o.v[1] + o.w * self.v[1] + c[1],
                self.w * o.v[2] + o.w * self.v[2] + c[2],
            ],
        }
    }

    /// The inverse rotation.
    pub fn conj(self) -> Self {
        Self { w: self.w, v: scale(self.v, -1.0) }
    }

    /// Rescaled to unit norm.
    pub fn normalised(self) -> Self {
        let n = (self.w * self.w + dot(self.v, self.v)).sqrt();
        Self { w: self.w / n, v: scale(self.v, 1.0 / n) }
    }

    /// Rotates `a` (body to world).
    pub fn rotate(self, a: V3) -> V3 {
        let t = scale(cross(self.v, a), 2.0);
        let u = cross(self.v, t);
        [a[0] + self.w * t[0] + u[0], a[1] + self.w * t[1] + u[1], a[2] + self.w * t[2] + u[2]]
    }

    /// Rotates `a` back (world to body).
    pub fn rotate_inv(self, a: V3) -> V3 {
        self.conj().rotate(a)
    }

    /// The rotation vector of `self` (angle times unit axis, angle in `[0, pi]`).
    pub fn to_rotvec(self) -> V3 {
        let q = if self.w < 0.0 { Self { w: -self.w, v: scale(self.v, -1.0) } } else { self };
        let s = norm(q.v);
        if s < 1e-12 {
            return scale(q.v, 2.0);
        }
        scale(q.v, 2.0 * s.atan2(q.w) / s)
    }

    /// Shortest-path spherical interpolation from `self` (`s = 0`) to `to` (`s = 1`).
    pub fn slerp(self, to: Self, s: f64) -> Self {
        let delta = self.conj().then_after(to).to_rotvec();
        self.then_after(Self::from_rotvec(scale(delta, s))).normalised()
    }
}
