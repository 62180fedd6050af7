//! Kinematic bones: bodies moved by the game along a path (an animated character's
//! bones), with infinite mass to the solver, pushing what they meet (Jolt's
//! `MotionType::Kinematic` and `Body::MoveKinematic`).
//!
//! A kinematic bone is static to every particle solver (fixed: no correction moves it;
//! the paper's and XPBD's particles get inverse mass 0) and moves with the velocity
//! `(v, ω)` it was given. [`ParticleWorld::move_kinematic`] sets that velocity so that
//! the bone reaches a target pose after `dt`: `v = (c* − c)/dt` for the centre of
//! mass, `ω = θ/dt` for the turn `θ` (axis × angle) from the orientation now to the
//! target's.
//!
//! At the start of each step the bone is moved along its path by a whole step,
//! `c += v Δt`, `q ← exp(ω Δt) q` — to the target exactly when `dt` is the timestep —
//! with its particles placed rigidly in the new frame (`place_bone`), and the step is
//! solved with the bone there: a dynamic bone it moved into is pushed out by the
//! contacts' position pass within the step, and a joint to it is pulled along. The
//! particle solvers' contacts see a static bone as still, so what it pushes takes its
//! displacement, not its velocity, from the contact (a position-level push). Before it
//! moves, every sleeping bone whose bounding box meets the box it sweeps wakes, with
//! its figure. After the step the bone reports `(v, ω)` as its velocities.

use super::ParticleWorld;
use super::xpbd::particles::PER_BONE;
use crate::method::{BodyState, BodyVelocity, Method};
use crate::scene::{BodyId, Pose};
use glam::{Quat, Vec3, Vec3A};
use parry3d::bounding_volume::BoundingVolume;

/// One kinematic bone's motion and what it gives back when it turns dynamic again.
#[derive(Clone, Copy, Debug)]
pub(crate) struct KinematicBone {
    /// Velocity of its centre of mass and angular velocity (world).
    pub velocity: BodyVelocity,
    /// Its particles' inverse masses before (paper), restored when it is let go.
    pub inv_mass: [f32; 4],
}

/// Which body's centre of mass, orientation and the velocity taking them to `target`
/// in `dt`.
pub(crate) fn velocity_towards(
    com: Vec3,
    rotation: Quat,
    target_com: Vec3,
    target_rotation: Quat,
    dt: f32,
) -> BodyVelocity {
    let mut turn = (target_rotation * rotation.inverse()).normalize();
    if turn.w < 0.0 {
        // The shorter way round.
        turn = -turn;
    }
    let (axis, angle) = turn.to_axis_angle();
    let dt = dt.max(f32::MIN_POSITIVE);
    BodyVelocity {
        linear: (target_com - com) / dt,
        angular: if angle.is_finite() {
            axis * (angle / dt)
        } else {
            Vec3::ZERO
        },
    }
}

/// The pose a shape frame `pose` with centre of mass `local_com` (shape frame) takes
/// after moving with `velocity` for `dt`: centre `c + v dt`, orientation `exp(ω dt) q`.
pub(crate) fn advanced(pose: Pose, local_com: Vec3, velocity: BodyVelocity, dt: f32) -> Pose {
    let com = pose.transform_point(local_com) + velocity.linear * dt;
    let rotation = (Quat::from_scaled_axis(velocity.angular * dt) * pose.rotation).normalize();
    Pose {
        position: com - rotation * local_com,
        rotation,
    }
}

impl ParticleWorld {
    /// Makes `body` kinematic (keeping its velocities) or dynamic again (moving on with
    /// the kinematic velocities), waking its figure. A fixed body stays fixed.
    pub(crate) fn set_kinematic(&mut self, body: BodyId, kinematic: bool) {
        let Some(i) = self.bone_of(body) else {
            return;
        };
        if self.kinematic.len() < self.bones.len() {
            self.kinematic.resize(self.bones.len(), None);
        }
        match (self.kinematic[i], kinematic) {
            (None, true) => {
                if self.bones[i].fixed {
                    return;
                }
                let mut states: Vec<BodyState> = Vec::new();
                self.body_states(&mut states);
                let velocity = BodyVelocity {
                    linear: states[i].linear_velocity,
                    angular: states[i].angular_velocity,
                };
                self.wake_figure(i);
                // The paper's particles' inverse masses, given back on release (the other
                // solvers keep none: zeros).
                let inv_mass = self.particles.of_bone.get(i).map_or([0.0; 4], |ids| {
                    ids.map(|k| self.particles.inv_mass[k as usize])
                });
                self.bones[i].fixed = true;
                if let Some(st) = self.xpbd.as_mut() {
                    // Fixed, so never woken (`XParticles::set_asleep`) while kinematic.
                    for k in PER_BONE * i..PER_BONE * (i + 1) {
                        st.particles.w[k] = 0.0;
                    }
                }
                if self.solver == super::ParticleSolver::Paper {
                    for k in self.particles.of_bone[i] {
                        self.particles.inv_mass[k as usize] = 0.0;
                    }
                }
                self.kinematic[i] = Some(KinematicBone { velocity, inv_mass });
                self.restore_kinematic_velocity(i);
            }
            (Some(k), false) => {
                self.kinematic[i] = None;
                self.bones[i].fixed = false;
                if let Some(st) = self.xpbd.as_mut() {
                    st.particles.set_asleep(i, false);
                }
                if self.solver == super::ParticleSolver::Paper {
                    for (p, inv) in self.particles.of_bone[i].into_iter().zip(k.inv_mass) {
                        self.particles.inv_mass[p as usize] = inv;
                    }
                }
                // Moving on as it moved: the rigid-frames velocity is stored half a
                // substep of gravity back (`particulated_bone`).
                if self.solver == super::ParticleSolver::RigidFrames {
                    let h = self.settings.timestep
                        / super::rigid_frames::substeps(&self.settings) as f32;
                    let b = &mut self.bones[i];
                    b.lin_vel = Vec3A::from(k.velocity.linear - self.settings.gravity * (0.5 * h));
                }
                self.wake_figure(i);
            }
            _ => {}
        }
    }

    /// Whether `body` is kinematic.
    pub(crate) fn is_kinematic(&self, body: BodyId) -> bool {
        self.bone_of(body)
            .is_some_and(|i| self.kinematic.get(i).is_some_and(Option::is_some))
    }

    /// Sets a kinematic body's velocity so that it reaches the shape-frame pose
    /// `target` after `dt` (module doc). Nothing for a body that is not kinematic.
    pub(crate) fn move_kinematic(&mut self, body: BodyId, target: Pose, dt: f32) {
        let Some(i) = self.bone_of(body) else {
            return;
        };
        let Some(Some(k)) = self.kinematic.get_mut(i) else {
            return;
        };
        let b = &self.bones[i];
        let kind = self.kinds.of(b);
        let pose = b.shape_pose(&self.kinds);
        let com = pose.transform_point(kind.shape_com);
        let target_com = target.transform_point(kind.shape_com);
        k.velocity = velocity_towards(com, pose.rotation, target_com, target.rotation, dt);
        self.restore_kinematic_velocity(i);
    }

    /// Start of a step: wakes what each kinematic bone will sweep, then moves it a
    /// step along its path (module doc).
    pub(crate) fn advance_kinematic(&mut self) {
        let dt = self.settings.timestep;
        for i in 0..self.kinematic.len().min(self.bones.len()) {
            let Some(k) = self.kinematic[i] else {
                continue;
            };
            let b = &self.bones[i];
            let kind = self.kinds.of(b);
            let pose = b.shape_pose(&self.kinds);
            let next = advanced(pose, kind.shape_com, k.velocity, dt);
            self.wake_swept(i, next);
            // The paper's particles of the bone move as if they were free (`place_bone`
            // leaves held particles alone).
            // The paper solver's particles of the bone (the others keep none).
            let held = self
                .particles
                .of_bone
                .get(i)
                .copied()
                .unwrap_or_default()
                .map(|p| p as usize);
            if self.solver == super::ParticleSolver::Paper {
                for (p, inv) in held.into_iter().zip(k.inv_mass) {
                    self.particles.inv_mass[p] = inv;
                }
            }
            self.place_bone(i, next, k.velocity, true);
            if self.solver == super::ParticleSolver::Paper {
                for p in held {
                    self.particles.inv_mass[p] = 0.0;
                }
            }
            self.restore_kinematic_velocity(i);
        }
    }

    /// End of a step: every kinematic bone reports its own velocities again (the
    /// solvers leave a static bone none).
    pub(crate) fn finish_kinematic(&mut self) {
        for i in 0..self.kinematic.len().min(self.bones.len()) {
            if self.kinematic[i].is_some() {
                self.restore_kinematic_velocity(i);
            }
        }
    }

    /// Writes kinematic bone `i`'s velocities where its solver's body state reads them:
    /// the frame (rigid frames), the particles (XPBD), the Verlet pasts (paper: `x_old =
    /// x − v_k Δt`, no gravity: it is not falling).
    fn restore_kinematic_velocity(&mut self, i: usize) {
        let Some(Some(k)) = self.kinematic.get(i).copied() else {
            return;
        };
        let v = k.velocity;
        let b = &mut self.bones[i];
        b.lin_vel = Vec3A::from(v.linear);
        b.ang_vel = Vec3A::from(v.angular);
        let kind = self.kinds.of(b);
        let com = b.shape_pose(&self.kinds).transform_point(kind.shape_com);
        let rigid = |x: Vec3| v.linear + v.angular.cross(x - com);
        if let Some(st) = self.xpbd.as_mut() {
            for p in PER_BONE * i..PER_BONE * (i + 1) {
                st.particles.v[p] = rigid(st.particles.x[p].as_vec3());
            }
        }
        if self.solver == super::ParticleSolver::Paper {
            let dt = self.settings.timestep;
            for p in self.particles.of_bone[i] {
                let p = p as usize;
                let x = self.particles.x[p];
                self.particles.x_prev[p] = x - rigid(x) * dt;
                self.particles.frame_start[p] = self.particles.x_prev[p];
            }
        }
    }

    /// Wakes every sleeping bone (with its figure) whose bounding box meets the box
    /// bone `i` sweeps from where it is to `next` (its shape frame's pose).
    fn wake_swept(&mut self, i: usize, next: Pose) {
        let kind = self.kinds.of(&self.bones[i]);
        let shape = kind.shape.get();
        let now = shape
            .shape()
            .compute_aabb(&self.bones[i].parry_pose(&self.kinds));
        let then = shape.shape().compute_aabb(&parry3d::math::Pose::from_parts(
            next.position,
            next.rotation,
        ));
        let swept = now.merged(&then);
        let asleep: Vec<usize> = (0..self.bones.len())
            .filter(|&j| j != i && self.bones[j].asleep && !self.bones[j].fixed)
            .filter(|&j| {
                let b = &self.bones[j];
                self.kinds
                    .of(b)
                    .shape
                    .get()
                    .shape()
                    .compute_aabb(&b.parry_pose(&self.kinds))
                    .intersects(&swept)
            })
            .collect();
        for j in asleep {
            self.wake_figure(j);
        }
    }
}
