//! The particle method's rigid-frames solver steps independent islands on all cores
//! and must stay deterministic: the same scene gives the same particles bit
//! for bit whatever the number of threads, and the same as the serial solver.
//!
//! The timing of the same scene, by hand (no timing is asserted in a test):
//!
//! ```text
//! cargo test --release -p ragdoll-sim --test particle_threads -- --ignored --nocapture
//! ```
//!
//! The machine must be otherwise idle: on two cores any other process halves the
//! second thread.

use ragdoll_sim::SceneDesc;
use ragdoll_sim::glam::Vec3;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::{Grab, Method};
use std::time::Instant;

/// The pile scene (scene 10) with `count` humans.
mod common;

use common::shipped_pile as pile;

/// Steps `frames` frames, in a pool of `threads` threads or (`None`) in rayon's global
/// pool, holding `grab` throughout, and returns every particle position.
fn run(scene: &SceneDesc, frames: usize, threads: Option<usize>, grab: Option<Grab>) -> Vec<Vec3> {
    let mut w = ParticleWorld::new(scene, ParticleSolver::RigidFrames).unwrap();
    w.set_grab(grab);
    let mut steps = || {
        for _ in 0..frames {
            w.step();
        }
    };
    match threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(steps),
        None => steps(),
    }
    let mut x = Vec::new();
    w.particle_positions(&mut x);
    x
}

fn bits(x: &[Vec3]) -> Vec<[u32; 3]> {
    x.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

/// FNV-1a over the bits of every coordinate: a fingerprint to compare runs by eye.
fn fingerprint(x: &[Vec3]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for c in bits(x).iter().flatten() {
        for byte in c.to_le_bytes() {
            h = (h ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

#[test]
fn pile_is_bit_identical_on_any_number_of_threads() {
    // Eight humans in two crosswise layers: 120 frames take them through the fall, the
    // landing on each other and the floor, and the first islands falling asleep.
    let scene = pile(8);
    let frames = 120;
    let serial = run(&scene, frames, Some(1), None);
    println!("1 thread: fingerprint {:016x}", fingerprint(&serial));
    for threads in [Some(2), Some(4), None] {
        let x = run(&scene, frames, threads, None);
        println!("{threads:?} threads: fingerprint {:016x}", fingerprint(&x));
        assert!(
            bits(&x) == bits(&serial),
            "{threads:?} threads differ from 1 thread"
        );
    }
}

#[test]
fn a_grabbed_human_is_bit_identical_on_any_number_of_threads() {
    // The mouse spring belongs to its bone's island: the fourth human's chest is held
    // 2 m above where it starts while the others fall.
    let scene = pile(8);
    let chest = scene
        .body_id("chest.3")
        .expect("the pile has a fourth human");
    let grab = Some(Grab {
        body: chest,
        local_point: Vec3::ZERO,
        target: scene.bodies[chest.index()].pose.position + Vec3::Y * 2.0,
    });
    let serial = run(&scene, 90, Some(1), grab);
    let parallel = run(&scene, 90, Some(2), grab);
    assert!(bits(&parallel) == bits(&serial), "2 threads differ from 1");
    assert!(
        bits(&serial) != bits(&run(&scene, 90, Some(1), None)),
        "the grab had no effect"
    );
}

#[test]
#[ignore = "timing, run by hand with --ignored --nocapture"]
fn pile_of_100_humans_timing() {
    let scene = pile(100);
    let frames = 600;
    // PILE_THREADS=t times only t threads (one run per process, to compare by `time`).
    let only: Option<usize> = std::env::var("PILE_THREADS")
        .ok()
        .and_then(|v| v.parse().ok());
    for threads in [1, 2].into_iter().filter(|t| only.is_none_or(|o| o == *t)) {
        let mut w = ParticleWorld::new(&scene, ParticleSolver::RigidFrames).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let t0 = Instant::now();
        pool.install(|| {
            for _ in 0..frames {
                w.step();
            }
        });
        let ms = t0.elapsed().as_secs_f64() * 1e3 / frames as f64;
        let mut x = Vec::new();
        w.particle_positions(&mut x);
        println!(
            "pile, 100 humans ({} bones), {frames} frames, {threads} thread(s): {ms:.2} ms/frame, fingerprint {:016x}",
            w.body_count(),
            fingerprint(&x)
        );
    }
}
