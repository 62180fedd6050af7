//! Joint limits of the improved solver, and the limit angles both solvers are measured
//! by (`max_limit_violation_deg`, measured from the bone frames).
//!
//! Every limit is an angle between directions attached to the two bones. Body1 ("a")
//! carries the shaft / the measured direction, body2 ("b", or the world) the axis, as in
//! Doom 3. A breach is corrected by an XPBD angular correction (Müller et al. 2020,
//! section 3.3.3 "joint limits") that rotates the bones back onto the limit, split by
//! generalised inverse inertia.

use super::bone::{Bone, Side, angular, side_rot};
use glam::{Quat, Vec3};

/// A swing limit in the bones' frames.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Swing {
    /// Shaft within `half_angle` of the axis.
    Cone {
        /// Half-angle (rad).
        half_angle: f32,
    },
    /// Shaft within two half-angles measured in the planes (axis, u) and (axis, v).
    Pyramid {
        /// Half-angle towards `u`.
        h1: f32,
        /// Half-angle towards `v`.
        h2: f32,
        /// First pyramid direction, body2 frame.
        u: Vec3,
        /// Second pyramid direction, body2 frame.
        v: Vec3,
    },
}

/// A swing limit: shaft (body1 frame) against axis (body2 frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SwingLimit {
    /// Shaft in body1's frame.
    pub shaft_a: Vec3,
    /// Axis in body2's frame.
    pub axis_b: Vec3,
    /// Cone or pyramid.
    pub kind: Swing,
}

/// An angle range about an axis: hinge range or twist limit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AngleLimit {
    /// The axis in body1's frame.
    pub axis_a: Vec3,
    /// The same world direction at rest, body2's frame (for drawing the range).
    pub ref_b: Vec3,
    /// Orientation of body1 relative to body2 at rest, `q_b⁻¹ q_a`.
    pub rest_rel: Quat,
    /// Lower bound (rad).
    pub min: f32,
    /// Upper bound (rad).
    pub max: f32,
}

/// Any unit vector perpendicular to `n`.
pub(crate) fn perpendicular(n: Vec3) -> Vec3 {
    n.any_orthonormal_vector()
}

impl AngleLimit {
    /// Current angle: rotation of body1 relative to body2 about the axis, right-handed,
    /// zero at rest — the twist of the swing–twist decomposition of body1's rotation
    /// since rest relative to body2, `Δ = (q_b⁻¹ q_a)_rest⁻¹ (q_b⁻¹ q_a)` in body1's
    /// frame: `2 atan2(Δ_xyz · axis, Δ_w)`. Unlike projecting a reference direction it
    /// stays defined however far the joint swings (short of a half turn).
    pub fn angle(&self, bones: &[Bone], a: Side, b: Side) -> (f32, Vec3) {
        let qa = side_rot(bones, a);
        let qb = side_rot(bones, b);
        let mut d = self.rest_rel.inverse() * (qb.inverse() * qa);
        if d.w < 0.0 {
            d = -d;
        }
        let phi = 2.0 * Vec3::new(d.x, d.y, d.z).dot(self.axis_a).atan2(d.w);
        (phi, qa * self.axis_a)
    }

    /// Excess beyond the range (rad, ≥ 0).
    pub fn violation(&self, bones: &[Bone], a: Side, b: Side) -> f32 {
        let (phi, _) = self.angle(bones, a, b);
        (phi - self.max).max(self.min - phi).max(0.0)
    }

    /// Rotates the bones back into the range.
    pub fn solve(&self, bones: &mut [Bone], a: Side, b: Side, alpha_tilde: f32) {
        let (phi, t) = self.angle(bones, a, b);
        let target = phi.clamp(self.min, self.max);
        if target != phi {
            angular(bones, a, b, t * (target - phi), alpha_tilde);
        }
    }
}

impl SwingLimit {
    fn dirs(&self, bones: &[Bone], a: Side, b: Side) -> (Vec3, Vec3, glam::Quat) {
        let qb = side_rot(bones, b);
        (side_rot(bones, a) * self.shaft_a, qb * self.axis_b, qb)
    }

    /// The direction the shaft must be rotated to, if it is outside the limit.
    fn target(&self, bones: &[Bone], a: Side, b: Side) -> Option<(Vec3, f32)> {
        let (s, ax, qb) = self.dirs(bones, a, b);
        match self.kind {
            Swing::Cone { half_angle } => {
                let phi = s.dot(ax).clamp(-1.0, 1.0).acos();
                (phi > half_angle).then(|| {
                    let mut n = s.cross(ax);
                    if n.length_squared() < 1e-12 {
                        n = perpendicular(ax);
                    }
                    (n.normalize(), phi - half_angle)
                })
            }
            Swing::Pyramid { h1, h2, u, v } => {
                let (u, v) = (qb * u, qb * v);
                let (x, y, z) = (s.dot(u), s.dot(v), s.dot(ax));
                let (a1, a2) = (x.atan2(z), y.atan2(z));
                let excess = (a1.abs() - h1).max(a2.abs() - h2);
                (excess > 0.0).then(|| {
                    let lim = 89f32.to_radians();
                    let c1 = a1.clamp(-h1.min(lim), h1.min(lim));
                    let c2 = a2.clamp(-h2.min(lim), h2.min(lim));
                    let t = (ax + u * c1.tan() + v * c2.tan()).normalize();
                    let mut n = s.cross(t);
                    if n.length_squared() < 1e-12 {
                        n = perpendicular(s);
                    }
                    (n.normalize(), s.dot(t).clamp(-1.0, 1.0).acos())
                })
            }
        }
    }

    /// Excess beyond the limit (rad, ≥ 0).
    pub fn violation(&self, bones: &[Bone], a: Side, b: Side) -> f32 {
        let (s, ax, qb) = self.dirs(bones, a, b);
        match self.kind {
            Swing::Cone { half_angle } => (s.dot(ax).clamp(-1.0, 1.0).acos() - half_angle).max(0.0),
            Swing::Pyramid { h1, h2, u, v } => {
                let (u, v) = (qb * u, qb * v);
                let (x, y, z) = (s.dot(u), s.dot(v), s.dot(ax));
                (x.atan2(z).abs() - h1).max(y.atan2(z).abs() - h2).max(0.0)
            }
        }
    }

    /// Rotates the shaft back onto the cone or pyramid.
    pub fn solve(&self, bones: &mut [Bone], a: Side, b: Side, alpha_tilde: f32) {
        if let Some((n, angle)) = self.target(bones, a, b) {
            angular(bones, a, b, n * angle, alpha_tilde);
        }
    }
}
