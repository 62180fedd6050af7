//! Bones in SIMD lanes: four constraints' bones on one side, one to a lane, and the
//! XPBD corrections of `bone.rs` (`Lever`, `Correction`, `point`, `angular`) four
//! at a time. The joint pass (`joint_lanes`) solves four figures' joints side by side
//! with these.
//!
//! Every operation is lane by lane (`crate::lanes`), so a constraint's correction is the
//! same bits whichever constraints share its instruction: the batches of islands, which
//! group constraints differently, give the serial result on any number of threads.

use super::bone::{Aim, Bone, Side};
use crate::lanes::{LANES, Quatx4, Vec3x4, f4};
use glam::{Quat, Vec3};
use wide::f32x4;

/// A lane mask with every lane where `f(k)` holds.
pub(super) fn mask(f: impl Fn(usize) -> bool) -> f32x4 {
    f4(|k| if f(k) { f32::from_bits(u32::MAX) } else { 0.0 })
}

/// `f` of each lane of `x` set in `mask`, else 0: the scalar functions (`acos`, `atan2`,
/// `asin`) of the few lanes near a limit.
pub(super) fn per_lane(mask: f32x4, x: f32x4, f: impl Fn(usize, f32) -> f32) -> f32x4 {
    let bits = mask.to_bitmask();
    let x = x.to_array();
    f4(|k| {
        if bits & (1 << k) != 0 {
            f(k, x[k])
        } else {
            0.0
        }
    })
}

/// Each lane's bone on one side of its constraint (the world, and an empty lane, as a
/// bone that never moves): what the corrections read and write of it.
pub(super) struct SideLanes {
    com: Vec3x4,
    dcom: Vec3x4,
    /// The frame now.
    pub rot: Quatx4,
    /// The turn since the substep's start (`Bone::dturn`).
    dturn: Quatx4,
    inv_mass: f32x4,
    inv_inertia: Vec3x4,
    /// Lanes whose bone takes corrections.
    moving: f32x4,
}

impl SideLanes {
    /// The bones `sides` (the world for `None`), one per lane.
    pub fn gather(bones: &[Bone], sides: &[Side; LANES]) -> SideLanes {
        let mut com = [Vec3::ZERO; LANES];
        let mut dcom = [Vec3::ZERO; LANES];
        let mut rot = [Quat::IDENTITY; LANES];
        let mut dturn = [Quat::IDENTITY; LANES];
        let mut inv_mass = [0.0; LANES];
        let mut inv_inertia = [Vec3::ZERO; LANES];
        let mut moving = [false; LANES];
        for (k, s) in sides.iter().enumerate() {
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
            com: Vec3x4::from_fn(|k| com[k]),
            dcom: Vec3x4::from_fn(|k| dcom[k]),
            rot: Quatx4::from_fn(|k| rot[k]),
            dturn: Quatx4::from_fn(|k| dturn[k]),
            inv_mass: f32x4::new(inv_mass),
            inv_inertia: Vec3x4::from_fn(|k| inv_inertia[k]),
            moving: mask(|k| moving[k]),
        }
    }

    /// Writes the moving lanes' frames back to their bones.
    pub fn scatter(&self, bones: &mut [Bone], sides: &[Side; LANES]) {
        let moving = self.moving.to_bitmask();
        for (k, s) in sides.iter().enumerate() {
            if let Some(i) = *s
                && moving & (1 << k) != 0
            {
                let b = &mut bones[i];
                b.dcom = self.dcom.lane(k).into();
                b.rot = self.rot.lane(k);
                b.dturn = self.dturn.lane(k);
            }
        }
    }

    /// World position of a point given in the bone frame, `com + (dcom + R p)`.
    pub fn world(&self, local: Vec3x4) -> Vec3x4 {
        self.com + (self.dcom + self.rot.rotate(local))
    }

    /// The lever of a correction whose angular part is `axis` (`(p − c) × n`, or `n`
    /// for a pure turn): `I⁻¹ (R⁻¹ axis)` in the bone frame and the generalised inverse
    /// mass `linear + local · turn` (`bone::Lever::of`); zero for a bone that takes no
    /// correction.
    fn lever(&self, axis: Vec3x4, linear: f32x4) -> (Vec3x4, f32x4) {
        let local = self.rot.inverse_rotate(axis);
        let turn = self.inv_inertia.mul_elem(local);
        (turn, linear + local.dot(turn))
    }

    /// A point constraint's side (`point`): the point's arm in the bone frame, from
    /// the frame at the substep's start (`d⁻¹ p`) or now (`p`), and its `K` in the world, `1/M − [r₀]× I⁻¹ [r₀]×`, as
    /// `xx, yy, zz, xy, xz, yz`.
    fn point_block(&self, local: Vec3x4, aim: Aim) -> (Vec3x4, [f32x4; 6]) {
        let arm = match aim {
            Aim::Start => self.dturn.inverse_rotate(local),
            Aim::End => local,
        };
        let zero = f32x4::ZERO;
        let col = |x, y, z| Vec3x4 { x, y, z };
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
    fn apply_point(&mut self, mask: f32x4, arm: Vec3x4, p: Vec3x4) {
        let turn = self
            .inv_inertia
            .mul_elem(arm.cross(self.rot.inverse_rotate(p)));
        self.apply(mask, Some(p), turn);
    }

    /// Turns the lanes in `mask` by `turn` (bone frame) and moves them by `shift`
    /// times the inverse mass (world): `bone::Lever::apply`.
    #[inline]
    fn apply(&mut self, mask: f32x4, shift: Option<Vec3x4>, turn: Vec3x4) {
        let mask = mask & self.moving;
        if let Some(shift) = shift {
            self.dcom = Vec3x4::select(mask, self.dcom + shift * self.inv_mass, self.dcom);
        }
        self.rot = Quatx4::select(mask, self.rot.rotate_local(turn), self.rot);
        self.dturn = Quatx4::select(mask, self.dturn.rotate_local(turn), self.dturn);
    }
}

/// `bone::Correction::turning` in lanes: a turn between two sides about a direction,
/// its levers computed once.
#[derive(Clone, Copy)]
pub(super) struct Correction {
    ta: Vec3x4,
    tb: Vec3x4,
    /// Generalised inverse inertia about it.
    pub w: f32x4,
}

impl Correction {
    /// `Correction::turning`: turning `a` about `n` and `b` against it.
    pub fn turning(a: &SideLanes, b: &SideLanes, n: Vec3x4) -> Correction {
        let (ta, wa) = a.lever(n, f32x4::ZERO);
        let (tb, wb) = b.lever(n, f32x4::ZERO);
        Correction { ta, tb, w: wa + wb }
    }

    /// Applies the multiplier `λ` in the lanes of `mask`: `a` turns by `n λ w`
    /// relative to `b`.
    #[inline]
    pub fn apply(&self, a: &mut SideLanes, b: &mut SideLanes, lambda: f32x4, mask: f32x4) {
        a.apply(mask, None, self.ta * lambda);
        b.apply(mask, None, self.tb * -lambda);
    }
}

/// `bone::point` in lanes: moves point `local_a` of `a` and `local_b` of `b` (bone
/// frames) so that `pa − pb` changes by `delta`, in one 3×3 solve against the arms
/// `aim` takes, in the lanes of `mask`.
pub(super) fn point(
    (a, local_a): (&mut SideLanes, Vec3x4),
    (b, local_b): (&mut SideLanes, Vec3x4),
    delta: Vec3x4,
    aim: Aim,
    mask: f32x4,
) {
    // `K = Σ (1/M + Σ_i I⁻¹_i u_i u_iᵀ)` with `u_i = R (e_i × r₀)`: `−[r₀]× I⁻¹ [r₀]×`
    // in the world, `r₀` the arm in the bone frame at the substep's start.
    let (arm_a, ka) = a.point_block(local_a, aim);
    let (arm_b, kb) = b.point_block(local_b, aim);
    let k: [f32x4; 6] = std::array::from_fn(|i| ka[i] + kb[i]);
    let [xx, yy, zz, xy, xz, yz] = k;
    // The adjugate of the symmetric `K`, and its determinant.
    let (axx, ayy, azz) = (yy * zz - yz * yz, xx * zz - xz * xz, xx * yy - xy * xy);
    let (axy, axz, ayz) = (xz * yz - xy * zz, xy * yz - xz * yy, xy * xz - xx * yz);
    let det = xx * axx + xy * axy + xz * axz;
    let mask = mask
        & delta.length_squared().simd_ge(f32x4::splat(1e-18))
        & det.abs().simd_gt(f32x4::splat(1e-30));
    if !mask.any() {
        return;
    }
    let inv = f32x4::ONE / det;
    let impulse = Vec3x4 {
        x: (axx * delta.x + axy * delta.y + axz * delta.z) * inv,
        y: (axy * delta.x + ayy * delta.y + ayz * delta.z) * inv,
        z: (axz * delta.x + ayz * delta.y + azz * delta.z) * inv,
    };
    a.apply_point(mask, arm_a, impulse);
    b.apply_point(mask, arm_b, -impulse);
}

/// `bone::angular` in lanes: turns `a` relative to `b` by `dphi`, compliance `α̃`, in
/// the lanes of `mask`.
pub(super) fn angular(
    a: &mut SideLanes,
    b: &mut SideLanes,
    dphi: Vec3x4,
    alpha: f32x4,
    mask: f32x4,
) {
    let angle2 = dphi.length_squared();
    let corr = Correction::turning(a, b, dphi);
    let den = corr.w + alpha * angle2;
    let mask = mask & angle2.simd_ge(f32x4::splat(1e-18)) & den.simd_gt(f32x4::ZERO);
    corr.apply(a, b, angle2 / den, mask);
}
