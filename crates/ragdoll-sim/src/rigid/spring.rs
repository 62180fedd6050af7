//! Doom 3 spring between an anchor on each body: stiffness `stretch` when longer than
//! the rest length and `compress` when shorter, viscous `damping`, and optional hard
//! minimum and maximum lengths.

// `!(k > ε)` on purpose: it is also true for NaN, which must skip the row too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::body::BodyStates;
use super::joint::{JointFrame, JointSolve};
use super::soft::{Softness, Spring, StepContext};
use glam::{Vec3, Vec3A};

/// A spring joint.
#[derive(Clone, Debug)]
pub struct SpringJoint {
    /// Bodies; `local_a`/`local_b` are the two (different) anchors.
    pub frame: JointFrame,
    /// Stiffness when stretched (N/m).
    pub stretch: f32,
    /// Stiffness when compressed (N/m).
    pub compress: f32,
    /// Damping (N·s/m).
    pub damping: f32,
    /// Rest length (m).
    pub rest_length: f32,
    /// Minimum length (m, 0 = none).
    pub min_length: f32,
    /// Maximum length (m, 0 = none).
    pub max_length: f32,
    /// Accumulated impulses: spring, min, max.
    pub impulse: [f32; 3],
}

impl SpringJoint {
    /// Direction, length and offsets now.
    fn geometry(&self, s: &BodyStates) -> (Vec3, f32, Vec3, Vec3) {
        let f = &self.frame;
        let (ra, rb) = f.offsets(s);
        let d = (s.com[f.b] + rb) - (s.com[f.a] + ra);
        let len = d.length();
        let n = if len > 1e-6 { d / len } else { Vec3::Y };
        (n, len, ra, rb)
    }

    fn apply(&self, s: &mut BodyStates, n: Vec3, ra: Vec3, rb: Vec3, l: f32) {
        let (ra, rb, n) = (Vec3A::from(ra), Vec3A::from(rb), Vec3A::from(n));
        s.apply_impulse(self.frame.a, ra, -n * l);
        s.apply_impulse(self.frame.b, rb, n * l);
    }
}

impl JointSolve for SpringJoint {
    type Rows = ();

    fn frame(&self) -> &JointFrame {
        &self.frame
    }

    fn prepare(&mut self, _: &mut (), _: &BodyStates) {}

    fn warm_start(&self, _: &(), s: &mut BodyStates) {
        let (n, _, ra, rb) = self.geometry(s);
        let total = self.impulse[0] + self.impulse[1] - self.impulse[2];
        self.apply(s, n, ra, rb, total);
    }

    fn solve(&mut self, _: &(), s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        let f = self.frame;
        let (n, len, ra, rb) = self.geometry(s);
        let (ja, jb) = (ra.cross(n), rb.cross(n));
        let k = s.inv_mass[f.a]
            + s.inv_mass[f.b]
            + ja.dot(s.inv_inertia[f.a] * ja)
            + jb.dot(s.inv_inertia[f.b] * jb);
        if !(k > 1e-20) {
            return;
        }
        let cdot = |s: &BodyStates| {
            let (ra, rb) = (Vec3A::from(ra), Vec3A::from(rb));
            n.dot(Vec3::from(
                s.point_velocity(f.b, rb) - s.point_velocity(f.a, ra),
            ))
        };
        // The spring itself: a physical force, identical in both passes.
        let c = len - self.rest_length;
        let stiffness = if c > 0.0 { self.stretch } else { self.compress };
        if let Some(sp) = Spring::new(stiffness, self.damping, ctx.h) {
            let l = -(cdot(s) + sp.bias_rate * c + sp.gamma * self.impulse[0]) / (k + sp.gamma);
            self.impulse[0] += l;
            self.apply(s, n, ra, rb, l);
        }
        // Hard length bounds, one-sided like contacts.
        for (slot, bound, sign) in [(1, self.min_length, 1.0f32), (2, self.max_length, -1.0)] {
            if bound <= 0.0 {
                continue;
            }
            let c = sign * (len - bound);
            let (bias, soft) = if c > 0.0 {
                (c * ctx.inv_h, Softness::RIGID)
            } else if use_bias {
                (ctx.joint.bias_rate * c, ctx.joint)
            } else {
                (0.0, Softness::RIGID)
            };
            let old = self.impulse[slot];
            let l = -soft.mass_scale / k * (sign * cdot(s) + bias) - soft.impulse_scale * old;
            let new = (old + l).max(0.0);
            self.impulse[slot] = new;
            self.apply(s, n, ra, rb, sign * (new - old));
        }
    }

    fn gap(&self, _: &BodyStates) -> f32 {
        0.0
    }

    fn limit_violation(&self, _: &BodyStates) -> f32 {
        0.0
    }
}
