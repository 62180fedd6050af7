//! Joint motors on particle bones (the drive: [`crate::motor`]).
//!
//! Each step starts with every motor's angular impulse `±λ` on its two bones, one
//! motor after the other, each reading the velocities the ones before it left
//! (Gauss–Seidel: two motors on one bone do not both correct the same error), as a
//! couple: a rigid-frames bone's angular velocity takes `I⁻¹ λ`; an XPBD or paper bone's
//! particles take the turn `Δv_k = (I_p⁻¹ λ) × (x_k − c)` of their own inertia `I_p`
//! (`impulse::angular_velocity_change`), which the paper's Verlet keeps as
//! `x_old −= Δv_k Δt`. The motor's stiffness is measured against the same inertia it
//! turns. The step's constraints then act on the turned velocities. A motor between
//! two bones that are both static (asleep, fixed, kinematic) does nothing; setting
//! motors wakes the figures they act on.

use super::impulse::{angular_velocity_change, inverse_inertia, particle_inertia};
use super::xpbd::particles::PER_BONE;
use super::{ParticleSolver, ParticleWorld};
use crate::method::{BodyState, Method};
use crate::motor::{JointMotor, MotorBody, motor_impulse};
use glam::{Mat3, Vec3, Vec3A};

impl ParticleWorld {
    /// Replaces the motors by `motors` (none: all off) and wakes their figures.
    pub(crate) fn set_joint_motors(&mut self, motors: &[JointMotor]) {
        self.motors.clear();
        self.motors.extend_from_slice(motors);
        for m in motors {
            for body in [Some(m.body1), m.body2].into_iter().flatten() {
                if let Some(i) = self.bone_of(body) {
                    self.wake_figure(i);
                }
            }
        }
    }

    /// Bone `i`'s particles as its solver holds them (positions, masses), or `None` for
    /// rigid frames, which keeps none. A paper bone's particles held by the world or a
    /// fixed bone count in its inertia (a bone hinged to the world turns about them)
    /// but are not moved.
    fn bone_particles(&self, i: usize) -> Option<([Vec3; 4], [f32; 4])> {
        match self.solver {
            ParticleSolver::RigidFrames => None,
            ParticleSolver::Xpbd => {
                let st = self.xpbd.as_ref()?;
                let f = PER_BONE * i;
                Some((
                    st.particles.bone(i),
                    std::array::from_fn(|k| st.particles.mass[f + k]),
                ))
            }
            ParticleSolver::Paper => {
                let ids = self.particles.of_bone[i].map(|p| p as usize);
                let p = &self.particles;
                Some((ids.map(|k| p.x[k]), ids.map(|k| p.mass[k])))
            }
        }
    }

    /// Bone `i` as a motor sees it (`states` from `body_states`).
    fn motor_body(&self, i: usize, states: &[BodyState]) -> MotorBody {
        let b = &self.bones[i];
        let inv_inertia = if b.is_static() {
            Mat3::ZERO
        } else {
            match self.bone_particles(i) {
                None => b.inv_inertia_world(),
                Some((x, m)) => particle_inertia(&x, &m)
                    .map_or(Mat3::ZERO, |(_, _, i)| inverse_inertia(&i).as_mat3()),
            }
        };
        MotorBody {
            rotation: states[i].orientation,
            angular_velocity: states[i].angular_velocity,
            inv_inertia,
        }
    }

    /// Turns bone `i` by the angular impulse `l` (module doc).
    fn apply_angular_impulse(&mut self, i: usize, l: Vec3, inv_inertia: Mat3) {
        if self.bones[i].is_static() || l == Vec3::ZERO {
            return;
        }
        match self.bone_particles(i) {
            None => self.bones[i].ang_vel += Vec3A::from(inv_inertia * l),
            Some((x, m)) => {
                let dv = angular_velocity_change(&x, &m, l);
                if let Some(st) = self.xpbd.as_mut() {
                    for (k, dv) in dv.into_iter().enumerate() {
                        st.particles.v[PER_BONE * i + k] += dv;
                    }
                } else {
                    let dt = self.settings.timestep;
                    for (p, dv) in self.particles.of_bone[i].into_iter().zip(dv) {
                        let p = p as usize;
                        if self.particles.inv_mass[p] == 0.0 {
                            continue;
                        }
                        self.particles.x_prev[p] -= dv * dt;
                        self.particles.frame_start[p] -= dv * dt;
                    }
                }
            }
        }
    }

    /// Start of a step: every motor's impulse on its bones (module doc).
    pub(crate) fn apply_motors(&mut self) {
        if self.motors.is_empty() {
            return;
        }
        let mut states: Vec<BodyState> = Vec::new();
        self.body_states(&mut states);
        let h = self.settings.timestep;
        for n in 0..self.motors.len() {
            let m = self.motors[n];
            let Some(i1) = self.bone_of(m.body1) else {
                continue;
            };
            let i2 = m.body2.and_then(|b| self.bone_of(b));
            if self.bones[i1].is_static() && i2.is_none_or(|i| self.bones[i].is_static()) {
                continue;
            }
            let b1 = self.motor_body(i1, &states);
            let b2 = i2.map_or(MotorBody::STILL, |i| self.motor_body(i, &states));
            let l = motor_impulse(&m, &b1, &b2, h);
            self.apply_angular_impulse(i1, l, b1.inv_inertia);
            states[i1].angular_velocity += b1.inv_inertia * l;
            if let Some(i2) = i2 {
                self.apply_angular_impulse(i2, -l, b2.inv_inertia);
                states[i2].angular_velocity -= b2.inv_inertia * l;
            }
        }
    }
}
