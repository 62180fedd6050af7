//! Moving what a scene describes by a rigid transform of the world: the `.af` reader's
//! `transform` block and `replicate` grid, and nearby starts of one scene (ensembles,
//! tests). Bodies carry their velocities along; joints their world-space anchors, axes
//! and limit frames. The ground, gravity and camera stay where they are.

use super::{BodyDesc, JointKind, Pose, SceneDesc, SwingLimit};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::af::{AfOptions, parse};
    use glam::{Quat, Vec3};
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
}
