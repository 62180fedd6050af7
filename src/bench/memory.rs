//! Test 9 (paper section 5.2.1, table 1): bytes per simulation as the bones grow from 2
//! to 4096, measured with a counting global allocator rather than estimated.
//!
//! [`CountingAlloc`] wraps the system allocator and, while a [`footprint`] is being
//! measured, keeps the number of live heap bytes and their high-water mark in two
//! relaxed atomics: one `fetch_add`/`fetch_sub` and one `fetch_max` per allocation. At
//! any other time it only reads a flag, so the other benches and the demo, whose
//! threads allocate at once (the parallel narrow phase), do not contend for the
//! counters' cache line. The `ragdoll-lab`
//! binary installs it as its `#[global_allocator]`; a library user who does not
//! install it gets an error from this bench instead of zeros.
//!
//! Test 9's stack has no joints; a second table measures the pile of humans (scene 10),
//! 16 bones and 15 joints each, so that a ragdoll's joints (and the multibody method's
//! joint lanes) are in the figure per bone. Its rows also give each method's bytes by
//! owner (bodies, joints, contact points and pairs, broad phase, islands, solve
//! buffers, ...): the method drops one owner at a time
//! ([`ragdoll_sim::Method::drop_by_owner`]) and the counter reads what each frees.
//!
//! What is counted: every heap byte a method holds after it has been built from the
//! scene and stepped [`STEPS`] frames (so contact caches, islands and scratch buffers
//! have grown to their working size), minus what was live before it was built. The
//! scene description itself was allocated before and is not counted. Stack and static
//! memory are not heap and are not counted; neither method keeps state there.

use super::table::Table;
use super::{Flavor, Report, RowFilter, Size, progress, scenes};
use crate::AppError;
use serde_json::{Value, json};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicIsize, Ordering};

/// Frames stepped before the live bytes are read.
pub const STEPS: usize = 10;

/// Bytes allocated minus bytes freed while counting. Signed: a block allocated before
/// counting started and freed during it takes away bytes never added.
static LIVE: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);
/// Blocks allocated minus blocks freed while counting: each live block also costs the
/// system allocator a header and rounding that `LIVE` leaves out (glibc: 8 bytes of
/// header, sizes rounded up to 16, at least 32), reported so that the figure can be
/// judged.
static BLOCKS: AtomicIsize = AtomicIsize::new(0);
/// Whether allocations are being counted ([`Counting`]).
static COUNTING: AtomicBool = AtomicBool::new(false);

/// The system allocator, counting live bytes and their peak while a [`Counting`] lives.
pub struct CountingAlloc;

fn grew(bytes: usize) {
    if COUNTING.load(Ordering::Relaxed) {
        let now = LIVE.fetch_add(bytes as isize, Ordering::Relaxed) + bytes as isize;
        PEAK.fetch_max(now, Ordering::Relaxed);
    }
}

fn shrank(bytes: usize) {
    if COUNTING.load(Ordering::Relaxed) {
        LIVE.fetch_sub(bytes as isize, Ordering::Relaxed);
    }
}

fn opened() {
    if COUNTING.load(Ordering::Relaxed) {
        BLOCKS.fetch_add(1, Ordering::Relaxed);
    }
}

fn closed() {
    if COUNTING.load(Ordering::Relaxed) {
        BLOCKS.fetch_sub(1, Ordering::Relaxed);
    }
}

/// Allocations are counted while this lives (one at a time: the bench measures one
/// simulation after another).
pub struct Counting(());

impl Counting {
    /// Starts counting.
    pub fn start() -> Counting {
        COUNTING.store(true, Ordering::Relaxed);
        Counting(())
    }
}

impl Drop for Counting {
    fn drop(&mut self) {
        COUNTING.store(false, Ordering::Relaxed);
    }
}

// SAFETY: every call forwards to `System` with the caller's arguments unchanged; the
// counters are only bookkeeping and never affect the pointers returned.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, which we forward.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
            opened();
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
            opened();
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator, i.e. from `System`, with `layout`.
        unsafe { System.dealloc(ptr, layout) };
        shrank(layout.size());
        closed();
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: `ptr` came from `System` with `layout`; the caller upholds the rest.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                grew(new_size - layout.size());
            } else {
                shrank(layout.size() - new_size);
            }
        }
        p
    }
}

/// Heap bytes allocated and not freed while counting (0 forever if [`CountingAlloc`] is
/// not the global allocator).
pub fn live_bytes() -> isize {
    LIVE.load(Ordering::Relaxed)
}

/// Heap blocks allocated and not freed while counting.
pub fn live_blocks() -> isize {
    BLOCKS.load(Ordering::Relaxed)
}

/// Highest [`live_bytes`] since the last [`reset_peak`].
pub fn peak_bytes() -> isize {
    PEAK.load(Ordering::Relaxed)
}

/// Starts a new high-water mark at the bytes live now.
pub fn reset_peak() {
    PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
}

/// Whether [`CountingAlloc`] is the global allocator of this process (counting must
/// be on).
pub fn is_installed() -> bool {
    let before = live_bytes();
    let probe = std::hint::black_box(Vec::<u8>::with_capacity(4096));
    let during = live_bytes();
    drop(probe);
    during >= before + 4096
}

/// What one method holds for one scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Footprint {
    /// Heap bytes held after building and stepping.
    pub bytes: usize,
    /// Highest heap bytes held at any moment while building and stepping.
    pub peak_bytes: usize,
    /// Heap blocks held after building and stepping (each costs the system allocator
    /// a header and rounding beyond `bytes`).
    pub blocks: usize,
    /// `bytes` by owner, in the order the method drops them
    /// ([`ragdoll_sim::Method::drop_by_owner`]): the bytes freed when it dropped each
    /// one. An owner named twice (a kind of array the world and its island batches
    /// both keep) is summed; what the method held outside every named owner is
    /// [`REST`].
    pub owners: Owners,
}

/// Bytes by owner ([`Footprint::owners`]).
pub type Owners = Vec<(&'static str, usize)>;

/// The owner of the bytes a method frees outside the owners it names.
pub const REST: &str = "rest";

/// Builds `flavor` for `scene`, steps it [`STEPS`] frames and reads its heap footprint.
pub fn footprint(flavor: Flavor, scene: &ragdoll_sim::SceneDesc) -> Result<Footprint, AppError> {
    footprint_after(flavor, scene, STEPS)
}

/// Frames the pile rows step before reading: 1.5 s, the pile has landed and its
/// contacts are at their working size.
pub const PILE_STEPS: usize = 90;

/// Builds `flavor` for `scene`, steps it `steps` frames and reads its heap footprint.
pub fn footprint_after(
    flavor: Flavor,
    scene: &ragdoll_sim::SceneDesc,
    steps: usize,
) -> Result<Footprint, AppError> {
    let _counting = Counting::start();
    if !is_installed() {
        return Err(AppError::Other(
            "the memory bench needs ragdoll_lab::bench::memory::CountingAlloc as the global \
             allocator (the ragdoll-lab binary installs it)"
                .into(),
        ));
    }
    let (base, base_blocks) = (live_bytes(), live_blocks());
    reset_peak();
    let mut method = flavor.build(scene)?;
    for _ in 0..steps {
        method.step();
    }
    let held = live_bytes() - base;
    let peak = peak_bytes() - base;
    let blocks = live_blocks() - base_blocks;
    let mut owners: Owners = Vec::with_capacity(32);
    let mut last = live_bytes();
    method.drop_by_owner(&mut |owner| {
        let now = live_bytes();
        let freed = (last - now).max(0) as usize;
        last = now;
        match owners.iter_mut().find(|(o, _)| *o == owner) {
            Some((_, bytes)) => *bytes += freed,
            None => owners.push((owner, freed)),
        }
    });
    let named: usize = owners.iter().map(|&(_, b)| b).sum();
    owners.push((REST, (held.max(0) as usize).saturating_sub(named)));
    Ok(Footprint {
        bytes: held.max(0) as usize,
        peak_bytes: peak.max(0) as usize,
        blocks: blocks.max(0) as usize,
        owners,
    })
}

/// Makes the process's one-time allocations before anything is measured, so that none
/// is charged to the first simulation measured: rayon's global pool, built on first
/// use, and what each of its threads allocates for itself the first times it takes
/// and steals work (a few KB a thread, so the more threads, the more), made while the
/// first simulations that run on the pool step, each of them as far as it gets to it.
/// Stepping every method once on the pile of one human makes them all.
fn warm_up() -> Result<(), AppError> {
    let _ = rayon::current_num_threads();
    rayon::broadcast(|_| ());
    let scene = super::scale::pile(1)?;
    for flavor in MEASURED {
        let mut method = flavor.build(&scene)?;
        for _ in 0..PILE_STEPS {
            method.step();
        }
    }
    Ok(())
}

/// The paper's table 1: bones, particle-based KB, constraint-based KB.
pub const PAPER: [(usize, f64, f64); 12] = [
    (2, 3.5, 2.0),
    (4, 12.0, 4.0),
    (8, 24.0, 4.0),
    (16, 28.0, 16.0),
    (32, 76.0, 32.0),
    (64, 95.0, 60.0),
    (128, 176.0, 128.0),
    (256, 386.0, 264.0),
    (512, 886.0, 512.0),
    (1024, 1308.0, 1012.0),
    (2048, 3000.0, 2032.0),
    (4096, 6000.0, 4016.0),
];

/// The methods measured, in column order: the three particle solvers and the multibody
/// method.
pub const MEASURED: [Flavor; 4] = [
    Flavor::ParticlePaper,
    Flavor::ParticleRigidFrames,
    Flavor::ParticleXpbd,
    Flavor::Multibody,
];

/// Runs test 9.
pub fn run(size: Size, only: &RowFilter) -> Result<Report, AppError> {
    warm_up()?;
    let rows_wanted: &[(usize, f64, f64)] = match size {
        Size::Full => &PAPER,
        Size::Quick => &PAPER[..2],
    };
    let mut table = Table::new(
        format!(
            "Test 9 (table 1): heap memory per simulation, small boxes stacked with gaps, \
             after building and {STEPS} frames. KB = 1024 bytes."
        ),
        &[
            "Bones",
            "paper particle KB",
            "paper constraint KB",
            "particle(paper) KB",
            "B/bone",
            "particle(rigid-frames) KB",
            "B/bone",
            "particle(xpbd) KB",
            "B/bone",
            "multibody KB",
            "B/bone",
        ],
    );
    let mut rows = Vec::new();
    for &(bones, paper_particle, paper_constraint) in rows_wanted {
        if !only.keeps(bones as f64) {
            continue;
        }
        progress(&format!("memory: {bones} bones"));
        let scene = scenes::stacked_boxes(bones);
        let mut cells = vec![
            bones.to_string(),
            format!("{paper_particle}"),
            format!("{paper_constraint}"),
        ];
        let mut row = serde_json::Map::new();
        row.insert("bones".into(), json!(bones));
        row.insert(
            "paper_particle_bytes".into(),
            json!(paper_particle * 1024.0),
        );
        row.insert(
            "paper_constraint_bytes".into(),
            json!(paper_constraint * 1024.0),
        );
        for flavor in MEASURED {
            let f = footprint(flavor, &scene)?;
            cells.push(format!("{:.1}", f.bytes as f64 / 1024.0));
            cells.push(format!("{:.0}", f.bytes as f64 / bones as f64));
            row.insert(
                flavor.key().into(),
                json!({
                    "bytes": f.bytes,
                    "bytes_per_bone": f.bytes as f64 / bones as f64,
                    "peak_bytes": f.peak_bytes,
                    "blocks": f.blocks,
                }),
            );
        }
        table.row(cells);
        rows.push(Value::Object(row));
    }
    table.note("Goal: at most 512 B per bone for every solver.");
    let (pile_text, pile_rows) = pile_table(size, only)?;
    Ok(Report {
        json: json!({
            "bench": "memory",
            "steps": STEPS,
            "rows": rows,
            "pile_steps": PILE_STEPS,
            "pile_rows": pile_rows,
        }),
        text: table.render() + &pile_text,
    })
}

/// Humans in the pile rows of the memory table.
pub const PILE_HUMANS: [u32; 4] = [1, 10, 100, 1000];

/// Bytes per bone of the pile of humans, joints included: the rows whose number of
/// humans `only` keeps.
fn pile_table(size: Size, only: &RowFilter) -> Result<(String, Vec<Value>), AppError> {
    let humans: &[u32] = match size {
        Size::Full => &PILE_HUMANS,
        Size::Quick => &PILE_HUMANS[..1],
    };
    let mut table = Table::new(
        format!(
            "Heap memory of the pile of humans (16 bones, 15 joints each), after building and \
             {PILE_STEPS} frames (landed), bytes per bone"
        ),
        &[
            "Humans",
            "Bones",
            "particle(paper)",
            "particle(rigid frames)",
            "particle(xpbd)",
            "multibody",
        ],
    );
    let mut rows = Vec::new();
    // Per method, per pile row: its bytes by owner, and the row's bones.
    let mut owners: Vec<Vec<(usize, Owners)>> = vec![Vec::new(); MEASURED.len()];
    for &n in humans.iter().filter(|&&n| only.keeps(n as f64)) {
        progress(&format!("memory: pile of {n} humans"));
        let scene = super::scale::pile(n)?;
        let bones = scene.dynamic_body_count();
        let mut cells = vec![n.to_string(), bones.to_string()];
        let mut row = serde_json::Map::new();
        row.insert("humans".into(), json!(n));
        row.insert("bones".into(), json!(bones));
        for (m, flavor) in MEASURED.into_iter().enumerate() {
            let f = footprint_after(flavor, &scene, PILE_STEPS)?;
            let per_bone = f.bytes as f64 / bones as f64;
            cells.push(format!("{per_bone:.0}"));
            let by_owner: serde_json::Map<String, Value> = (f.owners.iter())
                .map(|&(o, b)| (o.to_string(), json!(b)))
                .collect();
            row.insert(
                flavor.key().into(),
                json!({
                    "bytes": f.bytes,
                    "bytes_per_bone": per_bone,
                    "peak_bytes": f.peak_bytes,
                    "blocks": f.blocks,
                    "owners": by_owner,
                }),
            );
            owners[m].push((bones, f.owners));
        }
        table.row(cells);
        rows.push(Value::Object(row));
    }
    table.note("Goal: at most 512 B per bone for every solver.");
    table.note(
        "Bytes asked of the allocator; each live block (JSON: blocks) costs it about 16 B \
         more of header and rounding.",
    );
    let mut text = table.render();
    for (flavor, per_row) in MEASURED.into_iter().zip(&owners) {
        text += &owner_table(flavor, per_row).map_or(String::new(), |t| t.render());
    }
    Ok((text, rows))
}

/// Where one method's bytes per bone go on each pile row measured, owner by owner
/// (`None` for a method that names no owners, or no rows).
fn owner_table(flavor: Flavor, per_row: &[(usize, Owners)]) -> Option<Table> {
    // Every owner any row names, in the order they first come.
    let mut names: Vec<&'static str> = Vec::new();
    for (_, owners) in per_row {
        for &(o, _) in owners {
            if o != REST && !names.contains(&o) {
                names.push(o);
            }
        }
    }
    if names.len() <= 1 {
        return None;
    }
    names.push(REST);
    let bones: Vec<String> = per_row.iter().map(|(b, _)| format!("{b} bones")).collect();
    let mut header = vec!["Owner"];
    header.extend(bones.iter().map(String::as_str));
    let mut table = Table::new(
        format!(
            "Heap memory of the pile of humans by owner, {}, bytes per bone",
            flavor.key()
        ),
        &header,
    );
    for owner in names {
        let mut cells = vec![owner.to_string()];
        for (bones, owners) in per_row {
            let bytes = owners
                .iter()
                .find(|(o, _)| *o == owner)
                .map_or(0, |&(_, b)| b);
            cells.push(format!("{:.0}", bytes as f64 / *bones as f64));
        }
        table.row(cells);
    }
    table.note("Bytes freed as the method dropped each owner in turn.");
    Some(table)
}
