//! A particle solver's heap bytes on the pile of N humans, by owner: the total a
//! counting allocator sees after building the world and stepping it (as the memory
//! bench, `ragdoll-lab bench memory`, counts it), and the arrays it is made of
//! ([`ParticleWorld::heap_owners`]), so that the largest owners can be found and cut.
//!
//! ```text
//! cargo run --release -p ragdoll-sim --example memory_owners -- [HUMANS] [FRAMES] [--solver NAME]
//! ```
//!
//! Defaults: 100 humans, 90 frames (the bench's landed pile), rigid frames; NAME is
//! `paper`, `rigid-frames` or `xpbd`.

use ragdoll_sim::Method;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::af::{AfOptions, load};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicIsize, Ordering};

/// Bytes allocated minus bytes freed since the program started.
static LIVE: AtomicIsize = AtomicIsize::new(0);

/// The system allocator, counting live bytes.
struct Counting;

// SAFETY: every call forwards to `System` with the caller's arguments unchanged; the
// counter is only bookkeeping.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, which we forward.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        // SAFETY: `ptr` came from `System` with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LIVE.fetch_add(
            new_size as isize - layout.size() as isize,
            Ordering::Relaxed,
        );
        // SAFETY: `ptr` came from `System` with `layout`; the caller upholds the rest.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// Frame length (s), as the bench steps the pile.
const FRAME_DT: f32 = 1.0 / 60.0;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("memory_owners: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let solver_at = args.iter().position(|a| a == "--solver");
    let solver = match solver_at.map(|i| args.get(i + 1)) {
        None => ParticleSolver::RigidFrames,
        Some(name) => {
            let name = name.ok_or("--solver needs a name")?;
            [
                ParticleSolver::Paper,
                ParticleSolver::RigidFrames,
                ParticleSolver::Xpbd,
            ]
            .into_iter()
            .find(|s| s.name() == name)
            .ok_or_else(|| format!("--solver {name:?}: not one of paper, rigid-frames, xpbd"))?
        }
    };
    let skip = solver_at.map(|i| i + 1);
    let mut numbers = Vec::new();
    for (_, a) in
        (args.iter().enumerate()).filter(|&(i, a)| !a.starts_with("--") && Some(i) != skip)
    {
        numbers.push(
            a.parse::<usize>()
                .map_err(|e| format!("argument {a:?}: {e}"))?,
        );
    }
    let humans = numbers.first().copied().unwrap_or(100);
    let frames = numbers.get(1).copied().unwrap_or(90);

    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/pile.af");
    let opts = AfOptions {
        count: Some(humans as u32),
        ..Default::default()
    };
    let mut scene = load(&path, &opts).map_err(|e| e.to_string())?.desc;
    scene.settings.timestep = FRAME_DT;
    // The pool's one-time allocations (its threads' queues and locals) before counting.
    rayon::broadcast(|_| ());
    let before = LIVE.load(Ordering::Relaxed);
    let mut world = ParticleWorld::new(&scene, solver).map_err(|e| e.to_string())?;
    for _ in 0..frames {
        world.step();
    }
    let held = LIVE.load(Ordering::Relaxed) - before;
    let bones = world.body_count().max(1);
    let owners = world.heap_owners();
    let listed: usize = owners.iter().map(|o| o.bytes).sum();
    println!(
        "{} on {humans} humans ({bones} bones) after {frames} frames: {held} B held, {:.0} B a bone",
        solver.name(),
        held as f64 / bones as f64
    );
    println!("{:>12} {:>9} {:>6}  owner", "bytes", "B/bone", "used");
    for o in &owners {
        println!(
            "{:>12} {:>9.1} {:>5.0}%  {}",
            o.bytes,
            o.bytes as f64 / bones as f64,
            100.0 * o.used as f64 / o.bytes as f64,
            o.name
        );
    }
    let rest = held - listed as isize;
    println!(
        "{:>12} {:>9.1}  (held but in no array listed)",
        rest,
        rest as f64 / bones as f64
    );
    Ok(())
}
