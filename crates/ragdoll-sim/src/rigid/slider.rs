//! Slider (prismatic) joint: no relative rotation, relative translation only along an
//! axis fixed in body2 (the rail; the world when body2 is `"world"`). Body1's centre of
//! mass slides on the line through where it was at rest. With the rail on body2 and the
//! point at body1's centre of mass, the rail's reaction puts no torque on body1.

// `!(k > ε)` on purpose: it is also true for NaN, which must skip the row too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::body::BodyStates;
use super::joint::{AngularLock3, JointFrame, JointSolve};
use super::soft::{Softness, StepContext};
use glam::{Vec3, Vec3A};

/// A slider joint.
#[derive(Clone, Debug)]
pub struct SliderJoint {
    /// Bodies and anchor (on a: its centre of mass).
    pub frame: JointFrame,
    /// Slide axis in b.
    pub axis_b: Vec3,
    /// Accumulated impulses of the two perpendicular rows.
    pub impulse: [f32; 2],
    /// The orientation lock.
    pub lock: AngularLock3,
}

impl SliderJoint {
    /// The perpendicular rows: for `C = u·d`, `d = p_a − p_b`, u fixed in b,
    /// `Ċ = u·v_a + (r_a×u)·ω_a − u·v_b − ((r_b+d)×u)·ω_b`. Returns the two directions,
    /// the angular Jacobians' lever arms for a and b, and d.
    fn rows(&self, s: &BodyStates) -> ([Vec3; 2], Vec3, Vec3, Vec3) {
        let f = &self.frame;
        let axis = s.rot[f.b] * self.axis_b;
        let (u, v) = axis.any_orthonormal_pair();
        let (ra, rb) = f.offsets(s);
        let d = (s.com[f.a] + ra) - (s.com[f.b] + rb);
        ([u, v], ra, rb + d, d)
    }

    fn apply(&self, s: &mut BodyStates, u: Vec3, ra: Vec3, rbd: Vec3, l: f32) {
        let f = &self.frame;
        s.lin_vel[f.a] += Vec3A::from(u * (l * s.inv_mass[f.a]));
        s.ang_vel[f.a] += Vec3A::from(s.inv_inertia[f.a] * ra.cross(u) * l);
        s.lin_vel[f.b] -= Vec3A::from(u * (l * s.inv_mass[f.b]));
        s.ang_vel[f.b] -= Vec3A::from(s.inv_inertia[f.b] * rbd.cross(u) * l);
    }

    /// Perpendicular offset of b's anchor from a's slide line (m), the slider's gap.
    pub fn off_axis(&self, s: &BodyStates) -> f32 {
        let (_, _, _, d) = self.rows(s);
        let axis = s.rot[self.frame.b] * self.axis_b;
        (d - axis * axis.dot(d)).length()
    }
}

impl JointSolve for SliderJoint {
    type Rows = ();

    fn frame(&self) -> &JointFrame {
        &self.frame
    }

    fn prepare(&mut self, _: &mut (), _: &BodyStates) {}

    fn warm_start(&self, _: &(), s: &mut BodyStates) {
        self.lock.warm_start(&self.frame, s);
        let (uv, ra, rbd, _) = self.rows(s);
        for (u, l) in uv.into_iter().zip(self.impulse) {
            self.apply(s, u, ra, rbd, l);
        }
    }

    fn solve(&mut self, _: &(), s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        self.lock.solve(&self.frame, s, ctx, use_bias);
        let f = self.frame;
        let (uv, ra, rbd, d) = self.rows(s);
        let soft = if use_bias { ctx.joint } else { Softness::RIGID };
        for (k, u) in uv.into_iter().enumerate() {
            let (ja, jb) = (ra.cross(u), rbd.cross(u));
            let kk = s.inv_mass[f.a]
                + s.inv_mass[f.b]
                + ja.dot(s.inv_inertia[f.a] * ja)
                + jb.dot(s.inv_inertia[f.b] * jb);
            if !(kk > 1e-20) {
                continue;
            }
            let cdot = u.dot(Vec3::from(s.lin_vel[f.a])) + ja.dot(Vec3::from(s.ang_vel[f.a]))
                - u.dot(Vec3::from(s.lin_vel[f.b]))
                - jb.dot(Vec3::from(s.ang_vel[f.b]));
            let l = -soft.mass_scale / kk * (cdot + soft.bias_rate * u.dot(d))
                - soft.impulse_scale * self.impulse[k];
            self.impulse[k] += l;
            self.apply(s, u, ra, rbd, l);
        }
    }

    fn gap(&self, s: &BodyStates) -> f32 {
        self.off_axis(s)
    }

    fn limit_violation(&self, _: &BodyStates) -> f32 {
        0.0
    }
}
