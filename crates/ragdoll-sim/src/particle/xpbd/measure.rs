//! The metrics from the particles: energy from each particle's own velocity,
//! `E = Σ ½ m_p |v_p|² + m_p g h_p` (the integrator's state, not a difference of
//! positions), and each body's velocities from its particles' momentum.

use super::super::ParticleWorld;
use super::XpbdState;
use super::particles::PER_BONE;
use crate::method::BodyState;
use crate::metrics::potential_energy;
use glam::{Mat3, Vec3};

/// Kinetic and potential energy (J).
pub(crate) fn energy(w: &ParticleWorld, st: &XpbdState) -> (f64, f64) {
    let p = &st.particles;
    let (mut kinetic, mut potential) = (0.0f64, 0.0f64);
    for k in 0..p.len() {
        if p.mass[k] > 0.0 {
            kinetic += 0.5 * p.mass[k] as f64 * p.v[k].length_squared() as f64;
            potential += potential_energy(&w.settings, p.mass[k], p.x[k].as_vec3());
        }
    }
    (kinetic, potential)
}

/// Each bone's state: centre of mass and orientation from its read frame, linear
/// velocity the particles' mean, angular velocity `I⁻¹ Σ m r × v` (their angular
/// momentum about the centre over the inertia they reproduce).
pub(crate) fn body_states(w: &ParticleWorld, st: &XpbdState, out: &mut Vec<BodyState>) {
    out.clear();
    let p = &st.particles;
    for (i, b) in w.bones.iter().enumerate() {
        let kind = w.kinds.of(b);
        let pose = b.shape_pose(&w.kinds);
        let f = PER_BONE * i;
        let c = p.centre(i);
        let x = p.bone64(i).map(|xk| (xk - c).as_vec3());
        let v = (p.v[f] + p.v[f + 1] + p.v[f + 2] + p.v[f + 3]) * 0.25;
        let l: Vec3 = (0..PER_BONE)
            .map(|k| x[k].cross(p.v[f + k] - v) * (b.mass * 0.25))
            .sum();
        let r = Mat3::from_quat(b.rot);
        let inv_i = r * Mat3::from_diagonal(Vec3::from(b.inv_inertia_local)) * r.transpose();
        let om = inv_i * l;
        out.push(BodyState {
            com: pose.transform_point(kind.shape_com),
            orientation: pose.rotation,
            linear_velocity: if v.is_finite() { v } else { Vec3::ZERO },
            angular_velocity: if om.is_finite() { om } else { Vec3::ZERO },
        });
    }
}
