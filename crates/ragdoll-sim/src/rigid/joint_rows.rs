//! The ball joint's and the hinge's rows, written once over a lane type
//! ([`crate::lanes::Real`]): the point constraint, the axis alignment and the
//! one-dimensional angular row of a limit. [`super::joint`] runs them one joint at a time
//! (`R = f32`), [`super::joint_wide`] four joints to an instruction (`R = f32x4`).
//!
//! A lane operation is the `f32` operation on each lane, unfused, so the same code gives
//! the same bits in a lane as one by one, on every target: a world solved in lanes and
//! one solved island by island on other threads agree bit for bit.
//!
//! A kernel reads and writes the velocities of its joints' two bodies ([`Velocities`]),
//! gathered before and written back after; what it would skip one by one (a singular
//! effective mass, a sleeping joint, an inactive row) it masks: the lanes `on` take the
//! update, the others keep their old values by a select.

// `!(k > ε)` as a mask on purpose, as one by one: NaN must skip the row too.

use super::body::BodyStates;
use super::soft::{Softness, StepContext};
use crate::lanes::{M3, Q, Real, V3};
use glam::Vec3;

/// The soft coefficients of a pass in lanes: the joint softness in the biased
/// iterations, [`Softness::RIGID`] in the relax pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Soft<R> {
    pub bias_rate: R,
    pub mass_scale: R,
    pub impulse_scale: R,
    pub inv_h: R,
    pub use_bias: bool,
}

impl<R: Real> Soft<R> {
    #[inline]
    pub fn new(ctx: &StepContext, use_bias: bool) -> Soft<R> {
        let s = if use_bias { ctx.joint } else { Softness::RIGID };
        Soft {
            bias_rate: R::splat(s.bias_rate),
            mass_scale: R::splat(s.mass_scale),
            impulse_scale: R::splat(s.impulse_scale),
            inv_h: R::splat(ctx.inv_h),
            use_bias,
        }
    }
}

/// The velocities of the lanes' bodies: linear and angular of a and of b.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Velocities<R> {
    pub va: V3<R>,
    pub wa: V3<R>,
    pub vb: V3<R>,
    pub wb: V3<R>,
}

impl Velocities<f32> {
    /// The velocities of bodies `a` and `b`.
    #[inline]
    pub fn of(s: &BodyStates, a: usize, b: usize) -> Velocities<f32> {
        let v = |x: glam::Vec3A| V3 {
            x: x.x,
            y: x.y,
            z: x.z,
        };
        Velocities {
            va: v(s.lin_vel[a]),
            wa: v(s.ang_vel[a]),
            vb: v(s.lin_vel[b]),
            wb: v(s.ang_vel[b]),
        }
    }

    /// Writes the velocities back to `a` and `b`, each only if its inverse mass is
    /// positive: static and sleeping bodies keep theirs (as in the lanes,
    /// `BodyStates::set_velocities_x4`).
    #[inline]
    pub fn store(&self, s: &mut BodyStates, a: usize, b: usize) {
        if s.inv_mass[a] > 0.0 {
            s.lin_vel[a] = self.va.lane(0).into();
            s.ang_vel[a] = self.wa.lane(0).into();
        }
        if s.inv_mass[b] > 0.0 {
            s.lin_vel[b] = self.vb.lane(0).into();
            s.ang_vel[b] = self.wb.lane(0).into();
        }
    }
}

/// The poses and world inverse inertias the rows are prepared on.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pose<R> {
    pub rot_a: Q<R>,
    pub rot_b: Q<R>,
    pub com_a: V3<R>,
    pub com_b: V3<R>,
    pub ia: M3<R>,
    pub ib: M3<R>,
}

impl Pose<f32> {
    /// The pose and inertias of bodies `a` and `b` now.
    #[inline]
    pub fn of(s: &BodyStates, a: usize, b: usize) -> Pose<f32> {
        let v = |x: Vec3| V3 {
            x: x.x,
            y: x.y,
            z: x.z,
        };
        let q = |q: glam::Quat| Q {
            v: V3 {
                x: q.x,
                y: q.y,
                z: q.z,
            },
            w: q.w,
        };
        Pose {
            rot_a: q(s.rot[a]),
            rot_b: q(s.rot[b]),
            com_a: v(s.com[a]),
            com_b: v(s.com[b]),
            ia: inertia(s, a),
            ib: inertia(s, b),
        }
    }
}

/// The world inverse inertia of body `i`.
#[inline]
pub(crate) fn inertia(s: &BodyStates, i: usize) -> M3<f32> {
    let m = &s.inv_inertia[i];
    let v = |c: glam::Vec3A| V3 {
        x: c.x,
        y: c.y,
        z: c.z,
    };
    M3 {
        cols: [v(m.x_axis), v(m.y_axis), v(m.z_axis)],
    }
}

/// A point's response to an impulse on a body of inverse mass `m` and world inverse
/// inertia `ii` at world offset `r`: the turn `T = I⁻¹ r̂` (`Δω = T p`) and the entries
/// `m00, m01, m02, m11, m12, m22` of the point-mass matrix `m⁻¹ 1 − r̂ I⁻¹ r̂ =
/// m⁻¹ 1 + r̂ᵀ T`, whose entry `(j, k)` is `ĉ_j · t_k` with `ĉ_j` the columns of `r̂` and
/// `t_k` those of `T` (symmetric, so half the products of a general one).
#[inline]
pub(crate) fn point_response<R: Real>(ii: M3<R>, m: R, r: V3<R>) -> (M3<R>, [R; 6]) {
    let [c0, c1, c2] = M3::skew(r).cols;
    let t = point_turn(ii, r).cols;
    let k = [
        m + c0.dot(t[0]),
        c0.dot(t[1]),
        c0.dot(t[2]),
        m + c1.dot(t[1]),
        c1.dot(t[2]),
        m + c2.dot(t[2]),
    ];
    (M3 { cols: t }, k)
}

/// The turn `T = I⁻¹ r̂` of [`point_response`] alone, by the columns `ĉ_k` of `r̂`:
/// `t_k = I⁻¹ ĉ_k`.
#[inline]
pub(crate) fn point_turn<R: Real>(ii: M3<R>, r: V3<R>) -> M3<R> {
    let [c0, c1, c2] = M3::skew(r).cols;
    M3 {
        cols: [ii * c0, ii * c1, ii * c2],
    }
}

/// Inverse of a symmetric 3×3 matrix given by its six entries (as [`point_response`]),
/// by its cofactors, with the mask of the lanes where it is defined (`1e-20 < |det| <
/// ∞`; not where both bodies are static).
#[inline]
pub(crate) fn invert_symmetric<R: Real>(k: [R; 6]) -> (M3<R>, R::Mask) {
    let [a, b, c, d, e, f] = k;
    let (ca, cb, cc) = (d * f - e * e, c * e - b * f, b * e - c * d);
    let det = a * ca + b * cb + c * cc;
    let size = det.abs();
    let ok = size.gt(R::splat(1e-20)) & size.lt(R::splat(f32::INFINITY));
    let inv = R::ONE / det;
    let (cd, ce, cf) = (a * f - c * c, b * c - a * e, a * d - b * b);
    let col = |x, y, z| V3 { x, y, z } * inv;
    (
        M3 {
            cols: [col(ca, cb, cc), col(cb, cd, ce), col(cc, ce, cf)],
        },
        ok,
    )
}

/// Two unit vectors completing the unit `d` to an orthonormal basis (Duff et al. 2017,
/// "Building an orthonormal basis, revisited"), with the sign `s = −1` for `d_z < 0`
/// and `+1` otherwise, so `s + d_z` is never near 0.
#[inline]
pub(crate) fn orthonormal_pair<R: Real>(d: V3<R>) -> (V3<R>, V3<R>) {
    let sign = R::select(d.z.lt(R::ZERO), -R::ONE, R::ONE);
    let a = -R::ONE / (sign + d.z);
    let b = d.x * d.y * a;
    (
        V3 {
            x: R::ONE + sign * d.x * d.x * a,
            y: sign * b,
            z: -sign * d.x,
        },
        V3 {
            x: b,
            y: sign + d.y * d.y * a,
            z: -d.y,
        },
    )
}

/// The ball-and-socket point constraint `p_b − p_a = 0`, three rows solved as a block:
/// `K = (m_a⁻¹ + m_b⁻¹) 1 − r̂_a I_a⁻¹ r̂_a − r̂_b I_b⁻¹ r̂_b`.
///
/// `K⁻¹` depends only on the positions and inertias, which hold still from
/// [`PointRows::prepare`] (after the substep's velocity integration) until the positions
/// are integrated: the substep's biased iterations share one inverse, as Box2D and Jolt
/// share a joint's effective mass between velocity iterations.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PointRows<R: Real> {
    /// World offsets of the anchor from each centre of mass.
    pub ra: V3<R>,
    pub rb: V3<R>,
    /// `p_b − p_a`.
    pub c: V3<R>,
    /// How an impulse `p` on b turns each body, `Δω_b = I_b⁻¹ (r_b × p) = T_b p` and
    /// `Δω_a = −T_a p`: `T = I⁻¹ r̂`, so an iteration applies its impulse with two
    /// matrix–vector products and no cross products.
    pub turn_a: M3<R>,
    pub turn_b: M3<R>,
    pub k_inv: M3<R>,
    /// The live lanes with an invertible `K`.
    pub on: R::Mask,
}

impl<R: Real> PointRows<R> {
    /// Offsets and error on the pose, then [`PointRows::weigh`].
    #[inline]
    pub fn prepare(&mut self, local: [V3<R>; 2], p: &Pose<R>, inv_mass: [R; 2], live: R::Mask) {
        self.place(local, p);
        self.weigh([p.ia, p.ib], inv_mass, live);
    }

    /// The offsets of the anchor `local` (in a's and b's space) and the error on the
    /// pose: all that a joint tree reads of rows whose block it solves itself.
    #[inline]
    pub fn place(&mut self, local: [V3<R>; 2], p: &Pose<R>) {
        self.ra = p.rot_a.rotate(local[0]);
        self.rb = p.rot_b.rotate(local[1]);
        self.c = (p.com_b + self.rb) - (p.com_a + self.ra);
    }

    /// The turns alone for the offsets of the last preparation and these inertias (the
    /// turns of [`PointRows::weigh`]): what applying an impulse reads, for rows whose
    /// `K⁻¹` a joint tree's factorisation stands in for.
    #[inline]
    pub fn turn(&mut self, [ia, ib]: [M3<R>; 2]) {
        self.turn_a = point_turn(ia, self.ra);
        self.turn_b = point_turn(ib, self.rb);
    }

    /// The turns and `K⁻¹` for the offsets of the last preparation and these inertias.
    #[inline]
    pub fn weigh(&mut self, [ia, ib]: [M3<R>; 2], [ma, mb]: [R; 2], live: R::Mask) {
        let (ta, ka) = point_response(ia, ma, self.ra);
        let (tb, kb) = point_response(ib, mb, self.rb);
        self.turn_a = ta;
        self.turn_b = tb;
        let (k_inv, ok) = invert_symmetric(std::array::from_fn(|j| ka[j] + kb[j]));
        self.k_inv = k_inv;
        self.on = live & ok;
    }

    /// Applies `p` on b and `−p` on a in the lanes `on`.
    #[inline]
    pub fn apply(&self, v: &mut Velocities<R>, [ma, mb]: [R; 2], p: V3<R>, on: R::Mask) {
        v.va = V3::select(on, v.va - p * ma, v.va);
        v.wa = V3::select(on, v.wa - self.turn_a * p, v.wa);
        v.vb = V3::select(on, v.vb + p * mb, v.vb);
        v.wb = V3::select(on, v.wb + self.turn_b * p, v.wb);
    }

    /// One soft Gauss–Seidel update of the block in the lanes `on` (within
    /// [`PointRows::on`]):
    /// `p = −s_m K⁻¹ (Ċ + β C) − s_i P` with `Ċ = v_b + ω_b × r_b − v_a − ω_a × r_a`.
    #[inline]
    pub fn solve(
        &self,
        v: &mut Velocities<R>,
        inv_mass: [R; 2],
        impulse: &mut V3<R>,
        soft: &Soft<R>,
        on: R::Mask,
    ) {
        let cdot = (v.vb + v.wb.cross(self.rb)) - (v.va + v.wa.cross(self.ra));
        let p = (self.k_inv * (cdot + self.c * soft.bias_rate)) * -soft.mass_scale
            - *impulse * soft.impulse_scale;
        *impulse = V3::select(on, *impulse + p, *impulse);
        self.apply(v, inv_mass, p, on);
    }
}

impl PointRows<wide::f32x4> {
    /// Lane `k`, as one joint's rows.
    pub fn lane(&self, k: usize) -> PointRows<f32> {
        let v = |x: V3<wide::f32x4>| V3::<f32>::from_fn(|_| x.lane(k));
        let m = |x: M3<wide::f32x4>| M3::<f32>::from_fn(|_| x.lane(k));
        PointRows {
            ra: v(self.ra),
            rb: v(self.rb),
            c: v(self.c),
            turn_a: m(self.turn_a),
            turn_b: m(self.turn_b),
            k_inv: m(self.k_inv),
            on: self.on.as_array()[k].to_bits() != 0,
        }
    }
}

/// Keeps a direction fixed in a aligned with one fixed in b: two rows about the
/// directions `u`, `v` perpendicular to it (the hinge's rotational part; a 0° cone).
/// `C = P (d_b × d_a)`, `Ċ ≈ P (ω_a − ω_b)` with P the projection off `d_a`; the 2×2
/// effective mass `K = [u v]ᵀ (I_a⁻¹ + I_b⁻¹) [u v]`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct AlignRows<R: Real> {
    /// Two world directions perpendicular to `d_a`.
    pub u: V3<R>,
    pub v: V3<R>,
    /// The error `d_b × d_a` along `u` and `v`.
    pub error: [R; 2],
    /// `k11`, `k12`, `k22` and the determinant.
    pub k: [R; 4],
    /// `I_a⁻¹ u`, `I_a⁻¹ v`, `I_b⁻¹ u`, `I_b⁻¹ v`: how a unit impulse along each row
    /// turns each body.
    pub turn: [V3<R>; 4],
    /// The live lanes with a non-singular `K`.
    pub on: R::Mask,
}

impl<R: Real> AlignRows<R> {
    /// The rows and the error for the directions `local` (in a's and b's space) on the
    /// pose, then [`AlignRows::weigh`].
    #[inline]
    pub fn prepare(&mut self, local: [V3<R>; 2], p: &Pose<R>, live: R::Mask) {
        let da = p.rot_a.rotate(local[0]);
        let db = p.rot_b.rotate(local[1]);
        let (u, v) = orthonormal_pair(da);
        let e = db.cross(da);
        self.u = u;
        self.v = v;
        self.error = [u.dot(e), v.dot(e)];
        self.weigh([p.ia, p.ib], live);
    }

    /// The turns and the effective mass for the rows of the last preparation.
    #[inline]
    pub fn weigh(&mut self, [ia, ib]: [M3<R>; 2], live: R::Mask) {
        let (u, v) = (self.u, self.v);
        self.turn = [ia * u, ia * v, ib * u, ib * v];
        let [au, av, bu, bv] = self.turn;
        let (k11, k12, k22) = (u.dot(au + bu), u.dot(av + bv), v.dot(av + bv));
        let det = k11 * k22 - k12 * k12;
        self.k = [k11, k12, k22, det];
        self.on = live & det.abs().gt(R::splat(1e-20));
    }

    /// Applies the angular impulse `u l₀ + v l₁` to a and its opposite to b in the
    /// lanes `on`.
    #[inline]
    pub fn apply(&self, v: &mut Velocities<R>, [l0, l1]: [R; 2], on: R::Mask) {
        let [au, av, bu, bv] = self.turn;
        v.wa = V3::select(on, v.wa + (au * l0 + av * l1), v.wa);
        v.wb = V3::select(on, v.wb - (bu * l0 + bv * l1), v.wb);
    }

    /// One soft 2×2 block update, solved by Cramer's rule.
    #[inline]
    pub fn solve(&self, v: &mut Velocities<R>, impulse: &mut [R; 2], soft: &Soft<R>) {
        let w = v.wa - v.wb;
        let [k11, k12, k22, det] = self.k;
        let r0 = self.u.dot(w) + soft.bias_rate * self.error[0];
        let r1 = self.v.dot(w) + soft.bias_rate * self.error[1];
        let sol0 = (k22 * r0 - k12 * r1) / det;
        let sol1 = (k11 * r1 - k12 * r0) / det;
        let [i0, i1] = *impulse;
        let l0 = -soft.mass_scale * sol0 - soft.impulse_scale * i0;
        let l1 = -soft.mass_scale * sol1 - soft.impulse_scale * i1;
        let on = self.on;
        *impulse = [R::select(on, i0 + l0, i0), R::select(on, i1 + l1, i1)];
        self.apply(v, [l0, l1], on);
    }
}

/// One angular row `Ċ = axis · (ω_a − ω_b)` of a hard limit (`C ≥ 0`, impulse ≥ 0) or
/// an equality (`C = 0`), as set on the pose by `super::joint::AxisRow::set`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct AngularRow<R: Real> {
    pub axis: V3<R>,
    /// Position value, positive inside a limit.
    pub c: R,
    /// `1/k`, `k = axisᵀ (I_a⁻¹ + I_b⁻¹) axis`.
    pub m: R,
    /// `I_a⁻¹ axis`, `I_b⁻¹ axis`.
    pub turn: [V3<R>; 2],
    /// Lanes whose row is active (warm-started).
    pub active: R::Mask,
    /// Active lanes with a positive `k` (solved).
    pub on: R::Mask,
}

impl<R: Real> AngularRow<R> {
    /// Re-applies the accumulated impulse in the active lanes.
    #[inline]
    pub fn warm_start(&self, v: &mut Velocities<R>, impulse: R) {
        let on = self.active;
        v.wa = V3::select(on, v.wa + self.turn[0] * impulse, v.wa);
        v.wb = V3::select(on, v.wb - self.turn[1] * impulse, v.wb);
    }

    /// One update. A limit (`limit` true) past its bound (`C ≤ 0`) is soft, short of it
    /// speculative (the gap may close this substep, `bias = C/h`, rigid) and its
    /// impulse never pulls; an equality is soft on both sides. The relax pass takes no
    /// bias (0, not 0 · C) and is rigid.
    #[inline]
    pub fn solve(&self, v: &mut Velocities<R>, impulse: &mut R, soft: &Soft<R>, limit: bool) {
        let (zero, one) = (R::ZERO, R::ONE);
        let cdot = self.axis.dot(v.wa - v.wb);
        let old = *impulse;
        let (mut bias, mut mass_scale, mut impulse_scale) = if soft.use_bias {
            (soft.bias_rate * self.c, soft.mass_scale, soft.impulse_scale)
        } else {
            (zero, one, zero)
        };
        if limit {
            let speculative = self.c.gt(zero);
            bias = R::select(speculative, self.c * soft.inv_h, bias);
            mass_scale = R::select(speculative, one, mass_scale);
            impulse_scale = R::select(speculative, zero, impulse_scale);
        }
        let l = -self.m * mass_scale * (cdot + bias) - impulse_scale * old;
        let new = if limit { (old + l).max(zero) } else { old + l };
        let on = self.on;
        *impulse = R::select(on, new, old);
        let d = new - old;
        v.wa = V3::select(on, v.wa + self.turn[0] * d, v.wa);
        v.wb = V3::select(on, v.wb - self.turn[1] * d, v.wb);
    }
}
