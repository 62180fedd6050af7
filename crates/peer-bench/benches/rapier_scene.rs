//! A `SceneDesc` rebuilt in Rapier, as close to what our methods simulate as Rapier's
//! joints allow.
//!
//! - Bodies: the same shapes, poses, initial velocities and masses (our `mass_props`;
//!   Rapier derives the inertia from the shape at uniform density, as we do).
//! - Contacts: the body's μ combined by the geometric mean (our `sqrt(μ1·μ2)`), the
//!   larger restitution; none between the two bodies of a joint.
//! - Joints: Rapier's generic joint with a frame on each body. The frames are the
//!   joint's world frame at the rest pose carried into each body, so every angle is zero
//!   at rest as in `SceneDesc`. A ball joint's cone becomes limits of ±half-angle on the
//!   two swing axes (a pyramid circumscribing the cone: Rapier has no cone limit), its
//!   twist a limit on the twist axis; a hinge's range a limit on its axis.
//! - Sleeping: Rapier's own policy, or none when the scene turns sleeping off.
//! - Solver budget: `substeps` solver iterations (Rapier's substeps) of `iterations` PGS
//!   iterations each, one step per frame of `timestep`.

use glam::{Quat, Vec3};
use ragdoll_sim::SceneDesc;
use ragdoll_sim::scene::{BodyRef, JointKind, Shape, SwingLimit, scene_mass_props};
use rapier3d::prelude::*;

/// Rapier limits: an axis and its `[min, max]`.
type Limits = Vec<(JointAxis, [f32; 2])>;

/// A joint in Rapier's terms: locked axes, world anchor, the world orientation of the
/// joint frame on body1 and on body2 at rest, and the limits.
type JointFrames = (JointAxesMask, Vec3, Quat, Quat, Limits);

/// The Rapier world and what could not be carried over.
pub struct RapierScene {
    /// The world, ready to step.
    pub world: PhysicsWorld,
    /// Features of the scene Rapier got only approximately or not at all.
    pub approximations: Vec<String>,
}

fn pose(position: Vec3, rotation: Quat) -> Pose {
    Pose::from_parts(position, rotation)
}

fn collider(shape: &Shape) -> ColliderBuilder {
    match shape {
        Shape::Box { half_extents: h } => ColliderBuilder::cuboid(h.x, h.y, h.z),
        Shape::Capsule {
            half_height,
            radius,
        } => ColliderBuilder::capsule_y(*half_height, *radius),
        Shape::Cylinder {
            half_height,
            radius,
            ..
        } => ColliderBuilder::cylinder(*half_height, *radius),
        Shape::Cone {
            half_height,
            radius,
            ..
        } => ColliderBuilder::cone(*half_height, *radius),
        Shape::ConvexHull { points } => ColliderBuilder::convex_hull(points).unwrap_or_else(|| {
            ColliderBuilder::ball(Shape::local_half_extents(shape).max_element())
        }),
    }
}

/// A rotation taking the frame's X axis onto `x` (unit), the rest of the frame arbitrary.
fn frame_with_x(x: Vec3) -> Quat {
    Quat::from_rotation_arc(Vec3::X, x.normalize())
}

/// Builds the Rapier world for `scene`.
pub fn build(scene: &SceneDesc) -> RapierScene {
    let s = &scene.settings;
    let mut world = PhysicsWorld::new();
    let mut approximations = Vec::new();
    world.gravity = s.gravity;
    world.integration_parameters.dt = s.timestep;
    world.integration_parameters.num_solver_iterations = s.substeps.max(1) as usize;
    world.integration_parameters.num_internal_pgs_iterations = s.iterations.max(1) as usize;

    let props = scene_mass_props(scene).expect("the pile scene is valid");
    let mut handles = Vec::with_capacity(scene.bodies.len());
    let mut poses = Vec::with_capacity(scene.bodies.len());
    for (b, mp) in scene.bodies.iter().zip(&props) {
        let builder = if b.is_fixed() {
            RigidBodyBuilder::fixed()
        } else {
            RigidBodyBuilder::dynamic()
        };
        let body = builder
            .pose(pose(b.pose.position, b.pose.rotation))
            .linvel(b.linear_velocity)
            .angvel(b.angular_velocity)
            .linear_damping(b.friction.linear)
            .angular_damping(b.friction.angular)
            // Sleeping off in the scene (`SleepSettings::disable`, `--no-sleep`): off here.
            .can_sleep(s.sleep.enabled())
            .build();
        let h = world.bodies.insert(body);
        let c = collider(&b.shape)
            .mass(mp.mass)
            .friction(b.friction.contact)
            .friction_combine_rule(CoefficientCombineRule::GeometricMean)
            .restitution(b.restitution)
            .restitution_combine_rule(CoefficientCombineRule::Max)
            .build();
        world.colliders.insert_with_parent(c, h, &mut world.bodies);
        handles.push(h);
        poses.push(pose(b.pose.position, b.pose.rotation));
        if !b.self_collision {
            approximations.push(format!("{}: self_collision off not modelled", b.name));
        }
        if b.inertia_scale.is_some() {
            approximations.push(format!("{}: inertiaScale ignored", b.name));
        }
    }

    if let Some(g) = s.ground {
        // A large fixed slab whose top face is the ground plane.
        let rotation = Quat::from_rotation_z(g.tilt);
        let top = Vec3::new(0.0, g.height, 0.0);
        let half_t = 0.5 * g.thickness.max(0.01);
        let ground = RigidBodyBuilder::fixed()
            .pose(pose(top - rotation * Vec3::new(0.0, half_t, 0.0), rotation))
            .build();
        let h = world.bodies.insert(ground);
        let c = ColliderBuilder::cuboid(2000.0, half_t, 2000.0)
            .friction(g.friction)
            .friction_combine_rule(CoefficientCombineRule::GeometricMean)
            .restitution(g.restitution)
            .build();
        world.colliders.insert_with_parent(c, h, &mut world.bodies);
    }
    // Joints to the world attach to a fixed body at the origin.
    let world_body = world.bodies.insert(RigidBodyBuilder::fixed().build());

    for c in &scene.constraints {
        let h1 = handles[c.body1.index()];
        let p1 = poses[c.body1.index()];
        let (h2, p2) = match c.body2 {
            BodyRef::Body(b) => (handles[b.index()], poses[b.index()]),
            BodyRef::World => (world_body, Pose::IDENTITY),
        };
        // World frames of the joint on body1 and body2 at rest, and the joint's axes.
        let (mask, anchor, r1, r2, limits): JointFrames = match &c.kind {
            JointKind::BallAndSocket {
                anchor,
                swing,
                twist,
                ..
            } => {
                let mut limits = Vec::new();
                let (r1, r2) = match swing {
                    Some(SwingLimit::Cone {
                        axis,
                        half_angle,
                        shaft,
                    }) => {
                        limits.push((JointAxis::AngY, [-half_angle, *half_angle]));
                        limits.push((JointAxis::AngZ, [-half_angle, *half_angle]));
                        (frame_with_x(*shaft), frame_with_x(*axis))
                    }
                    Some(SwingLimit::Pyramid {
                        axis,
                        half_angle1,
                        half_angle2,
                        roll,
                        shaft,
                    }) => {
                        limits.push((JointAxis::AngY, [-half_angle1, *half_angle1]));
                        limits.push((JointAxis::AngZ, [-half_angle2, *half_angle2]));
                        let roll = Quat::from_rotation_x(*roll);
                        (frame_with_x(*shaft) * roll, frame_with_x(*axis) * roll)
                    }
                    None => match twist {
                        Some(t) => (frame_with_x(t.axis), frame_with_x(t.axis)),
                        None => (Quat::IDENTITY, Quat::IDENTITY),
                    },
                };
                if let Some(t) = twist {
                    limits.push((JointAxis::AngX, [t.min, t.max]));
                    if swing.is_some() {
                        approximations
                            .push(format!("{}: twist measured about the swing axis", c.name));
                    }
                }
                (
                    JointAxesMask::LOCKED_SPHERICAL_AXES,
                    *anchor,
                    r1,
                    r2,
                    limits,
                )
            }
            JointKind::Hinge {
                anchor,
                axis,
                limit,
            } => {
                let r = frame_with_x(*axis);
                let limits = limit
                    .map(|l| vec![(JointAxis::AngX, [l.min, l.max])])
                    .unwrap_or_default();
                (JointAxesMask::LOCKED_REVOLUTE_AXES, *anchor, r, r, limits)
            }
            JointKind::Universal {
                anchor,
                shaft1,
                shaft2,
                swing,
                axis_ranges,
            } => {
                // Free about both shafts, locked about their common perpendicular.
                let r = frame_with_x(shaft1.cross(*shaft2));
                if swing.is_some() || axis_ranges.is_some() {
                    approximations.push(format!("{}: universal joint limits ignored", c.name));
                }
                (
                    JointAxesMask::LOCKED_SPHERICAL_AXES | JointAxesMask::ANG_X,
                    *anchor,
                    r,
                    r,
                    Vec::new(),
                )
            }
            JointKind::Fixed => (
                JointAxesMask::LOCKED_FIXED_AXES,
                p1.translation,
                Quat::IDENTITY,
                Quat::IDENTITY,
                Vec::new(),
            ),
            JointKind::Slider { axis } => {
                let r = frame_with_x(*axis);
                (
                    JointAxesMask::LOCKED_PRISMATIC_AXES,
                    p1.translation,
                    r,
                    r,
                    Vec::new(),
                )
            }
            JointKind::Spring { .. } => {
                approximations.push(format!("{}: spring not modelled", c.name));
                continue;
            }
        };
        let mut joint = GenericJointBuilder::new(mask)
            .local_frame1(p1.inverse() * pose(anchor, r1))
            .local_frame2(p2.inverse() * pose(anchor, r2))
            .contacts_enabled(false);
        for (axis, range) in limits {
            joint = joint.limits(axis, range);
        }
        world.impulse_joints.insert(h1, h2, joint.build(), true);
    }
    RapierScene {
        world,
        approximations,
    }
}
