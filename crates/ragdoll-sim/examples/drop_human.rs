//! Drops the paper's 16-bone human (test 8) with every solver and prints, every half
//! second, where the pelvis is, how far the right knee is bent (and
//! how far off its hinge axis) and the figure's energy.
//!
//! `cargo run --release -p ragdoll-sim --example drop_human [-- path/to/scene.af]`

use ragdoll_sim::{Error, Solver, World};
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

fn run(path: &std::path::Path) -> Result<(), Error> {
    for solver in Solver::ALL {
        let mut world = World::from_file(path, solver)?;
        println!("{} ({}):", solver.name(), world.method().solver_label());
        // The pelvis of the human scenes; any other figure: its first body.
        let pelvis = world
            .body("hip")
            .or_else(|| world.body("pelvis"))
            .unwrap_or(ragdoll_sim::scene::BodyId(0));
        let knee = world.joint("right_knee");
        for _ in 0..=6 {
            let pose = world.body_pose(pelvis);
            // A hinge's angle is its twist; its swing is how far it is off its axis.
            let (bend, off_axis) = knee.map_or((0.0, 0.0), |k| {
                let a = world.joint_angles(k);
                (a.twist.to_degrees(), a.swing.to_degrees())
            });
            let sample = world.method().sample();
            println!(
                "  t {:4.2} s  pelvis ({:6.3}, {:6.3}, {:6.3}) m  right knee {:6.1} deg (off axis {:4.1})  \
                 energy {:8.2} J  joint gap {:.4} m",
                world.time(),
                pose.position.x,
                pose.position.y,
                pose.position.z,
                bend,
                off_axis,
                sample.energy,
                sample.max_joint_gap,
            );
            world.advance(0.5);
        }
    }
    Ok(())
}
