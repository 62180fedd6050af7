//! Bodies put at new poses from outside (Jolt's `Ragdoll::SetPose`): a teleport of
//! bone frames, the particles following rigidly.
//!
//! A bone's frame is its shape frame's pose composed with the bone frame's place in it,
//! `F = P ∘ S⁻¹` (`S = shape_in_bone`). Each particle is put at its rest position in the
//! new frame, `x_k = F r_k`, so a deformed tetrahedron (paper) comes back to its rest
//! shape, and takes the velocity of the rigid motion `v_k = v + ω × (x_k − c)` (`c` the
//! centre of mass): the given velocities, or the ones the body had. Per solver:
//! - rigid frames: the frame itself (its substep's displacement and turn cleared);
//!   the stored linear velocity keeps its half-substep offset `−½ g h` (`particulated_bone`),
//!   so a body set moving falls as one built moving;
//! - XPBD: the four particles and their velocities;
//! - paper: the four particles, their Verlet pasts `x_old = x − v_k Δt + ½ g Δt²` (the
//!   start `Particles::push` gives), and the joint particles tied to the bone by sticks
//!   (not among its four) moved with the bone's rigid motion from its old frame to
//!   the new one. A particle shared by two bones takes the place the last set gives it.
//!
//! A bone set at a pose may overlap something: like every overlap older than a substep,
//! the rigid-frames solver undoes it at the push-out speed
//! (`Settings::max_push_out_speed`), as for a body added inside another.

use super::ParticleWorld;
use super::xpbd::particles::PER_BONE;
use crate::method::{BodyPoseSet, BodyState, BodyVelocity, Method};
use crate::scene::Pose;
use glam::{Quat, Vec3, Vec3A};

impl ParticleWorld {
    /// Puts the bodies of `poses` at their poses (module doc).
    pub(crate) fn set_body_poses(&mut self, poses: &[BodyPoseSet]) {
        let mut states: Vec<BodyState> = Vec::new();
        self.body_states(&mut states);
        for set in poses {
            let Some(i) = self.bone_of(set.body) else {
                continue;
            };
            if self.bones[i].fixed
                || !set.pose.position.is_finite()
                || !set.pose.rotation.is_finite()
            {
                continue;
            }
            let velocity = set.velocity.unwrap_or(BodyVelocity {
                linear: states[i].linear_velocity,
                angular: states[i].angular_velocity,
            });
            self.wake_figure(i);
            let pose = Pose {
                position: set.pose.position,
                rotation: set.pose.rotation.normalize(),
            };
            self.place_bone(i, pose, velocity, set.velocity.is_some());
            self.bones[i].wake();
        }
    }

    /// Puts bone `i`'s shape frame at `pose` moving with `velocity` (of its centre of
    /// mass), its particles following (module doc); `new_velocity` false keeps a
    /// rigid-frames bone's own velocities bit for bit. Neither wakes it nor marks it.
    pub(crate) fn place_bone(
        &mut self,
        i: usize,
        pose: Pose,
        velocity: BodyVelocity,
        new_velocity: bool,
    ) {
        let (kind, placement) = (
            self.kinds.of(&self.bones[i]),
            self.kinds.placement(&self.bones[i]),
        );
        let s = &placement.shape_in_bone;
        let bone_in_shape = Pose {
            position: -(s.rotation.inverse() * s.position),
            rotation: s.rotation.inverse(),
        };
        let frame = pose.mul_pose(&bone_in_shape);
        let old = Pose {
            position: Vec3::from(self.bones[i].center()),
            rotation: self.bones[i].rot,
        };
        let com = pose.transform_point(kind.shape_com);
        let rigid = |x: Vec3| velocity.linear + velocity.angular.cross(x - com);
        let (g, dt) = (self.settings.gravity, self.settings.timestep);
        let b = &mut self.bones[i];
        b.com = Vec3A::from(frame.position);
        b.dcom = Vec3A::ZERO;
        b.rot = frame.rotation;
        b.prev_rot = frame.rotation;
        b.dturn = Quat::IDENTITY;
        if let Some(st) = self.xpbd.as_mut() {
            let f = PER_BONE * i;
            for k in 0..PER_BONE {
                let x = frame.transform_point(placement.rest[k]);
                st.particles.x[f + k] = x.as_dvec3();
                st.particles.x_prev[f + k] = x.as_dvec3();
                st.particles.v[f + k] = rigid(x);
            }
            b.lin_vel = Vec3A::from(velocity.linear);
            b.ang_vel = Vec3A::from(velocity.angular);
            return;
        }
        if let Some(paper) = self.paper.as_ref() {
            let own = self.particles.of_bone[i];
            let rest = placement.rest;
            let past = |x: Vec3, v: Vec3| x - v * dt + g * (0.5 * dt * dt);
            // Joint particles tied to the bone by sticks, not among its four: moved
            // with it, once each (a bone's own six sticks join core particles only).
            let core = |k: u32| self.particles.of_bone.iter().any(|ids| ids.contains(&k));
            let mut tied: Vec<u32> = Vec::new();
            for (a, b) in paper.loose_sticks(&self.particles.of_bone) {
                for (end, other) in [(a, b), (b, a)] {
                    if own.contains(&end)
                        && !own.contains(&other)
                        && !tied.contains(&other)
                        && !core(other)
                    {
                        tied.push(other);
                    }
                }
            }
            let p = &mut self.particles;
            for k in tied {
                let k = k as usize;
                if p.inv_mass[k] > 0.0 {
                    let x = frame.transform_point(old.inverse_transform_point(p.x[k]));
                    p.x[k] = x;
                    p.x_prev[k] = past(x, rigid(x));
                    p.frame_start[k] = p.x_prev[k];
                }
            }
            for (k, r) in own.iter().zip(rest) {
                let k = *k as usize;
                if p.inv_mass[k] > 0.0 {
                    let x = frame.transform_point(r);
                    p.x[k] = x;
                    p.x_prev[k] = past(x, rigid(x));
                    p.frame_start[k] = p.x_prev[k];
                }
            }
            self.bones[i].paper_frame(self.particles.of_bone[i], &self.particles.x);
            return;
        }
        // Rigid frames.
        if new_velocity {
            let h = dt / super::rigid_frames::substeps(&self.settings) as f32;
            b.lin_vel = Vec3A::from(velocity.linear - g * (0.5 * h));
            b.ang_vel = Vec3A::from(velocity.angular);
        }
    }
}
