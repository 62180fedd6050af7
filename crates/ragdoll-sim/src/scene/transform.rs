//! Moving what a scene describes by a rigid transform of the world: the `.af` reader's
//! `transform` block and `replicate` grid, and nearby starts of one scene (ensembles,
//! tests). Bodies carry their velocities along; joints their world-space anchors, axes
//! and limit frames. The ground, gravity and camera stay where they are.

use super::{BodyDesc, JointKind, Pose, SceneDesc, SwingLimit, pyramid_sides};
use glam::{Quat, Vec3};
use std::f32::consts::{PI, TAU};

impl BodyDesc {
    /// Moves the body by `t`, its velocities turned with it.
    pub fn transform(&mut self, t: &Pose) {
        self.pose = t.mul_pose(&self.pose);
        self.linear_velocity = t.rotation * self.linear_velocity;
        self.angular_velocity = t.rotation * self.angular_velocity;
    }
}

impl JointKind {
    /// Moves the joint's world-space anchors and axes by `t`.
    pub fn transform(&mut self, t: &Pose) {
        let r = t.rotation;
        let swing = |s: &mut SwingLimit| match s {
            SwingLimit::Cone { axis, shaft, .. } | SwingLimit::Pyramid { axis, shaft, .. } => {
                *axis = r * *axis;
                *shaft = r * *shaft;
            }
        };
        match self {
            JointKind::BallAndSocket {
                anchor,
                swing: s,
                twist,
                ..
            } => {
                *anchor = t.transform_point(*anchor);
                if let Some(s) = s {
                    swing(s);
                }
                if let Some(tw) = twist {
                    tw.axis = r * tw.axis;
                }
            }
            JointKind::Universal {
                anchor,
                shaft1,
                shaft2,
                swing: s,
                ..
            } => {
                *anchor = t.transform_point(*anchor);
                *shaft1 = r * *shaft1;
                *shaft2 = r * *shaft2;
                if let Some(s) = s {
                    swing(s);
                }
            }
            JointKind::Hinge { anchor, axis, .. } => {
                *anchor = t.transform_point(*anchor);
                *axis = r * *axis;
            }
            JointKind::Slider { axis } => *axis = r * *axis,
            JointKind::Fixed => {}
            JointKind::Spring {
                anchor1, anchor2, ..
            } => {
                *anchor1 = t.transform_point(*anchor1);
                *anchor2 = t.transform_point(*anchor2);
            }
        }
    }
}

impl SceneDesc {
    /// Moves every body and every joint by `t` (the ground, gravity and camera stay):
    /// `Pose::from_position(Vec3::Y * 0.01)` drops the scene from 1 cm higher.
    pub fn transform(&mut self, t: &Pose) {
        for b in &mut self.bodies {
            b.transform(t);
        }
        for c in &mut self.constraints {
            c.kind.transform(t);
        }
    }
}

/// The rotation angle of `q` about the unit `axis` (the twist of a swing-twist split),
/// right-handed, in (−π, π].
fn twist_angle(q: Quat, axis: Vec3) -> f32 {
    let a = 2.0 * Vec3::new(q.x, q.y, q.z).dot(axis).atan2(q.w);
    if a > PI {
        a - TAU
    } else if a <= -PI {
        a + TAU
    } else {
        a
    }
}

/// The rigid motion T taking pose `from` to pose `to`: T · from = to.
fn motion(from: &Pose, to: &Pose) -> Pose {
    let r = to.rotation * from.rotation.inverse();
    Pose {
        position: to.position - r * from.position,
        rotation: r.normalize(),
    }
}

impl SceneDesc {
    /// Puts body i at `poses[i]` (scene order) as its new rest pose and re-expresses
    /// every joint so that it means what it meant at the old rest, in each body's own
    /// frame, as a Doom 3 constraint keeps its body-local frames when `idAF::SetupPose`
    /// moves the bodies onto an animation.
    ///
    /// With Tᵢ = Pᵢ,new Pᵢ,oldⁱⁿᵛ the motion of body i (the identity for the world):
    /// what the joint attaches to body1 (anchor, shaft, twist axis, hinge axis, spring
    /// anchor 1) moves with T₁, what it attaches to body2 (a swing limit's axis, a
    /// universal joint's shaft 2, a slider's axis, spring anchor 2) with T₂. Ranges
    /// measured from the rest pose (a hinge's, a twist limit's) shift by the angle θ₀ the
    /// new pose is already turned: θ₀ is the twist, about the old axis, of body1's motion
    /// relative to body2, D = R₂,old R₂,newᵀ R₁,new R₁,oldᵀ, and [min, max] becomes
    /// [min − θ₀, max − θ₀]. A pyramid's roll changes by the turn of its base about the
    /// new axis (its base is fixed in body2). Left as at the new pose: a universal
    /// joint's per-axis ranges and a fixed joint's relative pose.
    pub fn repose(&mut self, poses: &[Pose]) {
        // A body past the end of `poses` stays where it is.
        let moved: Vec<Pose> = self
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| {
                poses
                    .get(i)
                    .map_or(Pose::IDENTITY, |to| motion(&b.pose, to))
            })
            .collect();
        for (b, p) in self.bodies.iter_mut().zip(poses) {
            b.pose = *p;
        }
        for c in &mut self.constraints {
            let t1 = moved[c.body1.index()];
            let t2 = c.body2.body().map_or(Pose::IDENTITY, |b| moved[b.index()]);
            let d = t2.rotation.inverse() * t1.rotation;
            let swing = |s: &mut SwingLimit| match s {
                SwingLimit::Cone { axis, shaft, .. } => {
                    *axis = t2.rotation * *axis;
                    *shaft = t1.rotation * *shaft;
                }
                SwingLimit::Pyramid {
                    axis, shaft, roll, ..
                } => {
                    let (base, _) = pyramid_sides(*axis, *roll);
                    *axis = (t2.rotation * *axis).normalize();
                    *shaft = t1.rotation * *shaft;
                    // The base B₀ is fixed in body2: the roll that rebuilds it about the
                    // new axis. B₀ turns right-handedly about the axis as roll grows
                    // (`pyramid_sides`), so the turn from the rebuilt B₀ is added.
                    let want = t2.rotation * base;
                    let (rebuilt, _) = pyramid_sides(*axis, *roll);
                    let turn = rebuilt.cross(want).dot(*axis).atan2(rebuilt.dot(want));
                    let (plus, _) = pyramid_sides(*axis, *roll + turn);
                    let (minus, _) = pyramid_sides(*axis, *roll - turn);
                    *roll += if plus.distance(want) <= minus.distance(want) {
                        turn
                    } else {
                        -turn
                    };
                }
            };
            match &mut c.kind {
                JointKind::BallAndSocket {
                    anchor,
                    swing: s,
                    twist,
                    ..
                } => {
                    *anchor = t1.transform_point(*anchor);
                    if let Some(s) = s {
                        swing(s);
                    }
                    if let Some(tw) = twist {
                        let shift = twist_angle(d, tw.axis);
                        tw.axis = t1.rotation * tw.axis;
                        tw.min -= shift;
                        tw.max -= shift;
                    }
                }
                JointKind::Universal {
                    anchor,
                    shaft1,
                    shaft2,
                    swing: s,
                    ..
                } => {
                    *anchor = t1.transform_point(*anchor);
                    *shaft1 = t1.rotation * *shaft1;
                    *shaft2 = t2.rotation * *shaft2;
                    if let Some(s) = s {
                        swing(s);
                    }
                }
                JointKind::Hinge {
                    anchor,
                    axis,
                    limit,
                } => {
                    if let Some(l) = limit {
                        let shift = twist_angle(d, *axis);
                        l.min -= shift;
                        l.max -= shift;
                    }
                    *anchor = t1.transform_point(*anchor);
                    *axis = t1.rotation * *axis;
                }
                JointKind::Slider { axis } => *axis = t2.rotation * *axis,
                JointKind::Fixed => {}
                JointKind::Spring {
                    anchor1, anchor2, ..
                } => {
                    *anchor1 = t1.transform_point(*anchor1);
                    *anchor2 = t2.transform_point(*anchor2);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::af::{AfOptions, parse};
    use std::path::Path;

    /// A transform and its inverse give back the scene (to rounding), anchors included.
    #[test]
    fn a_transform_and_its_inverse_give_the_scene_back() {
        let src = r#"
            body "a" { model box( ( -0.1, -0.1, -0.1 ), ( 0.1, 0.1, 0.1 ) ) origin ( 0, 1, 0 ) density 1000 }
            body "b" { model box( ( -0.1, -0.1, -0.1 ), ( 0.1, 0.1, 0.1 ) ) origin ( 0.2, 1, 0 ) density 1000 }
            hinge "h" { body1 "b" body2 "a" anchor ( 0.1, 1, 0 ) axis ( 0, 0, 1 ) }
        "#;
        let scene = match parse(src, Path::new("t.af"), &AfOptions::default()) {
            Ok(s) => s.desc,
            Err(e) => panic!("{e}"),
        };
        let t = Pose {
            position: Vec3::new(0.3, -0.2, 1.5),
            rotation: Quat::from_rotation_y(0.7),
        };
        let mut moved = scene.clone();
        moved.transform(&t);
        let hinge = |s: &SceneDesc| match s.constraints[0].kind {
            JointKind::Hinge { anchor, axis, .. } => (anchor, axis),
            _ => panic!("not a hinge"),
        };
        let ((anchor, axis), (moved_anchor, moved_axis)) = (hinge(&scene), hinge(&moved));
        assert!(moved_anchor.distance(t.transform_point(anchor)) < 1e-6);
        assert!(moved_axis.distance(t.rotation * axis) < 1e-6);
        let inverse = Pose {
            position: -(t.rotation.inverse() * t.position),
            rotation: t.rotation.inverse(),
        };
        moved.transform(&inverse);
        for (a, b) in scene.bodies.iter().zip(&moved.bodies) {
            assert!(
                a.pose.position.distance(b.pose.position) < 1e-6,
                "{}",
                a.name
            );
            assert!(
                a.pose.rotation.angle_between(b.pose.rotation) < 1e-5,
                "{}",
                a.name
            );
        }
    }

    fn two_boxes_on_a_hinge() -> SceneDesc {
        let src = r#"
            body "a" { model box( ( -0.1, -0.1, -0.1 ), ( 0.1, 0.1, 0.1 ) ) origin ( 0, 1, 0 ) density 1000 }
            body "b" { model box( ( -0.1, -0.1, -0.1 ), ( 0.1, 0.1, 0.1 ) ) origin ( 0.2, 1, 0 ) density 1000 }
            hinge "h" { body1 "b" body2 "a" anchor ( 0.1, 1, 0 ) axis ( 0, 0, 1 ) limit 0, 60, 0 }
        "#;
        match parse(src, Path::new("t.af"), &AfOptions::default()) {
            Ok(s) => s.desc,
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn reposing_every_body_by_one_motion_is_that_transform() {
        let scene = two_boxes_on_a_hinge();
        let t = Pose {
            position: Vec3::new(0.3, -0.2, 1.5),
            rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, -0.2),
        };
        let mut moved = scene.clone();
        moved.transform(&t);
        let mut reposed = scene.clone();
        let poses: Vec<Pose> = moved.bodies.iter().map(|b| b.pose).collect();
        reposed.repose(&poses);
        match (&moved.constraints[0].kind, &reposed.constraints[0].kind) {
            (
                JointKind::Hinge {
                    anchor,
                    axis,
                    limit,
                },
                JointKind::Hinge {
                    anchor: a2,
                    axis: x2,
                    limit: l2,
                },
            ) => {
                assert!(anchor.distance(*a2) < 1e-5 && axis.distance(*x2) < 1e-5);
                let (l, l2) = (limit.unwrap(), l2.unwrap());
                assert!((l.min - l2.min).abs() < 1e-5 && (l.max - l2.max).abs() < 1e-5);
            }
            _ => panic!("not a hinge"),
        }
    }

    #[test]
    fn a_hinge_bent_by_the_new_pose_keeps_its_limits_where_they_were() {
        let scene = two_boxes_on_a_hinge();
        let (before, pivot, hinge_axis) = match scene.constraints[0].kind {
            JointKind::Hinge {
                limit,
                anchor,
                axis,
            } => (limit.unwrap(), anchor, axis),
            _ => panic!("not a hinge"),
        };
        // Body "b" (body1) turned 0.4 rad about the hinge axis through the anchor.
        let turn = Pose {
            position: Vec3::ZERO,
            rotation: Quat::from_axis_angle(hinge_axis, 0.4),
        };
        let about = |p: &Pose| {
            let mut q = *p;
            q.position = pivot + turn.rotation * (p.position - pivot);
            q.rotation = turn.rotation * p.rotation;
            q
        };
        let poses = vec![scene.bodies[0].pose, about(&scene.bodies[1].pose)];
        let mut reposed = scene.clone();
        reposed.repose(&poses);
        match reposed.constraints[0].kind {
            JointKind::Hinge {
                anchor,
                axis,
                limit,
            } => {
                let l = limit.unwrap();
                assert!((l.min - (before.min - 0.4)).abs() < 1e-5, "{l:?}");
                assert!((l.max - (before.max - 0.4)).abs() < 1e-5, "{l:?}");
                assert!(anchor.distance(pivot) < 1e-6 && axis.distance(hinge_axis) < 1e-6);
            }
            _ => panic!("not a hinge"),
        }
    }

    #[test]
    fn a_pyramid_base_stays_fixed_in_body2() {
        let axis = Vec3::new(0.2, -0.9, 0.3).normalize();
        let roll = 0.3;
        let t2 = Quat::from_euler(glam::EulerRot::XYZ, 0.5, -0.4, 1.1);
        let mut scene = two_boxes_on_a_hinge();
        scene.constraints[0].kind = JointKind::BallAndSocket {
            anchor: Vec3::new(0.1, 1.0, 0.0),
            swing: Some(SwingLimit::Pyramid {
                axis,
                half_angle1: 0.5,
                half_angle2: 0.3,
                roll,
                shaft: Vec3::X,
            }),
            twist: None,
            limit_style: Default::default(),
        };
        let (base, _) = pyramid_sides(axis, roll);
        let turned = |p: &Pose| Pose {
            position: p.position,
            rotation: t2 * p.rotation,
        };
        let poses = vec![turned(&scene.bodies[0].pose), scene.bodies[1].pose];
        scene.repose(&poses);
        match scene.constraints[0].kind {
            JointKind::BallAndSocket {
                swing:
                    Some(SwingLimit::Pyramid {
                        axis: a, roll: r, ..
                    }),
                ..
            } => {
                assert!(a.distance(t2 * axis) < 1e-5);
                let (b, _) = pyramid_sides(a, r);
                assert!(b.distance(t2 * base) < 1e-4, "{b} vs {}", t2 * base);
            }
            _ => panic!("not a pyramid"),
        }
    }
}
