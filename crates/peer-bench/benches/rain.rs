//! The rain (`ragdoll_lab::bench::rain`: humans dropped in groups at a steady rate) in
//! Rapier and in both of our methods, in turn, in one process, one thread each: ms per
//! frame, the busy frames, the moving bodies and µs per moving body per step, with our
//! time over Rapier's.
//!
//! ```text
//! cargo bench -p peer-bench --bench rain                 # sleeping on, as Box3D's rain
//! cargo bench -p peer-bench --bench rain -- --no-sleep   # sleeping off in all three
//! cargo bench -p peer-bench --bench rain -- --frames 300
//! ```
//!
//! Rapier gets the same scene (`rapier_scene.rs`), its air drag read as a rate like the
//! particle method's; the multibody method gets the drag written as it reads it
//! (`rain::scene_for`), so the groups fall and land alike in all three.

mod rapier_scene;

use ragdoll_lab::bench::busy::FrameLog;
use ragdoll_lab::bench::rain::{self, RainCost, RainRun};
use ragdoll_lab::bench::{Flavor, on_threads, thread_cpu_seconds};

/// Rapier's run of the rain, and what Rapier got only approximately for the first human
/// (every human is the same).
fn rapier_run(scene: &ragdoll_sim::SceneDesc, frames: usize) -> (RainRun, Vec<String>) {
    let mut r = rapier_scene::build(scene);
    let mut log = FrameLog::new(scene.settings.timestep as f64, frames);
    let mut airborne = Vec::with_capacity(frames);
    let mut total = 0.0;
    for _ in 0..frames {
        // Counted outside the timed span, as for our methods.
        let (mut awake, mut high) = (0, 0);
        for (_, b) in r.world.bodies.iter().filter(|(_, b)| b.is_dynamic()) {
            awake += usize::from(!b.is_sleeping());
            high += usize::from(b.center_of_mass().y > rain::LANDED_HEIGHT);
        }
        airborne.push(high);
        let cpu0 = thread_cpu_seconds();
        r.world.step();
        let ms = 1e3 * (thread_cpu_seconds() - cpu0);
        total += ms;
        log.push(ms, awake);
    }
    let finite = r
        .world
        .bodies
        .iter()
        .all(|(_, b)| b.translation().is_finite());
    let first: Vec<String> = r
        .approximations
        .into_iter()
        .filter(|a| a.contains("#0.0"))
        .collect();
    (
        RainRun {
            log,
            airborne,
            mean_ms: total / frames.max(1) as f64,
            finite,
        },
        first,
    )
}

fn main() {
    let mut frames = rain::FRAMES;
    let mut no_sleep = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--no-sleep" {
            no_sleep = true;
        } else if a == "--frames" {
            frames = args.next().and_then(|f| f.parse().ok()).unwrap_or(frames);
        }
    }
    let groups = rain::group_count(frames);
    let scene_of = |flavor: Flavor| {
        let mut s = rain::scene_for(flavor, groups).unwrap_or_else(|e| {
            eprintln!("rain: {e}");
            std::process::exit(1);
        });
        if no_sleep {
            s.settings.sleep.disable();
        }
        s
    };
    // Rapier reads air drag as the particle method does.
    let rapier_scene = scene_of(Flavor::ParticleRigidFrames);
    let bodies = rapier_scene.dynamic_body_count();
    println!(
        "Rain: {} humans ({bodies} bones), one group of {} landing every {} frames at {} m/s, {frames} frames at 1/60 s, one thread, sleeping {}",
        groups * rain::GROUP_SIZE,
        rain::GROUP_SIZE,
        rain::DROP_EVERY,
        rain::FALL_SPEED,
        if no_sleep { "off in all three" } else { "on" }
    );
    let before = rain::frames_before_landing();
    let (rapier_run, approximations) = rapier_run(&rapier_scene, frames);
    let rapier = rapier_run.cost(before);
    let ours = |flavor: Flavor| -> Result<RainCost, String> {
        let scene = scene_of(flavor);
        on_threads(1, || rain::run_ours(flavor, &scene, frames))
            .map(|r| r.cost(before))
            .map_err(|e| e.to_string())
    };
    let runs = [
        ("rapier", Ok(rapier)),
        ("multibody", ours(Flavor::Multibody)),
        ("particle", ours(Flavor::ParticleRigidFrames)),
    ];
    println!(
        "{:>10} {:>8} {:>8} {:>8} {:>7} {:>7} {:>8} {:>10} {:>10} {:>6}",
        "engine",
        "mean",
        "p95",
        "max",
        "moving",
        "fewest",
        "airborne",
        "us/moving",
        "us/landed",
        "ratio"
    );
    for (name, run) in &runs {
        match run {
            Ok(c) => {
                let us = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.3}"));
                println!(
                    "{name:>10} {:>8.3} {:>8.3} {:>8.3} {:>7.0} {:>7} {:>8.0} {:>10} {:>10} {:>6.2}{}",
                    c.mean_ms,
                    c.busy.p95_ms,
                    c.busy.max_ms,
                    c.busy.mean_awake,
                    c.fewest_moving,
                    c.mean_airborne,
                    us(c.busy.us_per_awake_body_step),
                    us(c.us_per_landed_moving_body_step),
                    c.mean_ms / rapier.mean_ms,
                    if c.finite { "" } else { " !" }
                );
            }
            Err(e) => println!("{name:>10} error: {e}"),
        }
    }
    println!(
        "ms per frame (CPU); moving = bodies awake at a step's start (mean), fewest after the first landing; airborne = above {} m (mean); us/moving = us per moving body per step (airborne included), us/landed = over the landed moving ones; ratio = mean frame over Rapier's; ! = not finite at the end",
        rain::LANDED_HEIGHT
    );
    if !approximations.is_empty() {
        println!(
            "Rapier approximations (each human): {}",
            approximations.join("; ")
        );
    }
}
