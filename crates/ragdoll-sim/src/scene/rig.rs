//! Skeleton joints from body poses: how a Doom 3 figure's bodies move the skinned
//! model's joints (dhewm3 `idAF::ChangePose` / `idAF::UpdateAnimation`).
//!
//! Every body names the joint it modifies (`joint`) and how (`mod`): its orientation,
//! its position, or both. At load, with the skeleton in the pose the figure was built
//! from, each driven joint j of body b keeps
//!
//! ```text
//! o = R_jᵀ (p_b − p_j)        the body's origin in the joint's frame
//! R_rel = R_jᵀ R_b            the body's rotation relative to the joint
//! ```
//!
//! and later the body's pose gives the joint R = R_b R_relᵀ, p = p_b − R o. The pose is
//! rebuilt in joint order (parents first) from the load pose's parent-relative locals
//! (R_l, t_l):
//!
//! | mod | rotation | position |
//! |---|---|---|
//! | orientation | R_b R_relᵀ | p_parent + R_parent t_l |
//! | position | R_parent R_l | p_b − R_b R_relᵀ o |
//! | both | R_b R_relᵀ | p_b − R_b R_relᵀ o |
//! | (no body) | R_parent R_l | p_parent + R_parent t_l |
//!
//! The root joint follows the origin body as Doom 3's entity does: E = B₀ B₀,loadⁱⁿᵛ,
//! root = E · root_load. Everything here is in one frame (ours: metres, Y up); body
//! poses may be any frame fixed to each body (shape frame or centre of mass) as long as
//! the load poses and the later ones use the same.

use super::Pose;
use glam::{Quat, Vec3};

/// How a body drives its joint (Doom 3's `mod`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointMod {
    /// The joint turns with the body; its position follows its parent.
    Orientation,
    /// The joint moves with the body; its rotation follows its parent.
    Position,
    /// Both.
    Both,
}

/// A body driving a joint, with the body's pose in the joint's frame at load.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointDriver {
    /// The body's index in the scene.
    pub body: usize,
    /// How it drives the joint.
    pub mode: JointMod,
    /// o = R_jᵀ (p_b − p_j) at load.
    pub offset: Vec3,
    /// R_rel = R_jᵀ R_b at load.
    pub relative: Quat,
}

/// One joint of a rig.
#[derive(Clone, Debug, PartialEq)]
pub struct RigJoint {
    /// The skeleton's name for it.
    pub name: String,
    /// Parent joint (earlier in the list), `None` for a root.
    pub parent: Option<usize>,
    /// The load pose relative to the parent (relative to the world for a root).
    pub local: Pose,
    /// The body that drives it, if any.
    pub driver: Option<JointDriver>,
}

/// A skeleton driven by a figure's bodies.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// Joints, parents first.
    pub joints: Vec<RigJoint>,
    /// The body the root joints follow, with its load pose.
    pub origin: Option<(usize, Pose)>,
    /// The joints' world poses at load.
    pub rest: Vec<Pose>,
    /// The bodies' poses at load (scene order).
    pub body_rest: Vec<Pose>,
    /// How a vector in a joint's frame in the skeleton file (a mesh weight's offset)
    /// becomes ours: rotated by `file_axes`, scaled by `file_scale`.
    pub file_axes: Quat,
    /// Metres per file unit.
    pub file_scale: f32,
}

/// `a · b` for rigid transforms (apply b, then a).
fn mul(a: &Pose, b: &Pose) -> Pose {
    Pose {
        position: a.position + a.rotation * b.position,
        rotation: (a.rotation * b.rotation).normalize(),
    }
}

fn inverse(a: &Pose) -> Pose {
    let r = a.rotation.inverse();
    Pose {
        position: -(r * a.position),
        rotation: r,
    }
}

impl Rig {
    /// A rig from the joints' load poses (`(name, parent, world pose)`, parents first),
    /// the drivers (`(body, joint, mod)`), every body's load pose, and the origin body.
    pub fn new(
        joints: &[(String, Option<usize>, Pose)],
        drivers: &[(usize, usize, JointMod)],
        body_rest: &[Pose],
        origin_body: Option<usize>,
    ) -> Rig {
        let rest: Vec<Pose> = joints.iter().map(|j| j.2).collect();
        let mut out: Vec<RigJoint> = joints
            .iter()
            .map(|(name, parent, pose)| RigJoint {
                name: name.clone(),
                parent: *parent,
                local: match parent {
                    Some(p) => mul(&inverse(&rest[*p]), pose),
                    None => *pose,
                },
                driver: None,
            })
            .collect();
        for &(body, joint, mode) in drivers {
            let (j, b) = (rest[joint], body_rest[body]);
            let r_t = j.rotation.inverse();
            out[joint].driver = Some(JointDriver {
                body,
                mode,
                offset: r_t * (b.position - j.position),
                relative: (r_t * b.rotation).normalize(),
            });
        }
        Rig {
            joints: out,
            origin: origin_body.map(|b| (b, body_rest[b])),
            rest,
            body_rest: body_rest.to_vec(),
            file_axes: Quat::IDENTITY,
            file_scale: 1.0,
        }
    }

    /// Every body's pose for the joints' poses `joints` (indexed as at load): the other
    /// way round, as Doom 3 places a figure on an animated skeleton (`idAF::SetupPose`),
    /// whatever the body's `mod`:
    ///
    /// ```text
    /// R_b = R_j R_rel        p_b = p_j + R_j o
    /// ```
    ///
    /// with the o and R_rel the load kept. A body that drives no joint (a second body on
    /// joint `origin`) moves rigidly with the root joint: B = J₀ J₀,loadⁱⁿᵛ B_load. With
    /// the load skeleton this gives the load poses back.
    pub fn body_poses(&self, joints: &[Pose]) -> Vec<Pose> {
        let root = mul(&joints[0], &inverse(&self.rest[0]));
        let mut out: Vec<Pose> = self.body_rest.iter().map(|b| mul(&root, b)).collect();
        for (j, joint) in self.joints.iter().enumerate() {
            if let Some(d) = joint.driver {
                let jp = joints[j];
                out[d.body] = Pose {
                    position: jp.position + jp.rotation * d.offset,
                    rotation: (jp.rotation * d.relative).normalize(),
                };
            }
        }
        out
    }

    /// A joint pose of the skeleton file (file units and axes) in ours: the position
    /// rotated by `file_axes` and scaled by `file_scale`, the rotation conjugated by
    /// `file_axes` (R' = A R Aᵀ).
    pub fn from_file(&self, pose: &Pose) -> Pose {
        Pose {
            position: self.file_axes * pose.position * self.file_scale,
            rotation: (self.file_axes * pose.rotation * self.file_axes.inverse()).normalize(),
        }
    }

    /// Every joint's world pose for the bodies' current poses (indexed as at load).
    pub fn joint_poses(&self, bodies: &[Pose]) -> Vec<Pose> {
        let entity = match self.origin {
            Some((b, load)) => mul(&bodies[b], &inverse(&load)),
            None => Pose::IDENTITY,
        };
        let mut out: Vec<Pose> = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            let follow = match j.parent {
                Some(p) => mul(&out[p], &j.local),
                None => mul(&entity, &j.local),
            };
            let pose = match j.driver {
                None => follow,
                Some(d) => {
                    let b = bodies[d.body];
                    let r = (b.rotation * d.relative.inverse()).normalize();
                    let p = b.position - r * d.offset;
                    match d.mode {
                        JointMod::Orientation => Pose {
                            position: follow.position,
                            rotation: r,
                        },
                        JointMod::Position => Pose {
                            position: p,
                            rotation: follow.rotation,
                        },
                        JointMod::Both => Pose {
                            position: p,
                            rotation: r,
                        },
                    }
                }
            };
            out.push(pose);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain root → a → b → c along +Y with bodies 0 (origin, drives a), 1 (drives b,
    /// `mode`), and c driven by nobody.
    fn chain(mode: JointMod) -> (Rig, Vec<Pose>) {
        let turn = Quat::from_rotation_z(0.3);
        let joints = vec![
            ("root".to_string(), None, Pose::IDENTITY),
            (
                "a".to_string(),
                Some(0),
                Pose {
                    position: Vec3::new(0.0, 1.0, 0.0),
                    rotation: turn,
                },
            ),
            (
                "b".to_string(),
                Some(1),
                Pose {
                    position: Vec3::new(0.0, 2.0, 0.0),
                    rotation: turn,
                },
            ),
            (
                "c".to_string(),
                Some(2),
                Pose {
                    position: Vec3::new(0.0, 3.0, 0.0),
                    rotation: Quat::IDENTITY,
                },
            ),
        ];
        let bodies = vec![
            Pose {
                position: Vec3::new(0.1, 1.5, 0.0),
                rotation: Quat::from_rotation_x(0.2),
            },
            Pose {
                position: Vec3::new(0.0, 2.5, 0.2),
                rotation: Quat::from_rotation_y(-0.4),
            },
        ];
        let rig = Rig::new(
            &joints,
            &[(0, 1, JointMod::Orientation), (1, 2, mode)],
            &bodies,
            Some(0),
        );
        (rig, bodies)
    }

    fn close(a: &Pose, b: &Pose) -> bool {
        (a.position - b.position).length() < 1e-5 && a.rotation.dot(b.rotation).abs() > 1.0 - 1e-6
    }

    #[test]
    fn bodies_at_their_load_poses_give_the_load_skeleton() {
        for mode in [JointMod::Orientation, JointMod::Position, JointMod::Both] {
            let (rig, bodies) = chain(mode);
            let poses = rig.joint_poses(&bodies);
            for (p, r) in poses.iter().zip(&rig.rest) {
                assert!(close(p, r), "{mode:?}: {p:?} vs {r:?}");
            }
        }
    }

    #[test]
    fn bodies_placed_on_the_load_skeleton_are_at_their_load_poses() {
        for mode in [JointMod::Orientation, JointMod::Position, JointMod::Both] {
            let (rig, bodies) = chain(mode);
            for (p, r) in rig.body_poses(&rig.rest).iter().zip(&bodies) {
                assert!(close(p, r), "{mode:?}: {p:?} vs {r:?}");
            }
        }
    }

    #[test]
    fn bodies_placed_on_a_moved_skeleton_drive_it_back_to_itself() {
        // A skeleton with every joint turned and moved: bodies placed on it with `both`
        // give the same joints back through `joint_poses`.
        let (rig, _) = chain(JointMod::Both);
        let t = Pose {
            position: Vec3::new(0.5, -0.2, 1.0),
            rotation: Quat::from_rotation_y(0.8),
        };
        let mut moved: Vec<Pose> = rig.rest.iter().map(|r| mul(&t, r)).collect();
        moved[2].rotation = Quat::from_rotation_x(0.4) * moved[2].rotation;
        let bodies = rig.body_poses(&moved);
        let back = rig.joint_poses(&bodies);
        for j in 0..3 {
            assert!(
                close(&back[j], &moved[j]),
                "{j}: {:?} vs {:?}",
                back[j],
                moved[j]
            );
        }
    }

    #[test]
    fn a_rigid_motion_of_the_figure_moves_every_joint_with_it() {
        let t = Pose {
            position: Vec3::new(3.0, -1.0, 2.0),
            rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.7, -1.1, 0.4),
        };
        for mode in [JointMod::Orientation, JointMod::Position, JointMod::Both] {
            let (rig, bodies) = chain(mode);
            let moved: Vec<Pose> = bodies.iter().map(|b| mul(&t, b)).collect();
            for (p, r) in rig.joint_poses(&moved).iter().zip(&rig.rest) {
                assert!(close(p, &mul(&t, r)), "{mode:?}");
            }
        }
    }

    #[test]
    fn a_vertex_on_a_joint_moves_exactly_with_the_body_that_drives_both() {
        let (rig, mut bodies) = chain(JointMod::Both);
        let offset = Vec3::new(0.3, -0.2, 0.5);
        let vertex = |poses: &[Pose]| poses[2].position + poses[2].rotation * offset;
        let before = vertex(&rig.joint_poses(&bodies));
        // Move body 1 alone, far and turned: the vertex keeps its place on the body.
        let t = Pose {
            position: Vec3::new(-2.0, 0.5, 1.0),
            rotation: Quat::from_rotation_x(1.3),
        };
        let body_before = bodies[1];
        bodies[1] = mul(&t, &bodies[1]);
        let after = vertex(&rig.joint_poses(&bodies));
        let expect = bodies[1].transform_point(body_before.inverse_transform_point(before));
        assert!((after - expect).length() < 1e-5, "{after} vs {expect}");
    }

    #[test]
    fn an_orientation_driven_joint_turns_with_its_body_and_stays_on_its_parent() {
        let (rig, mut bodies) = chain(JointMod::Orientation);
        let rest = rig.joint_poses(&bodies);
        bodies[1].rotation = Quat::from_rotation_x(0.9) * bodies[1].rotation;
        let poses = rig.joint_poses(&bodies);
        // b stays where a puts it; c, driven by nobody, follows b.
        assert!((poses[2].position - rest[2].position).length() < 1e-5);
        let c_local = mul(&inverse(&poses[2]), &poses[3]);
        assert!(close(&c_local, &mul(&inverse(&rest[2]), &rest[3])));
        assert!(!close(&poses[3], &rest[3]));
    }
}
