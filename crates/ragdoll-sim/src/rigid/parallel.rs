//! Solving islands in batches of their own, on all cores.
//!
//! Within a step, islands (dynamic bodies linked by joints or touching contacts, see
//! [`super::island`]) do not interact: whatever an island's constraints read of a body
//! outside it is a fixed body, a sleeping one or the static anchor, which the solver
//! treats as static (zero inverse mass, never integrated). So the islands are dealt, in
//! order, into batches of about equal work, and each batch is gathered into dense local
//! arrays — its moving bodies first, then the static bodies its constraints read; its
//! joints and touching contact pairs with body indices rewritten to local ones — solved
//! by the same [`substeps::solve`] that solves a small world in place, and scattered
//! back. Jolt and Box2D v3 hand islands (or constraint colours) to threads for the same
//! reason. On one thread the batches serve the cache: a batch's arrays stay in it through
//! the batch's substeps and passes, where a large world's arrays would be walked from
//! memory at every pass ([`MIN_MOVING_FOR_CACHE`]).
//!
//! Determinism: every Gauss–Seidel loop runs over a batch's constraints in the relative
//! order they have in the world's arrays, and where the solver regroups them (contact
//! colours, joint bundles) it looks only at a constraint's own bodies and keeps each
//! body's constraints in order; no island reads a body another island writes. So each
//! island's result is bit for bit what the serial solve gives it, whatever the batches,
//! the number of threads or the order they finish in.

use super::body::{BodyMotion, BodyStates, Motions};
use super::contact::ContactPair;
use super::island::Islands;
use super::joint_set::JointSet;
use super::joint_tree::JointTrees;
use super::substeps::{self, SolveBuffers, SolveParams};
use rayon::prelude::*;
use std::sync::{Mutex, MutexGuard, PoisonError};

/// No island / no local index.
const NONE: u32 = u32::MAX;

/// Below this much work in a step (moving bodies + joints + touching pairs) the world is
/// solved in place: a figure or two has little to share out, fits in cache as it is,
/// and gathering and waking threads would cost about what they save.
const MIN_PARALLEL_WORK: usize = 256;

/// Moving bodies from which a world on one thread is solved in batches, for the cache
/// ([`solve_islands`]). A smaller world's arrays stay in cache as they are, and in place
/// its ball joints and hinges are solved four at a time in SIMD lanes
/// ([`JointSet::lanes`]), which a gathered batch does not plan; from about this size
/// (a few hundred humans) the cache gains more than the lanes give.
const MIN_MOVING_FOR_CACHE: usize = 4096;

/// Batches per thread ([`crate::batches`]). A task per island would gather every
/// island into arrays of its own, most of them a single figure; a batch of consecutive
/// islands pays that once. Batches are dealt by work, not by count, and there are many
/// per thread so that work stealing evens out what dealing cannot foresee (islands of
/// unequal cost): with few, the last large batch leaves the other threads idle. The
/// batches change no result: each is solved as an island would be.
const BATCHES_PER_THREAD: usize = 16;

/// For each joint type, the world index of every joint of a batch's local set.
#[derive(Default)]
struct JointSlots {
    ball: Vec<usize>,
    hinge: Vec<usize>,
    universal: Vec<usize>,
    fixed: Vec<usize>,
    slider: Vec<usize>,
    spring: Vec<usize>,
}

/// What a batched solve keeps between steps, so that once grown a step allocates
/// little: the batches' contents, the gathered batches' arrays, and each batch's joint
/// trees.
///
/// Each batch is one rayon task that gathers it into a set of local arrays, solves it
/// and scatters it back; the tasks run as threads come free (work stealing), not in
/// rounds of one batch per thread, so a thread that finishes a cheap batch takes the next
/// instead of waiting for its partner's dear one. Gathering and scattering read and write
/// the world's arrays and so take turns ([`Shared`]'s lock), but one thread's gather or
/// scatter overlaps the other threads' solves. The local arrays are taken from a free
/// list and given back after the scatter: there are as many as batches solved at once
/// (the threads), each as large as a batch, not as the world — a batch is a share of the
/// step's work over `BATCHES_PER_THREAD` times the threads.
#[derive(Default)]
pub struct IslandTasks {
    plan: BatchPlan,
    /// Gathered batches' arrays not in use, refilled for every batch.
    free: Mutex<Vec<IslandTask>>,
    /// Per batch: its joint trees, kept so that a batch holding the same islands next
    /// step keeps them ([`super::joint_tree::JointTrees::rebuild`]); swapped into the
    /// gathered arrays for its solve.
    trees: Vec<JointTrees>,
    /// Per world body: its index in its batch's arrays while the batch is gathered,
    /// `NONE` for a body that does not move.
    local_of_moving: Vec<u32>,
    /// Solve every world in place (`Some(true)`) or in batches (`Some(false)`), for the
    /// test that batches give the bits of the world in place.
    #[cfg(test)]
    pub(crate) in_place: Option<bool>,
}

impl IslandTasks {
    /// Drops the batches' state by owner (see `Method::drop_by_owner`): the plan and
    /// per-body map, the gathered arrays (split as a solve in place's are), the
    /// batches' joint trees.
    pub(crate) fn drop_by_owner(self, dropped: &mut dyn FnMut(&'static str)) {
        let IslandTasks {
            plan,
            free,
            trees,
            local_of_moving,
            ..
        } = self;
        drop((plan, local_of_moving));
        dropped("batch plan");
        drop(trees);
        dropped("batch joint trees");
        let free = free.into_inner().unwrap_or_else(PoisonError::into_inner);
        for task in free {
            let IslandTask {
                bodies,
                states,
                motion,
                awake,
                mut joints,
                joint_slots,
                pairs,
                buffers,
                pair_slots,
                ..
            } = task;
            drop((bodies, states, motion, awake));
            dropped("batch body copies");
            drop(std::mem::take(&mut joints.rows));
            dropped("joint rows");
            drop((joints, joint_slots, pairs, pair_slots));
            dropped("batch joint, pair copies");
            buffers.drop_by_owner(dropped);
        }
    }
}

/// What the batches' gathers and scatters read and write, behind one lock: the world's
/// bodies, joints and pairs, and the per-batch and per-body bookkeeping. A batch reads
/// and writes only its own moving bodies, joints, pairs and trees (and reads static
/// bodies nobody writes), so the order in which batches take the lock changes nothing.
struct Shared<'a> {
    s: &'a mut BodyStates,
    joints: &'a mut JointSet,
    pairs: &'a mut [ContactPair],
    trees: &'a mut [JointTrees],
    local_of_moving: &'a mut [u32],
}

/// Takes a lock whether or not a task panicked while holding it: a panic in a batch's
/// solve reaches the caller through rayon anyway, and the data is only ever left between
/// two whole batches.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The step's batches: per batch, its moving bodies, joints and touching pairs in world
/// order, each list `start[b]..start[b + 1]` of its array.
#[derive(Default)]
struct BatchPlan {
    body_start: Vec<u32>,
    bodies: Vec<u32>,
    /// Joints numbered across the types in the order ball, hinge, universal, fixed,
    /// slider, spring ([`JointSet::for_each_pair`]'s).
    joint_start: Vec<u32>,
    joints: Vec<u32>,
    pair_start: Vec<u32>,
    pairs: Vec<u32>,
    /// Each item's batch (`NONE`: none), while one of the lists is made.
    batch_of_item: Vec<u32>,
}

/// Lists the items of `batch_of_item` by batch (`batches` of them), each batch's items
/// in ascending order: batch `b`'s are `out[start[b]..start[b + 1]]` (a counting sort).
fn group_by_batch(batch_of_item: &[u32], batches: usize, start: &mut Vec<u32>, out: &mut Vec<u32>) {
    start.clear();
    start.resize(batches + 1, 0);
    for &b in batch_of_item.iter().filter(|&&b| b != NONE) {
        start[b as usize + 1] += 1;
    }
    for b in 0..batches {
        start[b + 1] += start[b];
    }
    out.clear();
    out.resize(start[batches] as usize, 0);
    // `start[b]` serves as batch b's cursor, ending at batch b + 1's start...
    for (i, &b) in batch_of_item.iter().enumerate() {
        if b != NONE {
            out[start[b as usize] as usize] = i as u32;
            start[b as usize] += 1;
        }
    }
    // ...and is moved back to where the batch starts.
    for b in (1..=batches).rev() {
        start[b] = start[b - 1];
    }
    start[0] = 0;
}

/// The `b`th list of a [`group_by_batch`] grouping.
fn list(start: &[u32], items: &[u32], b: usize) -> impl Iterator<Item = usize> {
    items[start[b] as usize..start[b + 1] as usize]
        .iter()
        .map(|&i| i as usize)
}

/// One batch of islands, gathered into local arrays.
#[derive(Default)]
struct IslandTask {
    /// World index of each local body: the batch's moving bodies in ascending order,
    /// then the static bodies its constraints read.
    bodies: Vec<usize>,
    /// How many leading entries of `bodies` move; only these are written back.
    moving: usize,
    states: BodyStates,
    motion: Vec<BodyMotion>,
    awake: Vec<bool>,
    joints: JointSet,
    joint_slots: JointSlots,
    pairs: Vec<ContactPair>,
    /// The batch's constraint arrays (its joint trees lent by [`IslandTasks::trees`]).
    buffers: SolveBuffers,
    /// Per local pair: its slot in the world's pair array and its world bodies.
    pair_slots: Vec<(usize, u32, u32)>,
}

impl IslandTask {
    /// Empties the task for another batch, keeping its arrays' capacity.
    fn clear(&mut self) {
        self.bodies.clear();
        self.moving = 0;
        self.states.clear();
        self.motion.clear();
        self.awake.clear();
        macro_rules! clear_joints {
            ($($kind:ident),*) => {$(
                self.joints.$kind.clear();
                self.joint_slots.$kind.clear();
            )*};
        }
        clear_joints!(ball, hinge, universal, fixed, slider, spring);
        let j = &mut self.joints;
        (j.lanes, j.direct, j.tree_points, j.live_points) = (None, false, 0, 0);
        self.pairs.clear();
        self.pair_slots.clear();
    }

    /// Local index of world body `i`: a moving body's from `local_of_moving`, otherwise
    /// it is added as a static body on first use. A batch reads only a handful of static
    /// bodies (the anchor, the fixed bodies its islands touch: on the 1000-human pile
    /// never more than the anchor), so a linear search is the cheapest lookup.
    fn local(&mut self, i: usize, local_of_moving: &[u32]) -> usize {
        if local_of_moving[i] != NONE {
            return local_of_moving[i] as usize;
        }
        match self.bodies[self.moving..].iter().position(|&b| b == i) {
            Some(k) => self.moving + k,
            None => {
                self.bodies.push(i);
                self.bodies.len() - 1
            }
        }
    }
}

/// The awake islands of a step, numbered in the order of their lowest body.
struct Numbering<'a> {
    awake: &'a [bool],
    /// Each body's island, `NONE` for a body that does not move.
    island_of_body: Vec<u32>,
    count: u32,
}

impl<'a> Numbering<'a> {
    /// Numbers the islands of the first `n` (movable) of `len` bodies.
    fn new(islands: &mut Islands, awake: &'a [bool], n: usize, len: usize) -> Self {
        let mut island_of_root = vec![NONE; n];
        let mut island_of_body = vec![NONE; len];
        let mut count = 0u32;
        for i in 0..n {
            if !awake[i] {
                continue;
            }
            let root = islands.root(i);
            if island_of_root[root] == NONE {
                island_of_root[root] = count;
                count += 1;
            }
            island_of_body[i] = island_of_root[root];
        }
        Numbering {
            awake,
            island_of_body,
            count,
        }
    }

    /// The island of a constraint between `a` and `b`: that of its moving body (both
    /// are in the same one when both move); `None` between bodies that do not move,
    /// which are not solved at all.
    fn of(&self, a: usize, b: usize) -> Option<usize> {
        let t = if self.awake[a] {
            self.island_of_body[a]
        } else {
            self.island_of_body[b]
        };
        (t != NONE).then_some(t as usize)
    }

    /// Each island's work (its moving bodies and constraints), dealt into batches of
    /// about equal work, consecutive islands together: the batch of each island.
    fn deal(&self, joints: &JointSet, pairs: &[ContactPair]) -> Vec<u32> {
        let mut island_work = vec![0usize; self.count as usize];
        for &t in self.island_of_body.iter().filter(|&&t| t != NONE) {
            island_work[t as usize] += 1;
        }
        let mut count = |a: usize, b: usize| {
            if let Some(t) = self.of(a, b) {
                island_work[t] += 1;
            }
        };
        joints.for_each_pair(&mut count);
        for pair in pairs.iter().filter(|p| p.touching()) {
            count(pair.a as usize, pair.b as usize);
        }
        let wanted = rayon::current_num_threads() * BATCHES_PER_THREAD;
        crate::batches::deal(&island_work, wanted)
    }
}

/// Solves the step of every awake island (see [`substeps::solve`]) in batches, in
/// parallel on the current rayon pool; a world with little work, one island, or on one
/// thread fewer than [`MIN_MOVING_FOR_CACHE`] moving bodies, in place. `islands` must
/// hold this step's links; `buffers` serve a solve in place, `tasks` the batches.
#[allow(clippy::too_many_arguments)]
pub fn solve_islands(
    s: &mut BodyStates,
    motion: Motions<'_>,
    joints: &mut JointSet,
    pairs: &mut [ContactPair],
    islands: &mut Islands,
    awake: &[bool],
    buffers: &mut SolveBuffers,
    tasks: &mut IslandTasks,
    p: &SolveParams,
) {
    let n = motion.bodies.len();
    let moving = awake[..n].iter().filter(|&&a| a).count();
    let work = moving + joints.len() + pairs.iter().filter(|p| p.touching()).count();
    let in_place = work < MIN_PARALLEL_WORK
        || (rayon::current_num_threads() == 1 && moving < MIN_MOVING_FOR_CACHE);
    #[cfg(test)]
    let in_place = tasks.in_place.unwrap_or(in_place);
    if in_place {
        // Too little to share out: solve in place.
        substeps::solve(s, motion, joints, pairs, awake, buffers, p);
        return;
    }
    let numbering = Numbering::new(islands, awake, n, s.len());
    if numbering.count < 2 {
        // One island: nothing to share out, solve in place.
        substeps::solve(s, motion, joints, pairs, awake, buffers, p);
        return;
    }
    joints.release_rows();
    let batch_of_island = numbering.deal(joints, pairs);
    let batches = batch_of_island.last().map_or(0, |&b| b as usize + 1);
    let batch_of = |a: usize, b: usize| numbering.of(a, b).map_or(NONE, |t| batch_of_island[t]);
    tasks.plan.make(
        &numbering,
        &batch_of_island,
        batches,
        joints,
        pairs,
        batch_of,
    );
    let IslandTasks {
        plan,
        free,
        trees,
        local_of_moving,
        ..
    } = tasks;
    local_of_moving.clear();
    local_of_moving.resize(s.len(), NONE);
    trees.resize_with(batches, JointTrees::default);
    let plan = &*plan;
    let shared = Mutex::new(Shared {
        s,
        joints,
        pairs,
        trees,
        local_of_moving,
    });
    let full = motion.full;
    let run = |b: usize| {
        let mut task = lock(free).pop().unwrap_or_default();
        {
            let w = &mut *lock(&shared);
            task.gather(plan, b, w.local_of_moving, w.s, motion, w.joints, w.pairs);
            std::mem::swap(task.buffers.trees_mut(), &mut w.trees[b]);
        }
        let t = &mut task;
        substeps::solve(
            &mut t.states,
            Motions {
                bodies: &t.motion,
                full,
            },
            &mut t.joints,
            &mut t.pairs,
            &t.awake,
            &mut t.buffers,
            p,
        );
        {
            let w = &mut *lock(&shared);
            std::mem::swap(task.buffers.trees_mut(), &mut w.trees[b]);
            task.scatter(w.s, w.joints, w.pairs);
        }
        lock(free).push(task);
    };
    if rayon::current_num_threads() == 1 {
        (0..batches).for_each(run);
    } else {
        (0..batches).into_par_iter().with_max_len(1).for_each(run);
    }
}

impl BatchPlan {
    /// Each batch's moving bodies (ascending world order, its islands interleaved),
    /// joints and touching pairs; `batch_of(a, b)` is the batch of a constraint between
    /// `a` and `b` (its island's), `NONE` for one that is not solved.
    fn make(
        &mut self,
        numbering: &Numbering,
        batch_of_island: &[u32],
        batches: usize,
        joints: &JointSet,
        pairs: &[ContactPair],
        batch_of: impl Fn(usize, usize) -> u32,
    ) {
        let items = &mut self.batch_of_item;
        items.clear();
        items.extend((numbering.island_of_body.iter()).map(|&t| {
            if t == NONE {
                NONE
            } else {
                batch_of_island[t as usize]
            }
        }));
        group_by_batch(items, batches, &mut self.body_start, &mut self.bodies);
        items.clear();
        joints.for_each_pair(|a, b| items.push(batch_of(a, b)));
        group_by_batch(items, batches, &mut self.joint_start, &mut self.joints);
        items.clear();
        items.extend(pairs.iter().map(|pair| {
            if pair.touching() {
                batch_of(pair.a as usize, pair.b as usize)
            } else {
                NONE
            }
        }));
        group_by_batch(items, batches, &mut self.pair_start, &mut self.pairs);
    }
}

impl IslandTask {
    /// Gathers batch `b` of `plan`: its moving bodies, then the static bodies its
    /// constraints read; every joint and touching pair of it, re-indexed to the task's
    /// bodies, in world order (a pair is moved out and put back by [`IslandTask::scatter`]).
    #[allow(clippy::too_many_arguments)]
    fn gather(
        &mut self,
        plan: &BatchPlan,
        b: usize,
        local_of_moving: &mut [u32],
        s: &BodyStates,
        motion: Motions<'_>,
        joints: &JointSet,
        pairs: &mut [ContactPair],
    ) {
        self.clear();
        for i in list(&plan.body_start, &plan.bodies, b) {
            local_of_moving[i] = self.bodies.len() as u32;
            self.bodies.push(i);
        }
        self.moving = self.bodies.len();
        let local_of_moving = &*local_of_moving;
        // The joints numbered across the types: each type's first number.
        let ends = [
            joints.ball.len(),
            joints.hinge.len(),
            joints.universal.len(),
            joints.fixed.len(),
            joints.slider.len(),
            joints.spring.len(),
        ];
        let mut first = [0usize; 6];
        for t in 1..6 {
            first[t] = first[t - 1] + ends[t - 1];
        }
        macro_rules! gather_joint {
            ($kind:ident, $k:expr) => {{
                let mut j = joints.$kind[$k].clone();
                j.frame.a = self.local(j.frame.a, local_of_moving);
                j.frame.b = self.local(j.frame.b, local_of_moving);
                self.joints.$kind.push(j);
                self.joint_slots.$kind.push($k);
            }};
        }
        for g in list(&plan.joint_start, &plan.joints, b) {
            let t = first.partition_point(|&f| f <= g) - 1;
            let k = g - first[t];
            match t {
                0 => gather_joint!(ball, k),
                1 => gather_joint!(hinge, k),
                2 => gather_joint!(universal, k),
                3 => gather_joint!(fixed, k),
                4 => gather_joint!(slider, k),
                _ => gather_joint!(spring, k),
            }
        }
        for k in list(&plan.pair_start, &plan.pairs, b) {
            let mut local = std::mem::take(&mut pairs[k]);
            self.pair_slots.push((k, local.a, local.b));
            local.a = self.local(local.a as usize, local_of_moving) as u32;
            local.b = self.local(local.b as usize, local_of_moving) as u32;
            self.pairs.push(local);
        }
        for &i in &self.bodies {
            self.states.push_copy(s, i);
        }
        let moving = &self.bodies[..self.moving];
        self.motion.extend(moving.iter().map(|&i| motion.bodies[i]));
        self.awake
            .extend((0..self.bodies.len()).map(|l| l < self.moving));
    }

    /// Writes the solved batch back: its moving bodies' states, its joints (keeping the
    /// world's body indices) and its pairs.
    fn scatter(&mut self, s: &mut BodyStates, joints: &mut JointSet, pairs: &mut [ContactPair]) {
        macro_rules! scatter_joints {
            ($($kind:ident),*) => {$(
                for (j, &k) in self.joints.$kind.drain(..).zip(&self.joint_slots.$kind) {
                    let frame = joints.$kind[k].frame;
                    joints.$kind[k] = j;
                    joints.$kind[k].frame = frame;
                }
            )*};
        }
        for (l, &i) in self.bodies[..self.moving].iter().enumerate() {
            s.copy_from(i, &self.states, l);
        }
        scatter_joints!(ball, hinge, universal, fixed, slider, spring);
        for (mut pair, &(k, a, b)) in self.pairs.drain(..).zip(&self.pair_slots) {
            pair.a = a;
            pair.b = b;
            pairs[k] = pair;
        }
    }
}
