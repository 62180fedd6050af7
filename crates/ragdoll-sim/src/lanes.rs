//! Vectors and quaternions four to an instruction: one value per lane of an `f32x4`
//! (structure of arrays), for the solvers that step four independent constraints at once
//! (the multibody's contact bundles, `rigid::contact_wide`; the particle method's joints
//! of four figures, `particle::joint_lanes`).
//!
//! Every operation here is lane by lane — no sum across lanes, no shuffle — so a lane's
//! result is the same bits whatever the other lanes hold: a constraint solved in a lane
//! gets the same numbers whichever constraints share its instruction, or none.

use glam::{Mat3, Quat, Vec3};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};
use wide::f32x4;

/// Values per `f32x4`.
pub(crate) const LANES: usize = 4;

/// `f(k)` for each lane as an `f32x4`.
#[inline]
pub(crate) fn f4(f: impl Fn(usize) -> f32) -> f32x4 {
    f32x4::new(std::array::from_fn(f))
}

/// Four `Vec3`s, one per lane, stored as three `f32x4`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Vec3x4 {
    pub x: f32x4,
    pub y: f32x4,
    pub z: f32x4,
}

impl Vec3x4 {
    /// The vectors `f(0) … f(3)` in the four lanes.
    #[inline]
    pub fn from_fn(f: impl Fn(usize) -> Vec3) -> Vec3x4 {
        let v: [Vec3; LANES] = std::array::from_fn(f);
        Vec3x4 {
            x: f32x4::new([v[0].x, v[1].x, v[2].x, v[3].x]),
            y: f32x4::new([v[0].y, v[1].y, v[2].y, v[3].y]),
            z: f32x4::new([v[0].z, v[1].z, v[2].z, v[3].z]),
        }
    }

    /// Lane `k`.
    #[inline]
    pub fn lane(&self, k: usize) -> Vec3 {
        Vec3::new(
            self.x.as_array()[k],
            self.y.as_array()[k],
            self.z.as_array()[k],
        )
    }

    /// Dot product per lane, `x + y + z` in that order.
    #[inline]
    pub fn dot(self, o: Vec3x4) -> f32x4 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Squared length per lane.
    #[inline]
    pub fn length_squared(self) -> f32x4 {
        self.dot(self)
    }

    /// Cross product per lane.
    #[inline]
    pub fn cross(self, o: Vec3x4) -> Vec3x4 {
        Vec3x4 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    /// glam's `Vec3A::cross` per lane: `a_y b_z − b_y a_z` (and so on) with the second
    /// product subtracted by a fused multiply–subtract where the target has one (x86-64
    /// with FMA), as glam's SSE2 cross does, and by a product and a subtraction
    /// otherwise. [`Vec3x4::cross`] is glam's `Vec3::cross`, never fused.
    #[inline]
    pub fn cross_a(self, o: Vec3x4) -> Vec3x4 {
        Vec3x4 {
            x: o.y.mul_neg_add(self.z, self.y * o.z),
            y: o.z.mul_neg_add(self.x, self.z * o.x),
            z: o.x.mul_neg_add(self.y, self.x * o.y),
        }
    }

    /// Component-wise product.
    #[inline]
    pub fn mul_elem(self, o: Vec3x4) -> Vec3x4 {
        Vec3x4 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }

    /// `a` where `mask` is set, else `b` (a mask from the `simd_*` comparisons).
    #[inline]
    pub fn select(mask: f32x4, a: Vec3x4, b: Vec3x4) -> Vec3x4 {
        Vec3x4 {
            x: mask.select(a.x, b.x),
            y: mask.select(a.y, b.y),
            z: mask.select(a.z, b.z),
        }
    }
}

impl Add for Vec3x4 {
    type Output = Vec3x4;
    #[inline]
    fn add(self, o: Vec3x4) -> Vec3x4 {
        Vec3x4 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for Vec3x4 {
    type Output = Vec3x4;
    #[inline]
    fn sub(self, o: Vec3x4) -> Vec3x4 {
        Vec3x4 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Neg for Vec3x4 {
    type Output = Vec3x4;
    #[inline]
    fn neg(self) -> Vec3x4 {
        Vec3x4 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl Mul<f32x4> for Vec3x4 {
    type Output = Vec3x4;
    #[inline]
    fn mul(self, s: f32x4) -> Vec3x4 {
        Vec3x4 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl AddAssign for Vec3x4 {
    #[inline]
    fn add_assign(&mut self, o: Vec3x4) {
        *self = *self + o;
    }
}

impl SubAssign for Vec3x4 {
    #[inline]
    fn sub_assign(&mut self, o: Vec3x4) {
        *self = *self - o;
    }
}

/// Four 3×3 matrices, one per lane, by columns.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Mat3x4 {
    pub cols: [Vec3x4; 3],
}

impl Mat3x4 {
    /// The matrices `f(0) … f(3)` in the four lanes.
    #[inline]
    pub fn from_fn(f: impl Fn(usize) -> Mat3) -> Mat3x4 {
        let m: [Mat3; LANES] = std::array::from_fn(f);
        Mat3x4 {
            cols: [
                Vec3x4::from_fn(|k| m[k].x_axis),
                Vec3x4::from_fn(|k| m[k].y_axis),
                Vec3x4::from_fn(|k| m[k].z_axis),
            ],
        }
    }

    /// The cross-product matrices of four vectors, `skew(a) b = a × b` in each lane: the
    /// columns `(0, a_z, −a_y)`, `(−a_z, 0, a_x)`, `(a_y, −a_x, 0)`, zeros included, as
    /// the scalar forms build them.
    #[inline]
    pub fn skew(a: Vec3x4) -> Mat3x4 {
        let zero = f32x4::ZERO;
        let col = |x, y, z| Vec3x4 { x, y, z };
        Mat3x4 {
            cols: [
                col(zero, a.z, -a.y),
                col(-a.z, zero, a.x),
                col(a.y, -a.x, zero),
            ],
        }
    }

    /// Lane `k`.
    #[inline]
    pub fn lane(&self, k: usize) -> Mat3 {
        Mat3::from_cols(
            self.cols[0].lane(k),
            self.cols[1].lane(k),
            self.cols[2].lane(k),
        )
    }

    /// The transpose in each lane (data movement only).
    #[inline]
    pub fn transpose(self) -> Mat3x4 {
        let [a, b, c] = self.cols;
        Mat3x4 {
            cols: [
                Vec3x4 {
                    x: a.x,
                    y: b.x,
                    z: c.x,
                },
                Vec3x4 {
                    x: a.y,
                    y: b.y,
                    z: c.y,
                },
                Vec3x4 {
                    x: a.z,
                    y: b.z,
                    z: c.z,
                },
            ],
        }
    }
}

impl Mul for Mat3x4 {
    type Output = Mat3x4;
    /// Column by column, as glam's `Mat3A * Mat3A`.
    #[inline]
    fn mul(self, o: Mat3x4) -> Mat3x4 {
        Mat3x4 {
            cols: o.cols.map(|c| self * c),
        }
    }
}

impl Mul<Vec3x4> for Mat3x4 {
    type Output = Vec3x4;
    /// `x_axis v.x + y_axis v.y + z_axis v.z`, summed in glam's order.
    #[inline]
    fn mul(self, v: Vec3x4) -> Vec3x4 {
        let [c0, c1, c2] = self.cols;
        c0 * v.x + c1 * v.y + c2 * v.z
    }
}

/// Four quaternions `(x, y, z, w)`, one per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Quatx4 {
    pub v: Vec3x4,
    pub w: f32x4,
}

impl Quatx4 {
    /// The quaternions `f(0) … f(3)` in the four lanes.
    #[inline]
    pub fn from_fn(f: impl Fn(usize) -> Quat) -> Quatx4 {
        let q: [Quat; LANES] = std::array::from_fn(f);
        Quatx4 {
            v: Vec3x4 {
                x: f32x4::new([q[0].x, q[1].x, q[2].x, q[3].x]),
                y: f32x4::new([q[0].y, q[1].y, q[2].y, q[3].y]),
                z: f32x4::new([q[0].z, q[1].z, q[2].z, q[3].z]),
            },
            w: f32x4::new([q[0].w, q[1].w, q[2].w, q[3].w]),
        }
    }

    /// Lane `k`.
    #[inline]
    pub fn lane(&self, k: usize) -> Quat {
        let v = self.v.lane(k);
        Quat::from_xyzw(v.x, v.y, v.z, self.w.as_array()[k])
    }

    /// The conjugate, the inverse of a unit quaternion.
    #[inline]
    pub fn conjugate(self) -> Quatx4 {
        Quatx4 {
            v: -self.v,
            w: self.w,
        }
    }

    /// `v` rotated by the unit quaternion: `v + w t + u × t` with `t = 2 u × v`.
    #[inline]
    pub fn rotate(self, v: Vec3x4) -> Vec3x4 {
        let t = self.v.cross(v) * f32x4::splat(2.0);
        v + t * self.w + self.v.cross(t)
    }

    /// `v` rotated by the unit quaternion with glam's `Quat * Vec3` operations, in its
    /// order: `v (w² − u·u) + u (2 v·u) + (u × v)(2w)`, the cross product glam's
    /// `Vec3A` one, so a lane holds glam's bits.
    #[inline]
    pub fn rotate_as_glam(self, v: Vec3x4) -> Vec3x4 {
        let two = f32x4::splat(2.0);
        let u = self.v;
        (v * (self.w * self.w - u.dot(u)) + u * (v.dot(u) * two)) + u.cross_a(v) * (self.w * two)
    }

    /// `v` rotated by the inverse of the unit quaternion.
    #[inline]
    pub fn inverse_rotate(self, v: Vec3x4) -> Vec3x4 {
        self.conjugate().rotate(v)
    }

    /// The Hamilton product `self · o`.
    #[inline]
    pub fn mul_quat(self, o: Quatx4) -> Quatx4 {
        let (a, b) = (self.v, o.v);
        Quatx4 {
            v: b * self.w + a * o.w + a.cross(b),
            w: self.w * o.w - a.dot(b),
        }
    }

    /// Squared norm.
    #[inline]
    pub fn length_squared(self) -> f32x4 {
        self.v.length_squared() + self.w * self.w
    }

    /// Every component times `s`.
    #[inline]
    pub fn scale(self, s: f32x4) -> Quatx4 {
        Quatx4 {
            v: self.v * s,
            w: self.w * s,
        }
    }

    /// Component-wise sum.
    #[inline]
    pub fn add(self, o: Quatx4) -> Quatx4 {
        Quatx4 {
            v: self.v + o.v,
            w: self.w + o.w,
        }
    }

    /// `a` where `mask` is set, else `b`.
    #[inline]
    pub fn select(mask: f32x4, a: Quatx4, b: Quatx4) -> Quatx4 {
        Quatx4 {
            v: Vec3x4::select(mask, a.v, b.v),
            w: mask.select(a.w, b.w),
        }
    }

    /// `q + ½ q [θ, 0]`, normalised: the XPBD orientation update for a small turn given
    /// in the body frame (`particle::bone::rotate_local`, lane by lane). `|r|² = 1 + d`
    /// is scaled by the series `1 − d/2 + 3d²/8` for `|d| < 4e-3`, exactly otherwise.
    #[inline]
    pub fn rotate_local(self, theta: Vec3x4) -> Quatx4 {
        let half = f32x4::splat(0.5);
        let turned = Quatx4 {
            v: theta * self.w + self.v.cross(theta),
            w: -self.v.dot(theta),
        };
        let r = self.add(turned.scale(half));
        let n2 = r.length_squared();
        let d = n2 - f32x4::ONE;
        let series = f32x4::ONE - d * (half - f32x4::splat(0.375) * d);
        let exact = f32x4::ONE / n2.sqrt();
        r.scale(d.abs().simd_lt(f32x4::splat(4e-3)).select(series, exact))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-6 * (1.0 + b.length())
    }

    /// The lane operations are glam's, lane by lane (to rounding): rotations, their
    /// inverses, products and the XPBD update, on four different quaternions.
    #[test]
    fn lanes_agree_with_glam() {
        let qs = [
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
            Quat::IDENTITY,
            Quat::from_axis_angle(Vec3::new(0.6, 0.0, 0.8), 2.9),
            Quat::from_euler(glam::EulerRot::ZYX, -2.0, 0.4, 0.1),
        ];
        let vs = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-0.2, 0.0, 0.5),
            Vec3::X,
            Vec3::new(0.01, -4.0, 0.3),
        ];
        let (q, v) = (Quatx4::from_fn(|k| qs[k]), Vec3x4::from_fn(|k| vs[k]));
        let o = Quatx4::from_fn(|k| qs[(k + 1) % 4]);
        let theta = Vec3x4::from_fn(|k| vs[k] * 1e-2);
        for k in 0..LANES {
            assert!(close(q.rotate(v).lane(k), qs[k] * vs[k]), "lane {k}");
            assert!(close(q.inverse_rotate(v).lane(k), qs[k].inverse() * vs[k]));
            let p = q.mul_quat(o).lane(k) - qs[k] * qs[(k + 1) % 4];
            assert!(p.length() < 1e-6, "product, lane {k}");
            let t = vs[k] * 1e-2;
            let dq = qs[k] * Quat::from_xyzw(t.x, t.y, t.z, 0.0);
            let exact = (qs[k] + dq * 0.5).normalize();
            assert!((q.rotate_local(theta).lane(k) - exact).length() < 1e-6);
        }
    }
}
