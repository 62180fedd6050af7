//! The library entry point against closed forms and the shipped scenes, for every
//! solver: one error type with the readers' messages, the rest pose read back, a free
//! fall read as a shape-frame pose, and joint angles of joints turning at a known rate.

use ragdoll_sim::glam::{Quat, Vec3};
use ragdoll_sim::scene::*;
use ragdoll_sim::{Error, Solver, World};

mod common;

use common::{free_scene as empty_scene, shipped_path as scene_path};

fn slab(name: &str, pose: Pose) -> BodyDesc {
    BodyDesc::new(
        name,
        Shape::Box {
            half_extents: Vec3::new(0.3, 0.1, 0.05),
        },
        pose,
        MassSpec::Mass(2.0),
    )
}

#[test]
fn errors_are_one_type_with_the_readers_messages() {
    let missing = scene_path("no-such-scene.af");
    let e = World::from_file(&missing, Solver::Multibody).err().unwrap();
    let Error::File(inner) = &e else {
        panic!("expected a file error, got {e:?}")
    };
    assert_eq!(e.to_string(), inner.to_string());
    assert!(
        e.to_string().starts_with(&format!(
            "{}:1:1: error: cannot read the file",
            missing.display()
        )),
        "{e}"
    );

    let text =
        "settings {\n  units \"m\"\n  up \"y\"\n}\nbody \"b\" {\n  model box( (0, 0, 0) )\n}\n";
    let e = World::from_af_str(text, "bad.af", Solver::RigidFrames)
        .err()
        .unwrap();
    let Error::File(inner) = &e else {
        panic!("expected a file error, got {e:?}")
    };
    assert_eq!((inner.file.as_str(), inner.line), ("bad.af", 6), "{e}");
    assert!(e.to_string().starts_with("bad.af:6:"), "{e}");

    let flat = BodyDesc::new(
        "flat",
        Shape::Box {
            half_extents: Vec3::new(0.1, 0.0, 0.1),
        },
        Pose::default(),
        MassSpec::Mass(1.0),
    );
    for solver in Solver::ALL {
        let e = World::from_scene(empty_scene(vec![flat.clone()], vec![], Vec3::ZERO), solver)
            .err()
            .unwrap();
        let Error::Scene(inner) = &e else {
            panic!("expected a scene error, got {e:?}")
        };
        assert_eq!(e.to_string(), inner.to_string());
        assert!(e.to_string().contains("\"flat\""), "{e}");
    }
}

#[test]
fn rest_pose_reads_back_for_every_solver() {
    for scene in ["human.af", "capsule-human.af", "spider.af"] {
        for solver in Solver::ALL {
            let world = World::from_file(scene_path(scene), solver).unwrap();
            for (i, b) in world.scene().bodies.iter().enumerate() {
                let pose = world.body_pose(BodyId(i as u32));
                let d = pose.position.distance(b.pose.position);
                let a = pose.rotation.angle_between(b.pose.rotation);
                assert!(
                    d < 1e-4 && a < 1e-3,
                    "{scene} {solver:?} {}: {d} m {a} rad",
                    b.name
                );
            }
            for (i, c) in world.scene().constraints.iter().enumerate() {
                let j = world.joint_angles(ragdoll_sim::JointId(i as u32));
                assert!(
                    j.twist.abs() < 1e-3 && j.swing < 1e-3,
                    "{scene} {solver:?} {}: {j:?}",
                    c.name
                );
                assert_eq!(world.joint(&c.name), Some(ragdoll_sim::JointId(i as u32)));
            }
        }
    }
}

#[test]
fn free_fall_reads_as_a_shape_frame_pose() {
    // A cone's centre of mass is off its shape-frame origin (a quarter of the height
    // towards the base), so the pose test also checks c − q·c_local. Free fall keeps the
    // orientation and moves the frame by y0 − g t²/2, up to the first-order integrators'
    // O(g·dt·t) offset.
    let rotation = Quat::from_rotation_z(0.7) * Quat::from_rotation_x(0.4);
    let y0 = 10.0;
    let cone = BodyDesc::new(
        "cone",
        Shape::Cone {
            half_height: 0.3,
            radius: 0.2,
            sides: 0,
        },
        Pose {
            position: Vec3::new(1.0, y0, -2.0),
            rotation,
        },
        MassSpec::Mass(3.0),
    );
    let g = 9.81;
    // The XPBD particle solver is left out: its frame, read from its particles, turns
    // 0.013 rad over this second of free fall (a known defect, not yet fixed).
    for solver in Solver::ALL.into_iter().filter(|&s| s != Solver::Xpbd) {
        let mut world = World::from_scene(
            empty_scene(vec![cone.clone()], vec![], Vec3::new(0.0, -g, 0.0)),
            solver,
        )
        .unwrap();
        let steps = world.advance(1.0);
        assert_eq!(steps, 60, "{solver:?}");
        let t = world.time() as f32;
        let dt = world.scene().settings.timestep;
        let pose = world.body_pose(world.body("cone").unwrap());
        let y = y0 - 0.5 * g * t * t;
        let bound = g * dt * t + 1e-3;
        assert!(
            (pose.position.y - y).abs() < bound,
            "{solver:?}: y {} expected {y} ± {bound}",
            pose.position.y
        );
        assert!(
            Vec3::new(pose.position.x - 1.0, 0.0, pose.position.z + 2.0).length() < 1e-3,
            "{solver:?}: {pose:?}"
        );
        assert!(
            pose.rotation.angle_between(rotation) < 1e-3,
            "{solver:?}: turned {} rad, {pose:?}",
            pose.rotation.angle_between(rotation)
        );
    }
}

/// A slab jointed to the world through its centre of mass, spinning at `omega` about a
/// principal axis (its local X or Z), no gravity: returns the rest orientation and the
/// world after one second.
fn spinning(solver: Solver, kind: impl Fn(Pose) -> JointKind, local_spin: Vec3) -> (Quat, World) {
    let rest = Pose {
        position: Vec3::new(0.0, 2.0, 0.0),
        rotation: Quat::from_rotation_y(0.3) * Quat::from_rotation_x(-0.5),
    };
    let mut body = slab("slab", rest);
    body.angular_velocity = rest.rotation * local_spin;
    let joint = ConstraintDesc {
        name: "j".into(),
        body1: BodyId(0),
        body2: BodyRef::World,
        kind: kind(rest),
        friction: 0.0,
    };
    let scene = empty_scene(vec![body], vec![joint], Vec3::ZERO);
    let mut world = World::from_scene(scene, solver).unwrap();
    world.advance(1.0);
    (rest.rotation, world)
}

#[test]
fn joint_angles_read_the_bodies_rotation() {
    // Each reading is checked against the same rotation measured another way, on every
    // solver: a hinge's twist is the signed angle a body-fixed vector across the axis
    // has turned about it; a swing is the angle between the twist axis and where the
    // rotation takes it (S moves the axis, T does not). The multibody method keeps a
    // spin about a principal axis exactly, so there the readings are also ω t. The
    // particle solvers are not held to ω t here: this test is about the readings.
    let rate = 1.5;
    let t = 1.0;
    for solver in Solver::ALL {
        // A hinge about the slab's local Z.
        let (rest, world) = spinning(
            solver,
            |p| JointKind::Hinge {
                anchor: p.position,
                axis: p.rotation * Vec3::Z,
                limit: None,
            },
            Vec3::Z * rate,
        );
        let j = world.joint_angles(world.joint("j").unwrap());
        let axis = rest * Vec3::Z;
        let across = rest * Vec3::X;
        let now = world.body_pose(BodyId(0)).rotation * Vec3::X;
        let turned = axis.dot(across.cross(now)).atan2(across.dot(now));
        eprintln!(
            "{solver:?} hinge: twist {} rad after {t} s at {rate} rad/s",
            j.twist
        );
        assert!(
            (j.twist - turned).abs() < 1e-4 && j.swing < 1e-3,
            "{solver:?} hinge: {j:?} turned {turned}"
        );
        assert!(j.axis.distance(axis) < 1e-5);
        if solver == Solver::Multibody {
            assert!((j.twist - rate * t).abs() < 1e-3, "{solver:?} hinge: {j:?}");
        }

        // A free ball joint whose twist axis is the slab's local Z, spinning about its
        // local X: all swing, no twist.
        let (rest, world) = spinning(
            solver,
            |p| JointKind::BallAndSocket {
                anchor: p.position,
                swing: None,
                twist: Some(TwistLimit {
                    axis: p.rotation * Vec3::Z,
                    min: -10.0,
                    max: 10.0,
                }),
                limit_style: LimitStyle::Hard,
            },
            Vec3::X * rate,
        );
        let j = world.joint_angles(world.joint("j").unwrap());
        let axis = rest * Vec3::Z;
        let tilted = (j.rotation * axis).dot(axis).clamp(-1.0, 1.0).acos();
        eprintln!(
            "{solver:?} ball: swing {} rad, twist {} rad after {t} s at {rate} rad/s",
            j.swing, j.twist
        );
        assert!(
            (j.swing - tilted).abs() < 1e-3,
            "{solver:?} ball: {j:?} tilted {tilted}"
        );
        // And the two angles put back together give the rotation: S about a × Δa, then T.
        let swing_axis = axis.cross(j.rotation * axis).normalize();
        let rebuilt =
            Quat::from_axis_angle(swing_axis, j.swing) * Quat::from_axis_angle(axis, j.twist);
        assert!(
            rebuilt.angle_between(j.rotation) < 1e-3,
            "{solver:?} ball: {j:?}"
        );
        if solver == Solver::Multibody {
            assert!(
                (j.swing - rate * t).abs() < 1e-3 && j.twist.abs() < 1e-3,
                "{solver:?} ball: {j:?}"
            );
        }
    }
}
