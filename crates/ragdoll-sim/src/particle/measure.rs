//! The metrics (`docs/metrics.md`) for the particle method, computed from the
//! particles and the bone frames they imply.
//!
//! - E(t) = Σ ½ m_p |v_p|² + m_p g h_p over particles, `v_p` the velocity the state
//!   holds (see [`state_energy`]), potential from [`crate::metrics`].
//! - Penetration: deepest overlap of colliding pairs (the solver's own filter) and of
//!   each shape with the ground, from parry contact manifolds at the current frames.
//! - Joint gap: distance between the anchor as seen from each bone's frame.
//! - Limit violation: excess of each limit's angle, measured from the bone frames.
//! - Bone stretch: largest relative stick-length error.

use super::bone::{Bone, gram_schmidt};
use super::contacts::{broad_phase, ground_pair, shape_pair};
use super::{ParticleSolver, ParticleWorld};
use crate::method::{BodyState, Sample};
use crate::metrics::potential_energy;
use glam::Vec3;

/// The sample for the current state.
pub(crate) fn sample(w: &ParticleWorld) -> Sample {
    let (kinetic, potential) = energy_parts(w);
    let mut pen = 0.0f32;
    let zero = vec![0.0; w.bones.len()];
    let mut pairs = Vec::new();
    // Asleep bones are static to the solver; the metric looks at every colliding pair.
    let mut bones = w.bones.clone();
    for b in bones.iter_mut() {
        b.asleep = false;
    }
    let bones = (&bones[..], &w.kinds);
    broad_phase(bones, &zero, &w.filter, &mut pairs);
    let mut manifolds = Vec::new();
    for &(i, j) in &pairs {
        shape_pair(bones, i, j, 0.0, &mut manifolds, |_, _, _, d| {
            pen = pen.max(-d)
        });
    }
    if let Some(ground) = w.settings.ground {
        for (i, b) in bones.0.iter().enumerate() {
            if !b.fixed {
                ground_pair(bones, i, &ground, 0.0, &mut manifolds, |_, _, _, d| {
                    pen = pen.max(-d)
                });
            }
        }
    }
    let kind = |j| w.joint_kinds.of(j);
    let gap = w
        .joints
        .iter()
        .map(|j| j.gap(kind(j), &w.bones))
        .fold(0.0, f32::max);
    let limit = w
        .joints
        .iter()
        .map(|j| j.limit_violation(kind(j), &w.bones))
        .fold(0.0, f32::max);
    let stretch = (0..w.bones.len())
        .filter(|&i| !w.bones[i].fixed)
        .map(|i| Bone::stretch(&w.corners(i), &w.stick_rest(i)))
        .fold(0.0, f32::max);
    let all_asleep =
        w.solver != ParticleSolver::Paper && w.bones.iter().all(|b| b.fixed || b.asleep);
    Sample {
        energy: kinetic + potential,
        kinetic,
        max_penetration: pen,
        max_joint_gap: gap,
        max_limit_violation_deg: limit.to_degrees(),
        max_bone_stretch: Some(stretch),
        all_asleep,
    }
}

/// The state's energy: particle velocities as the integrator holds them (paper mode:
/// Verlet's `(x − x_old)/Δt`; rigid frames: each corner's `v + ω × r` after the last
/// substep, the velocity the next step starts from).
pub(crate) fn state_energy(w: &ParticleWorld) -> f64 {
    let (kinetic, potential) = energy_parts(w);
    kinetic + potential
}

/// (kinetic, potential) energy (J) of the state, `Σ ½ m_p |v_p|²` and `Σ m_p g h_p` over
/// the particles, with the velocities of [`state_energy`]. A velocity differenced over
/// the frame, `(x(t) − x(t−Δt))/Δt`, is the velocity of half a frame ago: in free fall
/// it reads `½ m g² (t − Δt/2)²` and the total loses `m g² t Δt / 2` that the state
/// never lost, and at an impact it under-reads.
fn energy_parts(w: &ParticleWorld) -> (f64, f64) {
    let dt = w.settings.timestep;
    let mut kinetic = 0.0f64;
    let mut potential = 0.0f64;
    let mut add = |m: f32, v: Vec3, x: Vec3| {
        kinetic += 0.5 * m as f64 * v.length_squared() as f64;
        potential += potential_energy(&w.settings, m, x);
    };
    match w.solver {
        ParticleSolver::RigidFrames => {
            for b in w.bones.iter().filter(|b| !b.fixed) {
                for k in 0..4 {
                    add(
                        b.mass * 0.25,
                        b.corner_velocity(&w.kinds, k),
                        b.corner(&w.kinds, k),
                    );
                }
            }
        }
        // Its own particles' velocities (`ParticleWorld::sample` and `state_energy`
        // answer from them).
        ParticleSolver::Xpbd => {}
        ParticleSolver::Paper => {
            let p = &w.particles;
            for i in (0..p.len()).filter(|&i| p.mass[i] > 0.0) {
                add(p.mass[i], (p.x[i] - p.x_prev[i]) / dt, p.x[i]);
            }
        }
    }
    (kinetic, potential)
}

/// Kinematic state of every bone, as its frame implies.
pub(crate) fn body_states(w: &ParticleWorld, out: &mut Vec<BodyState>) {
    out.clear();
    let dt = w.settings.timestep;
    for (i, b) in w.bones.iter().enumerate() {
        let kind = w.kinds.of(b);
        let pose = b.shape_pose(&w.kinds);
        let com = pose.transform_point(kind.shape_com);
        let (lin, ang) = match w.solver {
            ParticleSolver::RigidFrames | ParticleSolver::Xpbd => {
                (Vec3::from(b.lin_vel), Vec3::from(b.ang_vel))
            }
            ParticleSolver::Paper => {
                let x = &w.particles.frame_start;
                let ids = w.particles.of_bone[i];
                let p0 = x[ids[0] as usize];
                let (r, _) = gram_schmidt(x[ids[1] as usize] - p0, x[ids[2] as usize] - p0);
                let prev = crate::scene::Pose {
                    position: p0,
                    rotation: r,
                }
                .mul_pose(&w.kinds.placement(b).shape_in_bone);
                let prev_com = prev.transform_point(kind.shape_com);
                let (axis, angle) = (pose.rotation * prev.rotation.inverse()).to_axis_angle();
                let angle = if angle > std::f32::consts::PI {
                    angle - std::f32::consts::TAU
                } else {
                    angle
                };
                ((com - prev_com) / dt, axis * angle / dt)
            }
        };
        out.push(BodyState {
            com,
            orientation: pose.rotation,
            linear_velocity: if lin.is_finite() { lin } else { Vec3::ZERO },
            angular_velocity: if ang.is_finite() { ang } else { Vec3::ZERO },
        });
    }
}
