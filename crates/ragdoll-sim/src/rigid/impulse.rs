//! What acts on bodies from outside: an impulse (a hit, a shot, an explosion), a new
//! pose (a teleport), joint motors ([`crate::motor`]), and the wake they bring.
//!
//! Newton for a rigid body: an impulse `J` at the world point `p` changes the velocity
//! of the centre of mass `c` by `J/m` and the angular velocity by
//! `I_w⁻¹ ((p − c) × J)`, `I_w = R I Rᵀ`, so the momentum changes by `J` and the angular
//! momentum about `c` by `(p − c) × J`. The inverse mass and inertia are the body's own
//! (from its description), not the solver's arrays, which hold zero for a sleeping body:
//! the body is woken, with its figure and island, before it moves.

use super::body::{BodyInfo, BodyStates, Motions};
use super::island::Islands;
use super::solver;
use crate::method::BodyVelocity;
use crate::motor::{JointMotor, MotorBody, motor_impulse};
use crate::scene::Pose;
use glam::{Mat3, Mat3A, Vec3, Vec3A};
use parry3d::shape::SharedShape;

/// What waking and pushing a body touch of the world.
pub(crate) struct Bodies<'a> {
    /// The hot state.
    pub states: &'a mut BodyStates,
    /// The cold data (mass, figure, fixed: a kinematic body is fixed to the solver).
    pub info: &'a mut [BodyInfo],
    /// Inertia tensors.
    pub motion: Motions<'a>,
    /// Sleep state.
    pub islands: &'a mut Islands,
    /// Per body (and the anchor): moved by the solver this step.
    pub awake: &'a mut [bool],
    /// Per body: neither fixed nor kinematic.
    pub dynamic: &'a mut [bool],
    /// Per body: kinematic (`kinematic`).
    pub kinematic: &'a mut [bool],
    /// The convex hulls' colliders (`BodyInfo::collider`).
    pub hulls: &'a [SharedShape],
}

impl Bodies<'_> {
    /// Wakes body `i`'s island as the last step found it (joints and touching contacts)
    /// and every body of its figure (joined to it, even if the world has not stepped
    /// yet), then gives the solver their inverse masses back.
    pub(crate) fn wake(&mut self, i: usize) {
        let figure = self.info[i].figure;
        for k in 0..self.info.len() {
            if self.info[k].figure == figure && self.islands.asleep[k] {
                self.islands.asleep[k] = false;
                self.islands.still_time[k] = 0.0;
            }
        }
        self.islands.request_wake(i);
        self.islands.apply_wakes();
        solver::refresh_awake(
            self.states,
            self.info,
            self.islands,
            self.awake,
            self.dynamic,
        );
    }

    /// Body `i`'s world inverse inertia `R I⁻¹ Rᵀ` from its description.
    pub(crate) fn world_inv_inertia(&self, i: usize) -> Mat3 {
        let r = Mat3::from_quat(self.states.rot[i]);
        r * self.motion.bodies[i].inv_inertia_local(self.motion.full) * r.transpose()
    }

    /// Applies `impulse` at the world `point` to body `i` (module doc); nothing for a
    /// fixed body or an index past the bodies.
    pub(crate) fn apply_impulse(&mut self, i: usize, impulse: Vec3, point: Vec3) {
        if i >= self.info.len() || self.info[i].fixed {
            return;
        }
        if !impulse.is_finite() || !point.is_finite() {
            return;
        }
        self.wake(i);
        let arm = point - self.states.com[i];
        let inv_inertia = Mat3A::from(self.world_inv_inertia(i));
        self.states.lin_vel[i] += Vec3A::from(impulse * self.info[i].inv_mass());
        self.states.ang_vel[i] += inv_inertia * Vec3A::from(arm.cross(impulse));
    }
}

impl Bodies<'_> {
    /// Puts body `i`'s shape frame at `pose` (its centre of mass at `pose · c_local`),
    /// moving with `velocity` or with its own; wakes it with its figure. Nothing for a
    /// fixed body or an index past the bodies. The contact cache matches the new
    /// manifolds by feature at the next detection, as after any step.
    pub(crate) fn set_pose(&mut self, i: usize, pose: Pose, velocity: Option<BodyVelocity>) {
        if i >= self.info.len() || self.info[i].fixed {
            return;
        }
        if !pose.position.is_finite() || !pose.rotation.is_finite() {
            return;
        }
        self.wake(i);
        let rotation = pose.rotation.normalize();
        self.states.rot[i] = rotation;
        self.states.com[i] = pose.position + rotation * self.info[i].local_com;
        if let Some(v) = velocity {
            self.states.lin_vel[i] = Vec3A::from(v.linear);
            self.states.ang_vel[i] = Vec3A::from(v.angular);
        }
        // The world inverse inertia follows the new orientation (the solver refreshes
        // it each substep of an awake body; this keeps it right until then).
        if self.awake[i] {
            self.states.inv_inertia[i] = Mat3A::from(self.world_inv_inertia(i));
        }
    }
}

impl Bodies<'_> {
    /// Body `i` as a motor sees it: fixed, kinematic and sleeping bodies take no
    /// impulse (zero inverse inertia) but turn the target with their orientation.
    fn motor_body(&self, i: usize) -> MotorBody {
        MotorBody {
            rotation: self.states.rot[i],
            angular_velocity: self.states.ang_vel[i].into(),
            inv_inertia: if self.awake[i] {
                self.world_inv_inertia(i)
            } else {
                Mat3::ZERO
            },
        }
    }

    /// Start of a step: every motor's angular impulse `±λ` on its two bodies
    /// ([`crate::motor`]), one after the other in the motors' order, each reading the
    /// velocities the ones before it left (Gauss–Seidel: two motors on one body do not
    /// both correct the same error).
    pub(crate) fn apply_motors(&mut self, motors: &[JointMotor], h: f32) {
        let n = self.info.len();
        for m in motors {
            let i1 = m.body1.index();
            let i2 = m.body2.map(|b| b.index());
            if i1 >= n || i2.is_some_and(|i| i >= n) {
                continue;
            }
            let b1 = self.motor_body(i1);
            let b2 = i2.map_or(MotorBody::STILL, |i| self.motor_body(i));
            let l = motor_impulse(m, &b1, &b2, h);
            self.states.ang_vel[i1] += Vec3A::from(b1.inv_inertia * l);
            if let Some(i2) = i2 {
                self.states.ang_vel[i2] -= Vec3A::from(b2.inv_inertia * l);
            }
        }
    }

    /// Wakes the figures the motors act on.
    pub(crate) fn wake_motored(&mut self, motors: &[JointMotor]) {
        let n = self.info.len();
        for m in motors {
            for b in [Some(m.body1), m.body2].into_iter().flatten() {
                if b.index() < n && self.dynamic[b.index()] {
                    self.wake(b.index());
                }
            }
        }
    }
}
