//! Rolling resistance of the improved particle solvers: the contact material's
//! `ρ r λₙ` of `crate::scene::rolling`, applied as the multibody applies it.
//!
//! After a substep's contact velocity passes, each manifold whose sides roll opposes
//! their relative angular velocity `ω_b − ω_a` with one angular impulse `L` (on `b`,
//! `−L` on `a`): the impulse that stops it, `L = −(I_a⁻¹ + I_b⁻¹)⁻¹ (ω_b − ω_a)`, capped
//! at `|L| ≤ ρ r Λ`, `Λ` the manifold's net normal impulse of the substep (the position
//! pass's push over `h` and the velocity pass's change). A pure couple: no point moves,
//! linear momentum is kept, and the energy it takes is the rolling it resists. The
//! floor's friction then turns the slower spin into a slower roll, as it does a real
//! body's: the next substep's friction pass holds the contact point, and the body
//! decelerates at `ρ g / (1 + I / (m r²))` (module `crate::scene::rolling`).
//!
//! Once per substep, after the velocity passes rather than inside them: the cap is on
//! the substep's normal impulse, which only the velocity passes finish, and a manifold
//! then needs no accumulated impulse of its own between passes.

use super::bone::{Bone, Side};
use super::contacts::{ContactPoint, Manifold, ranges};
use glam::{Mat3, Vec3, Vec3A};

/// The angular impulse on `b` (and its opposite on `a`) that stops a relative spin
/// `spin = ω_b − ω_a` between sides of world inverse inertias `inv_a`, `inv_b`, capped
/// at length `cap`; `None` when there is nothing to resist or the pair cannot turn
/// (both inverse inertias zero or degenerate, as the multibody leaves such a pair).
pub(crate) fn impulse(spin: Vec3, inv_a: Mat3, inv_b: Mat3, cap: f32) -> Option<Vec3> {
    if cap <= 0.0 || spin == Vec3::ZERO {
        return None;
    }
    let k = inv_a + inv_b;
    if k.determinant().abs() <= 1e-20 {
        return None;
    }
    let free = -(k.inverse() * spin);
    let len2 = free.length_squared();
    Some(if len2 > cap * cap {
        free * (cap / len2.sqrt())
    } else {
        free
    })
}

/// World inverse inertia of a side, `R I⁻¹ Rᵀ`; zero for the ground or a bone that
/// takes no correction.
fn inv_inertia(bones: &[Bone], s: Side) -> Mat3 {
    match s {
        Some(i) if !bones[i].is_static() => bones[i].inv_inertia_world(),
        _ => Mat3::ZERO,
    }
}

/// Angular velocity of a side (zero for the ground or a static bone).
fn spin_of(bones: &[Bone], s: Side) -> Vec3 {
    match s {
        Some(i) if !bones[i].is_static() => Vec3::from(bones[i].ang_vel),
        _ => Vec3::ZERO,
    }
}

/// The rigid-frames solver's rolling resistance for one substep `h` (module doc), over
/// `manifolds` and their `points` after the velocity passes: each point's net normal
/// impulse is `λ_n / h + λ_v` (`friction::solve_velocities`).
pub(crate) fn solve(bones: &mut [Bone], manifolds: &[Manifold], points: &[ContactPoint], h: f32) {
    for (m, run) in manifolds.iter().zip(ranges(manifolds, points.len())) {
        if m.roll <= 0.0 {
            continue;
        }
        let normal: f32 = points[run]
            .iter()
            .map(|c| c.lambda_n / h + c.lambda_tv)
            .sum();
        // No normal impulse, no rolling resistance (`impulse`'s cap is zero): most
        // manifolds of a busy pile are speculative ones no pass pressed, and forming
        // their world inverse inertias was most of this pass's cost.
        if normal <= 0.0 {
            continue;
        }
        let (a, b) = (Some(m.a()), m.b());
        let (inv_a, inv_b) = (inv_inertia(bones, a), inv_inertia(bones, b));
        let spin = spin_of(bones, b) - spin_of(bones, a);
        if let Some(l) = impulse(spin, inv_a, inv_b, m.roll * normal) {
            if let Some(i) = a.filter(|&i| !bones[i].is_static()) {
                bones[i].ang_vel -= Vec3A::from(inv_a * l);
            }
            if let Some(i) = b.filter(|&i| !bones[i].is_static()) {
                bones[i].ang_vel += Vec3A::from(inv_b * l);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within the cap the impulse stops the relative spin; beyond it, it is the cap
    /// along the spin's opposite.
    #[test]
    fn impulse_stops_the_spin_within_its_cap() {
        let inv_a = Mat3::from_diagonal(Vec3::new(2.0, 4.0, 8.0));
        let inv_b = Mat3::ZERO;
        let spin = Vec3::new(0.0, 0.0, -0.5);
        let l = impulse(spin, inv_a, inv_b, 1.0).expect("a spin to resist");
        // ω_b − ω_a after: spin + (I_a⁻¹ + I_b⁻¹) L.
        assert!((spin + (inv_a + inv_b) * l).length() < 1e-7);
        let capped = impulse(spin, inv_a, inv_b, 0.01).expect("a spin to resist");
        assert!((capped.length() - 0.01).abs() < 1e-8);
        assert!(capped.normalize().dot(-spin.normalize()) > 1.0 - 1e-6);
        assert_eq!(impulse(spin, Mat3::ZERO, Mat3::ZERO, 1.0), None);
        assert_eq!(impulse(Vec3::ZERO, inv_a, inv_b, 1.0), None);
        assert_eq!(impulse(spin, inv_a, inv_b, 0.0), None);
    }
}
