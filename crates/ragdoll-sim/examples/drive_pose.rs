//! A powered ragdoll, with every solver: the paper's human carried by its pelvis along
//! a path (a kinematic body, as an animated character's root), its joints driven to
//! the rest pose by motors; struck on the head at 1 s; let go at 2 s (motors off, the
//! pelvis dynamic again), so it falls as a ragdoll from where it was carried; and at
//! 3.5 s set back, still, in its rest pose where it was let go (it falls again). Prints, every quarter second, where the pelvis
//! is, the joint furthest from its rest angle, and the figure's energy.
//!
//! `cargo run --release -p ragdoll-sim --example drive_pose [-- path/to/scene.af]`

use ragdoll_sim::glam::{Quat, Vec3};
use ragdoll_sim::scene::{BodyId, Pose};
use ragdoll_sim::{BodyPoseSet, BodyVelocity, Error, JointId, MotorDrive, Solver, World};
use std::path::PathBuf;

fn main() {
    let path = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/human.af")
        });
    if let Err(e) = run(&path) {
        eprintln!("{e}");
        std::process::exit(1);
    }
}

/// The joint furthest from its rest angle: its name and that angle (degrees).
fn worst_joint(world: &World) -> (String, f32) {
    let mut worst = (String::from("-"), 0.0f32);
    for (i, c) in world.scene().constraints.iter().enumerate() {
        let a = world.joint_angles(JointId(i as u32));
        // The angle of the whole relative rotation since rest.
        let angle = 2.0 * a.rotation.xyz().length().min(1.0).asin();
        if angle.to_degrees() > worst.1 {
            worst = (c.name.clone(), angle.to_degrees());
        }
    }
    worst
}

fn run(path: &std::path::Path) -> Result<(), Error> {
    for solver in Solver::ALL {
        let mut world = World::from_file(path, solver)?;
        println!("{} ({}):", solver.name(), world.method().solver_label());
        let pelvis = world
            .body("hip")
            .or_else(|| world.body("pelvis"))
            .unwrap_or(BodyId(0));
        let head = world.body("head").unwrap_or(pelvis);
        let rest: Vec<Pose> = world.scene().bodies.iter().map(|b| b.pose).collect();
        // The animated root: carried forward at 0.5 m/s, turning at 0.3 rad/s.
        let start = world.body_pose(pelvis);
        let carried = |t: f32| Pose {
            position: start.position + Vec3::new(0.5 * t, 0.0, 0.0),
            rotation: Quat::from_rotation_y(0.3 * t) * start.rotation,
        };
        world.set_kinematic(pelvis, true);
        world.drive_to_pose(
            &rest,
            MotorDrive {
                frequency: 30.0,
                damping_ratio: 1.0,
                max_torque: 500.0,
            },
        )?;
        let dt = world.scene().settings.timestep;
        let mut next_print = 0.0;
        while world.time() < 5.0 {
            let t = world.time() as f32;
            if world.is_kinematic(pelvis) {
                world.move_kinematic(pelvis, carried(t + dt), dt);
            }
            world.step();
            let now = world.time() as f32;
            if (t..now).contains(&1.0) {
                // A blow to the side of the head, 20 N·s, 5 cm above its centre.
                let at = world.body_state(head).com + Vec3::new(0.0, 0.05, 0.0);
                world.apply_impulse(head, Vec3::new(0.0, 0.0, 20.0), at);
                println!("  t {now:4.2} s  struck on the head");
            }
            if (t..now).contains(&2.0) {
                world.stop_motors();
                world.set_kinematic(pelvis, false);
                println!("  t {now:4.2} s  let go");
            }
            if (t..now).contains(&3.5) {
                // Back up where the root was carried, at rest: every body at its rest
                // pose moved rigidly with the pelvis.
                let to = carried(2.0);
                let move_rest = to.mul_pose(&Pose {
                    position: -(start.rotation.inverse() * start.position),
                    rotation: start.rotation.inverse(),
                });
                let sets: Vec<BodyPoseSet> = rest
                    .iter()
                    .enumerate()
                    .map(|(i, p)| BodyPoseSet {
                        body: BodyId(i as u32),
                        pose: move_rest.mul_pose(p),
                        velocity: Some(BodyVelocity::default()),
                    })
                    .collect();
                world.set_pose(&sets);
                println!("  t {now:4.2} s  set back in its rest pose where it was let go");
            }
            if now >= next_print {
                next_print += 0.25;
                let p = world.body_pose(pelvis).position;
                let (joint, angle) = worst_joint(&world);
                println!(
                    "  t {now:4.2} s  pelvis ({:6.3}, {:6.3}, {:6.3}) m  furthest joint {joint:>14} {angle:6.1} deg  energy {:8.2} J",
                    p.x,
                    p.y,
                    p.z,
                    world.method().sample().energy,
                );
            }
        }
    }
    Ok(())
}
