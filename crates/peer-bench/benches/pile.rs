//! The pile of humans in Rapier and in both of our methods, in turn, in one process:
//! milliseconds per frame and our time over Rapier's.
//!
//! ```text
//! cargo bench -p peer-bench --bench pile                  # 1, 10, 100, 270, 1000 humans
//! cargo bench -p peer-bench --bench pile -- 100 270 --frames 300
//! ```
//!
//! All three run single-threaded (Rapier without its `parallel` feature), the same
//! scene description, timestep and solver budget; see `rapier_scene.rs` for how the
//! scene is carried over. Goals (issue 6): our multibody at or below Rapier's time, the
//! particle method at half of it.

mod rapier_scene;

use ragdoll_lab::bench::scale::{self, FrameCost};
use ragdoll_lab::bench::{Flavor, median};
use std::time::Instant;

fn rapier_cost(scene: &ragdoll_sim::SceneDesc, frames: usize) -> (FrameCost, Vec<String>) {
    let mut r = rapier_scene::build(scene);
    let mut per_frame = Vec::with_capacity(frames);
    for _ in 0..frames {
        let t0 = Instant::now();
        r.world.step();
        per_frame.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let finite = r
        .world
        .bodies
        .iter()
        .all(|(_, b)| b.translation().is_finite());
    let mean_ms = per_frame.iter().sum::<f64>() / frames as f64;
    (
        FrameCost {
            mean_ms,
            median_ms: median(&mut per_frame),
            finite,
        },
        r.approximations,
    )
}

fn main() {
    // `cargo bench` passes `--bench`; numbers are human counts, `--frames F` the frames.
    let mut humans: Vec<u32> = Vec::new();
    let mut frames = scale::FRAMES;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--frames" {
            frames = args.next().and_then(|f| f.parse().ok()).unwrap_or(frames);
        } else if let Ok(n) = a.parse() {
            humans.push(n);
        }
    }
    if humans.is_empty() {
        humans = scale::HUMANS.to_vec();
    }
    println!("Pile of humans, {frames} frames at 1/60 s, one thread; ms per frame (mean / median)");
    println!(
        "{:>6} {:>6} {:>17} {:>17} {:>6} {:>17} {:>6}",
        "humans", "bones", "rapier", "multibody", "ratio", "particle", "ratio"
    );
    for n in humans {
        let scene = match scale::pile(n) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("pile of {n}: {e}");
                std::process::exit(1);
            }
        };
        let bones = scene.dynamic_body_count();
        let (rapier, approx) = rapier_cost(&scene, frames);
        let ours = |f: Flavor| scale::measure(f, &scene, frames).map_err(|e| e.to_string());
        let cell = |c: &FrameCost| {
            let s = format!("{:.3} / {:.3}", c.mean_ms, c.median_ms);
            if c.finite { s } else { format!("{s}!") }
        };
        let cells = |r: Result<FrameCost, String>| match r {
            Ok(c) => (cell(&c), format!("{:.2}", c.mean_ms / rapier.mean_ms)),
            Err(e) => (format!("error: {e}"), "-".into()),
        };
        let (mb, mb_ratio) = cells(ours(Flavor::Multibody));
        let (pa, pa_ratio) = cells(ours(Flavor::ParticleImproved));
        println!(
            "{n:>6} {bones:>6} {:>17} {mb:>17} {mb_ratio:>6} {pa:>17} {pa_ratio:>6}",
            cell(&rapier)
        );
        if n == 1 && !approx.is_empty() {
            println!("  Rapier approximations: {}", approx.join("; "));
        }
    }
    println!(
        "ratio = our mean ms / Rapier's mean ms (goal: multibody <= 1, particle <= 0.5); ! = state not finite at the end"
    );
}
