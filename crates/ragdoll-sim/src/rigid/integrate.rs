//! Semi-implicit (symplectic) Euler integration of rigid bodies, one substep at a time.
//!
//! Velocities first (gravity, air friction, the gyroscopic term), then — after the
//! constraints have corrected the velocities — positions from the new velocities. This
//! is the integrator of Box2D v3's soft step and of Catto's GDC 2015 talk
//! "Numerical methods".

use super::body::{BodyStates, Motions};
use crate::lanes::{LANES, Mat3x4, Quatx4, Vec3x4};
use glam::{Mat3A, Quat, Vec3, Vec3A};
use wide::f32x4;

/// World inverse inertia `R I⁻¹ Rᵀ` for every awake body, refreshed before the
/// constraints use it. Sleeping and fixed bodies keep zero.
///
/// Four awake bodies at a time, each lane with glam's operations in their order
/// (`Mat3A::from_quat`, `Mat3A * Mat3A` column by column), so the same bits as one by one.
pub fn update_inertia(states: &mut BodyStates, motion: Motions<'_>, awake: &[bool]) {
    for (i, &moving) in awake.iter().enumerate().take(motion.bodies.len()) {
        if !moving {
            states.inv_inertia[i] = Mat3A::ZERO;
        }
    }
    for_each_group(&awake[..motion.bodies.len()], |group| {
        let body = |k: usize| group[k.min(group.len() - 1)];
        let world = world_inertia(
            Quatx4::from_fn(|k| states.rot[body(k)]),
            Mat3x4::from_fn(|k| motion.bodies[body(k)].inv_inertia_local(motion.full)),
        );
        for (k, &i) in group.iter().enumerate() {
            states.inv_inertia[i] = Mat3A::from(world.lane(k));
        }
    });
}

/// Calls `f` with the indices of the set entries of `awake`, four at a time (fewer in
/// the last group), in order, without collecting them.
fn for_each_group(awake: &[bool], mut f: impl FnMut(&[usize])) {
    let mut group = [0; LANES];
    let mut len = 0;
    for i in (0..awake.len()).filter(|&i| awake[i]) {
        group[len] = i;
        len += 1;
        if len == LANES {
            f(&group);
            len = 0;
        }
    }
    if len > 0 {
        f(&group[..len]);
    }
}

/// `R M Rᵀ` in each lane (`R` from the orientation): glam's
/// `Mat3A::from_quat(q) * m * r.transpose()`, the same operations in their order.
fn world_inertia(rot: Quatx4, m: Mat3x4) -> Mat3x4 {
    let r = rotation_matrix(rot);
    r * m * r.transpose()
}

/// `Mat3A::from_quat` in lanes, its operations in its order.
fn rotation_matrix(q: Quatx4) -> Mat3x4 {
    let (x, y, z, w) = (q.v.x, q.v.y, q.v.z, q.w);
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, xy, xz) = (x * x2, x * y2, x * z2);
    let (yy, yz, zz) = (y * y2, y * z2, z * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    let one = f32x4::ONE;
    Mat3x4 {
        cols: [
            Vec3x4 {
                x: one - (yy + zz),
                y: xy + wz,
                z: xz - wy,
            },
            Vec3x4 {
                x: xy - wz,
                y: one - (xx + zz),
                z: yz + wx,
            },
            Vec3x4 {
                x: xz + wy,
                y: yz - wx,
                z: one - (xx + yy),
            },
        ],
    }
}

/// One implicit Euler step of Euler's equation `I ω̇ + ω × I ω = 0` in body space,
/// linearised once (a single Newton step), as Catto recommends: explicit integration of
/// the gyroscopic term adds energy to tumbling bodies, the implicit one removes a little.
///
/// `f(ω) = I (ω − ω₀) + h ω × I ω`, `J = I + h (ω̂ I − (Iω)^)`, `ω₁ = ω₀ − J⁻¹ f(ω₀)`.
///
/// Four bodies at a time, one per lane, each lane with glam's operations in their order
/// (`Quat * Vec3`, `Mat3A * Vec3A` and `Mat3A * Mat3A` column by column, the cross
/// product's products, `Mat3A::determinant` and `Mat3A::inverse` by their cofactors):
/// a lane holds the bits of the one-body form in glam's types (`tests::one_body`), which
/// the tests compare. A lane whose `J` is singular keeps its velocity.
fn gyroscopic(w_world: Vec3x4, rot: Quatx4, inertia: Mat3x4, h: f32x4) -> Vec3x4 {
    let w = rot.conjugate().rotate_as_glam(w_world);
    let iw = inertia * w;
    let f = w.cross(iw) * h;
    let (sw, siw) = (Mat3x4::skew(w), Mat3x4::skew(iw));
    let col = |c: usize| inertia.cols[c] + ((sw * inertia.cols[c]) - siw.cols[c]) * h;
    let [x, y, z] = [col(0), col(1), col(2)];
    // `Mat3A`'s columns are `Vec3A`s: their cross products are glam's `Vec3A` ones.
    let (t0, t1, t2) = (y.cross_a(z), z.cross_a(x), x.cross_a(y));
    let det = x.dot(t0);
    let size = det.abs();
    let ok = size.simd_gt(f32x4::splat(1e-12)) & size.simd_lt(f32x4::splat(f32::INFINITY));
    let inv_det = f32x4::ONE / det;
    // `J⁻¹`: the cofactor columns over the determinant, transposed.
    let inverse = Mat3x4 {
        cols: [t0 * inv_det, t1 * inv_det, t2 * inv_det],
    }
    .transpose();
    let turned = rot.rotate_as_glam(w - inverse * f);
    Vec3x4::select(ok, turned, w_world)
}

/// Puts back what the implicit gyroscopic step lost: `ω₁` (world) moved onto the
/// angular velocities with the body-space |L| and kinetic energy of `ω₀`.
///
/// Without torque, Euler's equation `L̇_b = L_b × I⁻¹ L_b` keeps both |L_b|² and
/// `L_bᵀ I⁻¹ L_b = 2 T` (two quadratic invariants). The linearised implicit step keeps
/// neither: it dissipates (a box tumbling about a general axis lost 15 % of its kinetic
/// energy and 8 % of |L| in 10 s at 240 Hz), which is damping the scene never asked for.
/// The standard projection method (Hairer, Lubich & Wanner, "Geometric Numerical
/// Integration", IV.4) moves the step's result back onto the invariant manifold:
/// Gauss–Newton on `c₁ = |L|² − |L₀|²`, `c₂ = Lᵀ I⁻¹ L − L₀ᵀ I⁻¹ L₀` along their
/// gradients `2L`, `2ω`, `δ = a L + b ω` with
/// `[L·L  L·ω; ω·L  ω·ω] (a, b) = −½ (c₁, c₂)`. About a principal axis L ∥ ω and the
/// two conditions coincide: |L| alone is restored by scaling. Only the gyroscopic term
/// is corrected (gravity, air friction and constraints act after), so a body that
/// should lose energy still does.
fn keep_invariants(w0_world: Vec3, w1_world: Vec3, rot: Quat, inertia: glam::Mat3) -> Vec3 {
    let inv = inertia.inverse();
    if !inv.is_finite() || !w1_world.is_finite() {
        return w1_world;
    }
    let l0 = inertia * (rot.inverse() * w0_world);
    let (ll0, e0) = (l0.length_squared(), l0.dot(inv * l0));
    if ll0 <= 1e-30 {
        return w1_world;
    }
    let mut l = inertia * (rot.inverse() * w1_world);
    for _ in 0..3 {
        let w = inv * l;
        let (c1, c2) = (l.length_squared() - ll0, l.dot(w) - e0);
        let (a11, a12, a22) = (l.dot(l), l.dot(w), w.dot(w));
        let det = a11 * a22 - a12 * a12;
        if det > 1e-6 * a11 * a22 {
            let a = -0.5 * (c1 * a22 - c2 * a12) / det;
            let b = -0.5 * (a11 * c2 - a12 * c1) / det;
            l += a * l + b * w;
        } else if l.length_squared() > 0.0 {
            l *= (ll0 / l.length_squared()).sqrt();
        }
    }
    let w = rot * (inv * l);
    if w.is_finite() { w } else { w1_world }
}

/// Velocity half of the substep: gravity, Doom 3 air friction (a fraction of the velocity
/// lost per second, applied as exact exponential decay), the gyroscopic term.
pub fn integrate_velocities(
    states: &mut BodyStates,
    motion: Motions<'_>,
    awake: &[bool],
    gravity: Vec3,
    h: f32,
) {
    // The gyroscopic term of the awake bodies four at a time (see `gyroscopic`); a
    // last group of fewer repeats its last body.
    let awake = &awake[..motion.bodies.len()];
    let hx4 = f32x4::splat(h);
    for_each_group(awake, |group| {
        let body = |k: usize| group[k.min(group.len() - 1)];
        let w = gyroscopic(
            Vec3x4::from_fn(|k| Vec3::from(states.ang_vel[body(k)])),
            Quatx4::from_fn(|k| states.rot[body(k)]),
            Mat3x4::from_fn(|k| motion.bodies[body(k)].inertia(motion.full)),
            hx4,
        );
        for (k, &i) in group.iter().enumerate() {
            let inertia = motion.bodies[i].inertia(motion.full);
            let before = Vec3::from(states.ang_vel[i]);
            states.ang_vel[i] =
                Vec3A::from(keep_invariants(before, w.lane(k), states.rot[i], inertia));
        }
    });
    for (i, b) in motion.bodies.iter().enumerate() {
        if !awake[i] {
            continue;
        }
        let mut v = states.lin_vel[i] + Vec3A::from(gravity * h);
        let mut w = states.ang_vel[i];
        if b.linear_damping > 0.0 {
            v *= (1.0 - b.linear_damping.min(1.0)).max(0.0).powf(h);
        }
        if b.angular_damping > 0.0 {
            w *= (1.0 - b.angular_damping.min(1.0)).max(0.0).powf(h);
        }
        states.lin_vel[i] = v;
        states.ang_vel[i] = w;
    }
}

/// Position half of the substep: `x += h v`, `q += ½ h (ω, 0) q`, renormalised.
pub fn integrate_positions(states: &mut BodyStates, awake: &[bool], h: f32) {
    for (i, &moving) in awake.iter().enumerate() {
        if !moving {
            continue;
        }
        states.com[i] += Vec3::from(states.lin_vel[i] * h);
        let w = states.ang_vel[i];
        let q = states.rot[i];
        let dq = Quat::from_xyzw(w.x, w.y, w.z, 0.0) * q;
        states.rot[i] = (q + dq * (0.5 * h)).normalize();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particle::uniform;
    use glam::Mat3;

    /// The gyroscopic step of one body in glam's types: the form the lanes repeat.
    fn one_body(w_world: Vec3, rot: Quat, inertia: Mat3, h: f32) -> Vec3 {
        let skew = |a: Vec3| {
            Mat3A::from_cols(
                Vec3A::new(0.0, a.z, -a.y),
                Vec3A::new(-a.z, 0.0, a.x),
                Vec3A::new(a.y, -a.x, 0.0),
            )
        };
        let inertia = Mat3A::from(inertia);
        let w = rot.inverse() * w_world;
        let iw = inertia * w;
        let f = h * w.cross(iw);
        let j = inertia + h * (skew(w) * inertia - skew(iw));
        let det = j.determinant();
        if !(det.is_finite() && det.abs() > 1e-12) {
            return w_world;
        }
        rot * (w - j.inverse() * f)
    }

    /// Random bodies: tumbling fast and slow, diagonal and full inertia tensors, a
    /// massless one (a singular `J`); every lane has the one-body bits, whatever its
    /// neighbours hold, and so does the world inverse inertia.
    // The lanes repeat glam's x86-64 (SSE2) code; elsewhere glam orders its sums otherwise
    // (every path uses the lanes there, so results still do not depend on threads).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn lanes_give_the_one_body_bits() {
        let mut r = uniform(0x9e37_79b9);
        let mut v = |scale: f32| Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * scale;
        for case in 0..500 {
            let w: [Vec3; LANES] = std::array::from_fn(|_| v(40.0));
            let rot: [Quat; LANES] = std::array::from_fn(|_| {
                let q = v(2.0);
                Quat::from_xyzw(q.x, q.y, q.z, 0.7).normalize()
            });
            let inertia: [Mat3; LANES] = std::array::from_fn(|k| {
                let d = Mat3::from_diagonal(v(1.0).abs() + Vec3::splat(0.01));
                match (case + k) % 3 {
                    0 => d,
                    1 => {
                        let q = Quat::from_scaled_axis(v(3.0));
                        Mat3::from_quat(q) * d * Mat3::from_quat(q).transpose()
                    }
                    _ if case % 7 == 0 => Mat3::ZERO,
                    _ => d,
                }
            });
            let h = 1.0 / 240.0;
            let lanes = gyroscopic(
                Vec3x4::from_fn(|k| w[k]),
                Quatx4::from_fn(|k| rot[k]),
                Mat3x4::from_fn(|k| inertia[k]),
                f32x4::splat(h),
            );
            let world = world_inertia(Quatx4::from_fn(|k| rot[k]), Mat3x4::from_fn(|k| inertia[k]));
            for k in 0..LANES {
                let one = one_body(w[k], rot[k], inertia[k], h);
                let got = lanes.lane(k);
                assert!(
                    got.to_array().map(f32::to_bits) == one.to_array().map(f32::to_bits),
                    "case {case} lane {k}: {got} against {one}"
                );
                let r = Mat3A::from_quat(rot[k]);
                let expected = r * Mat3A::from(inertia[k]) * r.transpose();
                let got = Mat3A::from(world.lane(k));
                let bits = |m: Mat3A| m.to_cols_array().map(f32::to_bits);
                assert!(bits(got) == bits(expected), "case {case} lane {k}: inertia");
            }
        }
    }
}
