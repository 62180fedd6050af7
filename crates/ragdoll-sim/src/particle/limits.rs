//! Joint limits of the improved solver, and the limit angles both solvers are measured
//! by (`max_limit_violation_deg`, measured from the bone frames).
//!
//! Every limit is an angle between directions attached to the two bones. Body1 ("a")
//! carries the shaft / the measured direction, body2 ("b", or the world) the axis, as in
//! Doom 3. A breach is corrected by an XPBD angular correction (Müller et al. 2020,
//! section 3.3.3 "joint limits") that rotates the bones back onto the limit, split by
//! generalised inverse inertia, about the joint's anchor held where it is
//! (`bone_lanes::angular_held`): the turn and the anchor's three rows solved together,
//! so that a limit under load does not open its joint.

use super::bone::{Bone, Side, side_rot};
use super::bone_lanes::{SideLanes, angular_held, holds, on_pair, per_lane};
use crate::lanes::{Q, Real, V3};
use glam::{Quat, Vec3, Vec3A};

/// A swing limit in the bones' frames.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Swing {
    /// Shaft within `half_angle` of the axis.
    Cone {
        /// Half-angle (rad).
        half_angle: f32,
        /// `cos` of the half-angle pulled in by [`INSIDE_MARGIN`] (`+∞` for a cone that
        /// narrow: no inside): a shaft whose cosine to the axis exceeds it is inside the
        /// cone, known without the `acos` ([`Swing::cone`]).
        cos_inside: f32,
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

impl Swing {
    /// A cone of half-angle `half_angle` (rad), with its quick inside test.
    pub fn cone(half_angle: f32) -> Swing {
        let inner = half_angle - INSIDE_MARGIN;
        Swing::Cone {
            half_angle,
            cos_inside: if inner > INSIDE_MARGIN && inner < std::f32::consts::PI {
                inner.cos()
            } else {
                f32::INFINITY
            },
        }
    }
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
    /// `tan` of the half-bounds pulled into the range by [`INSIDE_MARGIN`]
    /// ([`AngleLimit::inside_bounds`]): a relative rotation whose `(v · x) / w` lies
    /// between them is inside the range, known without the `atan2`.
    pub inside: [f32; 2],
}

/// How far inside its range (rad, on the half-angle) a limit's angle must be for
/// [`RangeLanes::solve`] (and a cone for [`ConeLanes::solve`]) to pass it by without measuring it: far beyond the rounding of
/// `tan`, `atan2` and the products (~1e-7 rad), so the quick test never says inside
/// when the measured angle is not.
const INSIDE_MARGIN: f32 = 1e-4;

/// Any unit vector perpendicular to `n`.
pub(crate) fn perpendicular(n: Vec3) -> Vec3 {
    n.any_orthonormal_vector()
}

impl AngleLimit {
    /// Current angle: rotation of body1 relative to body2 about the axis, right-handed,
    /// zero at rest — the twist of the swing–twist decomposition of body1's rotation
    /// since rest relative to body2, `Δ = (q_b⁻¹ q_a)_rest⁻¹ (q_b⁻¹ q_a) = (w, v)` in
    /// body1's frame: `φ = 2 atan2(v · x, w)` with `x` the axis. Unlike projecting a
    /// reference direction it stays defined however far the joint swings (short of a
    /// half turn).
    ///
    /// Also returns the angle's gradient `J` (world), `φ̇ = J · (ω_a − ω_b)`. A turn `δ`
    /// of body1 in its own frame moves `Δ` to `Δ (0, δ/2)`, so with `y = v · x`
    /// ```text
    /// J = q_a (w² x + w (x × v) + y v) / (w² + y²)
    /// ```
    /// and a turn of body2 acts as the opposite turn of body1. In pure twist `J` is the
    /// axis; once the joint has swung, turns across the axis move the twist too (by up
    /// to `tan(swing/2)` times as much), and the swing–twist angle is no longer a
    /// rotation about the axis alone.
    pub fn angle(&self, bones: &[Bone], a: Side, b: Side) -> (f32, Vec3) {
        let qa = side_rot(bones, a);
        let (phi, grad) = self.angle_of(self.relative(bones, a, b), qa);
        (phi, Vec3::from(grad))
    }

    /// Body1's rotation since rest relative to body2, `Δ` of [`AngleLimit::angle`], with
    /// `w ≥ 0`.
    #[inline]
    fn relative(&self, bones: &[Bone], a: Side, b: Side) -> Quat {
        let qa = side_rot(bones, a);
        let qb = side_rot(bones, b);
        let d = self.rest_rel.inverse() * (qb.inverse() * qa);
        if d.w < 0.0 { -d } else { d }
    }

    /// [`AngleLimit::angle`] from `Δ` and body1's orientation `qa`.
    #[inline]
    fn angle_of(&self, d: Quat, qa: Quat) -> (f32, Vec3A) {
        let (x, v, w) = (Vec3A::from(self.axis_a), Vec3A::new(d.x, d.y, d.z), d.w);
        let y = v.dot(x);
        let phi = 2.0 * y.atan2(w);
        let n = w * w + y * y;
        let grad = if n > 1e-12 {
            (x * (w * w) + x.cross(v) * w + v * y) / n
        } else {
            x
        };
        (phi, qa * grad)
    }

    /// [`AngleLimit::inside`] for the range `[min, max]`: `φ = 2 atan(y / w)` for
    /// `w > 0`, so `φ` lies in `[min + 2ε, max − 2ε]` exactly when `y / w` lies between
    /// `tan(min/2 + ε)` and `tan(max/2 − ε)` (ε = [`INSIDE_MARGIN`]); a half-bound at or
    /// past a quarter turn bounds nothing (`φ` never passes ±π). An empty range (a 0°
    /// limit) has no inside: every pass measures it.
    pub fn inside_bounds(min: f32, max: f32) -> [f32; 2] {
        let (lo, hi) = (0.5 * min + INSIDE_MARGIN, 0.5 * max - INSIDE_MARGIN);
        if lo >= hi || lo.is_nan() || hi.is_nan() {
            return [f32::INFINITY, f32::NEG_INFINITY];
        }
        let quarter = std::f32::consts::FRAC_PI_2;
        [
            if lo <= -quarter {
                f32::NEG_INFINITY
            } else {
                lo.tan()
            },
            if hi >= quarter {
                f32::INFINITY
            } else {
                hi.tan()
            },
        ]
    }

    /// Excess beyond the range (rad, ≥ 0).
    pub fn violation(&self, bones: &[Bone], a: Side, b: Side) -> f32 {
        let (phi, _) = self.angle(bones, a, b);
        (phi - self.max).max(self.min - phi).max(0.0)
    }

    /// Rotates the bones back into the range widened by `slack` on both sides, about
    /// the joint's anchor (`anchors`: in body1's and body2's frames)
    /// ([`RangeLanes::solve`], for this one joint).
    pub fn solve(
        &self,
        bones: &mut [Bone],
        (a, b): (Side, Side),
        anchors: (Vec3, Vec3),
        alpha_tilde: f32,
        slack: f32,
    ) {
        let range = RangeLanes::<f32>::from_fn(|_| (*self, slack));
        let anchors = (V3::from_fn(|_| anchors.0), V3::from_fn(|_| anchors.1));
        on_pair(bones, a, b, |sa, sb| {
            range.solve(sa, sb, anchors, alpha_tilde, true)
        });
    }
}

/// Angle ranges ([`AngleLimit`]) of one constraint per lane, their range widened by the
/// joint's `slack` (`Joint::slack`; built for a run of substeps, while it holds).
pub(super) struct RangeLanes<R: Real> {
    axis_a: V3<R>,
    /// `(q_b⁻¹ q_a)` at rest, inverted.
    rest_inv: Q<R>,
    min: R,
    max: R,
    /// [`AngleLimit::inside`], made for the range itself.
    lo: R,
    hi: R,
}

impl<R: Real> RangeLanes<R> {
    /// The limit and slack `f(k)` in lane `k`.
    pub fn from_fn(f: impl Fn(usize) -> (AngleLimit, f32)) -> RangeLanes<R> {
        RangeLanes {
            axis_a: V3::from_fn(|k| f(k).0.axis_a),
            rest_inv: Q::from_fn(|k| f(k).0.rest_rel.inverse()),
            min: R::from_fn(|k| f(k).0.min - f(k).1),
            max: R::from_fn(|k| f(k).0.max + f(k).1),
            lo: R::from_fn(|k| f(k).0.inside[0]),
            hi: R::from_fn(|k| f(k).0.inside[1]),
        }
    }

    /// Whether the relative rotation `Δ` ([`AngleLimit::angle`], `w ≥ 0`) is inside the
    /// range by [`INSIDE_MARGIN`] at least, told without its angle: `(v · x) / w`
    /// between the bounds of [`AngleLimit::inside`].
    #[inline]
    fn inside(&self, d: Q<R>) -> R::Mask {
        let y = d.v.dot(self.axis_a);
        d.w.gt(R::ZERO) & y.ge(d.w * self.lo) & y.le(d.w * self.hi)
    }

    /// Rotates the bones back into the range, in the lanes of `active`: XPBD on `C = φ −
    /// bound` along its gradient `J` ([`AngleLimit::angle`]), `Δλ = −C / (Jᵀ W J)` with
    /// `W` the two inverse inertias, compliance `α̃`.
    ///
    /// Turning about the axis alone (`J`'s value in pure twist) also restores the angle,
    /// but at a large swing it is far from the least-inertia correction: the capsule
    /// human's shoulder (twist ±45°, swung 130°) then turned the upper arm, light about
    /// its own axis, back and forth against the elbow every substep and spun the arm up
    /// to 60-120 rad/s; along the gradient the state energy stays within 0.6 %.
    ///
    /// Most limits are inside their range most of the time: that is told from `Δ` alone
    /// ([`RangeLanes::inside`]), and the `atan2` and the gradient are only evaluated for
    /// a limit near or past a bound (the same corrections: a limit the quick test passes
    /// by is one whose measured angle its clamp would leave as it is). The slack widens
    /// the range; the quick test, made for the range itself, stays a sure one.
    pub fn solve(
        &self,
        a: &mut SideLanes<R>,
        b: &mut SideLanes<R>,
        (anchor_a, anchor_b): (V3<R>, V3<R>),
        alpha: R,
        active: R::Mask,
    ) {
        let d = self.rest_inv.mul_quat(b.rot.conjugate().mul_quat(a.rot));
        let flip = d.w.lt(R::ZERO);
        let d = Q::select(flip, d.scale(R::splat(-1.0)), d);
        let near = active & !self.inside(d);
        if !R::any(near) {
            return;
        }
        let (w, y) = (d.w, d.v.dot(self.axis_a));
        let phi = per_lane(near, y, |k, y| 2.0 * y.atan2(w.lane(k)));
        let n = w * w + y * y;
        let x = self.axis_a;
        let grad = (x * (w * w) + x.cross(d.v) * w + d.v * y) * (R::ONE / n);
        let grad = V3::select(n.gt(R::splat(1e-12)), grad, x);
        let j = a.rot.rotate(grad);
        let target = phi.max(self.min).min(self.max);
        let j2 = j.length_squared();
        let moved = target.lt(phi) | target.gt(phi);
        let fix = near & moved & j2.gt(R::splat(1e-12));
        // A turn by an angle along a unit direction: `J/|J|` by `C/|J|`, about the
        // held anchor (`angular_held`).
        let dphi = j * ((target - phi) / j2);
        angular_held((a, anchor_a), (b, anchor_b), dphi, alpha, fix);
    }
}

/// Cone swing limits ([`Swing::Cone`]) of one constraint per lane, widened by the
/// joint's `slack`.
pub(super) struct ConeLanes<R: Real> {
    shaft_a: V3<R>,
    axis_b: V3<R>,
    half_angle: R,
    /// [`Swing::Cone`]'s `cos_inside`, made for the cone itself.
    cos_inside: R,
}

impl<R: Real> ConeLanes<R> {
    /// The cone and slack `f(k)` in lane `k`; `None` if a lane's swing is no cone.
    pub fn from_fn(f: impl Fn(usize) -> (SwingLimit, f32)) -> Option<ConeLanes<R>> {
        let cone = |k: usize| match f(k).0.kind {
            Swing::Cone {
                half_angle,
                cos_inside,
            } => Some((half_angle + f(k).1, cos_inside)),
            Swing::Pyramid { .. } => None,
        };
        let cones: Vec<(f32, f32)> = (0..R::WIDTH).map(cone).collect::<Option<_>>()?;
        Some(ConeLanes {
            shaft_a: V3::from_fn(|k| f(k).0.shaft_a),
            axis_b: V3::from_fn(|k| f(k).0.axis_b),
            half_angle: R::from_fn(|k| cones[k].0),
            cos_inside: R::from_fn(|k| cones[k].1),
        })
    }

    /// The shaft `s`'s angle to the axis `ax` in the lanes of `active` where it is past
    /// the cone, and those lanes; `None` when none is. Most shafts are well inside
    /// their cone most of the time: told from the cosine, the `acos` only for a shaft
    /// near or past the cone (the same answer: `acos` is decreasing, and the margin far
    /// exceeds its rounding).
    fn breach(&self, s: V3<R>, ax: V3<R>, active: R::Mask) -> Option<(R, R::Mask)> {
        let c = s.dot(ax);
        let near = active & !c.gt(self.cos_inside);
        if !R::any(near) {
            return None;
        }
        let phi = per_lane(near, c, |_, c| c.clamp(-1.0, 1.0).acos());
        let over = near & phi.gt(self.half_angle);
        R::any(over).then_some((phi, over))
    }

    /// Turns the shaft back onto the cone, in the lanes of `active`, compliance `α̃`:
    /// about `s × axis` (any perpendicular when they are parallel) by the excess, the
    /// anchor held (`angular_held`).
    pub fn solve(
        &self,
        a: &mut SideLanes<R>,
        b: &mut SideLanes<R>,
        (anchor_a, anchor_b): (V3<R>, V3<R>),
        alpha: R,
        active: R::Mask,
    ) {
        let s = a.rot.rotate(self.shaft_a);
        let ax = b.rot.rotate(self.axis_b);
        let Some((phi, over)) = self.breach(s, ax, active) else {
            return;
        };
        let mut n = s.cross(ax);
        let degenerate = over & n.length_squared().lt(R::splat(1e-12));
        if R::any(degenerate) {
            let p = V3::from_fn(|k| {
                if holds::<R>(degenerate, k) {
                    perpendicular(ax.lane(k))
                } else {
                    Vec3::ZERO
                }
            });
            n = V3::select(degenerate, p, n);
        }
        let n = n * (R::ONE / n.length_squared().sqrt());
        let dphi = n * (phi - self.half_angle);
        angular_held((a, anchor_a), (b, anchor_b), dphi, alpha, over);
    }
}

impl SwingLimit {
    fn dirs(&self, bones: &[Bone], a: Side, b: Side) -> (Vec3, Vec3, glam::Quat) {
        let qb = side_rot(bones, b);
        (side_rot(bones, a) * self.shaft_a, qb * self.axis_b, qb)
    }

    /// A pyramid's shaft turn back onto the pyramid widened by `slack` (rad), if it is
    /// outside: the unit axis and the angle (a cone is solved by [`ConeLanes`]).
    fn pyramid_target(&self, bones: &[Bone], a: Side, b: Side, slack: f32) -> Option<(Vec3, f32)> {
        let (s, ax, qb) = self.dirs(bones, a, b);
        match self.kind {
            Swing::Cone { .. } => None,
            Swing::Pyramid { h1, h2, u, v } => {
                let (h1, h2) = (h1 + slack, h2 + slack);
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
            Swing::Cone { half_angle, .. } => {
                (s.dot(ax).clamp(-1.0, 1.0).acos() - half_angle).max(0.0)
            }
            Swing::Pyramid { h1, h2, u, v } => {
                let (u, v) = (qb * u, qb * v);
                let (x, y, z) = (s.dot(u), s.dot(v), s.dot(ax));
                (x.atan2(z).abs() - h1).max(y.atan2(z).abs() - h2).max(0.0)
            }
        }
    }

    /// Rotates the shaft back onto the cone or pyramid widened by `slack`, about the
    /// joint's anchor (`anchors`: in body1's and body2's frames).
    pub fn solve(
        &self,
        bones: &mut [Bone],
        (a, b): (Side, Side),
        anchors: (Vec3, Vec3),
        alpha_tilde: f32,
        slack: f32,
    ) {
        let anchors = (V3::from_fn(|_| anchors.0), V3::from_fn(|_| anchors.1));
        if let Some(cone) = ConeLanes::<f32>::from_fn(|_| (*self, slack)) {
            on_pair(bones, a, b, |sa, sb| {
                cone.solve(sa, sb, anchors, alpha_tilde, true)
            });
        } else if let Some((n, angle)) = self.pyramid_target(bones, a, b, slack) {
            let dphi = V3::from_fn(|_| n * angle);
            on_pair(bones, a, b, |sa, sb| {
                angular_held((sa, anchors.0), (sb, anchors.1), dphi, alpha_tilde, true)
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{scene_world, uniform};
    use super::Swing;
    use glam::{Quat, Vec3, Vec3A};

    /// `AngleLimit::angle`'s `J` is the twist angle's gradient: turning body1 by a small
    /// world rotation `δ` changes the angle by `J · δ`, turning body2 by `−J · δ`. Checked
    /// by central differences on the capsule human's shoulder swung 130° and twisted
    /// 30°, where `J` is far from the axis.
    #[test]
    fn twist_gradient_matches_finite_differences() {
        let mut w = scene_world("capsule-human.af", None);
        let joint = w
            .joints
            .iter()
            .find(|j| {
                let k = w.joint_kinds.of(j);
                k.swing.is_some() && !k.angle_limits.is_empty()
            })
            .expect("a ball joint with a twist limit")
            .clone();
        let (a, b) = (joint.a(), joint.b());
        let (ia, ib) = (a.expect("body1"), b.expect("body2"));
        let limit = w.joint_kinds.of(&joint).angle_limits[0];
        let qa0 = w.bones[ia].rot;
        let twist_axis = qa0 * limit.axis_a;
        let swing_axis = twist_axis.any_orthonormal_vector();
        w.bones[ia].rot = Quat::from_axis_angle(swing_axis, 130f32.to_radians())
            * Quat::from_axis_angle(twist_axis, 30f32.to_radians())
            * qa0;
        let (phi, grad) = limit.angle(&w.bones, a, b);
        assert!(
            (phi - 30f32.to_radians()).abs() < 1e-4,
            "twist read {} deg",
            phi.to_degrees()
        );
        let axis_now = w.bones[ia].rot * limit.axis_a;
        assert!(
            grad.normalize().dot(axis_now) < 0.95,
            "the gradient should lean off the axis at this swing: {grad}"
        );
        let eps = 1e-3;
        for (i, sign) in [(ia, 1.0f32), (ib, -1.0)] {
            let q = w.bones[i].rot;
            for d in [Vec3::X, Vec3::Y, Vec3::Z] {
                w.bones[i].rot = (Quat::from_scaled_axis(d * eps) * q).normalize();
                let (plus, _) = limit.angle(&w.bones, a, b);
                w.bones[i].rot = (Quat::from_scaled_axis(d * -eps) * q).normalize();
                let (minus, _) = limit.angle(&w.bones, a, b);
                w.bones[i].rot = q;
                let fd = (plus - minus) / (2.0 * eps);
                assert!(
                    (fd - sign * grad.dot(d)).abs() < 2e-3,
                    "bone {i}, turn about {d}: finite difference {fd}, gradient {}",
                    sign * grad.dot(d)
                );
            }
        }
    }

    /// A limit turns its bones about the joint's anchor, held: on the human's hinges
    /// (a range) and ball joints (a cone), body1 turned about 2° past the limit about the
    /// anchor is brought back onto it in one solve, the anchor moves by the second order
    /// of the turn only (under a twentieth of the `r θ` a turn about body1's centre
    /// would open it by, `r` the anchor's distance from that centre), and the centre of
    /// mass of the pair does not move (the anchor's impulse acts on both).
    #[test]
    fn a_limit_turns_about_its_held_anchor() {
        use super::super::joints::JointType;
        let mut w = scene_world("human.af", None);
        let picked: Vec<usize> = (0..w.joints.len())
            .filter(|&k| {
                let j = &w.joints[k];
                let kind = w.joint_kinds.of(j);
                j.a().is_some()
                    && j.b().is_some()
                    && match kind.joint_type {
                        JointType::Hinge { .. } => !kind.angle_limits.is_empty(),
                        JointType::Ball => {
                            matches!(kind.swing.map(|s| s.kind), Some(Swing::Cone { .. }))
                        }
                        _ => false,
                    }
            })
            .collect();
        let hinges = picked
            .iter()
            .filter(|&&k| {
                let kind = w.joint_kinds.of(&w.joints[k]);
                matches!(kind.joint_type, JointType::Hinge { .. })
            })
            .count();
        assert!(hinges >= 2 && picked.len() > hinges, "{picked:?}");
        for k in picked {
            let j = w.joints[k].clone();
            let kind = w.joint_kinds.of(&j).clone();
            let (ia, ib) = (j.a().unwrap(), j.b().unwrap());
            let saved = (w.bones[ia].clone(), w.bones[ib].clone());
            // Past the limit by 20°, turned about the anchor so the joint stays closed.
            let (anchor, _) = j.anchors(&w.bones);
            let (axis, past) = if let Some(l) = kind.angle_limits.first() {
                let (phi, _) = l.angle(&w.bones, j.a(), j.b());
                let axis = w.bones[ia].rot * l.axis_a;
                (axis, l.max - phi + 2f32.to_radians())
            } else {
                let s = kind.swing.unwrap();
                let Swing::Cone { half_angle, .. } = s.kind else {
                    unreachable!()
                };
                let shaft = w.bones[ia].rot * s.shaft_a;
                let ax = w.bones[ib].rot * s.axis_b;
                let n = shaft.cross(ax);
                let n = if n.length_squared() > 1e-8 {
                    -n.normalize()
                } else {
                    super::perpendicular(ax)
                };
                let now = shaft.dot(ax).clamp(-1.0, 1.0).acos();
                (n, half_angle - now + 2f32.to_radians())
            };
            let turn = Quat::from_axis_angle(axis, past);
            let b = &mut w.bones[ia];
            let c = Vec3::from(b.center());
            b.com = (anchor + turn * (c - anchor)).into();
            b.dcom = Vec3A::ZERO;
            b.rot = (turn * b.rot).normalize();
            let before = j.limit_violation(&kind, &w.bones).to_degrees();
            assert!(before > 1.5, "joint {k}: {before}° past");
            let arm = (Vec3::from(w.bones[ia].center()) - anchor).length();
            let (ma, mb) = (w.bones[ia].mass, w.bones[ib].mass);
            let centre = |w: &super::super::ParticleWorld| {
                (Vec3::from(w.bones[ia].center()) * ma + Vec3::from(w.bones[ib].center()) * mb)
                    / (ma + mb)
            };
            let centre_before = centre(&w);
            let anchors = (j.anchor_a, j.anchor_b);
            if let Some(s) = &kind.swing {
                s.solve(&mut w.bones, (j.a(), j.b()), anchors, 0.0, 0.0);
            }
            for l in &kind.angle_limits {
                l.solve(&mut w.bones, (j.a(), j.b()), anchors, 0.0, 0.0);
            }
            let after = j.limit_violation(&kind, &w.bones).to_degrees();
            let gap = j.gap(&kind, &w.bones);
            let drift = (centre(&w) - centre_before).length();
            assert!(after < 0.05, "joint {k}: still {after}° past");
            let first_order = arm * before.to_radians();
            assert!(
                gap < first_order / 20.0,
                "joint {k}: the anchor opened {gap} m (r θ = {first_order} m)"
            );
            assert!(drift < 1e-5, "joint {k}: the pair's centre moved {drift} m");
            (w.bones[ia], w.bones[ib]) = saved;
        }
    }

    /// The cone's quick inside test (`ConeLanes::breach`) gives the measured angle's
    /// answer for every shaft, and passes by every shaft well inside: nine half-angles
    /// from 0 to 180°, half the shafts within 5e-4 rad of the cone.
    #[test]
    fn cone_quick_inside_test_agrees_with_the_acos() {
        use super::{ConeLanes, Swing, SwingLimit, V3};
        let axis = Vec3::new(-0.2, 0.9, 0.4).normalize();
        let across = axis.any_orthonormal_vector();
        let mut next = uniform(0x1234_5678_u32);
        let (mut passed, mut well_inside) = (0, 0);
        for deg in [0.0f32, 0.01, 1.0, 30.0, 45.0, 90.0, 135.0, 179.99, 180.0] {
            let h = deg.to_radians();
            let limit = SwingLimit {
                shaft_a: Vec3::ZERO,
                axis_b: axis,
                kind: Swing::cone(h),
            };
            for k in 0..20_000 {
                // Half the shafts within 5e-4 rad of the cone, where a margin turned the
                // wrong way would show; half anywhere.
                let angle = if k % 2 == 0 {
                    h + (next() * 2.0 - 1.0) * 5e-4
                } else {
                    next() * std::f32::consts::PI
                };
                let about = Quat::from_axis_angle(axis, next() * std::f32::consts::TAU);
                let shaft = about * (Quat::from_axis_angle(across, angle) * axis);
                let limit = SwingLimit {
                    shaft_a: shaft,
                    ..limit
                };
                // The solver's answer against the measured angle's.
                let cone = ConeLanes::<f32>::from_fn(|_| (limit, 0.0)).expect("a cone");
                let measured = shaft.dot(axis).clamp(-1.0, 1.0).acos() > h;
                let (s, ax) = (V3::from_fn(|_| shaft), V3::from_fn(|_| axis));
                assert_eq!(
                    cone.breach(s, ax, true).is_some(),
                    measured,
                    "{deg} deg cone, shaft at {angle} rad"
                );
                if angle < h - 1e-3 {
                    well_inside += 1;
                    passed += usize::from(shaft.dot(axis) > cone.cos_inside);
                }
            }
        }
        assert!(well_inside > 30_000, "{well_inside}");
        assert_eq!(passed, well_inside, "well inside yet measured");
    }

    /// The quick inside test of `RangeLanes::solve` never passes by a limit whose
    /// measured angle is outside its range, and does pass by one well inside: over
    /// rotations of every twist and swing, for hinge, twist and cone-like ranges, a 0°
    /// range and a whole turn.
    #[test]
    fn quick_inside_test_agrees_with_the_measured_angle() {
        use super::{AngleLimit, Q, RangeLanes};
        let d = |deg: f32| deg.to_radians();
        let ranges = [
            (d(-45.0), d(45.0)),
            (0.0, d(135.0)),
            (d(-90.0), d(90.0)),
            (0.0, 0.0),
            (d(-180.0), d(180.0)),
            (d(-170.0), d(-160.0)),
        ];
        let axis = Vec3::new(0.3, -0.8, 0.5).normalize();
        let mut next = uniform(0x9e37_79b9_u32);
        let (mut passed, mut well_inside) = (0, 0);
        for (min, max) in ranges {
            let limit = AngleLimit {
                axis_a: axis,
                ref_b: axis.any_orthonormal_vector(),
                rest_rel: Quat::IDENTITY,
                min,
                max,
                inside: AngleLimit::inside_bounds(min, max),
            };
            for _ in 0..20_000 {
                let twist = Quat::from_axis_angle(axis, (next() * 2.0 - 1.0) * d(181.0));
                let swing_axis = axis.cross(Vec3::new(next(), next(), next()) - 0.5);
                let swing = Quat::from_scaled_axis(swing_axis.normalize() * next() * d(170.0));
                let mut q = (swing * twist).normalize();
                if q.w < 0.0 {
                    q = -q;
                }
                let (phi, _) = limit.angle_of(q, Quat::IDENTITY);
                let range = RangeLanes::<f32>::from_fn(|_| (limit, 0.0));
                let quick = range.inside(Q::from_fn(|_| q));
                assert!(
                    !quick || (min..=max).contains(&phi),
                    "[{min}, {max}]: passed by at {phi}"
                );
                if phi > min + 1e-3 && phi < max - 1e-3 {
                    well_inside += 1;
                    passed += usize::from(quick);
                }
            }
        }
        assert!(well_inside > 10_000);
        assert_eq!(passed, well_inside, "well inside yet measured");
    }
}
