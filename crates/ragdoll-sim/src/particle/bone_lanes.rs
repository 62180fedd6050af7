//! Bones in lanes: each constraint's bone on one side, one to a lane of a [`Real`]
//! (`f32`: one constraint; `f32x4`: four side by side), and the XPBD corrections of the
//! joints written once over it: the 3×3 point solve ([`point`]) and the turn
//! ([`angular`]). The joint pass (`joint_lanes`) solves four figures' joints side by
//! side with these; a joint solved alone ([`super::joints::Joint::solve_between`]) runs
//! the same code with `R = f32` ([`on_pair`]).
//!
//! Every operation is lane by lane (`crate::lanes`), so a constraint's correction is the
//! same bits whichever constraints share its instruction, or none: the batches of
//! islands, which group constraints differently, give the serial result on any number of
//! threads, and a joint solved alone gets the bits it gets in a group.

use super::bone::{Aim, Bone, Side};
use crate::lanes::{LANES, Q, Real, V3};
use glam::{Quat, Vec3};

/// A lane mask with every lane where `f(k)` holds.
pub(super) fn mask<R: Real>(f: impl Fn(usize) -> bool) -> R::Mask {
    R::from_fn(|k| if f(k) { 1.0 } else { 0.0 }).gt(R::ZERO)
}

/// Whether `m` holds in lane `k`.
#[inline]
pub(super) fn holds<R: Real>(m: R::Mask, k: usize) -> bool {
    R::select(m, R::ONE, R::ZERO).lane(k) != 0.0
}

/// `f` of each lane of `x` set in `mask`, else 0: the scalar functions (`acos`, `atan2`,
/// `asin`) of the few lanes near a limit.
pub(super) fn per_lane<R: Real>(m: R::Mask, x: R, f: impl Fn(usize, f32) -> f32) -> R {
    let on = R::select(m, R::ONE, R::ZERO);
    R::from_fn(|k| {
        if on.lane(k) != 0.0 {
            f(k, x.lane(k))
        } else {
            0.0
        }
    })
}

/// Each lane's bone on one side of its constraint (the world, and an empty lane, as a
/// bone that never moves): what the corrections read and write of it.
pub(super) struct SideLanes<R: Real> {
    com: V3<R>,
    dcom: V3<R>,
    /// The frame now.
    pub rot: Q<R>,
    /// The turn since the substep's start (`Bone::dturn`).
    dturn: Q<R>,
    inv_mass: R,
    inv_inertia: V3<R>,
    /// Lanes whose bone takes corrections.
    moving: R::Mask,
}

impl<R: Real> SideLanes<R> {
    /// The bones `sides` (the world for `None`), one per lane: `sides[k]` for lane `k <
    /// R::WIDTH`.
    pub fn gather(bones: &[Bone], sides: &[Side]) -> SideLanes<R> {
        // One pass over the bones into arrays, then each field into lanes.
        let mut com = [Vec3::ZERO; LANES];
        let mut dcom = [Vec3::ZERO; LANES];
        let mut rot = [Quat::IDENTITY; LANES];
        let mut dturn = [Quat::IDENTITY; LANES];
        let mut inv_mass = [0.0; LANES];
        let mut inv_inertia = [Vec3::ZERO; LANES];
        let mut moving = [false; LANES];
        for (k, s) in sides.iter().enumerate().take(R::WIDTH) {
            let Some(i) = *s else { continue };
            let b = &bones[i];
            (com[k], dcom[k]) = (b.com.into(), b.dcom.into());
            rot[k] = b.rot;
            dturn[k] = b.dturn;
            if !b.is_static() {
                inv_mass[k] = 1.0 / b.mass;
                inv_inertia[k] = b.inv_inertia_local.into();
                moving[k] = true;
            }
        }
        SideLanes {
            com: V3::from_fn(|k| com[k]),
            dcom: V3::from_fn(|k| dcom[k]),
            rot: Q::from_fn(|k| rot[k]),
            dturn: Q::from_fn(|k| dturn[k]),
            inv_mass: R::from_fn(|k| inv_mass[k]),
            inv_inertia: V3::from_fn(|k| inv_inertia[k]),
            moving: mask::<R>(|k| moving[k]),
        }
    }

    /// Writes the moving lanes' frames back to their bones.
    pub fn scatter(&self, bones: &mut [Bone], sides: &[Side]) {
        for (k, s) in sides.iter().enumerate().take(R::WIDTH) {
            if let Some(i) = *s
                && holds::<R>(self.moving, k)
            {
                let b = &mut bones[i];
                b.dcom = self.dcom.lane(k).into();
                b.rot = self.rot.lane(k);
                b.dturn = self.dturn.lane(k);
            }
        }
    }

    /// World position of a point given in the bone frame, `com + (dcom + R p)`.
    pub fn world(&self, local: V3<R>) -> V3<R> {
        self.com + (self.dcom + self.rot.rotate(local))
    }

    /// The lever of a turn about `axis`: `I⁻¹ (R⁻¹ axis)` in the bone frame and the
    /// inverse inertia about `axis`, `local · turn` (times `|axis|²`); zero for a bone
    /// that takes no correction.
    fn lever(&self, axis: V3<R>) -> (V3<R>, R) {
        let local = self.rot.inverse_rotate(axis);
        let turn = self.inv_inertia.mul_elem(local);
        (turn, local.dot(turn))
    }

    /// A point constraint's side ([`point`]): the point's arm in the bone frame, from
    /// the frame at the substep's start (`d⁻¹ p`) or now (`p`), and its `K` in the
    /// world, `1/M − [r₀]× I⁻¹ [r₀]×`, as `xx, yy, zz, xy, xz, yz`.
    fn point_block(&self, local: V3<R>, aim: Aim) -> (V3<R>, [R; 6]) {
        let arm = match aim {
            Aim::Start => self.dturn.inverse_rotate(local),
            Aim::End => local,
        };
        let zero = R::ZERO;
        let col = |x, y, z| V3 { x, y, z };
        let d = [self.inv_inertia.x, self.inv_inertia.y, self.inv_inertia.z];
        let u = [
            col(zero, -arm.z, arm.y),
            col(arm.z, zero, -arm.x),
            col(-arm.y, arm.x, zero),
        ]
        .map(|e| self.rot.rotate(e));
        let m = self.inv_mass;
        let mut k = [m, m, m, zero, zero, zero];
        for (u, d) in u.iter().zip(d) {
            k[0] += d * u.x * u.x;
            k[1] += d * u.y * u.y;
            k[2] += d * u.z * u.z;
            k[3] += d * u.x * u.y;
            k[4] += d * u.x * u.z;
            k[5] += d * u.y * u.z;
        }
        (arm, k)
    }

    /// Applies a point constraint's impulse `p` (world) at the arm `arm` (`point_block`)
    /// in the lanes of `mask`: the centre moves by `p / M`, the frame turns by
    /// `I⁻¹ (arm × R⁻¹ p)` (bone frame).
    fn apply_point(&mut self, mask: R::Mask, arm: V3<R>, p: V3<R>) {
        let turn = self
            .inv_inertia
            .mul_elem(arm.cross(self.rot.inverse_rotate(p)));
        self.apply(mask, Some(p), turn);
    }

    /// Turns the lanes in `mask` by `turn` (bone frame, `q + ½ q [turn, 0]` normalised:
    /// `bone::rotate_local`) and moves them by `shift` times the inverse mass (world).
    #[inline]
    fn apply(&mut self, mask: R::Mask, shift: Option<V3<R>>, turn: V3<R>) {
        let mask = mask & self.moving;
        if let Some(shift) = shift {
            self.dcom = V3::select(mask, self.dcom + shift * self.inv_mass, self.dcom);
        }
        self.rot = Q::select(mask, self.rot.rotate_local(turn), self.rot);
        self.dturn = Q::select(mask, self.dturn.rotate_local(turn), self.dturn);
    }
}

/// Runs `rows` on the bones of sides `a` and `b` of `bones` gathered one to a lane of
/// an `f32`, and writes them back: a joint solved alone, by the code the lanes run.
pub(super) fn on_pair(
    bones: &mut [Bone],
    a: Side,
    b: Side,
    rows: impl FnOnce(&mut SideLanes<f32>, &mut SideLanes<f32>),
) {
    let mut sa = SideLanes::<f32>::gather(bones, &[a]);
    let mut sb = SideLanes::<f32>::gather(bones, &[b]);
    rows(&mut sa, &mut sb);
    sa.scatter(bones, &[a]);
    sb.scatter(bones, &[b]);
}

/// [`angular`] of a joint solved alone: turns side `a` of `bones` relative to `b` by
/// the rotation vector `dphi` (world), compliance `α̃`.
pub(super) fn angular_pair(bones: &mut [Bone], a: Side, b: Side, dphi: Vec3, alpha: f32) {
    let dphi = V3::from_fn(|_| dphi);
    on_pair(bones, a, b, |sa, sb| angular(sa, sb, dphi, alpha, true));
}

/// Moves point `local_a` of `a` and `local_b` of `b` (bone frames) so that `pa − pb`
/// changes by `delta`, in one 3×3 solve against the arms `aim` takes (`bone::Aim`), in
/// the lanes of `mask`.
///
/// With the arms `r`, the impulse `Δλ = K⁻¹ delta`, `K = Σ (1/M − [r]× I⁻¹ [r]×)` over
/// the moving sides, moves each centre by `±Δλ / M` and turns each frame by
/// `±I⁻¹ (r × Δλ)`. One solve closes the gap to first order in every direction at
/// once; a correction along the gap alone (a scalar projection) leaves the directions
/// it couples to for the next pass.
pub(super) fn point<R: Real>(
    (a, local_a): (&mut SideLanes<R>, V3<R>),
    (b, local_b): (&mut SideLanes<R>, V3<R>),
    delta: V3<R>,
    aim: Aim,
    mask: R::Mask,
) {
    // `K = Σ (1/M + Σ_i I⁻¹_i u_i u_iᵀ)` with `u_i = R (e_i × r₀)`: `−[r₀]× I⁻¹ [r₀]×`
    // in the world, `r₀` the arm in the bone frame at the substep's start.
    let (arm_a, ka) = a.point_block(local_a, aim);
    let (arm_b, kb) = b.point_block(local_b, aim);
    let k: [R; 6] = std::array::from_fn(|i| ka[i] + kb[i]);
    let (adj_delta, det) = adjugate_times(k, delta);
    let mask = mask & delta.length_squared().ge(R::splat(1e-18)) & det.abs().gt(R::splat(1e-30));
    if !R::any(mask) {
        return;
    }
    let impulse = adj_delta * (R::ONE / det);
    a.apply_point(mask, arm_a, impulse);
    b.apply_point(mask, arm_b, -impulse);
}

/// `adj(K) v` and `det K` for the symmetric 3×3 `K` given as `[xx, yy, zz, xy, xz, yz]`:
/// `K⁻¹ v = adj(K) v / det K`, the anchor's solve in [`point`] and [`angular_held`].
fn adjugate_times<R: Real>(k: [R; 6], v: V3<R>) -> (V3<R>, R) {
    let [xx, yy, zz, xy, xz, yz] = k;
    let (axx, ayy, azz) = (yy * zz - yz * yz, xx * zz - xz * xz, xx * yy - xy * xy);
    let (axy, axz, ayz) = (xz * yz - xy * zz, xy * yz - xz * yy, xy * xz - xx * yz);
    let det = xx * axx + xy * axy + xz * axz;
    let adj_v = V3 {
        x: axx * v.x + axy * v.y + axz * v.z,
        y: axy * v.x + ayy * v.y + ayz * v.z,
        z: axz * v.x + ayz * v.y + azz * v.z,
    };
    (adj_v, det)
}

/// [`angular`] with the joint's anchor held: turns `a` relative to `b` by the rotation
/// vector `dphi` (world) while the anchor points `local_a` of `a` and `local_b` of `b`
/// (bone frames) keep their offset, in one solve of the turn's row and the anchor's three
/// rows together (the Schur complement of the 4×4 system), compliance `α̃`, in the lanes
/// of `mask`.
///
/// A limit turned about the bones' centres alone moves the anchor: a knee at its stop
/// under a figure's weight opens a few millimetres every pass, and what the pass leaves
/// open the next substep closes as a velocity (on the lab humanoid kneeling on its left
/// knee, with that knee's limit alone, 6 % of the energy scale; 0.6 % turned about the
/// held anchor). Turning about the held anchor is how the joint itself turns: an angular
/// impulse `λ` along `j = dphi` and an anchor impulse `p` with
///
/// ```text
/// K p + λ g = 0,    g · p + (w + α̃ |j|²) λ = |j|²,
/// ```
///
/// `K` the anchor's `Σ (1/M − [r]× I⁻¹ [r]×)` (arms from the frame now), `w = jᵀ (I_a⁻¹ +
/// I_b⁻¹) j` and `g = (I_a⁻¹ j) × r_a + (I_b⁻¹ j) × r_b` the anchor's motion per unit
/// of `λ`, so `λ = |j|² / (w + α̃ |j|² − gᵀ K⁻¹ g)` and `p = −λ K⁻¹ g`. Where the anchor
/// leaves no turn about `j` (`w − gᵀ K⁻¹ g` a vanishing part of `w`), the turn is left to
/// [`angular`].
pub(super) fn angular_held<R: Real>(
    (a, local_a): (&mut SideLanes<R>, V3<R>),
    (b, local_b): (&mut SideLanes<R>, V3<R>),
    dphi: V3<R>,
    alpha: R,
    mask: R::Mask,
) {
    let angle2 = dphi.length_squared();
    let (ta, wa) = a.lever(dphi);
    let (tb, wb) = b.lever(dphi);
    let (arm_a, ka) = a.point_block(local_a, Aim::End);
    let (arm_b, kb) = b.point_block(local_b, Aim::End);
    let g =
        a.rot.rotate(ta).cross(a.rot.rotate(arm_a)) + b.rot.rotate(tb).cross(b.rot.rotate(arm_b));
    let k: [R; 6] = std::array::from_fn(|i| ka[i] + kb[i]);
    let (adj_g, det) = adjugate_times(k, g);
    let w = wa + wb;
    let solvable = det.abs().gt(R::splat(1e-30));
    let inv = R::select(solvable, R::ONE / det, R::ZERO);
    // `K⁻¹ g` by the adjugate.
    let v = adj_g * inv;
    let free = w - g.dot(v);
    let held = mask & angle2.ge(R::splat(1e-18)) & solvable & free.gt(w * R::splat(1e-4));
    if R::any(held) {
        let lambda = angle2 / (free + alpha * angle2);
        let p = v * -lambda;
        let turn_a = ta * lambda + a.inv_inertia.mul_elem(arm_a.cross(a.rot.inverse_rotate(p)));
        let turn_b = tb * -lambda - b.inv_inertia.mul_elem(arm_b.cross(b.rot.inverse_rotate(p)));
        a.apply(held, Some(p), turn_a);
        b.apply(held, Some(-p), turn_b);
    }
    let rest = mask & !held;
    if R::any(rest) {
        angular(a, b, dphi, alpha, rest);
    }
}

/// XPBD angular constraint (Müller et al. 2020, eq. 2–5 for a turn): turns `a` relative
/// to `b` by the rotation vector `dphi`, split by generalised inverse inertia, compliance
/// `α̃` (compliance / h²), in the lanes of `mask`. With `φ = |dphi|` and `w` the inverse
/// inertia about `dphi / φ`, the turn is `μ = φ² / (W + α̃ φ²)` about `dphi` itself, `W =
/// φ² w` (the levers taken about `dphi` unnormalised), rather than `φ / (w + α̃)` about
/// `dphi / φ`: no square root and division before the levers.
pub(super) fn angular<R: Real>(
    a: &mut SideLanes<R>,
    b: &mut SideLanes<R>,
    dphi: V3<R>,
    alpha: R,
    mask: R::Mask,
) {
    let angle2 = dphi.length_squared();
    let (ta, wa) = a.lever(dphi);
    let (tb, wb) = b.lever(dphi);
    let den = wa + wb + alpha * angle2;
    let mask = mask & angle2.ge(R::splat(1e-18)) & den.gt(R::ZERO);
    if !R::any(mask) {
        return;
    }
    let lambda = angle2 / den;
    a.apply(mask, None, ta * lambda);
    b.apply(mask, None, tb * -lambda);
}
