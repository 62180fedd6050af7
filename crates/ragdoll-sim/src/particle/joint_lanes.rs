//! The joints of four figures solved side by side, one figure to a lane of an `f32x4`.
//!
//! A joint pass is Gauss–Seidel: each joint's correction moves its bones before the next
//! joint reads them, so the joints of one figure form a chain. Two figures share no bone
//! (a figure is a connected component of the joints), so the chains of four figures can
//! advance together — joint `k` of each in one instruction — and every figure sees the
//! same corrections in the same order as when the figures are solved one after another.
//! A pile of humans is made of figures with the same joints in the same order; those are
//! dealt four to a group ([`Lockstep::new`]).
//!
//! Ball joints and hinges (with a cone swing and an angle range or twist, as the human
//! and the capsule human carry them) are solved in lanes; any other joint is solved
//! alone ([`Joint::solve_between`]), lane after lane. Each row — hinge axes
//! ([`hinge_axes`]), anchor (`bone_lanes::point`), cone (`limits::ConeLanes`), range
//! (`limits::RangeLanes`) — is written once, generic over the lane type
//! (`crate::lanes::Real`), and run here with `f32x4` and by [`Joint::solve_between`]
//! with `f32`. Every operation is lane by lane and each `f32x4` operation is its `f32`
//! twin's, so a joint's correction is the same bits whichever figures share its group,
//! or alone: the batches of islands give the serial result on any number of threads.

use super::bone::{Aim, Bone, Side};
use super::bone_lanes::{SideLanes, angular, mask, per_lane, point};
use super::joint_kinds::JointKind;
use super::joints::{HINGE_SERIES_BELOW, Joint, JointType, hinge_turn_ratio};
use super::limits::{ConeLanes, RangeLanes, Swing};
use crate::lanes::{LANES, Real, V3};
use wide::f32x4;

/// A joint of a run: the joint, its kind and its two sides in the bones being stepped.
pub(crate) type Entry<'a> = (&'a Joint, &'a JointKind, Side, Side);

/// What decides whether joint `k` of two figures can share an instruction: the rows it
/// solves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Shape {
    /// A ball joint (`hinge` false) or a hinge, with or without a cone swing, with at
    /// most one angle range.
    Lanes { hinge: bool, cone: bool, ranges: u8 },
    /// Solved by its scalar code.
    Scalar,
}

impl Shape {
    fn of(j: &JointKind) -> Shape {
        let hinge = match j.joint_type {
            JointType::Ball => false,
            JointType::Hinge { .. } => true,
            _ => return Shape::Scalar,
        };
        let cone = match j.swing {
            None => false,
            Some(s) if matches!(s.kind, Swing::Cone { .. }) => true,
            Some(_) => return Shape::Scalar,
        };
        if j.angle_limits.len() > 1 {
            return Shape::Scalar;
        }
        Shape::Lanes {
            hinge,
            cone,
            ranges: j.angle_limits.len() as u8,
        }
    }
}

/// One step of a joint pass.
enum Step {
    /// Entry `i` by its scalar code.
    Scalar(u32),
    /// Up to four entries (one per lane, `None` for an empty lane) in lanes, with their
    /// constant data (`Lockstep::constants`).
    Lanes([Option<u32>; LANES], u32),
}

/// The joint pass over a run of joints, in lockstep where figures allow: built once for
/// the substeps between two collision detections, used by every pass.
pub(crate) struct Lockstep {
    steps: Vec<Step>,
    /// How many entries it was built for (`solve` takes the same ones).
    entries: usize,
    constants: Vec<Constants<f32x4>>,
}

impl Lockstep {
    /// Cuts `entries` (in solving order) into figures — runs of consecutive joints of one
    /// figure — and deals runs of the same shapes, up to four consecutive ones of
    /// different figures, into lanes. Solving the steps in order is solving the entries
    /// in order: a group only interleaves figures, which share no bone.
    pub fn new(entries: &[Entry], bones: &[Bone]) -> Lockstep {
        let figure = |&(_, _, a, b): &Entry| a.or(b).map_or(u32::MAX, |i| bones[i].figure);
        let shapes: Vec<Shape> = entries.iter().map(|e| Shape::of(e.1)).collect();
        // Runs of one figure: `start..end` of the entries.
        let mut runs: Vec<(usize, usize)> = Vec::new();
        for (i, e) in entries.iter().enumerate() {
            match runs.last_mut() {
                Some(r) if figure(&entries[r.0]) == figure(e) => r.1 = i + 1,
                _ => runs.push((i, i + 1)),
            }
        }
        let same = |r: (usize, usize), s: (usize, usize)| {
            r.1 - r.0 == s.1 - s.0 && shapes[r.0..r.1] == shapes[s.0..s.1]
        };
        let mut steps = Vec::with_capacity(entries.len() / LANES + runs.len());
        let mut constants = Vec::with_capacity(entries.len() / LANES + runs.len());
        let mut r = 0;
        while r < runs.len() {
            // Up to four runs from `r` on: `runs[r..r + count]`.
            let mut count = 1;
            while r + count < runs.len() && count < LANES {
                let next = runs[r + count];
                let f = figure(&entries[next.0]);
                let taken = &runs[r..r + count];
                if !same(runs[r], next) || taken.iter().any(|g| figure(&entries[g.0]) == f) {
                    break;
                }
                count += 1;
            }
            let group = &runs[r..r + count];
            let len = runs[r].1 - runs[r].0;
            for k in 0..len {
                let lanes: [Option<u32>; LANES] =
                    std::array::from_fn(|l| group.get(l).map(|g| (g.0 + k) as u32));
                if shapes[runs[r].0 + k] == Shape::Scalar {
                    steps.extend(lanes.iter().flatten().map(|&i| Step::Scalar(i)));
                } else {
                    steps.push(Step::Lanes(lanes, constants.len() as u32));
                    constants.push(Constants::new(
                        &lanes.map(|i| i.map(|i| entries[i as usize])),
                    ));
                }
            }
            r += count;
        }
        Lockstep {
            steps,
            constants,
            entries: entries.len(),
        }
    }

    /// One pass over the joints, `h` the substep, anchors aimed as `aim` says;
    /// `entries` are the ones it was built from.
    pub fn solve(&self, entries: &[Entry], bones: &mut [Bone], h: f32, aim: Aim) {
        debug_assert_eq!(entries.len(), self.entries, "a pass over other joints");
        for step in &self.steps {
            match step {
                Step::Scalar(i) => {
                    let (j, k, a, b) = entries[*i as usize];
                    j.solve_between(k, bones, a, b, h, aim);
                }
                Step::Lanes(lanes, c) => {
                    let c = &self.constants[*c as usize];
                    let sides = |f: fn(&Entry) -> Side| {
                        lanes.map(|i| i.and_then(|i| f(&entries[i as usize])))
                    };
                    let (a, b) = (sides(|e| e.2), sides(|e| e.3));
                    let mut sa = SideLanes::<f32x4>::gather(bones, &a);
                    let mut sb = SideLanes::<f32x4>::gather(bones, &b);
                    c.solve(&mut sa, &mut sb, h, aim);
                    sa.scatter(bones, &a);
                    sb.scatter(bones, &b);
                }
            }
        }
    }
}

/// What a group's joints hold constant, one joint to a lane.
struct Constants<R: Real> {
    /// Lanes with a joint.
    active: R::Mask,
    anchor_a: V3<R>,
    anchor_b: V3<R>,
    /// A hinge's axis in each bone's frame.
    hinge: Option<(V3<R>, V3<R>)>,
    cone: Option<ConeLanes<R>>,
    range: Option<RangeLanes<R>>,
    limit_compliance: R,
}

impl<R: Real> Constants<R> {
    /// The constants of up to `R::WIDTH` joints of one [`Shape`] (`lanes[k]` for lane
    /// `k`; an empty lane holds a copy of the first joint, masked off).
    fn new(lanes: &[Option<Entry>]) -> Constants<R> {
        let first = *lanes.iter().flatten().next().expect("a group has a joint");
        let joint = |k: usize| lanes[k].unwrap_or(first).0;
        let kind = |k: usize| lanes[k].unwrap_or(first).1;
        let hinge = matches!(first.1.joint_type, JointType::Hinge { .. }).then(|| {
            let axis = |k: usize| match kind(k).joint_type {
                JointType::Hinge { axis_a, axis_b } => (axis_a, axis_b),
                _ => unreachable!("a group's joints share their shape"),
            };
            (V3::from_fn(|k| axis(k).0), V3::from_fn(|k| axis(k).1))
        });
        let cone = first.1.swing.is_some().then(|| {
            let swing = |k: usize| kind(k).swing.expect("a group's joints share their shape");
            ConeLanes::from_fn(|k| (swing(k), joint(k).slack))
                .expect("a group's joints share their shape")
        });
        let range = (!first.1.angle_limits.is_empty())
            .then(|| RangeLanes::from_fn(|k| (kind(k).angle_limits[0], joint(k).slack)));
        Constants {
            active: mask::<R>(|k| lanes[k].is_some()),
            anchor_a: V3::from_fn(|k| joint(k).anchor_a),
            anchor_b: V3::from_fn(|k| joint(k).anchor_b),
            hinge,
            cone,
            range,
            limit_compliance: R::from_fn(|k| kind(k).limit_compliance),
        }
    }

    /// [`Joint::solve_between`] for the lanes: the hinge's axes, the anchor, the swing,
    /// the range.
    fn solve(&self, a: &mut SideLanes<R>, b: &mut SideLanes<R>, h: f32, aim: Aim) {
        let active = self.active;
        if let Some((axis_a, axis_b)) = self.hinge {
            hinge_axes(a, b, axis_a, axis_b, active);
        }
        let (pa, pb) = (a.world(self.anchor_a), b.world(self.anchor_b));
        point((a, self.anchor_a), (b, self.anchor_b), pb - pa, aim, active);
        let alpha = self.limit_compliance * R::splat(1.0 / (h * h));
        let anchors = (self.anchor_a, self.anchor_b);
        if let Some(cone) = &self.cone {
            cone.solve(a, b, anchors, alpha, active);
        }
        if let Some(range) = &self.range {
            range.solve(a, b, anchors, alpha, active);
        }
    }
}

/// A hinge's axes aligned, in the lanes of `active`: body1 turned by the rotation taking
/// its axis (`axis_a`, its frame) onto body2's (`axis_b`), split by inverse inertia.
///
/// The turn is `asin(s)` about `c / s` for the misalignment `c = a × b` of the world
/// axes, `s = |c|`: `c asin(s) / s`, the ratio [`hinge_turn_ratio`] evaluated as its
/// series in every lane and exactly only in the lanes past [`HINGE_SERIES_BELOW`].
pub(super) fn hinge_axes<R: Real>(
    a: &mut SideLanes<R>,
    b: &mut SideLanes<R>,
    axis_a: V3<R>,
    axis_b: V3<R>,
    active: R::Mask,
) {
    let c = a.rot.rotate(axis_a).cross(b.rot.rotate(axis_b));
    let s2 = c.length_squared();
    let small = s2.lt(R::splat(HINGE_SERIES_BELOW));
    let series = R::ONE + s2 * (R::splat(1.0 / 6.0) + s2 * R::splat(3.0 / 40.0));
    let large = active & !small;
    let ratio = if R::any(large) {
        let exact = per_lane(large, s2, |_, s2| hinge_turn_ratio(s2));
        R::select(small, series, exact)
    } else {
        series
    };
    let turn = active & s2.gt(R::splat(1e-18));
    angular(a, b, c * ratio, R::ZERO, turn);
}

#[cfg(test)]
mod tests {
    use super::super::joints::JointSet;
    use super::super::{ParticleWorld, scene_world, uniform};
    use super::*;
    use glam::{Quat, Vec3};

    /// The pile of `count` humans (scene 10) with every bone knocked off its rest pose
    /// (turned by up to 0.6 rad, moved by up to 2 cm) so that anchors, hinge axes,
    /// cones and ranges all correct something; every fifth bone asleep.
    fn knocked_pile(count: u32, seed: u32) -> ParticleWorld {
        let mut w = scene_world("pile.af", Some(count));
        let mut next = uniform(seed);
        for (i, b) in w.bones.iter_mut().enumerate() {
            let turn = Vec3::new(next(), next(), next()) * 1.2 - Vec3::splat(0.6);
            b.rot = (b.rot * Quat::from_scaled_axis(turn)).normalize();
            b.dcom = (Vec3::new(next(), next(), next()) * 0.04 - Vec3::splat(0.02)).into();
            b.asleep = i % 5 == 3;
        }
        w
    }

    fn motion(bones: &[Bone]) -> Vec<(Vec3, Quat)> {
        bones.iter().map(|b| (Vec3::from(b.dcom), b.rot)).collect()
    }

    /// The lanes compute what a joint solved alone computes, bit for bit (one source,
    /// run with `f32x4` and with `f32`): one pass over the joints of four knocked-down
    /// humans, in lockstep and joint by joint; sleeping bones stay put.
    #[test]
    fn lanes_give_the_bits_of_joints_solved_alone() {
        let h = 1.0 / 1200.0;
        for seed in [0x2545_f491, 0x9e37_79b9, 0x1234_5678] {
            let w = knocked_pile(4, seed);
            let set = JointSet::All(&w.joints, &w.joint_kinds);
            let entries = set.entries();
            let lockstep = Lockstep::new(&entries, &w.bones);
            let lanes = lockstep
                .steps
                .iter()
                .filter(|s| matches!(s, Step::Lanes(l, _) if l.iter().all(Option::is_some)))
                .count();
            assert_eq!(lanes, w.joints.len() / 4, "four humans, one group");
            for aim in [Aim::Start, Aim::End] {
                let mut ours = w.bones.clone();
                lockstep.solve(&entries, &mut ours, h, aim);
                let mut theirs = w.bones.clone();
                for &(j, k, a, b) in &entries {
                    j.solve_between(k, &mut theirs, a, b, h, aim);
                }
                let moved = motion(&w.bones);
                assert!(motion(&ours) == motion(&theirs), "{aim:?}: lanes differ");
                for (i, m) in motion(&ours).iter().enumerate() {
                    if w.bones[i].asleep {
                        assert_eq!(*m, moved[i], "a sleeping bone moved");
                    }
                }
                assert!(motion(&ours) != moved, "the joints corrected nothing");
            }
        }
    }

    /// A figure's corrections are the same bits in a group of four as alone in its
    /// group: what lets the batches of islands, which group figures differently, give
    /// the serial result.
    #[test]
    fn a_figure_gets_the_same_bits_in_any_group() {
        let h = 1.0 / 1200.0;
        let w = knocked_pile(5, 0x0bad_cafe);
        let set = JointSet::All(&w.joints, &w.joint_kinds);
        let entries = set.entries();
        let mut together = w.bones.clone();
        Lockstep::new(&entries, &w.bones).solve(&entries, &mut together, h, Aim::Start);
        // Each figure alone: its joints only, a lockstep of one lane.
        let mut alone = w.bones.clone();
        let per_figure = entries.len() / 5;
        for figure in entries.chunks(per_figure) {
            Lockstep::new(figure, &alone).solve(figure, &mut alone, h, Aim::Start);
        }
        assert!(motion(&together) == motion(&alone));
    }

    /// A hinge whose axes are a right angle apart (their cross product rounding to a
    /// length above one, where `asin` is NaN) is turned back, not poisoned: alone and in
    /// lanes it stays finite, with the same bits.
    #[test]
    fn hinge_at_a_right_angle_stays_finite() {
        let h = 1.0 / 1200.0;
        let mut w = scene_world("human.af", None);
        let (k, axis_a, axis_b) = w
            .joints
            .iter()
            .enumerate()
            .find_map(|(k, j)| match w.joint_kinds.of(j).joint_type {
                JointType::Hinge { axis_a, axis_b } => Some((k, axis_a, axis_b)),
                _ => None,
            })
            .expect("the human has hinges");
        let (a, b) = (
            w.joints[k].a().expect("a bone"),
            w.joints[k].b().expect("a bone"),
        );
        let mut next = uniform(0x0dd_ba11);
        let mut over = 0;
        for _ in 0..3000 {
            let turn = Vec3::new(next(), next(), next()) * 6.0 - Vec3::splat(3.0);
            w.bones[b].rot = Quat::from_scaled_axis(turn).normalize();
            let tb = w.bones[b].rot * axis_b;
            let p = tb.any_orthonormal_pair();
            let angle = next() * std::f32::consts::TAU;
            let target = p.0 * angle.cos() + p.1 * angle.sin();
            let ta = w.bones[a].rot * axis_a;
            w.bones[a].rot = (Quat::from_rotation_arc(ta, target) * w.bones[a].rot).normalize();
            // As the scalar hinge measures it.
            let ta = w.bones[a].rot * glam::Vec3A::from(axis_a);
            let c = ta.cross(w.bones[b].rot * glam::Vec3A::from(axis_b));
            over += usize::from(c.length_squared() > 1.0);
            let (joint, kind) = (&w.joints[k], w.joint_kinds.of(&w.joints[k]));
            let entries = [(joint, kind, Some(a), Some(b))];
            let mut scalar = w.bones.clone();
            joint.solve_between(kind, &mut scalar, Some(a), Some(b), h, Aim::Start);
            let mut lanes = w.bones.clone();
            Lockstep::new(&entries, &w.bones).solve(&entries, &mut lanes, h, Aim::Start);
            for i in [a, b] {
                assert!(
                    scalar[i].rot.is_finite() && lanes[i].rot.is_finite(),
                    "NaN frame"
                );
                assert_eq!(scalar[i].rot, lanes[i].rot, "one source, one result");
            }
        }
        assert!(over > 0, "no pose rounded past a right angle");
    }
}
