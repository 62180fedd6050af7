//! Micro-benchmarks of the methods' hot loops, through their public API: one `step` of a
//! small scene chosen so that one loop dominates it.
//!
//! - `joints`: a hanging chain of boxes, no ground, no contacts — the particle method's
//!   stick projection and joint coupling, the multibody method's joint rows.
//! - `contacts`: nine boxes resting in a 3 × 3 stack on the ground — contact solve with
//!   warm contacts, nothing else moving.
//! - `broad_phase`: a grid of separated boxes in free fall — no contact, no joint, so
//!   the cost is integration plus finding that no pair touches.
//! - `pile`: the pile scene with a few humans after it has landed — everything at once.
//!
//! Each bench builds and settles its world outside the timing, with sleeping off, then
//! times `step`.
//!
//! ```text
//! cargo bench -p ragdoll-sim --bench hot_loops
//! ```

use glam::{Quat, Vec3};
use ragdoll_sim::Method;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::af::{AfOptions, parse};
use ragdoll_sim::scene::{
    BodyDesc, BodyId, BodyRef, ConstraintDesc, JointKind, LimitStyle, MassSpec, Pose, SceneDesc,
    Settings, Shape,
};
use std::path::Path;

fn main() {
    divan::main();
}

/// Which method a bench runs.
#[derive(Clone, Copy, Debug)]
enum Which {
    ParticleRigidFrames,
    ParticlePaper,
    Multibody,
}

const ALL: [Which; 3] = [
    Which::ParticleRigidFrames,
    Which::ParticlePaper,
    Which::Multibody,
];

impl std::fmt::Display for Which {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Which::ParticleRigidFrames => "particle_rigid_frames",
            Which::ParticlePaper => "particle_paper",
            Which::Multibody => "multibody",
        })
    }
}

fn build(which: Which, scene: &SceneDesc, settle_steps: usize) -> Box<dyn Method> {
    // No sleeping: a bench of a resting stack must time the solver, not the sleep test.
    let mut scene = scene.clone();
    scene.settings.sleep.time = 1e9;
    let scene = &scene;
    let mut m: Box<dyn Method> = match which {
        Which::ParticleRigidFrames => {
            Box::new(ParticleWorld::new(scene, ParticleSolver::RigidFrames).unwrap())
        }
        Which::ParticlePaper => Box::new(ParticleWorld::new(scene, ParticleSolver::Paper).unwrap()),
        Which::Multibody => Box::new(MultibodyWorld::new(scene).unwrap()),
    };
    for _ in 0..settle_steps {
        m.step();
    }
    m
}

fn cube(name: String, position: Vec3, half: f32) -> BodyDesc {
    BodyDesc::new(
        name,
        Shape::Box {
            half_extents: Vec3::splat(half),
        },
        Pose::from_position(position),
        MassSpec::Mass(1.0),
    )
}

/// 20 boxes hanging from the world on ball joints, swinging, no ground; sleep cannot
/// stop it in the few seconds a bench runs.
fn chain() -> SceneDesc {
    let mut s = SceneDesc {
        name: "bench-chain".into(),
        settings: Settings {
            ground: None,
            ..Settings::default()
        },
        ..SceneDesc::default()
    };
    let pitch = 0.25;
    for i in 0..20 {
        // Laid out horizontally so it swings down.
        s.bodies.push(cube(
            format!("b{i}"),
            Vec3::new(pitch * (i as f32 + 0.5), 2.0, 0.0),
            0.1,
        ));
        s.constraints.push(ConstraintDesc {
            name: format!("j{i}"),
            body1: BodyId(i),
            body2: if i == 0 {
                BodyRef::World
            } else {
                BodyRef::Body(BodyId(i - 1))
            },
            kind: JointKind::BallAndSocket {
                anchor: Vec3::new(pitch * i as f32, 2.0, 0.0),
                swing: None,
                twist: None,
                limit_style: LimitStyle::Hard,
            },
            friction: 0.0,
        });
    }
    s
}

/// Nine boxes in a 3 × 3 stack on the ground, touching.
fn stack() -> SceneDesc {
    let mut s = SceneDesc {
        name: "bench-stack".into(),
        ..SceneDesc::default()
    };
    for i in 0..9u32 {
        let (col, level) = (i % 3, i / 3);
        s.bodies.push(cube(
            format!("b{i}"),
            Vec3::new(0.21 * col as f32, 0.1 + 0.2 * level as f32, 0.0),
            0.1,
        ));
    }
    s
}

/// 400 boxes in a 20 × 20 grid, 1 m apart, high above the ground.
fn free_fall() -> SceneDesc {
    let mut s = SceneDesc {
        name: "bench-free-fall".into(),
        ..SceneDesc::default()
    };
    for i in 0..400u32 {
        let mut b = cube(
            format!("b{i}"),
            Vec3::new((i % 20) as f32, 1000.0, (i / 20) as f32),
            0.1,
        );
        b.pose.rotation = Quat::from_rotation_y(0.1 * i as f32);
        s.bodies.push(b);
    }
    s
}

fn pile(humans: u32) -> SceneDesc {
    let text = include_str!("../../../assets/scenes/pile.af");
    let opts = AfOptions {
        count: Some(humans),
        ..AfOptions::default()
    };
    parse(text, Path::new("assets/scenes/pile.af"), &opts)
        .unwrap()
        .desc
}

#[divan::bench(args = ALL)]
fn joints(bencher: divan::Bencher, which: Which) {
    let mut m = build(which, &chain(), 30);
    bencher.bench_local(|| m.step());
}

#[divan::bench(args = ALL)]
fn contacts(bencher: divan::Bencher, which: Which) {
    let mut m = build(which, &stack(), 30);
    bencher.bench_local(|| m.step());
}

#[divan::bench(args = ALL)]
fn broad_phase(bencher: divan::Bencher, which: Which) {
    let mut m = build(which, &free_fall(), 1);
    bencher.bench_local(|| m.step());
}

#[divan::bench(args = [Which::ParticleRigidFrames, Which::Multibody], sample_count = 30)]
fn pile_of_4(bencher: divan::Bencher, which: Which) {
    // 90 frames: the humans have landed on each other.
    let mut m = build(which, &pile(4), 90);
    bencher.bench_local(|| m.step());
}
