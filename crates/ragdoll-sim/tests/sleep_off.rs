//! Sleeping turned off through the scene's settings (`SleepSettings::disable`, the
//! benchmarks' `--no-sleep`) keeps every body of both methods awake, where the same
//! scene with its own settings falls asleep; and `Method::awake_body_count` counts what
//! the sleep flags say.

use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::{Method, SceneDesc};

/// The spider (scene 7): a body and eight legs dropped onto the floor, asleep within
/// 2.6 s in both methods with the scene's own settings. (The human is not used: with no
/// joint or air friction in its file, when it comes to rest depends on how one chaotic
/// landing leaves a limb swinging.)
mod common;

fn spider() -> SceneDesc {
    common::shipped_scene("spider")
}

fn methods(scene: &SceneDesc) -> Vec<Box<dyn Method>> {
    vec![
        Box::new(ParticleWorld::new(scene, ParticleSolver::RigidFrames).unwrap()),
        Box::new(MultibodyWorld::new(scene).unwrap()),
    ]
}

/// Steps `m` for `seconds`; returns the fewest bodies awake at the start of any step and
/// the number awake at the end.
fn run(m: &mut dyn Method, seconds: f64) -> (usize, usize) {
    let steps = (seconds / m.settings().timestep as f64).round() as usize;
    let mut fewest = usize::MAX;
    for _ in 0..steps {
        fewest = fewest.min(m.awake_body_count());
        m.step();
    }
    (fewest, m.awake_body_count())
}

#[test]
fn the_spider_falls_asleep_with_its_own_settings() {
    let scene = spider();
    assert!(scene.settings.sleep.enabled());
    for mut m in methods(&scene) {
        let dynamic = scene.dynamic_body_count();
        assert_eq!(
            m.awake_body_count(),
            dynamic,
            "{:?}: awake at the start",
            m.kind()
        );
        let (_, end) = run(m.as_mut(), 7.0);
        assert_eq!(end, 0, "{:?}: asleep by 7 s", m.kind());
        assert!(m.sample().all_asleep);
    }
}

#[test]
fn with_sleeping_off_every_body_stays_awake() {
    let mut scene = spider();
    scene.settings.sleep.disable();
    assert!(!scene.settings.sleep.enabled());
    let dynamic = scene.dynamic_body_count();
    for mut m in methods(&scene) {
        let (fewest, end) = run(m.as_mut(), 7.0);
        assert_eq!(fewest, dynamic, "{:?}: a body slept", m.kind());
        assert_eq!(end, dynamic, "{:?}", m.kind());
        assert!(!m.sample().all_asleep);
        assert!(m.sample().energy.is_finite());
    }
}
