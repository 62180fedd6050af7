//! The XPBD particle solver on the scene files (assets/scenes): the thresholds of
//! scenes 1–9 (energy gain ≤ 2 %, penetration ≤ 1 cm, joint gap ≤ 5 mm, limit excess
//! ≤ 3°, bone stretch ≤ 1 %, the spider and the human asleep with no kinetic energy
//! left), asserted on every variant of every scene.

use ragdoll_sim::metrics::{MethodStats, MetricsRecorder};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::{Method, SceneDesc};

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

mod common;

use common::shipped_variant as scene;

/// What `ragdoll-lab stats --method particle --particle-solver xpbd --seconds T`
/// measures.
fn run(s: &SceneDesc, seconds: f64) -> MethodStats {
    let mut w =
        ParticleWorld::new(s, ParticleSolver::Xpbd).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    let mut rec = MetricsRecorder::new(s).unwrap();
    rec.record(0.0, &w.sample());
    let frames = (seconds / s.settings.timestep as f64).round() as usize;
    for _ in 0..frames {
        w.step();
        rec.record(w.time(), &w.sample());
    }
    rec.stats()
}

/// Scene `n` (1-based) against the thresholds, variants `variants` (`None`: every
/// one): the failures.
fn check_scene(n: usize, variants: Option<&[u32]>) -> Vec<String> {
    let name = SCENES[n - 1];
    let mut failures = Vec::new();
    let all: Vec<u32> = (1..=scene(name, 1).variants.len().max(1) as u32).collect();
    for &v in variants.unwrap_or(&all) {
        let st = run(&scene(name, v), 10.0);
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
fn meets_the_thresholds_on_the_scenes_it_holds() {
    let mut failures = Vec::new();
    for n in 1..=9 {
        failures.extend(check_scene(n, None));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
