//! An impulse from outside (a hit, a shot, an explosion) on one body, and the wake it
//! brings.
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
use glam::{Mat3, Mat3A, Vec3, Vec3A};

/// What waking and pushing a body touch of the world.
pub(crate) struct Bodies<'a> {
    /// The hot state.
    pub states: &'a mut BodyStates,
    /// The cold data (mass, figure, fixed).
    pub info: &'a [BodyInfo],
    /// Inertia tensors.
    pub motion: Motions<'a>,
    /// Sleep state.
    pub islands: &'a mut Islands,
    /// Per body (and the anchor): moved by the solver this step.
    pub awake: &'a mut [bool],
    /// Per body: not fixed.
    pub dynamic: &'a [bool],
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
