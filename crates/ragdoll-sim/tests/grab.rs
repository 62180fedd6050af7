//! The mouse grab (Ctrl + left drag in the viewer) through the `Method` trait: grabbing a
//! body of a ragdoll that has come to rest and gone to sleep must wake its island and
//! carry the body to the target, on both sides. (Found trying the window under Xvfb: the
//! particle human, once asleep, ignored the drag because its island's rest timer put it
//! straight back to sleep.)

use ragdoll_sim::Method;
use ragdoll_sim::glam::Vec3;
use ragdoll_sim::method::Grab;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::SceneDesc;

mod common;

fn human() -> SceneDesc {
    common::shipped_scene("human")
}

fn com(m: &dyn Method, body: usize) -> Vec3 {
    let mut states = Vec::new();
    m.body_states(&mut states);
    states[body].com
}

/// Lets the human fall asleep, then holds its chest 60 cm above where it lies for two
/// seconds; returns how far the chest rose.
fn lift_sleeping_chest(m: &mut dyn Method, scene: &SceneDesc) -> f32 {
    let chest = scene
        .body_id("chest")
        .expect("the human has a chest")
        .index();
    for _ in 0..900 {
        m.step();
    }
    assert!(m.sample().all_asleep, "{:?}: asleep after 15 s", m.kind());
    let rest = com(m, chest);
    m.set_grab(Some(Grab {
        body: scene.body_id("chest").expect("chest"),
        local_point: Vec3::ZERO,
        target: rest + Vec3::Y * 0.6,
    }));
    for _ in 0..120 {
        m.step();
    }
    assert!(!m.sample().all_asleep, "{:?}: awake while held", m.kind());
    com(m, chest).y - rest.y
}

#[test]
fn grabbing_a_sleeping_body_wakes_it_and_lifts_it_on_both_sides() {
    let scene = human();
    let mut particle = ParticleWorld::new(&scene, ParticleSolver::RigidFrames).expect("particle");
    let mut multibody = MultibodyWorld::new(&scene).expect("multibody");
    // The chest's shape-frame origin is its centre. Held 60 cm up with the rest of the
    // body hanging from it, it must come within 10 cm of the target: both grabs are
    // springs that yield a few centimetres under the hanging weight (measured: particle
    // 0.59 m, multibody 0.58 m).
    for (m, rose) in [
        ("particle", lift_sleeping_chest(&mut particle, &scene)),
        ("multibody", lift_sleeping_chest(&mut multibody, &scene)),
    ] {
        assert!(
            rose > 0.5,
            "{m}: the held chest rose only {rose:.3} m of 0.6 m"
        );
    }
}
