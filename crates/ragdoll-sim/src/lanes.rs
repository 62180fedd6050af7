//! Vectors, matrices and quaternions over a lane type: `f32` (one value) or
//! `wide::f32x4` (four values, one per lane, structure of arrays). The solvers write a
//! constraint once, generic over [`Real`], and run it one at a time (`R = f32`) or four
//! independent constraints to an instruction (`R = f32x4`: the multibody's contact and
//! joint bundles, the particle method's joints of four figures).
//!
//! Every operation is lane by lane — no sum across lanes, no shuffle, no fused
//! multiply–add — and each `f32x4` operation is the IEEE-754 single-precision operation
//! of its `f32` twin (add, sub, mul, div, sqrt are correctly rounded in both; min/max,
//! compare and select are defined below by the same comparison). So a lane's result is
//! the same bits whatever the other lanes hold, and the `f32` instantiation of a generic
//! kernel gives exactly the bits of any lane of its `f32x4` instantiation, on every
//! target. (The one exception is [`V3::cross_a`], glam's fused cross, kept for code that
//! must reproduce glam.)

use glam::{Mat3, Quat, Vec3, Vec3A, Vec4};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Not, Sub, SubAssign};
use wide::f32x4;

/// Values per `f32x4`.
pub(crate) const LANES: usize = 4;

/// `f(k)` for each lane as an `f32x4`.
#[inline]
pub(crate) fn f4(f: impl Fn(usize) -> f32) -> f32x4 {
    f32x4::new(std::array::from_fn(f))
}

/// A lane type: one `f32` or several in lockstep. Arithmetic is the operator traits;
/// the rest is here. For `f32x4` a mask is an `f32x4` of all-ones / all-zeros lanes (as
/// `wide`'s comparisons return), for `f32` a `bool`.
#[allow(
    dead_code,
    reason = "the whole lane vocabulary, for kernels generic over it; each uses a part"
)]
pub(crate) trait Real:
    Copy
    + Default
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// The result of a comparison, one truth value per lane.
    type Mask: Copy
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;
    /// Values held (1 or [`LANES`]).
    const WIDTH: usize;
    const ZERO: Self;
    const ONE: Self;
    /// `x` in every lane.
    fn splat(x: f32) -> Self;
    /// `f(k)` in lane `k`, for `k < WIDTH`.
    fn from_fn(f: impl Fn(usize) -> f32) -> Self;
    /// Lane `k` (`k < WIDTH`).
    fn lane(self, k: usize) -> f32;
    /// Correctly rounded square root per lane.
    fn sqrt(self) -> Self;
    /// `|x|` per lane (the sign bit cleared).
    fn abs(self) -> Self;
    /// `self < o ? self : o` per lane (so `o` when either is NaN).
    fn min(self, o: Self) -> Self;
    /// `self > o ? self : o` per lane (so `o` when either is NaN).
    fn max(self, o: Self) -> Self;
    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    /// `a` where `m` holds, else `b`, per lane.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Whether `m` holds in any lane.
    fn any(m: Self::Mask) -> bool;
    /// Whether `m` holds in every lane.
    fn all(m: Self::Mask) -> bool;
    /// The vectors `v[0] … v[WIDTH − 1]` in the lanes (the rest of `v` unread).
    fn v3_from_lanes(v: [Vec3A; LANES]) -> V3<Self>;
    /// The lanes of `v` as vectors (the last `LANES − WIDTH` zero).
    fn v3_to_lanes(v: V3<Self>) -> [Vec3A; LANES];
}

impl Real for f32 {
    type Mask = bool;
    const WIDTH: usize = 1;
    const ZERO: f32 = 0.0;
    const ONE: f32 = 1.0;
    #[inline]
    fn splat(x: f32) -> f32 {
        x
    }
    #[inline]
    fn from_fn(f: impl Fn(usize) -> f32) -> f32 {
        f(0)
    }
    #[inline]
    fn lane(self, _k: usize) -> f32 {
        self
    }
    #[inline]
    fn sqrt(self) -> f32 {
        f32::sqrt(self)
    }
    #[inline]
    fn abs(self) -> f32 {
        f32::abs(self)
    }
    #[inline]
    fn min(self, o: f32) -> f32 {
        if self < o { self } else { o }
    }
    #[inline]
    fn max(self, o: f32) -> f32 {
        if self > o { self } else { o }
    }
    #[inline]
    fn lt(self, o: f32) -> bool {
        self < o
    }
    #[inline]
    fn le(self, o: f32) -> bool {
        self <= o
    }
    #[inline]
    fn gt(self, o: f32) -> bool {
        self > o
    }
    #[inline]
    fn ge(self, o: f32) -> bool {
        self >= o
    }
    #[inline]
    fn select(m: bool, a: f32, b: f32) -> f32 {
        if m { a } else { b }
    }
    #[inline]
    fn any(m: bool) -> bool {
        m
    }
    #[inline]
    fn all(m: bool) -> bool {
        m
    }
    #[inline]
    fn v3_from_lanes(v: [Vec3A; LANES]) -> V3<f32> {
        V3 {
            x: v[0].x,
            y: v[0].y,
            z: v[0].z,
        }
    }
    #[inline]
    fn v3_to_lanes(v: V3<f32>) -> [Vec3A; LANES] {
        [
            Vec3A::new(v.x, v.y, v.z),
            Vec3A::ZERO,
            Vec3A::ZERO,
            Vec3A::ZERO,
        ]
    }
}

impl Real for f32x4 {
    type Mask = f32x4;
    const WIDTH: usize = LANES;
    const ZERO: f32x4 = f32x4::ZERO;
    const ONE: f32x4 = f32x4::ONE;
    #[inline]
    fn splat(x: f32) -> f32x4 {
        f32x4::splat(x)
    }
    #[inline]
    fn from_fn(f: impl Fn(usize) -> f32) -> f32x4 {
        f4(f)
    }
    #[inline]
    fn lane(self, k: usize) -> f32 {
        self.as_array()[k]
    }
    #[inline]
    fn sqrt(self) -> f32x4 {
        f32x4::sqrt(self)
    }
    #[inline]
    fn abs(self) -> f32x4 {
        f32x4::abs(self)
    }
    #[inline]
    fn min(self, o: f32x4) -> f32x4 {
        self.simd_lt(o).select(self, o)
    }
    #[inline]
    fn max(self, o: f32x4) -> f32x4 {
        self.simd_gt(o).select(self, o)
    }
    #[inline]
    fn lt(self, o: f32x4) -> f32x4 {
        self.simd_lt(o)
    }
    #[inline]
    fn le(self, o: f32x4) -> f32x4 {
        self.simd_le(o)
    }
    #[inline]
    fn gt(self, o: f32x4) -> f32x4 {
        self.simd_gt(o)
    }
    #[inline]
    fn ge(self, o: f32x4) -> f32x4 {
        self.simd_ge(o)
    }
    #[inline]
    fn select(m: f32x4, a: f32x4, b: f32x4) -> f32x4 {
        m.select(a, b)
    }
    #[inline]
    fn any(m: f32x4) -> bool {
        m.any()
    }
    #[inline]
    fn all(m: f32x4) -> bool {
        m.all()
    }
    /// A 4×4 transpose of the vectors as rows (their fourth lane is dropped with the
    /// fourth row): whole registers moved, no lane read one at a time.
    #[inline]
    fn v3_from_lanes(v: [Vec3A; LANES]) -> Vec3x4 {
        let [x, y, z, _] = f32x4::transpose(v.map(|v| f32x4::new(v.extend(0.0).to_array())));
        V3 { x, y, z }
    }
    /// The transpose back: rows `x, y, z, 0` become the lanes' vectors.
    #[inline]
    fn v3_to_lanes(v: Vec3x4) -> [Vec3A; LANES] {
        f32x4::transpose([v.x, v.y, v.z, f32x4::ZERO])
            .map(|l| Vec3A::from_vec4(Vec4::from_array(*l.as_array())))
    }
}

/// The vectors `f(0) … f(R::WIDTH − 1)`, each evaluated once, for gathering into lanes.
#[inline]
fn gather<T: Copy + Default, R: Real>(f: impl Fn(usize) -> T) -> [T; LANES] {
    std::array::from_fn(|k| if k < R::WIDTH { f(k) } else { T::default() })
}

/// A 3-vector per lane, stored as three lane values (`V3<f32x4>`: four `Vec3`s).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct V3<R> {
    pub x: R,
    pub y: R,
    pub z: R,
}

/// Four `Vec3`s, one per lane.
pub(crate) type Vec3x4 = V3<f32x4>;

impl<R: Real> V3<R> {
    /// `(x, y, z)` in every lane.
    #[allow(dead_code, reason = "part of the lane vocabulary")]
    #[inline]
    pub fn splat(v: Vec3) -> V3<R> {
        V3 {
            x: R::splat(v.x),
            y: R::splat(v.y),
            z: R::splat(v.z),
        }
    }

    /// The vectors `f(0) … f(WIDTH − 1)` in the lanes (`f` called once per lane).
    #[inline]
    pub fn from_fn(f: impl Fn(usize) -> Vec3) -> V3<R> {
        let v = gather::<Vec3, R>(f);
        V3 {
            x: R::from_fn(|k| v[k].x),
            y: R::from_fn(|k| v[k].y),
            z: R::from_fn(|k| v[k].z),
        }
    }

    /// Lane `k`.
    #[inline]
    pub fn lane(&self, k: usize) -> Vec3 {
        Vec3::new(self.x.lane(k), self.y.lane(k), self.z.lane(k))
    }

    /// Dot product per lane, `x + y + z` in that order.
    #[inline]
    pub fn dot(self, o: V3<R>) -> R {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Squared length per lane.
    #[inline]
    pub fn length_squared(self) -> R {
        self.dot(self)
    }

    /// Cross product per lane (glam's `Vec3::cross`, never fused).
    #[inline]
    pub fn cross(self, o: V3<R>) -> V3<R> {
        V3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    /// Component-wise product.
    #[inline]
    pub fn mul_elem(self, o: V3<R>) -> V3<R> {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }

    /// `a` where `mask` is set, else `b` (a mask from the comparisons of [`Real`]).
    #[inline]
    pub fn select(mask: R::Mask, a: V3<R>, b: V3<R>) -> V3<R> {
        V3 {
            x: R::select(mask, a.x, b.x),
            y: R::select(mask, a.y, b.y),
            z: R::select(mask, a.z, b.z),
        }
    }
}

impl V3<f32x4> {
    /// glam's `Vec3A::cross` per lane: `a_y b_z − b_y a_z` (and so on) with the second
    /// product subtracted by a fused multiply–subtract where the target has one (x86-64
    /// with FMA), as glam's SSE2 cross does, and by a product and a subtraction
    /// otherwise. [`V3::cross`] is glam's `Vec3::cross`, never fused. Not generic: it
    /// exists to reproduce glam, not an `f32` twin.
    #[inline]
    pub fn cross_a(self, o: Vec3x4) -> Vec3x4 {
        Vec3x4 {
            x: o.y.mul_neg_add(self.z, self.y * o.z),
            y: o.z.mul_neg_add(self.x, self.z * o.x),
            z: o.x.mul_neg_add(self.y, self.x * o.y),
        }
    }
}

impl<R: Real> Add for V3<R> {
    type Output = V3<R>;
    #[inline]
    fn add(self, o: V3<R>) -> V3<R> {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<R: Real> Sub for V3<R> {
    type Output = V3<R>;
    #[inline]
    fn sub(self, o: V3<R>) -> V3<R> {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<R: Real> Neg for V3<R> {
    type Output = V3<R>;
    #[inline]
    fn neg(self) -> V3<R> {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl<R: Real> Mul<R> for V3<R> {
    type Output = V3<R>;
    #[inline]
    fn mul(self, s: R) -> V3<R> {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl<R: Real> AddAssign for V3<R> {
    #[inline]
    fn add_assign(&mut self, o: V3<R>) {
        *self = *self + o;
    }
}

impl<R: Real> SubAssign for V3<R> {
    #[inline]
    fn sub_assign(&mut self, o: V3<R>) {
        *self = *self - o;
    }
}

/// A 3×3 matrix per lane, by columns.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct M3<R> {
    pub cols: [V3<R>; 3],
}

/// Four 3×3 matrices, one per lane.
pub(crate) type Mat3x4 = M3<f32x4>;

impl<R: Real> M3<R> {
    /// The matrices `f(0) … f(WIDTH − 1)` in the lanes (`f` called once per lane).
    #[inline]
    pub fn from_fn(f: impl Fn(usize) -> Mat3) -> M3<R> {
        let m = gather::<Mat3, R>(f);
        M3 {
            cols: [
                V3::from_fn(|k| m[k].x_axis),
                V3::from_fn(|k| m[k].y_axis),
                V3::from_fn(|k| m[k].z_axis),
            ],
        }
    }

    /// The cross-product matrices, `skew(a) b = a × b` in each lane: the columns
    /// `(0, a_z, −a_y)`, `(−a_z, 0, a_x)`, `(a_y, −a_x, 0)`, zeros included, as the
    /// scalar forms build them.
    #[inline]
    pub fn skew(a: V3<R>) -> M3<R> {
        let zero = R::ZERO;
        let col = |x, y, z| V3 { x, y, z };
        M3 {
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
    pub fn transpose(self) -> M3<R> {
        let [a, b, c] = self.cols;
        M3 {
            cols: [
                V3 {
                    x: a.x,
                    y: b.x,
                    z: c.x,
                },
                V3 {
                    x: a.y,
                    y: b.y,
                    z: c.y,
                },
                V3 {
                    x: a.z,
                    y: b.z,
                    z: c.z,
                },
            ],
        }
    }
}

impl<R: Real> Mul for M3<R> {
    type Output = M3<R>;
    /// Column by column, as glam's `Mat3A * Mat3A`.
    #[inline]
    fn mul(self, o: M3<R>) -> M3<R> {
        M3 {
            cols: o.cols.map(|c| self * c),
        }
    }
}

impl<R: Real> Mul<V3<R>> for M3<R> {
    type Output = V3<R>;
    /// `x_axis v.x + y_axis v.y + z_axis v.z`, summed in glam's order.
    #[inline]
    fn mul(self, v: V3<R>) -> V3<R> {
        let [c0, c1, c2] = self.cols;
        c0 * v.x + c1 * v.y + c2 * v.z
    }
}

/// A quaternion `(x, y, z, w)` per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Q<R> {
    pub v: V3<R>,
    pub w: R,
}

/// Four quaternions, one per lane.
pub(crate) type Quatx4 = Q<f32x4>;

impl<R: Real> Q<R> {
    /// The quaternions `f(0) … f(WIDTH − 1)` in the lanes (`f` called once per lane).
    #[inline]
    pub fn from_fn(f: impl Fn(usize) -> Quat) -> Q<R> {
        let q = gather::<Quat, R>(f);
        Q {
            v: V3 {
                x: R::from_fn(|k| q[k].x),
                y: R::from_fn(|k| q[k].y),
                z: R::from_fn(|k| q[k].z),
            },
            w: R::from_fn(|k| q[k].w),
        }
    }

    /// Lane `k`.
    #[inline]
    pub fn lane(&self, k: usize) -> Quat {
        let v = self.v.lane(k);
        Quat::from_xyzw(v.x, v.y, v.z, self.w.lane(k))
    }

    /// The conjugate, the inverse of a unit quaternion.
    #[inline]
    pub fn conjugate(self) -> Q<R> {
        Q {
            v: -self.v,
            w: self.w,
        }
    }

    /// `v` rotated by the unit quaternion: `v + w t + u × t` with `t = 2 u × v`.
    #[inline]
    pub fn rotate(self, v: V3<R>) -> V3<R> {
        let t = self.v.cross(v) * R::splat(2.0);
        v + t * self.w + self.v.cross(t)
    }

    /// `v` rotated by the inverse of the unit quaternion.
    #[inline]
    pub fn inverse_rotate(self, v: V3<R>) -> V3<R> {
        self.conjugate().rotate(v)
    }

    /// The Hamilton product `self · o`.
    #[inline]
    pub fn mul_quat(self, o: Q<R>) -> Q<R> {
        let (a, b) = (self.v, o.v);
        Q {
            v: b * self.w + a * o.w + a.cross(b),
            w: self.w * o.w - a.dot(b),
        }
    }

    /// Squared norm.
    #[inline]
    pub fn length_squared(self) -> R {
        self.v.length_squared() + self.w * self.w
    }

    /// Every component times `s`.
    #[inline]
    pub fn scale(self, s: R) -> Q<R> {
        Q {
            v: self.v * s,
            w: self.w * s,
        }
    }

    /// Component-wise sum.
    #[inline]
    pub fn add(self, o: Q<R>) -> Q<R> {
        Q {
            v: self.v + o.v,
            w: self.w + o.w,
        }
    }

    /// `a` where `mask` is set, else `b`.
    #[inline]
    pub fn select(mask: R::Mask, a: Q<R>, b: Q<R>) -> Q<R> {
        Q {
            v: V3::select(mask, a.v, b.v),
            w: R::select(mask, a.w, b.w),
        }
    }

    /// `q + ½ q [θ, 0]`, normalised: the XPBD orientation update for a small turn given
    /// in the body frame (`particle::bone::rotate_local`, lane by lane). `|r|² = 1 + d`
    /// is scaled by the series `1 − d/2 + 3d²/8` for `|d| < 4e-3`, exactly otherwise.
    #[inline]
    pub fn rotate_local(self, theta: V3<R>) -> Q<R> {
        let half = R::splat(0.5);
        let turned = Q {
            v: theta * self.w + self.v.cross(theta),
            w: -self.v.dot(theta),
        };
        let r = self.add(turned.scale(half));
        let n2 = r.length_squared();
        let d = n2 - R::ONE;
        let series = R::ONE - d * (half - R::splat(0.375) * d);
        let exact = R::ONE / n2.sqrt();
        r.scale(R::select(d.abs().lt(R::splat(4e-3)), series, exact))
    }
}

impl Q<f32x4> {
    /// `v` rotated by the unit quaternion with glam's `Quat * Vec3` operations, in its
    /// order: `v (w² − u·u) + u (2 v·u) + (u × v)(2w)`, the cross product glam's
    /// `Vec3A` one, so a lane holds glam's bits. Not generic, as [`V3::cross_a`].
    #[inline]
    pub fn rotate_as_glam(self, v: Vec3x4) -> Vec3x4 {
        let two = f32x4::splat(2.0);
        let u = self.v;
        (v * (self.w * self.w - u.dot(u)) + u * (v.dot(u) * two)) + u.cross_a(v) * (self.w * two)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four different rotations and vectors, one per lane.
    fn samples() -> ([Quat; LANES], [Vec3; LANES]) {
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
        (qs, vs)
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-6 * (1.0 + b.length())
    }

    /// The lane operations are glam's, lane by lane (to rounding): rotations, their
    /// inverses, products and the XPBD update, on four different quaternions.
    #[test]
    fn lanes_agree_with_glam() {
        let (qs, vs) = samples();
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

    /// The `f32` instantiation gives exactly the bits of each lane of the `f32x4` one:
    /// a chain of every generic operation on four different inputs, compared bit for bit.
    #[test]
    fn scalar_gives_the_bits_of_each_lane() {
        fn chain<R: Real>(q: Q<R>, v: V3<R>, s: R) -> (Q<R>, V3<R>, R) {
            let m = M3::skew(v) * M3::skew(q.v).transpose();
            let r = q.rotate(m * v) + q.inverse_rotate(v).cross(v) * (s / (s * s + R::ONE));
            let n = r.length_squared().sqrt().max(s.abs()).min(R::splat(3.0));
            let pick = V3::select(r.x.lt(R::ZERO) | s.ge(R::ONE), r, -r);
            let q2 = q.mul_quat(q.conjugate()).rotate_local(v * R::splat(1e-2));
            (Q::select(n.gt(R::ONE), q2, q), pick.mul_elem(r) - v, n)
        }
        let (qs, vs) = samples();
        let ss = [0.7_f32, -2.5, 1.0, 1e-3];
        let (q4, v4, s4) = chain(
            Q::<f32x4>::from_fn(|k| qs[k]),
            V3::<f32x4>::from_fn(|k| vs[k]),
            f4(|k| ss[k]),
        );
        for k in 0..LANES {
            let (q1, v1, s1) = chain(
                Q::<f32>::from_fn(|_| qs[k]),
                V3::<f32>::from_fn(|_| vs[k]),
                ss[k],
            );
            let bits = |q: Quat| q.to_array().map(f32::to_bits);
            assert_eq!(bits(q4.lane(k)), bits(q1.lane(0)), "lane {k}");
            assert_eq!(
                v4.lane(k).to_array().map(f32::to_bits),
                v1.lane(0).to_array().map(f32::to_bits)
            );
            assert_eq!(s4.lane(k).to_bits(), s1.to_bits());
        }
    }
}
