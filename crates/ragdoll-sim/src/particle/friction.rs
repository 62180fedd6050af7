//! Contact response of the improved solver (after Müller et al. 2020, "Detailed rigid
//! body simulation with extended position based dynamics", sections 3.5–3.6).
//!
//! Position level, per substep: the normal constraint pushes the shapes apart; then the
//! tangential slip of the contact points during the substep is cancelled entirely when
//! its multiplier stays inside the Coulomb cone, `λ_t ≤ μ λ_n` (static friction), and
//! otherwise only up to `λ_t = μ λ_n` (kinetic friction). Clamping rather than
//! all-or-nothing lets Gauss–Seidel share the tangential load between the points of a
//! manifold — with all-or-nothing each point sees the whole body's slip against a
//! quarter of its normal load and a box creeps down a slope below the friction angle.
//!
//! Velocity level: the normal velocity is set to `−e v_n` (the approach speed before
//! the solve) above the restitution threshold and to zero below it, which also removes
//! any velocity the position projection created: pushing out of a penetration must not
//! add energy.

use super::bone::{Bone, Side, point_inv_mass, positional, rot_inv_mass, side_world};
use super::contacts::{ContactPoint, Manifold};
use glam::Vec3;

fn side_displacement(bones: &[Bone], s: Side, local: Vec3) -> Vec3 {
    match s {
        Some(i) => bones[i].displacement(local),
        None => Vec3::ZERO,
    }
}

/// Velocity of a side's material point at world `p`.
#[inline]
pub(crate) fn point_velocity(bones: &[Bone], s: Side, p: Vec3) -> Vec3 {
    match s {
        Some(i) if !bones[i].is_static() => {
            let b = &bones[i];
            b.lin_vel + b.ang_vel.cross(p - b.center())
        }
        _ => Vec3::ZERO,
    }
}

/// Normal position pass for one contact: push the shapes apart. Accumulates `lambda_n`.
pub(crate) fn solve_normal(bones: &mut [Bone], m: &Manifold, c: &mut ContactPoint) {
    let pa = bones[m.a].world(c.ra);
    let pb = side_world(bones, m.b, c.rb);
    let depth = (pa - pb).dot(m.n);
    if depth > 0.0 {
        c.lambda_n += positional(bones, Some(m.a), m.b, pa, pb, -m.n * depth, 0.0);
    }
}

/// Friction position pass for one contact of a manifold whose normal multipliers sum to
/// `group_n` and whose friction has spent `group_t` so far: cancel the contact point's
/// tangential slip during the substep entirely if that stays inside the Coulomb cone of
/// the whole manifold (static), else as far as the cone allows (kinetic). Returns the
/// tangential multiplier spent.
///
/// The cone is the manifold's, `Σλ_t ≤ μ Σλ_n`, not each point's: Gauss–Seidel does not
/// share the normal load evenly between a face's points within one pass, and a point
/// with little normal load would let the body slide (measured: a box on a 35° slope slid
/// 7 % further than Coulomb allows with per-point cones).
pub(crate) fn solve_friction(
    bones: &mut [Bone],
    m: &Manifold,
    c: &mut ContactPoint,
    group_n: f32,
    group_t: f32,
) -> f32 {
    let a = Some(m.a);
    let pa = bones[m.a].world(c.ra);
    let pb = side_world(bones, m.b, c.rb);
    let slip = bones[m.a].displacement(c.ra) - side_displacement(bones, m.b, c.rb);
    let slip_t = slip - m.n * slip.dot(m.n);
    let len = slip_t.length();
    if len < 1e-9 {
        return 0.0;
    }
    let t = slip_t / len;
    let w = point_inv_mass(bones, a, pa, t) + point_inv_mass(bones, m.b, pb, t);
    let allowed = m.mu * group_n - group_t;
    if w <= 0.0 || allowed <= 0.0 {
        return 0.0;
    }
    let frac = (allowed / (len / w)).min(1.0);
    let lt = positional(bones, a, m.b, pa, pb, -slip_t * frac, 0.0);
    c.lambda_t += lt;
    lt
}

/// Applies a velocity impulse `p` at world point `at` to a side.
fn apply_velocity_impulse(bones: &mut [Bone], s: Side, at: Vec3, p: Vec3) {
    if let Some(i) = s {
        let b = &mut bones[i];
        if b.is_static() {
            return;
        }
        let dw = b.inv_inertia_mul((at - b.center()).cross(p));
        b.lin_vel += p * b.inv_mass();
        b.ang_vel += dw;
    }
}

/// Radius of the contact patch a point contact stands for (m): the lever arm of its
/// torsional friction. A box resting on one corner otherwise spins about the normal
/// without losing energy, since a point cannot resist twist.
const PATCH_RADIUS: f32 = 0.01;

/// Velocity pass for one contact that was active this substep.
pub(crate) fn solve_velocity(
    bones: &mut [Bone],
    m: &Manifold,
    c: &ContactPoint,
    h: f32,
    restitution_threshold: f32,
) {
    if c.lambda_n <= 0.0 {
        return;
    }
    let a = Some(m.a);
    let pa = bones[m.a].world(c.ra);
    let pb = side_world(bones, m.b, c.rb);
    let v = point_velocity(bones, a, pa) - point_velocity(bones, m.b, pb);
    let vn = v.dot(m.n);
    // Normal: restitution on the approach speed before the solve, never more.
    let target = if c.vn_before > restitution_threshold {
        -m.e * c.vn_before
    } else {
        0.0
    };
    let wn = point_inv_mass(bones, a, pa, m.n) + point_inv_mass(bones, m.b, pb, m.n);
    if wn > 0.0 {
        let p = m.n * ((target - vn) / wn);
        apply_velocity_impulse(bones, a, pa, p);
        apply_velocity_impulse(bones, m.b, pb, -p);
    }
    // Torsional friction: twist about the normal, capped by μ r λ_n / h.
    let twist = |bones: &[Bone], s: Side| match s {
        Some(i) if !bones[i].is_static() => bones[i].ang_vel.dot(m.n),
        _ => 0.0,
    };
    let spin = twist(bones, a) - twist(bones, m.b);
    let wr = rot_inv_mass(bones, a, m.n) + rot_inv_mass(bones, m.b, m.n);
    if wr > 0.0 && spin != 0.0 {
        let l = spin.signum() * (spin.abs() / wr).min(m.mu * PATCH_RADIUS * c.lambda_n / h);
        for (s, sign) in [(a, -1.0f32), (m.b, 1.0)] {
            if let Some(i) = s {
                let b = &mut bones[i];
                if !b.is_static() {
                    b.ang_vel += b.inv_inertia_mul(m.n * (sign * l));
                }
            }
        }
    }
}
