//! The XPBD particle solver on the scene files (assets/scenes): the thresholds of
//! scenes 1–9.

use ragdoll_sim::metrics::{MethodStats, MetricsRecorder};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::af::{AfOptions, load};
use ragdoll_sim::{Method, SceneDesc};
use std::path::PathBuf;

/// The scene table, in order (scene N is `SCENES[N - 1]`).
const SCENES: [&str; 9] = [
    "collision",
    "ball-chain",
    "hinge-chain",
    "box-masses",
    "ball-limits",
    "hinge-limits",
    "spider",
    "human",
    "capsule-human",
];

fn scene(name: &str, variant: u32) -> SceneDesc {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/scenes")
        .join(format!("{name}.af"));
    let opts = AfOptions {
        variant,
        ..Default::default()
    };
    load(&path, &opts).unwrap_or_else(|e| panic!("{e}")).desc
}

/// What `ragdoll-lab stats --method particle --particle-solver xpbd --seconds T`
/// measures.
fn run(s: &SceneDesc, seconds: f64, verbose: bool) -> MethodStats {
    let mut w =
        ParticleWorld::new(s, ParticleSolver::Xpbd).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    let mut rec = MetricsRecorder::new(s).unwrap();
    rec.record(0.0, &w.sample());
    let frames = (seconds / s.settings.timestep as f64).round() as usize;
    for f in 0..frames {
        w.step();
        let sm = w.sample();
        if verbose {
            println!("{f} {:?}", sm);
        }
        rec.record(w.time(), &sm);
    }
    rec.stats()
}

#[test]
#[ignore]
fn trace_human() {
    run(&scene("human", 1), 1.0, true);
}

/// Scene `n` (1-based) against the thresholds, every variant: the failures.
fn check_scene(n: usize) -> Vec<String> {
    let name = SCENES[n - 1];
    let mut failures = Vec::new();
    let variants = scene(name, 1).variants.len().max(1) as u32;
    for v in 1..=variants {
        let st = run(&scene(name, v), 10.0, false);
        println!(
            "scene {n} {name} v{v}: energy_gain {:.4} final_kinetic {:.2e} penetration {:.4} m joint_gap {:.4} m limit {:.2}° stretch {:.1e} asleep_at {:?}",
            st.energy_gain,
            st.final_kinetic,
            st.max_penetration_m,
            st.max_joint_gap_m,
            st.max_limit_violation_deg,
            st.max_bone_stretch.unwrap_or(0.0),
            st.asleep_at_s
        );
        let mut check = |ok: bool, what: String| {
            if !ok {
                failures.push(format!("scene {n} {name} v{v}: {what}"));
            }
        };
        check(st.finite, "not finite".into());
        check(
            st.energy_gain <= 0.02,
            format!("energy_gain {}", st.energy_gain),
        );
        check(
            st.max_penetration_m <= 0.01,
            format!("max_penetration_m {}", st.max_penetration_m),
        );
        check(
            st.max_joint_gap_m <= 0.005,
            format!("max_joint_gap_m {}", st.max_joint_gap_m),
        );
        check(
            st.max_limit_violation_deg <= 3.0,
            format!("max_limit_violation_deg {}", st.max_limit_violation_deg),
        );
        check(
            st.max_bone_stretch.is_some_and(|s| s <= 0.01),
            format!("max_bone_stretch {:?}", st.max_bone_stretch),
        );
        if n == 7 || n == 8 {
            check(
                st.final_kinetic <= 1e-3,
                format!("final_kinetic {}", st.final_kinetic),
            );
            check(st.asleep_at_s.is_some(), "never asleep".into());
        }
    }
    failures
}

#[test]
#[ignore]
fn survey_scenes_1_to_9() {
    let mut all = Vec::new();
    for n in 1..=9 {
        all.extend(check_scene(n));
    }
    println!("{all:#?}");
}
