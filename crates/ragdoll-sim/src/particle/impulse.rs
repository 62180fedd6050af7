//! An impulse from outside (a hit, a shot, an explosion) on one bone, for every particle
//! solver, and the wake it brings.
//!
//! A bone is moved as a rigid body of its particles would be: an impulse `J` at the
//! world point `p` changes the velocity of particle `k` by
//!
//! `Δv_k = J / M + Δω × (x_k − c)`, `Δω = I⁻¹ ((p − c) × J)`,
//!
//! with `M = Σ m_k`, `c = Σ m_k x_k / M` and `I = Σ m_k (|r_k|² 𝟙 − r_k r_kᵀ)`,
//! `r_k = x_k − c`, the mass, centre and inertia of the particles themselves. Then
//! `Σ m_k Δv_k = J` (the `Δω` terms cancel because `Σ m_k r_k = 0`) and
//! `Σ m_k r_k × Δv_k = I Δω = (p − c) × J`: the particles' momentum changes by exactly
//! `J` and their angular momentum about `c` by exactly `(p − c) × J`, whatever the
//! particles. Where they reproduce the body's mass, centre of mass and inertia (the
//! rigid-frames and XPBD placements) this is the rigid body's response; the paper's
//! four particles at the shape's corners do not, so a paper bone turns as its
//! particles' inertia says.
//!
//! Per solver:
//! - rigid frames: no particles are stored; the frame's velocities take `J/M` and
//!   `R I_local⁻¹ Rᵀ ((p − c) × J)`, the same as above for the particles it implies;
//! - XPBD: each particle's velocity takes `Δv_k`;
//! - paper: each movable particle's Verlet velocity `(x − x_old)/Δt` takes `Δv_k`
//!   (`x_old −= Δv_k Δt`), with the particles' metric masses (a joint particle shared by
//!   two bones carries both shares); particles held by the world or a fixed bone take
//!   no part.
//!
//! An impulse on a fixed body does nothing. A sleeping bone wakes, with its figure (the
//! bones joined to it), before it moves.

use super::xpbd::particles::PER_BONE;
use super::xpbd::sleeping::Rest;
use super::{ParticleSolver, ParticleWorld};
use crate::scene::BodyId;
use glam::{DMat3, DVec3, Vec3, Vec3A};

/// The mass, centre of mass and inertia about it (world axes) of particles of masses
/// `m` at `x`; `None` when they have no mass.
pub(crate) fn particle_inertia<const N: usize>(
    x: &[Vec3; N],
    m: &[f32; N],
) -> Option<(f64, DVec3, DMat3)> {
    // In f64: the inertia of four points can be ill-conditioned (a thin bone), and its
    // inverse should not add more error than the f32 state can hold.
    let total: f64 = m.iter().map(|&m| m as f64).sum();
    if total <= 0.0 {
        return None;
    }
    let c = (0..N).map(|k| x[k].as_dvec3() * m[k] as f64).sum::<DVec3>() / total;
    let mut inertia = DMat3::ZERO;
    for k in 0..N {
        let r = x[k].as_dvec3() - c;
        inertia += (DMat3::from_diagonal(DVec3::splat(r.length_squared()))
            - DMat3::from_cols(r * r.x, r * r.y, r * r.z))
            * m[k] as f64;
    }
    Some((total, c, inertia))
}

/// `I⁻¹`, or zero when the particles are collinear (`det I` against its scale
/// `(trace/3)³`): they then take no turn.
pub(crate) fn inverse_inertia(inertia: &DMat3) -> DMat3 {
    let scale = (inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z) / 3.0;
    if inertia.determinant() > 1e-9 * scale.powi(3) {
        inertia.inverse()
    } else {
        DMat3::ZERO
    }
}

/// The velocity change of each particle of masses `m` at `x` (module doc). Particles of
/// mass 0 get none. With fewer than three non-collinear particles of mass the inertia
/// is singular and only the linear part is given.
pub(crate) fn rigid_velocity_change<const N: usize>(
    x: &[Vec3; N],
    m: &[f32; N],
    impulse: Vec3,
    point: Vec3,
) -> [Vec3; N] {
    let Some((total, c, inertia)) = particle_inertia(x, m) else {
        return [Vec3::ZERO; N];
    };
    let j = impulse.as_dvec3();
    let dv = j / total;
    let dw = inverse_inertia(&inertia) * (point.as_dvec3() - c).cross(j);
    std::array::from_fn(|k| {
        if m[k] > 0.0 {
            (dv + dw.cross(x[k].as_dvec3() - c)).as_vec3()
        } else {
            Vec3::ZERO
        }
    })
}

/// The velocity change of each particle for the angular impulse `l` (a couple): the
/// turn `Δω = I⁻¹ l` about the particles' centre of mass, `Δv_k = Δω × (x_k − c)`.
pub(crate) fn angular_velocity_change<const N: usize>(
    x: &[Vec3; N],
    m: &[f32; N],
    l: Vec3,
) -> [Vec3; N] {
    let Some((_, c, inertia)) = particle_inertia(x, m) else {
        return [Vec3::ZERO; N];
    };
    let dw = inverse_inertia(&inertia) * l.as_dvec3();
    std::array::from_fn(|k| {
        if m[k] > 0.0 {
            dw.cross(x[k].as_dvec3() - c).as_vec3()
        } else {
            Vec3::ZERO
        }
    })
}

impl ParticleWorld {
    /// The index in `bones` of scene body `body`, if it has a bone.
    pub(crate) fn bone_of(&self, body: BodyId) -> Option<usize> {
        // Bone `i` is body `i` except after a projectile that could not be built.
        match self.bones.get(body.index()) {
            Some(b) if b.body as usize == body.index() => Some(body.index()),
            _ => self
                .bones
                .iter()
                .position(|b| b.body as usize == body.index()),
        }
    }

    /// Wakes every sleeping bone of `bone`'s figure (the bones joined to it), restarting
    /// their rest timers so that the island does not fall straight back asleep.
    /// Contacts join islands too: a woken bone touching a sleeping one wakes it in the
    /// next step, as any moving bone does.
    pub(crate) fn wake_figure(&mut self, bone: usize) {
        let figure = self.bones[bone].figure;
        for i in 0..self.bones.len() {
            let b = &mut self.bones[i];
            if b.figure != figure || b.fixed {
                continue;
            }
            b.wake();
            if let Some(st) = self.xpbd.as_mut() {
                st.particles.set_asleep(i, false);
                st.rest[i] = Rest {
                    anchor: Vec3::from(b.center()),
                    turn: b.rot,
                    ..Rest::default()
                };
            }
        }
    }

    /// Applies the impulse `impulse` (N·s, world) at the world point `point` to `body`
    /// (module doc).
    pub(crate) fn apply_impulse(&mut self, body: BodyId, impulse: Vec3, point: Vec3) {
        let Some(i) = self.bone_of(body) else {
            return;
        };
        if self.bones[i].fixed || !impulse.is_finite() || !point.is_finite() {
            return;
        }
        self.wake_figure(i);
        if let Some(st) = self.xpbd.as_mut() {
            let f = PER_BONE * i;
            let x = st.particles.bone(i);
            let m = std::array::from_fn(|k| st.particles.mass[f + k]);
            let dv = rigid_velocity_change(&x, &m, impulse, point);
            for (k, dv) in dv.into_iter().enumerate() {
                st.particles.v[f + k] += dv;
            }
            return;
        }
        if self.solver == ParticleSolver::Paper {
            let dt = self.settings.timestep;
            let ids = self.particles.of_bone[i].map(|p| p as usize);
            let p = &mut self.particles;
            let x = ids.map(|k| p.x[k]);
            let m = ids.map(|k| if p.inv_mass[k] > 0.0 { p.mass[k] } else { 0.0 });
            let dv = rigid_velocity_change(&x, &m, impulse, point);
            for (&k, dv) in ids.iter().zip(dv) {
                p.x_prev[k] -= dv * dt;
                p.frame_start[k] -= dv * dt;
            }
            return;
        }
        // Rigid frames: the frame's own velocities.
        let b = &mut self.bones[i];
        let inv_inertia = b.inv_inertia_world();
        let arm = point - Vec3::from(b.center());
        b.lin_vel += Vec3A::from(impulse / b.mass);
        b.ang_vel += Vec3A::from(inv_inertia * arm.cross(impulse));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::Method;
    use crate::scene::{BodyDesc, MassSpec, Pose, SceneDesc, Settings, Shape};
    use glam::Quat;

    /// Σ m v and Σ m x × v over the solver's own particles (paper, XPBD) or the corners
    /// of its frames (rigid frames).
    fn particle_momentum(w: &ParticleWorld) -> (DVec3, DVec3) {
        let (mut p, mut l) = (DVec3::ZERO, DVec3::ZERO);
        let mut add = |m: f32, x: Vec3, v: Vec3| {
            let mv = v.as_dvec3() * m as f64;
            p += mv;
            l += x.as_dvec3().cross(mv);
        };
        match w.solver {
            ParticleSolver::RigidFrames => {
                for b in &w.bones {
                    for k in 0..4 {
                        add(
                            b.mass * 0.25,
                            b.corner(&w.kinds, k),
                            b.corner_velocity(&w.kinds, k),
                        );
                    }
                }
            }
            ParticleSolver::Xpbd => {
                let st = w.xpbd.as_ref().expect("an xpbd world has its state");
                for k in 0..st.particles.len() {
                    add(
                        st.particles.mass[k],
                        st.particles.x[k].as_vec3(),
                        st.particles.v[k],
                    );
                }
            }
            ParticleSolver::Paper => {
                let ps = &w.particles;
                let dt = w.settings.timestep;
                for k in 0..ps.len() {
                    add(ps.mass[k], ps.x[k], (ps.x[k] - ps.x_prev[k]) / dt);
                }
            }
        }
        (p, l)
    }

    #[test]
    fn an_impulse_changes_the_particles_momenta_by_j_and_r_cross_j() {
        // A tilted, spinning, moving box and a capsule: the change of the particles'
        // momentum is J and of their angular momentum about the origin (p × J, the
        // arm from the origin) whatever the particles' velocities before.
        let mut a = BodyDesc::new(
            "a",
            Shape::Box {
                half_extents: Vec3::new(0.4, 0.1, 0.2),
            },
            Pose {
                position: Vec3::new(1.0, 3.0, -0.5),
                rotation: Quat::from_rotation_z(0.7) * Quat::from_rotation_x(0.3),
            },
            MassSpec::Mass(3.0),
        );
        a.linear_velocity = Vec3::new(0.5, -1.0, 0.2);
        a.angular_velocity = Vec3::new(1.0, 2.0, -0.5);
        let b = BodyDesc::new(
            "b",
            Shape::Capsule {
                half_height: 0.3,
                radius: 0.1,
            },
            Pose::from_position(Vec3::new(-2.0, 1.0, 0.0)),
            MassSpec::Mass(1.5),
        );
        let scene = SceneDesc {
            name: "impulse".into(),
            bodies: vec![a, b],
            settings: Settings {
                gravity: Vec3::ZERO,
                ground: None,
                ..Settings::default()
            },
            ..SceneDesc::default()
        };
        for solver in [
            ParticleSolver::Paper,
            ParticleSolver::RigidFrames,
            ParticleSolver::Xpbd,
        ] {
            let mut w = ParticleWorld::new(&scene, solver).unwrap_or_else(|e| panic!("{e}"));
            w.step();
            for (body, j, point) in [
                (0, Vec3::new(2.0, 5.0, -1.0), Vec3::new(1.3, 3.05, -0.4)),
                (1, Vec3::new(0.0, 0.0, 4.0), Vec3::new(-1.9, 1.25, 0.1)),
            ] {
                let (p0, l0) = particle_momentum(&w);
                w.apply_impulse(BodyId(body), j, point);
                let (p1, l1) = particle_momentum(&w);
                let dp = p1 - p0;
                let dl = l1 - l0;
                let want_l = point.as_dvec3().cross(j.as_dvec3());
                assert!(
                    (dp - j.as_dvec3()).length() < 1e-4 * j.length() as f64,
                    "{solver:?} body {body}: Δp {dp} for J {j}"
                );
                assert!(
                    (dl - want_l).length() < 1e-4 * want_l.length().max(1.0),
                    "{solver:?} body {body}: ΔL {dl}, p × J {want_l}"
                );
            }
        }
    }
}
