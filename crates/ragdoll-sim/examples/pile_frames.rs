//! The pile of N humans (scene 10) frame by frame, multibody unless `--solver` names
//! another (`paper`, `rigid-frames`, `xpbd`, `multibody`), for profiling its busy and
//! slowest frames: the mean, 95th-percentile and slowest frame, the slowest frame's
//! phases ([`ragdoll_sim::PhaseTimes`]: collision, islands, substeps, sleep) and the
//! phases summed over the run, the stepping thread's CPU time per frame, and a hash of
//! the final state, so that a change meant to keep results bit for bit can be checked.
//!
//! ```text
//! cargo run --release -p ragdoll-sim --example pile_frames -- [HUMANS] [THREADS] [FRAMES] [--no-sleep] [--each] [--solver NAME]
//! ```
//!
//! Defaults: 1000 humans, one thread, 600 frames at 1/60 s. `--each` prints every
//! frame's time, the stepping thread's CPU time, phases and awake bodies. Wall-clock time counts other programs' turns
//! on a shared machine; the CPU time of the stepping thread does not, and on one thread
//! it is the step's cost (on several it leaves out the other threads' share). The bench
//! tables (`ragdoll-lab bench scale`) are the reference figures; this is the quick look.

use ragdoll_sim::Solver;
use ragdoll_sim::scene::af::{AfOptions, load};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Frame length (s), as the benchmarks step the pile.
const FRAME_DT: f32 = 1.0 / 60.0;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pile_frames: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let no_sleep = args.iter().any(|a| a == "--no-sleep");
    let each = args.iter().any(|a| a == "--each");
    let solver_at = args.iter().position(|a| a == "--solver");
    let solver = match solver_at.map(|i| args.get(i + 1)) {
        None => Solver::Multibody,
        Some(name) => {
            let name = name.ok_or("--solver needs a name")?;
            (Solver::ALL.into_iter().find(|s| s.name() == name)).ok_or_else(|| {
                format!("--solver {name:?}: not one of paper, rigid-frames, xpbd, multibody")
            })?
        }
    };
    let mut numbers = Vec::new();
    let skip = solver_at.map(|i| i + 1);
    for (_, a) in
        (args.iter().enumerate()).filter(|&(i, a)| !a.starts_with("--") && Some(i) != skip)
    {
        numbers.push(
            a.parse::<usize>()
                .map_err(|e| format!("argument {a:?}: {e}"))?,
        );
    }
    let humans = numbers.first().copied().unwrap_or(1000);
    let threads = numbers.get(1).copied().unwrap_or(1).max(1);
    let frames = numbers.get(2).copied().unwrap_or(600).max(1);

    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/pile.af");
    let opts = AfOptions {
        count: Some(humans as u32),
        ..Default::default()
    };
    let mut scene = load(&path, &opts).map_err(|e| e.to_string())?.desc;
    scene.settings.timestep = FRAME_DT;
    if no_sleep {
        scene.settings.sleep.disable();
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let mut world = solver.build(&scene).map_err(|e| e.to_string())?;

    let mut wall = Vec::with_capacity(frames);
    let mut cpu = Vec::with_capacity(frames);
    let mut slowest = (0.0f64, 0usize, ragdoll_sim::PhaseTimes::default());
    let mut phase_sums: Vec<(&'static str, f64)> = Vec::new();
    pool.install(|| {
        for frame in 0..frames {
            let (t, c) = (Instant::now(), thread_cpu_ns());
            world.step();
            let ms = t.elapsed().as_secs_f64() * 1e3;
            wall.push(ms);
            cpu.push(thread_cpu_ns().saturating_sub(c) as f64 * 1e-6);
            let phases = world.phase_times();
            for (name, s) in phases.phases() {
                match phase_sums.iter_mut().find(|p| p.0 == name) {
                    Some(p) => p.1 += s,
                    None => phase_sums.push((name, s)),
                }
            }
            if each {
                print!("frame {frame}: {ms:.2} ms, CPU {:.2} ms:", cpu[frame]);
                for (name, s) in phases.phases() {
                    print!(" {name} {:.2}", s * 1e3);
                }
                println!(", awake {}", world.awake_body_count());
            }
            if ms > slowest.0 {
                slowest = (ms, frame, phases);
            }
        }
    });

    println!(
        "{humans} humans, {}, {threads} thread(s), {frames} frames, sleeping {}",
        solver.name(),
        if no_sleep { "off" } else { "on" }
    );
    println!("  wall-clock: {}", summary(&wall));
    println!("  stepping thread's CPU: {}", summary(&cpu));
    print!("  slowest frame ({}) phases, ms:", slowest.1);
    for (name, s) in slowest.2.phases() {
        print!(" {name} {:.2}", s * 1e3);
    }
    println!(" (total {:.2})", slowest.2.total * 1e3);
    print!("  all frames' phases, ms:");
    for (name, s) in &phase_sums {
        print!(" {name} {:.0}", s * 1e3);
    }
    println!();

    let mut states = Vec::new();
    world.body_states(&mut states);
    // FNV-1a over the bits of every body's pose and velocities.
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for b in &states {
        let values = b.com.to_array().into_iter().chain(b.orientation.to_array());
        let values = values
            .chain(b.linear_velocity.to_array())
            .chain(b.angular_velocity.to_array());
        for x in values {
            hash = (hash ^ x.to_bits() as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    println!(
        "  final state hash {hash:016x}, all asleep: {}",
        world.sample().all_asleep
    );
    Ok(())
}

/// Mean, median, 95th percentile and largest of per-frame milliseconds, and the sums
/// over the first two simulated seconds.
fn summary(ms: &[f64]) -> String {
    let mut sorted = ms.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    let per_second = (1.0 / FRAME_DT).round() as usize;
    let second = |k: usize| ms.iter().skip(k * per_second).take(per_second).sum::<f64>();
    format!(
        "mean {:.2} ms, median {:.2}, p95 {:.2}, slowest {:.2}; 1st s {:.0} ms, 2nd s {:.0} ms",
        ms.iter().sum::<f64>() / n as f64,
        sorted[n / 2],
        sorted[(n * 95 / 100).min(n - 1)],
        sorted[n - 1],
        second(0),
        second(1)
    )
}

/// CPU time of the calling thread (ns) from the kernel's scheduler statistics; 0 where
/// they cannot be read (then the CPU figures are zero).
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}
