//! Every scene file loads; counts, masses and placements are the paper's.

use ragdoll_sim::glam::Vec3;
use ragdoll_sim::scene::af::{AfOptions, AfScene, load};
use ragdoll_sim::scene::{BodyRef, JointKind, MassSpec, Motion, SceneDesc, Shape, SwingLimit};
use std::path::PathBuf;

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes")
}

fn scene(name: &str, variant: u32) -> AfScene {
    let opts = AfOptions {
        variant,
        ..Default::default()
    };
    load(&scenes_dir().join(format!("{name}.af")), &opts).unwrap_or_else(|e| panic!("{e}"))
}

fn mass(s: &SceneDesc, name: &str) -> f32 {
    let b = &s.bodies[s
        .body_id(name)
        .unwrap_or_else(|| panic!("no body {name}"))
        .index()];
    match b.mass {
        MassSpec::Mass(m) => m,
        MassSpec::Density(_) => panic!("mass of {name} not resolved"),
    }
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn print_summaries() {
    for e in std::fs::read_dir(scenes_dir()).unwrap() {
        let p = e.unwrap().path();
        let s = load(&p, &AfOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let d = &s.desc;
        let lowest = d
            .bodies
            .iter()
            .map(|b| b.pose.position.y - b.shape.local_half_extents().length())
            .fold(f32::MAX, f32::min);
        let total: f32 = d
            .bodies
            .iter()
            .filter(|b| b.motion == Motion::Dynamic)
            .map(|b| match b.mass {
                MassSpec::Mass(m) => m,
                _ => 0.0,
            })
            .sum();
        println!(
            "{:?}: {} bodies, {} constraints, {:.2} kg, lowest ~{:.3}, variants {}",
            p.file_name().unwrap(),
            d.bodies.len(),
            d.constraints.len(),
            total,
            lowest,
            d.variants.len()
        );
    }
}
