//! Joint friction in the XPBD solver: the file's joint friction read as the other two
//! solvers read it (`Joint::with_friction`, `rigid::FrictionMotor`), the largest torque
//! `f · m₁ g r` (body1's mass, its anchor's arm `r`, at least 5 cm).
//!
//! Applied once a substep `h` in the velocity step, after the position passes, as
//! `Joint::solve_friction` does for rigid bones: the angular impulse between the two
//! sides that stops their relative turn, `Δλ = −K⁻¹ (ω_a − ω_b)`, `K = I_a⁻¹ + I_b⁻¹`
//! (world), capped at the friction torque times `h`. A bone's `ω` and `I` are those of
//! its particles about their centre `c`: `L = Σ m r_k × v_k`, `I = Σ m (|r_k|² 1 − r_k r_kᵀ)`,
//! `r_k = x_k − c`, `ω = I⁻¹ L` (the particulation reproduces the bone's inertia). The
//! impulse turns a side by `Δω = I⁻¹ Δλ`, each particle taking `Δv_k = Δω × r_k`:
//! `Σ m Δv_k = Δω × Σ m r_k = 0` keeps linear momentum, `Σ m r_k × Δv_k = I Δω = Δλ`
//! is exactly the impulse. It only removes relative spin: energy taken is at most
//! `|Δλ · (ω_a − ω_b)|`, never added.

use super::super::joint_kinds::JointKinds;
use super::super::joints::Joint;
use super::particles::{PER_BONE, XParticles};
use glam::{DVec3, Mat3, Vec3};

/// A bone's rigid spin as its particles carry it.
struct Spin {
    /// Particle centre `c`.
    center: DVec3,
    /// World inverse inertia about `c`.
    inv_inertia: Mat3,
    /// Angular velocity `I⁻¹ L`.
    omega: Vec3,
}

/// Bone `i`'s spin, or `None` if it takes no corrections (fixed or asleep) or its
/// particles are degenerate.
fn spin(p: &XParticles, i: Option<usize>) -> Option<Spin> {
    let i = i?;
    if !p.moves(i) {
        return None;
    }
    let f = PER_BONE * i;
    let ks = f..f + PER_BONE;
    let m_total: f32 = p.mass[ks.clone()].iter().sum();
    if m_total <= 0.0 {
        return None;
    }
    let center = ks.clone().map(|k| p.x[k] * p.mass[k] as f64).sum::<DVec3>() / m_total as f64;
    let v_c = ks.clone().map(|k| p.v[k] * p.mass[k]).sum::<Vec3>() / m_total;
    let mut inertia = Mat3::ZERO;
    let mut l = Vec3::ZERO;
    for k in ks {
        let r = (p.x[k] - center).as_vec3();
        let m = p.mass[k];
        inertia +=
            (Mat3::IDENTITY * r.length_squared() - Mat3::from_cols(r * r.x, r * r.y, r * r.z)) * m;
        l += r.cross(p.v[k] - v_c) * m;
    }
    let det = inertia.determinant();
    if !det.is_finite() || det.abs() <= 1e-30 {
        return None;
    }
    let inv_inertia = inertia.inverse();
    Some(Spin {
        center,
        inv_inertia,
        omega: inv_inertia * l,
    })
}

/// Turns bone `i`'s particles by `dw` about their centre (module doc).
fn turn(p: &mut XParticles, i: usize, s: &Spin, dw: Vec3) {
    for k in PER_BONE * i..PER_BONE * (i + 1) {
        p.v[k] += dw.cross((p.x[k] - s.center).as_vec3());
    }
}

/// Every joint's friction over a substep `h` (module doc), in joint order; their
/// kinds in `kinds`.
pub(crate) fn solve(p: &mut XParticles, joints: &[Joint], kinds: &JointKinds, h: f32) {
    for j in joints {
        let friction_torque = kinds.of(j).friction_torque;
        if friction_torque <= 0.0 {
            continue;
        }
        let (sa, sb) = (spin(p, j.a()), spin(p, j.b()));
        let inv = |s: &Option<Spin>| s.as_ref().map_or(Mat3::ZERO, |s| s.inv_inertia);
        let om = |s: &Option<Spin>| s.as_ref().map_or(Vec3::ZERO, |s| s.omega);
        let k = inv(&sa) + inv(&sb);
        // Neither side moves (or a NaN): nothing to hold.
        let det = k.determinant();
        if !det.is_finite() || det.abs() <= 1e-30 {
            continue;
        }
        let mut impulse = -(k.inverse() * (om(&sa) - om(&sb)));
        let cap = friction_torque * h;
        if impulse.length_squared() > cap * cap {
            impulse = impulse.normalize() * cap;
        }
        if let (Some(i), Some(s)) = (j.a(), &sa) {
            turn(p, i, s, s.inv_inertia * impulse);
        }
        if let (Some(i), Some(s)) = (j.b(), &sb) {
            turn(p, i, s, -(s.inv_inertia * impulse));
        }
    }
}
