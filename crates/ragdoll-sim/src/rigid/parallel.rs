//! Solving islands on all cores.
//!
//! Within a step, islands (dynamic bodies linked by joints or touching contacts, see
//! [`super::island`]) do not interact: whatever an island's constraints read of a body
//! outside it is a fixed body, a sleeping one or the static anchor, which the solver
//! treats as static (zero inverse mass, never integrated). So the islands are dealt, in
//! order, into batches of about equal work, and each batch is gathered into dense local
//! arrays — its moving bodies first, then the static bodies its constraints read; its
//! joints and touching contact pairs with body indices rewritten to local ones — solved
//! by the same [`substeps::solve`] that solves the whole world on one thread, and
//! scattered back. Jolt and Box2D v3 hand islands (or constraint colours) to threads for
//! the same reason.
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
use super::substeps::{self, SolveBuffers, SolveParams};
use rayon::prelude::*;

/// No island / no local index.
const NONE: u32 = u32::MAX;

/// Below this much work in a step (moving bodies + joints + touching pairs) the world is
/// solved in place: a figure or two has little to share out, and gathering and waking
/// threads would cost about what they save.
const MIN_PARALLEL_WORK: usize = 256;

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

/// The batches of the last parallel solve, kept with their arrays so that the next
/// step gathers into arrays already grown (and a batch holding the same islands keeps
/// its joint trees, [`super::joint_tree::JointTrees::rebuild`]).
#[derive(Default)]
pub struct IslandTasks(Vec<IslandTask>);

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
    /// The batch's constraint arrays.
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
        (j.lanes, j.direct, j.tree_points) = (None, false, 0);
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

/// Solves the step of every awake island (see [`substeps::solve`]) in parallel on the
/// current rayon pool. `islands` must hold this step's links; `buffers` serve a solve
/// in place, `tasks` the batches.
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
    let work = awake[..n].iter().filter(|&&a| a).count()
        + joints.len()
        + pairs.iter().filter(|p| p.touching()).count();
    if work < MIN_PARALLEL_WORK {
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
    let batch_of_island = numbering.deal(joints, pairs);
    let batch_of = |a: usize, b: usize| numbering.of(a, b).map(|t| batch_of_island[t] as usize);
    let tasks = &mut tasks.0;
    let local_of_moving = new_tasks(tasks, &numbering, &batch_of_island, n, s.len());
    gather(tasks, &local_of_moving, joints, pairs, batch_of);
    for task in tasks.iter_mut() {
        for &i in &task.bodies {
            task.states.push_copy(s, i);
        }
        let moving = &task.bodies[..task.moving];
        task.motion.extend(moving.iter().map(|&i| motion.bodies[i]));
        task.awake
            .extend((0..task.bodies.len()).map(|l| l < task.moving));
    }

    tasks.par_iter_mut().for_each(|t| {
        substeps::solve(
            &mut t.states,
            Motions {
                bodies: &t.motion,
                full: motion.full,
            },
            &mut t.joints,
            &mut t.pairs,
            &t.awake,
            &mut t.buffers,
            p,
        );
    });
    scatter(tasks, s, joints, pairs);
}

/// One task per batch (the last step's, emptied), holding the batch's moving bodies in
/// ascending world order (its islands interleaved); returns each moving body's index in
/// its task.
fn new_tasks(
    tasks: &mut Vec<IslandTask>,
    numbering: &Numbering,
    batch_of_island: &[u32],
    n: usize,
    len: usize,
) -> Vec<u32> {
    let batch_count = batch_of_island.last().map_or(0, |&b| b as usize + 1);
    let mut local_of_moving = vec![NONE; len];
    tasks.resize_with(batch_count, IslandTask::default);
    for task in tasks.iter_mut() {
        task.clear();
    }
    for (i, &island) in numbering.island_of_body[..n].iter().enumerate() {
        if island == NONE {
            continue;
        }
        let task = &mut tasks[batch_of_island[island as usize] as usize];
        local_of_moving[i] = task.bodies.len() as u32;
        task.bodies.push(i);
    }
    for task in tasks.iter_mut() {
        task.moving = task.bodies.len();
    }
    local_of_moving
}

/// Copies every joint and touching pair into its batch's task (a constraint's batch is
/// its island's), re-indexed to the task's bodies; a pair is moved out and put back by
/// [`scatter`].
fn gather(
    tasks: &mut [IslandTask],
    local_of_moving: &[u32],
    joints: &JointSet,
    pairs: &mut [ContactPair],
    batch_of: impl Fn(usize, usize) -> Option<usize>,
) {
    macro_rules! gather_joints {
        ($($kind:ident),*) => {$(
            for (k, j) in joints.$kind.iter().enumerate() {
                let Some(t) = batch_of(j.frame.a, j.frame.b) else { continue };
                let task = &mut tasks[t];
                let mut j = j.clone();
                j.frame.a = task.local(j.frame.a, local_of_moving);
                j.frame.b = task.local(j.frame.b, local_of_moving);
                task.joints.$kind.push(j);
                task.joint_slots.$kind.push(k);
            }
        )*};
    }
    gather_joints!(ball, hinge, universal, fixed, slider, spring);

    for (k, pair) in pairs.iter_mut().enumerate() {
        if !pair.touching() {
            continue;
        }
        let Some(t) = batch_of(pair.a as usize, pair.b as usize) else {
            continue;
        };
        let task = &mut tasks[t];
        let mut local = std::mem::take(pair);
        task.pair_slots.push((k, local.a, local.b));
        local.a = task.local(local.a as usize, local_of_moving) as u32;
        local.b = task.local(local.b as usize, local_of_moving) as u32;
        task.pairs.push(local);
    }
}

/// Writes the solved tasks back: their moving bodies' states, their joints (keeping the
/// world's body indices) and their pairs.
fn scatter(
    tasks: &mut [IslandTask],
    s: &mut BodyStates,
    joints: &mut JointSet,
    pairs: &mut [ContactPair],
) {
    macro_rules! scatter_joints {
        ($task:expr, $($kind:ident),*) => {$(
            for (j, &k) in $task.joints.$kind.drain(..).zip(&$task.joint_slots.$kind) {
                let frame = joints.$kind[k].frame;
                joints.$kind[k] = j;
                joints.$kind[k].frame = frame;
            }
        )*};
    }
    for task in tasks {
        for (l, &i) in task.bodies[..task.moving].iter().enumerate() {
            s.copy_from(i, &task.states, l);
        }
        scatter_joints!(task, ball, hinge, universal, fixed, slider, spring);
        for (mut pair, &(k, a, b)) in task.pairs.drain(..).zip(&task.pair_slots) {
            pair.a = a;
            pair.b = b;
            pairs[k] = pair;
        }
    }
}
