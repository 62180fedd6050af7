//! Semi-implicit (symplectic) Euler integration of rigid bodies, one substep at a time.
//!
//! Velocities first (gravity, air friction, the gyroscopic term), then — after the
//! constraints have corrected the velocities — positions from the new velocities. This
//! is the integrator of Box2D v3's soft step and of Catto's GDC 2015 talk
//! "Numerical methods".

use super::body::{BodyStates, Motions};
use glam::{Mat3, Mat3A, Quat, Vec3, Vec3A};

/// World inverse inertia `R I⁻¹ Rᵀ` for every awake body, refreshed before the
/// constraints use it. Sleeping and fixed bodies keep zero.
pub fn update_inertia(states: &mut BodyStates, motion: Motions<'_>, awake: &[bool]) {
    for (i, m) in motion.bodies.iter().enumerate() {
        if !awake[i] {
            states.inv_inertia[i] = Mat3A::ZERO;
            continue;
        }
        let r = Mat3A::from_quat(states.rot[i]);
        states.inv_inertia[i] = r * Mat3A::from(m.inv_inertia_local(motion.full)) * r.transpose();
    }
}

/// One implicit Euler step of Euler's equation `I ω̇ + ω × I ω = 0` in body space,
/// linearised once (a single Newton step), as Catto recommends: explicit integration of
/// the gyroscopic term adds energy to tumbling bodies, the implicit one removes a little.
///
/// `f(ω) = I (ω − ω₀) + h ω × I ω`, `J = I + h (ω̂ I − (Iω)^)`, `ω₁ = ω₀ − J⁻¹ f(ω₀)`.
///
/// In `Mat3A` (16-byte columns) so the products run in SIMD lanes without widening
/// each column first: the same operations, the same bits.
fn gyroscopic(w_world: Vec3, rot: Quat, inertia: Mat3, h: f32) -> Vec3 {
    let inertia = Mat3A::from(inertia);
    let w = rot.inverse() * w_world;
    let iw = inertia * w;
    let f = h * w.cross(iw);
    let j = inertia + h * (Mat3A::from(skew(w)) * inertia - Mat3A::from(skew(iw)));
    let det = j.determinant();
    if !(det.is_finite() && det.abs() > 1e-12) {
        return w_world;
    }
    rot * (w - j.inverse() * f)
}

/// The cross-product matrix: `skew(a) b = a × b`.
pub fn skew(a: Vec3) -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.0, a.z, -a.y),
        Vec3::new(-a.z, 0.0, a.x),
        Vec3::new(a.y, -a.x, 0.0),
    )
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
    for (i, b) in motion.bodies.iter().enumerate() {
        if !awake[i] {
            continue;
        }
        let mut v = states.lin_vel[i] + Vec3A::from(gravity * h);
        let mut w = Vec3A::from(gyroscopic(
            Vec3::from(states.ang_vel[i]),
            states.rot[i],
            b.inertia(motion.full),
            h,
        ));
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
