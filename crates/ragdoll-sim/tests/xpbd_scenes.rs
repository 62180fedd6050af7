//! The XPBD particle solver on the scene files (assets/scenes): the thresholds of
//! scenes 1–9 (energy gain ≤ 2 %, penetration ≤ 1 cm, joint gap ≤ 5 mm, limit excess
//! ≤ 3°, bone stretch ≤ 1 %, the spider, the human and the capsule human asleep with
//! no kinetic energy left), asserted on every variant of every scene.

mod common;

use common::particle::scene_failures;
use ragdoll_sim::particle::ParticleSolver;

#[test]
fn meets_the_thresholds_on_every_scene() {
    let mut failures = Vec::new();
    for n in 1..=9 {
        failures.extend(scene_failures(ParticleSolver::Xpbd, n, None, false));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
