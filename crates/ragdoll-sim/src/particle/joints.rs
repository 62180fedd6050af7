//! Joints of the improved solver: points and axes expressed in each bone's frame.
//!
//! The paper shares particles between bones (section 3.2), which ties the particle
//! placement to the joints and makes exact particulation impossible. Here a joint
//! couples a point given in each bone's frame — an affine combination of the bone's four
//! particles, since the frame is — and corrects it with the point's generalised inverse
//! mass (XPBD, Müller et al. 2020), so the particulation of every bone survives.
//!
//! A [`Joint`] keeps what is its own — its sides, its anchors, its slack — and names
//! its constant description, shared by the joints built alike, in the world's
//! [`JointKinds`].

use super::bone::{Aim, Bone, Side, positional, side_rot, side_world};
use super::bone_lanes::{angular_pair, on_pair, point};
use super::joint_kinds::{JointKind, JointKinds};
use super::joint_lanes::hinge_axes;
use crate::lanes::V3;

use super::limits::{AngleLimit, Swing, SwingLimit, perpendicular};
use crate::scene::{ConstraintDesc, JointKind as JointDesc, SwingLimit as SwingDesc};
use glam::{Mat3A, Quat, Vec3, Vec3A};

/// Type-specific data, in the bones' frames.
#[derive(Clone, Copy, Debug)]
pub(crate) enum JointType {
    /// Shared anchor only.
    Ball,
    /// Anchor plus an axis that both bones keep aligned.
    Hinge {
        /// Axis in body1's frame.
        axis_a: Vec3,
        /// Axis in body2's frame.
        axis_b: Vec3,
    },
    /// Anchor plus perpendicular shafts.
    Universal {
        /// Shaft 1 in body1's frame.
        shaft_a: Vec3,
        /// Shaft 2 in body2's frame.
        shaft_b: Vec3,
    },
    /// No relative motion.
    Fixed,
    /// Translation along an axis of body2 only.
    Slider {
        /// Slide axis in body2's frame.
        axis_b: Vec3,
    },
    /// A one-sided-stiffness spring with hard min/max lengths.
    Spring {
        /// Constant when stretched (N/m).
        stretch: f32,
        /// Constant when compressed (N/m).
        compress: f32,
        /// Rest length (m).
        rest: f32,
        /// Minimum length (m), 0 for none.
        min: f32,
        /// Maximum length (m), 0 for none.
        max: f32,
    },
}

/// A joint between body1 (`a`) and body2 (`b`, `None` for the world): what is its
/// own, 40 bytes; the rest is its kind's ([`JointKinds::of`]).
#[derive(Clone, Debug)]
pub(crate) struct Joint {
    /// Body1's bone and body2's bone or the world, packed ([`Joint::a`], [`Joint::b`]).
    sides: Link,
    /// Its kind in the world's [`JointKinds`].
    pub kind: u32,
    /// Anchor in body1's frame.
    pub anchor_a: Vec3,
    /// Anchor in body2's frame (world coordinates for the world).
    pub anchor_b: Vec3,
    /// How far the limits are widened (rad): the excess of a pose that started outside
    /// them, closed at a bounded speed by [`Joint::close_slack`]. Zero for every joint
    /// that started inside its limits.
    pub slack: f32,
}

/// A joint's two sides, packed in 8 bytes (two `Option<usize>` take 32): a [`Joint`]
/// keeps its own so, and the world keeps a copy of every joint's in an array of their
/// own, what the island search and sleeping ask of every joint each detection: they
/// walk 8 B a joint instead of a 40-byte `Joint`, in the serial part of the step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Link([u32; 2]);

/// A [`Link`]'s world side.
const WORLD: u32 = u32::MAX;

impl Link {
    /// The sides of `j`.
    pub fn of(j: &Joint) -> Link {
        j.sides
    }

    /// Sides `a` and `b` (a bone's index below `u32::MAX`, or the world).
    fn new(a: Side, b: Side) -> Link {
        let pack = |s: Side| s.map_or(WORLD, |i| i as u32);
        Link([pack(a), pack(b)])
    }

    /// The two sides, as the joint has them.
    #[inline]
    pub fn sides(self) -> (Side, Side) {
        let unpack = |i: u32| (i != WORLD).then_some(i as usize);
        (unpack(self.0[0]), unpack(self.0[1]))
    }
}

/// Frames the joints are built against: each bone's frame at rest.
pub(crate) struct RestFrames<'a> {
    /// Bone frame origin and orientation at rest, per bone.
    pub frames: &'a [(Vec3, Quat)],
}

impl RestFrames<'_> {
    fn local_point(&self, s: Side, p: Vec3) -> Vec3 {
        match s {
            Some(i) => self.frames[i].1.inverse() * (p - self.frames[i].0),
            None => p,
        }
    }
    fn local_dir(&self, s: Side, d: Vec3) -> Vec3 {
        match s {
            Some(i) => self.frames[i].1.inverse() * d,
            None => d,
        }
    }
    fn rot(&self, s: Side) -> Quat {
        s.map_or(Quat::IDENTITY, |i| self.frames[i].1)
    }
    fn origin(&self, s: Side) -> Vec3 {
        s.map_or(Vec3::ZERO, |i| self.frames[i].0)
    }
}

fn swing_limit(f: &RestFrames, a: Side, b: Side, s: &SwingDesc) -> SwingLimit {
    match *s {
        SwingDesc::Cone {
            axis,
            half_angle,
            shaft,
        } => SwingLimit {
            shaft_a: f.local_dir(a, shaft),
            axis_b: f.local_dir(b, axis),
            kind: Swing::cone(half_angle),
        },
        SwingDesc::Pyramid {
            axis,
            half_angle1,
            half_angle2,
            roll,
            shaft,
        } => {
            let (u, v) = crate::scene::pyramid_sides(axis, roll);
            SwingLimit {
                shaft_a: f.local_dir(a, shaft),
                axis_b: f.local_dir(b, axis),
                kind: Swing::Pyramid {
                    h1: half_angle1,
                    h2: half_angle2,
                    u: f.local_dir(b, u),
                    v: f.local_dir(b, v),
                },
            }
        }
    }
}

fn angle_limit(f: &RestFrames, a: Side, b: Side, axis: Vec3, min: f32, max: f32) -> AngleLimit {
    let r = perpendicular(axis);
    AngleLimit {
        axis_a: f.local_dir(a, axis),
        ref_b: f.local_dir(b, r),
        rest_rel: f.rot(b).inverse() * f.rot(a),
        min,
        max,
        inside: AngleLimit::inside_bounds(min, max),
    }
}

impl Joint {
    /// Body1's bone.
    #[inline]
    pub fn a(&self) -> Side {
        self.sides.sides().0
    }

    /// Body2's bone, or the world.
    #[inline]
    pub fn b(&self) -> Side {
        self.sides.sides().1
    }

    /// Builds the joint of constraint `c` between sides `a` and `b` (its anchors and axes
    /// world space at rest), its kind kept in `kinds`. `mass_a` is body1's mass and `g`
    /// gravity's magnitude, for the joint friction: the file's friction `c.friction`
    /// (Doom 3: a number in [0, 1] without units) read as the multibody method reads it
    /// (`rigid::FrictionMotor`) so that both methods agree, the largest friction torque
    /// that fraction of the torque gravity puts on body1 held horizontally at its arm,
    /// the anchor's distance from its centre of mass (at least 5 cm), `f · m₁ g r`. Only
    /// joints that turn take it (ball, hinge, universal).
    pub fn new(
        f: &RestFrames,
        (a, b): (Side, Side),
        c: &ConstraintDesc,
        (mass_a, g): (f32, f32),
        kinds: &mut JointKinds,
    ) -> Joint {
        let anchor = c.kind.anchor().unwrap_or_else(|| f.origin(a));
        let (mut anchor_a, mut anchor_b) = (f.local_point(a, anchor), f.local_point(b, anchor));
        let mut k = JointKind {
            rest_rel: f.rot(b).inverse() * f.rot(a),
            joint_type: JointType::Ball,
            angle_limits: Box::default(),
            swing: None,
            limit_compliance: 0.0,
            has_anchor: c.kind.anchor().is_some() || matches!(c.kind, JointDesc::Fixed),
            friction_torque: 0.0,
        };
        let mut angle_limits = Vec::new();
        match &c.kind {
            JointDesc::BallAndSocket {
                swing,
                twist,
                limit_style,
                ..
            } => {
                k.swing = swing.as_ref().map(|s| swing_limit(f, a, b, s));
                if let Some(t) = twist {
                    angle_limits.push(angle_limit(f, a, b, t.axis, t.min, t.max));
                }
                // The PyODE tutorial softens its limits because explicit restoring
                // torques cannot be stiff and stable at once; a position-level limit can,
                // so the improved solver holds soft limits hard (the metric measures the
                // limit itself). `limit_compliance` stays for springy limits.
                let _ = limit_style;
            }
            JointDesc::Universal {
                shaft1,
                shaft2,
                swing,
                axis_ranges,
                ..
            } => {
                k.joint_type = JointType::Universal {
                    shaft_a: f.local_dir(a, *shaft1),
                    shaft_b: f.local_dir(b, *shaft2),
                };
                k.swing = swing.as_ref().map(|s| swing_limit(f, a, b, s));
                if let Some([r1, r2]) = axis_ranges {
                    // PyODE's stops: rotation about shaft 2 (body2's axis) and about
                    // shaft 1; measured as angles about those axes from rest.
                    angle_limits.push(angle_limit(f, a, b, *shaft2, r1.min, r1.max));
                    angle_limits.push(angle_limit(f, a, b, *shaft1, r2.min, r2.max));
                }
            }
            JointDesc::Hinge { axis, limit, .. } => {
                k.joint_type = JointType::Hinge {
                    axis_a: f.local_dir(a, *axis),
                    axis_b: f.local_dir(b, *axis),
                };
                if let Some(l) = limit {
                    angle_limits.push(angle_limit(f, a, b, *axis, l.min, l.max));
                }
            }
            JointDesc::Slider { axis } => {
                k.joint_type = JointType::Slider {
                    axis_b: f.local_dir(b, *axis),
                };
            }
            JointDesc::Fixed => k.joint_type = JointType::Fixed,
            JointDesc::Spring {
                anchor1,
                anchor2,
                stretch,
                compress,
                rest_length,
                min_length,
                max_length,
                ..
            } => {
                anchor_a = f.local_point(a, *anchor1);
                anchor_b = f.local_point(b, *anchor2);
                k.joint_type = JointType::Spring {
                    stretch: *stretch,
                    compress: *compress,
                    rest: *rest_length,
                    min: *min_length,
                    max: *max_length,
                };
            }
        }
        k.angle_limits = angle_limits.into_boxed_slice();
        let turns = matches!(
            k.joint_type,
            JointType::Ball | JointType::Hinge { .. } | JointType::Universal { .. }
        );
        if turns && c.friction > 0.0 && a.is_some() {
            k.friction_torque = c.friction * mass_a * g * anchor_a.length().max(0.05);
        }
        Joint {
            sides: Link::new(a, b),
            kind: kinds.kind(k),
            anchor_a,
            anchor_b,
            slack: 0.0,
        }
    }

    /// Joint friction in the velocity pass of a substep `h`: an angular impulse
    /// between the two sides that stops their relative turn, `Δλ = −K⁻¹ (ω_a − ω_b)`
    /// with `K = I_a⁻¹ + I_b⁻¹` (world), capped at the friction torque times `h` — the
    /// joint holds under a small load and slips under a large one, taking energy
    /// `|Δλ · ω_rel|` at most. (As the multibody's capped motor: `rigid::FrictionMotor`.)
    /// `kind` is the joint's kind.
    pub fn solve_friction(kind: &JointKind, bones: &mut [Bone], a: Side, b: Side, h: f32) {
        let moving = |s: Side| s.filter(|&i| !bones[i].is_static());
        let (a, b) = (moving(a), moving(b));
        let inv_inertia = |s: Option<usize>| {
            s.map_or(Mat3A::ZERO, |i| {
                let r = Mat3A::from_quat(bones[i].rot);
                r * Mat3A::from_diagonal(Vec3::from(bones[i].inv_inertia_local)) * r.transpose()
            })
        };
        let spin = |s: Option<usize>| s.map_or(Vec3A::ZERO, |i| bones[i].ang_vel);
        let (wa, wb) = (inv_inertia(a), inv_inertia(b));
        let k = wa + wb;
        // Both sides static (or a NaN): nothing to hold.
        let det = k.determinant();
        if det.is_nan() || det.abs() <= 1e-30 {
            return;
        }
        let mut impulse = -(k.inverse() * (spin(a) - spin(b)));
        let cap = kind.friction_torque * h;
        if impulse.length_squared() > cap * cap {
            impulse = impulse.normalize() * cap;
        }
        if let Some(i) = a {
            bones[i].ang_vel += wa * impulse;
        }
        if let Some(i) = b {
            bones[i].ang_vel -= wb * impulse;
        }
    }

    /// Narrows the widened limits ([`Joint::slack`]) by what `dt` allows: body1's
    /// centre turns about the anchor at no more than `push_out_speed`
    /// (`Settings::max_push_out_speed`, the speed an old overlap of the contacts is
    /// pushed out at), an angular speed of `push_out_speed / r` for the anchor's
    /// distance `r` from it (at least 5 cm, as the friction of [`Joint::new`]). Returns
    /// whether the joint had slack.
    pub fn close_slack(&mut self, push_out_speed: f32, dt: f32) -> bool {
        if self.slack <= 0.0 {
            return false;
        }
        let rate = push_out_speed / self.anchor_a.length().max(0.05);
        self.slack = (self.slack - rate * dt).max(0.0);
        true
    }

    /// The anchor as seen from body1 and from body2 (world).
    pub fn anchors(&self, bones: &[Bone]) -> (Vec3, Vec3) {
        (
            Vec3::from(side_world(bones, self.a(), self.anchor_a)),
            Vec3::from(side_world(bones, self.b(), self.anchor_b)),
        )
    }

    /// Joint gap (m): distance between the anchor seen from each bone (`k` its kind).
    pub fn gap(&self, k: &JointKind, bones: &[Bone]) -> f32 {
        match k.joint_type {
            JointType::Spring { .. } | JointType::Slider { .. } => 0.0,
            _ => {
                let (pa, pb) = self.anchors(bones);
                pa.distance(pb)
            }
        }
    }

    /// Largest limit excess (rad) of the limits of its kind `k`.
    pub fn limit_violation(&self, k: &JointKind, bones: &[Bone]) -> f32 {
        let mut v = k
            .swing
            .map_or(0.0, |s| s.violation(bones, self.a(), self.b()));
        for l in &k.angle_limits {
            v = v.max(l.violation(bones, self.a(), self.b()));
        }
        v
    }

    /// The relative-orientation error of body1 (side `a`) against its rest orientation
    /// relative to body2 (side `b`) of its kind `k`, as a rotation vector to apply to
    /// body1.
    fn orientation_error(k: &JointKind, bones: &[Bone], a: Side, b: Side) -> Vec3 {
        let qa = side_rot(bones, a);
        let target = side_rot(bones, b) * k.rest_rel;
        let mut e = target * qa.inverse();
        if e.w < 0.0 {
            e = -e;
        }
        Vec3::new(e.x, e.y, e.z) * 2.0
    }

    /// One XPBD pass over the joint (of kind `k`) between body1 at `a` and body2 at `b`
    /// of `bones`: axes, anchor (aimed as `aim` says), then limits; `h` is the substep. A batch of
    /// islands stepped on its own thread holds its bones under its own indices. The
    /// rows the lanes also solve (hinge axes, anchor, cone, range) are their code run
    /// with one joint to a lane (`joint_lanes`), so a ball or hinge gets the same bits
    /// here as in a group of four.
    pub fn solve_between(
        &self,
        k: &JointKind,
        bones: &mut [Bone],
        a: Side,
        b: Side,
        h: f32,
        aim: Aim,
    ) {
        let inv_h2 = 1.0 / (h * h);
        match k.joint_type {
            JointType::Hinge { axis_a, axis_b } => {
                let (axis_a, axis_b) = (V3::from_fn(|_| axis_a), V3::from_fn(|_| axis_b));
                on_pair(bones, a, b, |sa, sb| {
                    hinge_axes(sa, sb, axis_a, axis_b, true)
                });
            }
            JointType::Universal { shaft_a, shaft_b } => {
                // The shafts kept perpendicular: turned about `s1 × s2` by the angle
                // their dot product is off a right angle, `asin(s1 · s2)`.
                let s1 = side_rot(bones, a) * shaft_a;
                let s2 = side_rot(bones, b) * shaft_b;
                let n = s1.cross(s2);
                let l = n.length();
                if l > 1e-9 {
                    let angle = s1.dot(s2).clamp(-1.0, 1.0).asin();
                    angular_pair(bones, a, b, -n / l * angle, 0.0);
                }
            }
            JointType::Fixed | JointType::Slider { .. } => {
                let e = Joint::orientation_error(k, bones, a, b);
                angular_pair(bones, a, b, e, 0.0);
            }
            JointType::Ball | JointType::Spring { .. } => {}
        }
        match k.joint_type {
            JointType::Spring {
                stretch,
                compress,
                rest,
                min,
                max,
            } => {
                let (pa, pb) = (
                    side_world(bones, a, self.anchor_a),
                    side_world(bones, b, self.anchor_b),
                );
                let d = pb - pa;
                let len = d.length();
                if len > 1e-9 {
                    let n = d / len;
                    let target = if max > 0.0 && len > max {
                        Some((max, 0.0))
                    } else if min > 0.0 && len < min {
                        Some((min, 0.0))
                    } else {
                        let stiffness = if len > rest { stretch } else { compress };
                        (stiffness > 0.0).then(|| (rest, inv_h2 / stiffness))
                    };
                    if let Some((l0, alpha)) = target {
                        positional(bones, a, b, pa, pb, n * (len - l0), alpha);
                    }
                }
            }
            JointType::Slider { axis_b } => {
                let (pa, pb) = (
                    side_world(bones, a, self.anchor_a),
                    side_world(bones, b, self.anchor_b),
                );
                let axis = side_rot(bones, b) * Vec3A::from(axis_b);
                let d = pb - pa;
                positional(bones, a, b, pa, pb, d - axis * axis.dot(d), 0.0);
            }
            _ => {
                let la = V3::from_fn(|_| self.anchor_a);
                let lb = V3::from_fn(|_| self.anchor_b);
                on_pair(bones, a, b, |sa, sb| {
                    let (pa, pb) = (sa.world(la), sb.world(lb));
                    point((sa, la), (sb, lb), pb - pa, aim, true);
                });
            }
        }
        let alpha = k.limit_compliance * inv_h2;
        let anchors = (self.anchor_a, self.anchor_b);
        if let Some(s) = &k.swing {
            s.solve(bones, (a, b), anchors, alpha, self.slack);
        }
        for l in &k.angle_limits {
            l.solve(bones, (a, b), anchors, alpha, self.slack);
        }
    }
}

/// Below this `s²` a hinge's [`hinge_turn_ratio`] is its series.
pub(super) const HINGE_SERIES_BELOW: f32 = 1e-4;

/// `asin(s) / s` from `s²`: the ratio of a hinge's turn to its misalignment `c`, `s =
/// |c|`. For the small misalignment a hinge has at every substep it is the series `1 +
/// s²/6 + 3 s⁴/40 + …`, from `s²` without a square root, `asin` or division (the next
/// term, `5 s⁶/112`, is below 5e-14 there); the lanes (`joint_lanes`) evaluate the same
/// series four at a time and call this for the rest.
pub(super) fn hinge_turn_ratio(s2: f32) -> f32 {
    if s2 < HINGE_SERIES_BELOW {
        1.0 + s2 * (1.0 / 6.0 + s2 * (3.0 / 40.0))
    } else {
        // Unit axes 90° apart can round to `s² > 1`, where `asin` is NaN.
        let s = s2.min(1.0).sqrt();
        s.asin() / s
    }
}

/// The joints one run of substeps solves, always in the world's order, with the
/// world's joint kinds.
#[derive(Clone, Copy)]
pub(crate) enum JointSet<'a> {
    /// All of the world's joints, on the world's bones.
    All(&'a [Joint], &'a JointKinds),
    /// Some of the world's joints on a batch's bones: each joint's index in the world and
    /// its two sides renumbered into the batch.
    Batch(&'a [Joint], &'a JointKinds, &'a [(u32, Side, Side)]),
}

impl<'a> JointSet<'a> {
    /// The set's joints in solving order (the world's), each with its kind and its two
    /// sides in the bones being stepped.
    pub fn entries(&self) -> Vec<super::joint_lanes::Entry<'a>> {
        match *self {
            JointSet::All(joints, kinds) => joints
                .iter()
                .map(|j| (j, kinds.of(j), j.a(), j.b()))
                .collect(),
            JointSet::Batch(joints, kinds, local) => local
                .iter()
                .map(|&(k, a, b)| {
                    let j = &joints[k as usize];
                    (j, kinds.of(j), a, b)
                })
                .collect(),
        }
    }
}

/// Whether the bone `i` (none: the world) is in one of `figures` (sorted).
pub(crate) fn in_figures(figures: &[u32], bones: &[Bone], i: Option<usize>) -> bool {
    i.is_some_and(|i| figures.binary_search(&bones[i].figure).is_ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A link gives back the sides it was made from, the world's too.
    #[test]
    fn links_give_back_their_sides() {
        for sides in [(Some(0), None), (Some(5), Some(70_000)), (None, Some(3))] {
            assert_eq!(Link::new(sides.0, sides.1).sides(), sides);
        }
    }
}
