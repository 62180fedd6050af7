//! The multibody's pile of 1000 humans comes to rest and falls asleep as a whole: the
//! piles must sleep (a landed pile costs next to nothing a frame only asleep). Small
//! piles (200, 400 humans) settle in fewer layers and do not show what this one does:
//! with the gyroscopic term added explicitly to the velocity of bodies in contact
//! (`rigid::integrate::integrate_positions`), six resting arms kept turning and held 12
//! humans awake for ten seconds.

use ragdoll_sim::Method;
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::af::{AfOptions, load};
use std::path::PathBuf;

/// Frame length (s), as the benchmarks step the pile.
const FRAME_DT: f32 = 1.0 / 60.0;

/// The pile lands within 1.2 s and is all asleep by 1.45 s; 2.5 s leaves room for a
/// slower settling without letting an island that never rests pass.
const ASLEEP_BY_S: f32 = 2.5;

#[test]
fn the_pile_of_1000_humans_falls_asleep() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/pile.af");
    let opts = AfOptions {
        count: Some(1000),
        ..Default::default()
    };
    let mut scene = load(&path, &opts).unwrap_or_else(|e| panic!("{e}")).desc;
    scene.settings.timestep = FRAME_DT;
    let mut world = MultibodyWorld::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let frames = (ASLEEP_BY_S / FRAME_DT).round() as usize;
    for _ in 0..frames {
        world.step();
    }
    let awake = world.awake_body_count();
    assert!(awake == 0, "{awake} bodies still awake at {ASLEEP_BY_S} s");
}
