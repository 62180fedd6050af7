//! The pile of humans in Rapier and in our engines, in turn, in one process: the
//! multibody method, the particle method's default solver (rigid frames) and its XPBD
//! solver on particles (`--particle-solver xpbd`); milliseconds per frame and our time
//! over Rapier's.
//!
//! ```text
//! cargo bench -p peer-bench --bench pile                  # 1, 10, 100, 270, 1000 humans
//! cargo bench -p peer-bench --bench pile -- 100 270 --frames 300
//! cargo bench -p peer-bench --bench pile -- 100 --timeline   # and CPU ms per second
//! cargo bench -p peer-bench --bench pile -- 100 270 --rounds 5
//! cargo bench -p peer-bench --bench pile -- 100 1000 --no-sleep   # sleeping off in all
//! cargo bench -p peer-bench --bench rain -- --no-sleep             # the rain benchmark
//! ```
//!
//! Beside each mean, the busy phase (`ragdoll_lab::bench::busy`): the 95th-percentile
//! and slowest frame, the CPU time of the first and second simulated seconds with our
//! time over Rapier's, and µs per awake body per step. `--no-sleep` turns sleeping off
//! in all four engines, so the ratios compare solvers, not sleep policies.
//!
//! All four run single-threaded (Rapier without its `parallel` feature), the same
//! scene description, timestep and solver budget; see `rapier_scene.rs` for how the
//! scene is carried over. Goals: our multibody at or below Rapier's time, the particle
//! method at half of it (`docs/benchmarks.md`).
//!
//! `--rounds N` runs the four engines in turn N times and reports each engine's median
//! mean and the median of the rounds' ratios, with their range: on a shared machine
//! the CPU time of the same run of the same binary drifts with the load, so one round's
//! ratio can be off by the drift between its engines' turns; engines taken in turn
//! within each round see the same drift.

mod rapier_scene;

use ragdoll_lab::bench::busy::FrameLog;
use ragdoll_lab::bench::scale::{self, FrameCost};
use ragdoll_lab::bench::{Flavor, median, on_threads, thread_cpu_seconds};
use rapier3d::prelude::PhysicsWorld;
use std::time::Instant;

/// Dynamic bodies of a Rapier world that are awake.
fn rapier_awake(world: &PhysicsWorld) -> usize {
    world
        .bodies
        .iter()
        .filter(|(_, b)| b.is_dynamic() && !b.is_sleeping())
        .count()
}

fn rapier_cost(scene: &ragdoll_sim::SceneDesc, frames: usize) -> (FrameCost, Vec<String>) {
    let mut r = rapier_scene::build(scene);
    let mut log = FrameLog::new(scene.settings.timestep as f64, frames);
    let mut t_real = 0.0;
    let mut t_wall = 0.0;
    for _ in 0..frames {
        // Counted outside the timed span, as for our methods.
        let awake = rapier_awake(&r.world);
        let cpu0 = thread_cpu_seconds();
        let t0 = Instant::now();
        r.world.step();
        t_wall += t0.elapsed().as_secs_f64();
        let cpu = thread_cpu_seconds() - cpu0;
        t_real += cpu;
        log.push(1e3 * cpu, awake);
    }
    let mean_ms = 1e3 * t_real / frames as f64;
    let finite = r
        .world
        .bodies
        .iter()
        .all(|(_, b)| b.translation().is_finite());
    let dynamic: Vec<_> = r
        .world
        .bodies
        .iter()
        .filter(|(_, b)| b.is_dynamic())
        .collect();
    let final_mean_height = dynamic
        .iter()
        .map(|(_, b)| b.center_of_mass().y as f64)
        .sum::<f64>()
        / dynamic.len().max(1) as f64;
    let asleep_at_end = dynamic.iter().all(|(_, b)| b.is_sleeping());
    let busy = log.summary();
    (
        FrameCost {
            mean_ms,
            wall_ms: 1e3 * t_wall / frames as f64,
            median_ms: busy.median_ms,
            max_ms: busy.max_ms,
            finite,
            final_mean_height,
            asleep_at_end,
            busy,
        },
        r.approximations,
    )
}

/// One round: each engine's run of the pile, in turn.
struct Round {
    rapier: FrameCost,
    multibody: Result<FrameCost, String>,
    particle: Result<FrameCost, String>,
    xpbd: Result<FrameCost, String>,
}

/// Which of our engines' runs of a round.
type Pick = fn(&Round) -> &Result<FrameCost, String>;

/// The run with the median mean CPU time of several (the lower middle one of an even
/// count), so that its other figures (median frame, end state) are those of a real run.
fn median_cost(mut runs: Vec<FrameCost>) -> FrameCost {
    runs.sort_by(|a, b| a.mean_ms.total_cmp(&b.mean_ms));
    runs[(runs.len() - 1) / 2]
}

/// CPU milliseconds each engine spends in each simulated second of the pile (`frames`
/// frames at 1/60 s): where a mean per frame comes from, active phase or rest.
fn timeline(scene: &ragdoll_sim::SceneDesc, frames: usize) -> Result<Vec<[f64; 4]>, String> {
    let seconds = frames.div_ceil(60);
    let mut out = vec![[0.0; 4]; seconds];
    let mut r = rapier_scene::build(scene);
    for f in 0..frames {
        let t0 = thread_cpu_seconds();
        r.world.step();
        out[f / 60][0] += 1e3 * (thread_cpu_seconds() - t0);
    }
    for (k, flavor) in [
        (1, Flavor::Multibody),
        (2, Flavor::ParticleRigidFrames),
        (3, Flavor::ParticleXpbd),
    ] {
        let ms = on_threads(1, || {
            let mut m = flavor.build(scene)?;
            let mut ms = vec![0.0; seconds];
            for f in 0..frames {
                let t0 = thread_cpu_seconds();
                m.step();
                ms[f / 60] += 1e3 * (thread_cpu_seconds() - t0);
            }
            Ok(ms)
        })
        .map_err(|e| e.to_string())?;
        for (row, v) in out.iter_mut().zip(ms) {
            row[k] = v;
        }
    }
    Ok(out)
}

fn main() {
    // `cargo bench` passes `--bench`; numbers are human counts, `--frames F` the frames.
    let mut humans: Vec<u32> = Vec::new();
    let mut frames = scale::FRAMES;
    let mut show_timeline = false;
    let mut no_sleep = false;
    let mut rounds = 1usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--timeline" {
            show_timeline = true;
        } else if a == "--no-sleep" {
            no_sleep = true;
        } else if a == "--frames" {
            frames = args.next().and_then(|f| f.parse().ok()).unwrap_or(frames);
        } else if a == "--rounds" {
            rounds = args
                .next()
                .and_then(|f| f.parse().ok())
                .unwrap_or(rounds)
                .max(1);
        } else if let Ok(n) = a.parse() {
            humans.push(n);
        }
    }
    if humans.is_empty() {
        humans = scale::HUMANS.to_vec();
    }
    let medians = if rounds > 1 {
        format!(", each the median of {rounds} rounds")
    } else {
        String::new()
    };
    println!(
        "Pile of humans, {frames} frames at 1/60 s, one thread, sleeping {}; ms per frame (mean CPU / median CPU){medians}",
        if no_sleep { "off in all four" } else { "on" }
    );
    println!(
        "{:>6} {:>6} {:>17} {:>17} {:>6} {:>17} {:>6} {:>17} {:>6}",
        "humans", "bones", "rapier", "multibody", "ratio", "particle", "ratio", "xpbd", "ratio"
    );
    for n in humans {
        let mut scene = match scale::pile(n) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("pile of {n}: {e}");
                std::process::exit(1);
            }
        };
        if no_sleep {
            // In all four engines (Rapier: `can_sleep(false)`, rapier_scene.rs).
            scene.settings.sleep.disable();
        }
        let bones = scene.dynamic_body_count();
        // On a one-thread pool: our methods share islands out over the pool they run in,
        // and Rapier here runs without its `parallel` feature.
        let ours = |f: Flavor| scale::measure_on(1, f, &scene, frames).map_err(|e| e.to_string());
        let mut runs: Vec<Round> = Vec::with_capacity(rounds);
        let mut approx = Vec::new();
        for _ in 0..rounds {
            let (rapier, a) = rapier_cost(&scene, frames);
            approx = a;
            runs.push(Round {
                rapier,
                multibody: ours(Flavor::Multibody),
                particle: ours(Flavor::ParticleRigidFrames),
                xpbd: ours(Flavor::ParticleXpbd),
            });
        }
        let rapier = median_cost(runs.iter().map(|r| r.rapier).collect());
        let of = |pick: Pick| {
            let costs: Result<Vec<FrameCost>, String> =
                runs.iter().map(|r| pick(r).clone()).collect();
            costs.map(median_cost)
        };
        let ratios = |pick: Pick| {
            let mut r: Vec<f64> = runs
                .iter()
                .filter_map(|run| {
                    pick(run)
                        .as_ref()
                        .ok()
                        .map(|c| c.mean_ms / run.rapier.mean_ms)
                })
                .collect();
            let (lo, hi) = r
                .iter()
                .fold((f64::MAX, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
            (median(&mut r), lo, hi)
        };
        let cell = |c: &FrameCost| {
            let s = format!("{:.3} / {:.3}", c.mean_ms, c.median_ms);
            if c.finite { s } else { format!("{s}!") }
        };
        let cells = |r: Result<FrameCost, String>, ratio: (f64, f64, f64)| match r {
            Ok(c) => (cell(&c), format!("{:.2}", ratio.0)),
            Err(e) => (format!("error: {e}"), "-".into()),
        };
        let (mb_ratios, pa_ratios) = (ratios(|r| &r.multibody), ratios(|r| &r.particle));
        let xp_ratios = ratios(|r| &r.xpbd);
        let (mb_run, pa_run) = (of(|r| &r.multibody), of(|r| &r.particle));
        let xp_run = of(|r| &r.xpbd);
        let (mb_cost, pa_cost) = (mb_run.clone().ok(), pa_run.clone().ok());
        let xp_cost = xp_run.clone().ok();
        let (mb, mb_ratio) = cells(mb_run, mb_ratios);
        let (pa, pa_ratio) = cells(pa_run, pa_ratios);
        let (xp, xp_ratio) = cells(xp_run, xp_ratios);
        println!(
            "{n:>6} {bones:>6} {:>17} {mb:>17} {mb_ratio:>6} {pa:>17} {pa_ratio:>6} {xp:>17} {xp_ratio:>6}",
            cell(&rapier)
        );
        if rounds > 1 {
            println!(
                "  ratios over {rounds} rounds: multibody {:.2}-{:.2}, particle {:.2}-{:.2}, xpbd {:.2}-{:.2}",
                mb_ratios.1, mb_ratios.2, pa_ratios.1, pa_ratios.2, xp_ratios.1, xp_ratios.2
            );
        }
        let state = |name: &str, c: Option<FrameCost>| {
            c.map(|c| {
                format!(
                    "{name} {:.3} m{}",
                    c.final_mean_height,
                    if c.asleep_at_end { " (asleep)" } else { "" }
                )
            })
        };
        let states: Vec<String> = [
            state("rapier", Some(rapier)),
            state("multibody", mb_cost),
            state("particle", pa_cost),
            state("xpbd", xp_cost),
        ]
        .into_iter()
        .flatten()
        .collect();
        println!("  mean body height at the end: {}", states.join(", "));
        // The busy phase, from the same runs: the frames a player feels and the first
        // seconds, while the pile falls and lands, with our time over Rapier's.
        let busy = |name: &str, c: Option<FrameCost>| {
            c.map(|c| {
                let b = c.busy;
                let sec = |k: usize| b.first_seconds_ms[k].map_or("-".into(), |x| format!("{x:.1}"));
                let ratio = |k: usize| match (b.first_seconds_ms[k], rapier.busy.first_seconds_ms[k]) {
                    (Some(x), Some(r)) if r > 0.0 && name != "rapier" => format!(" ({:.2}x)", x / r),
                    _ => String::new(),
                };
                format!(
                    "    {name:<9} p95 {:.3} max {:.3} ms; 1st s {}{} 2nd s {}{} ms; {} us per awake body-step (mean {:.0} awake)",
                    b.p95_ms,
                    b.max_ms,
                    sec(0),
                    ratio(0),
                    sec(1),
                    ratio(1),
                    b.us_per_awake_body_step.map_or("-".into(), |x| format!("{x:.3}")),
                    b.mean_awake,
                )
            })
        };
        println!(
            "  busy phase (frames CPU ms; seconds CPU ms per simulated second, over Rapier's):"
        );
        for line in [
            busy("rapier", Some(rapier)),
            busy("multibody", mb_cost),
            busy("particle", pa_cost),
            busy("xpbd", xp_cost),
        ]
        .into_iter()
        .flatten()
        {
            println!("{line}");
        }
        if show_timeline {
            match timeline(&scene, frames) {
                Ok(rows) => {
                    println!(
                        "  CPU ms per simulated second (rapier / multibody / particle / xpbd):"
                    );
                    for (k, [r, m, p, x]) in rows.iter().enumerate() {
                        println!("    {k:>2}-{:<2} s {r:9.1} {m:9.1} {p:9.1} {x:9.1}", k + 1);
                    }
                }
                Err(e) => println!("  timeline: {e}"),
            }
        }
        if n == 1 && !approx.is_empty() {
            println!("  Rapier approximations: {}", approx.join("; "));
        }
    }
    println!(
        "ratio = our mean CPU ms / Rapier's mean CPU ms{} (goal: multibody <= 1, particle and xpbd <= 0.5); ! = state not finite at the end",
        if rounds > 1 {
            ", the median of the rounds' ratios"
        } else {
            ""
        }
    );
}
