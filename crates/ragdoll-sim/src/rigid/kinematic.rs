//! Kinematic bodies: moved by the game along a path (an animated character's bones),
//! with infinite mass to the solver, pushing what they meet (Jolt's
//! `MotionType::Kinematic` and `Body::MoveKinematic`).
//!
//! A kinematic body is fixed to the solver (inverse mass and inertia 0, no gravity, it
//! never sleeps and links no island) but keeps a velocity `(v, ω)`:
//! [`Bodies::move_kinematic`] sets it so that the body reaches a target pose after
//! `dt`, `v = (c* − c)/dt`, `ω = θ/dt` (`θ` the turn, axis × angle, from the
//! orientation now to the target's). Every contact and joint row reads body
//! velocities, so the solver sees it moving: a box it meets is pushed at its speed, a
//! body jointed to it is dragged along. The step solves with the body where it
//! starts; after the step it is moved a whole step along its path, `c += v Δt`,
//! `q ← exp(ω Δt) q` — onto the target exactly when `dt` is the timestep. Before the
//! step, every sleeping body whose bounding box meets the box it sweeps wakes (a
//! resting body never meets a body that does not move to the solver otherwise).

use super::contact::shape_pose;
use super::impulse::Bodies;
use crate::method::BodyVelocity;
use crate::particle::kinematic::{advanced, velocity_towards};
use crate::scene::Pose;
use glam::{Quat, Vec3A};
use parry3d::bounding_volume::BoundingVolume;

impl Bodies<'_> {
    /// Makes body `i` kinematic (keeping its velocities) or dynamic again (moving on
    /// with them), waking its figure. A fixed body stays fixed.
    pub(crate) fn set_kinematic(&mut self, i: usize, kinematic: bool) {
        if i >= self.info.len() || self.kinematic[i] == kinematic {
            return;
        }
        if kinematic && self.info[i].fixed {
            return;
        }
        self.wake(i);
        self.kinematic[i] = kinematic;
        self.info[i].fixed = kinematic;
        self.dynamic[i] = !kinematic;
        self.islands.asleep[i] = false;
        self.islands.still_time[i] = 0.0;
        super::solver::refresh_awake(
            self.states,
            self.info,
            self.islands,
            self.awake,
            self.dynamic,
        );
        if !kinematic {
            self.wake(i);
        }
    }

    /// Sets kinematic body `i`'s velocity so that it reaches the shape-frame pose
    /// `target` after `dt` (module doc); nothing for a body that is not kinematic.
    pub(crate) fn move_kinematic(&mut self, i: usize, target: Pose, dt: f32) {
        if i >= self.info.len() || !self.kinematic[i] {
            return;
        }
        let local_com = self.info[i].local_com;
        let target_rot = target.rotation.normalize();
        let v = velocity_towards(
            self.states.com[i],
            self.states.rot[i],
            target.position + target_rot * local_com,
            target_rot,
            dt,
        );
        self.states.lin_vel[i] = Vec3A::from(v.linear);
        self.states.ang_vel[i] = Vec3A::from(v.angular);
    }

    /// Before a step of `dt`: wakes every sleeping body whose bounding box meets the
    /// box a kinematic body sweeps in the step.
    pub(crate) fn wake_kinematic_sweeps(&mut self, dt: f32) {
        for i in 0..self.info.len() {
            if !self.kinematic[i] {
                continue;
            }
            let now = shape_pose(self.states, self.info, i);
            let q = self.states.rot[i];
            let next = advanced(
                Pose {
                    position: self.states.com[i] - q * self.info[i].local_com,
                    rotation: q,
                },
                self.info[i].local_com,
                self.velocity(i),
                dt,
            );
            let shape = self.info[i].collider(self.hulls);
            let swept = shape
                .shape()
                .compute_aabb(&now)
                .merged(
                    &shape.shape().compute_aabb(&parry3d::math::Pose::from_parts(
                        next.position,
                        next.rotation,
                    )),
                );
            for j in 0..self.info.len() {
                if j == i || !self.dynamic[j] || !self.islands.asleep[j] {
                    continue;
                }
                let pose = shape_pose(self.states, self.info, j);
                let aabb = self.info[j]
                    .collider(self.hulls)
                    .shape()
                    .compute_aabb(&pose);
                if aabb.intersects(&swept) {
                    self.wake(j);
                }
            }
        }
    }

    /// After a step of `dt`: moves every kinematic body a step along its path.
    pub(crate) fn advance_kinematic(&mut self, dt: f32) {
        for i in 0..self.info.len() {
            if !self.kinematic[i] {
                continue;
            }
            let v = self.velocity(i);
            self.states.com[i] += v.linear * dt;
            self.states.rot[i] =
                (Quat::from_scaled_axis(v.angular * dt) * self.states.rot[i]).normalize();
        }
    }

    fn velocity(&self, i: usize) -> BodyVelocity {
        BodyVelocity {
            linear: self.states.lin_vel[i].into(),
            angular: self.states.ang_vel[i].into(),
        }
    }
}
