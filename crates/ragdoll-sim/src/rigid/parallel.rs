//! Solving islands on all cores.
//!
//! Within a step, islands (dynamic bodies linked by joints or touching contacts, see
//! [`super::island`]) do not interact: whatever an island's constraints read of a body
//! outside it is a fixed body, a sleeping one or the static anchor, which the solver
//! treats as static (zero inverse mass, never integrated). So each island is gathered
//! into dense local arrays — its moving bodies first, then the static bodies its
//! constraints read; its joints and touching contact pairs with body indices rewritten
//! to local ones — solved by the same [`solver::solve`] that solves the whole world on
//! one thread, and scattered back. Jolt and Box2D v3 hand islands (or constraint
//! colours) to threads for the same reason.
//!
//! Determinism: every Gauss–Seidel loop runs over an island's constraints in the
//! relative order they have in the world's arrays, and no island reads a body another
//! island writes, so each island's result is bit for bit what the serial solve gives
//! it, whatever the number of threads or the order they finish in.

use super::body::{BodyMotion, BodyStates, Motions};
use super::contact::ContactPair;
use super::island::Islands;
use super::joint_set::JointSet;
use super::solver::{self, SolveParams};
use rayon::prelude::*;

/// No island / no local index.
const NONE: u32 = u32::MAX;

/// Below this much work in a step (moving bodies + joints + touching pairs) the world is
/// solved in place: a figure or two has little to share out, and gathering and waking
/// threads would cost about what they save.
const MIN_PARALLEL_WORK: usize = 256;

/// For each joint type, the world index of every joint of an island's local set.
#[derive(Default)]
struct JointSlots {
    ball: Vec<usize>,
    hinge: Vec<usize>,
    universal: Vec<usize>,
    fixed: Vec<usize>,
    slider: Vec<usize>,
    spring: Vec<usize>,
}

/// One island, gathered into local arrays.
#[derive(Default)]
struct IslandTask {
    /// World index of each local body: the island's moving bodies in ascending order,
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
    /// Per local pair: its slot in the world's pair array and its world bodies.
    pair_slots: Vec<(usize, u32, u32)>,
}

impl IslandTask {
    /// Local index of world body `i`: a moving body's from `local_of_moving`, otherwise
    /// it is added as a static body on first use. An island reads only a handful of
    /// static bodies (the anchor, the fixed bodies it touches), so a linear search is
    /// the cheapest lookup.
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

/// Solves the step of every awake island (see [`solver::solve`]) in parallel on the
/// current rayon pool. `islands` must hold this step's links.
pub fn solve_islands(
    s: &mut BodyStates,
    motion: Motions<'_>,
    joints: &mut JointSet,
    pairs: &mut [ContactPair],
    islands: &mut Islands,
    awake: &[bool],
    p: &SolveParams,
) {
    let n = motion.bodies.len();
    let work = awake[..n].iter().filter(|&&a| a).count()
        + joints.len()
        + pairs.iter().filter(|p| p.touching()).count();
    if work < MIN_PARALLEL_WORK {
        // Too little to share out: solve in place.
        solver::solve(s, motion, joints, pairs, awake, p);
        return;
    }
    // Islands in the order of their lowest body, each with its moving bodies ascending.
    let mut task_of_root = vec![NONE; n];
    let mut task_of = vec![NONE; s.len()];
    let mut local_of_moving = vec![NONE; s.len()];
    let mut tasks: Vec<IslandTask> = Vec::new();
    for i in 0..n {
        if !awake[i] {
            continue;
        }
        let root = islands.root(i);
        if task_of_root[root] == NONE {
            task_of_root[root] = tasks.len() as u32;
            tasks.push(IslandTask::default());
        }
        let t = task_of_root[root];
        let task = &mut tasks[t as usize];
        task_of[i] = t;
        local_of_moving[i] = task.bodies.len() as u32;
        task.bodies.push(i);
    }
    if tasks.len() < 2 {
        // One island: nothing to share out, solve in place.
        solver::solve(s, motion, joints, pairs, awake, p);
        return;
    }
    for task in &mut tasks {
        task.moving = task.bodies.len();
    }
    // A constraint belongs to the island of its moving body (both are in the same one
    // when both move); constraints between static bodies are not solved at all.
    let island_of = |a: usize, b: usize| {
        let t = if awake[a] { task_of[a] } else { task_of[b] };
        (t != NONE).then_some(t as usize)
    };

    macro_rules! gather_joints {
        ($($kind:ident),*) => {$(
            for (k, j) in joints.$kind.iter().enumerate() {
                let Some(t) = island_of(j.frame.a, j.frame.b) else { continue };
                let task = &mut tasks[t];
                let mut j = j.clone();
                j.frame.a = task.local(j.frame.a, &local_of_moving);
                j.frame.b = task.local(j.frame.b, &local_of_moving);
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
        let Some(t) = island_of(pair.a as usize, pair.b as usize) else {
            continue;
        };
        let task = &mut tasks[t];
        let mut local = std::mem::take(pair);
        task.pair_slots.push((k, local.a, local.b));
        local.a = task.local(local.a as usize, &local_of_moving) as u32;
        local.b = task.local(local.b as usize, &local_of_moving) as u32;
        task.pairs.push(local);
    }

    for task in &mut tasks {
        for &i in &task.bodies {
            task.states.push_copy(s, i);
        }
        task.motion = task.bodies[..task.moving]
            .iter()
            .map(|&i| motion.bodies[i])
            .collect();
        task.awake = (0..task.bodies.len()).map(|l| l < task.moving).collect();
    }

    tasks.par_iter_mut().for_each(|t| {
        solver::solve(
            &mut t.states,
            Motions {
                bodies: &t.motion,
                full: motion.full,
            },
            &mut t.joints,
            &mut t.pairs,
            &t.awake,
            p,
        );
    });

    macro_rules! scatter_joints {
        ($task:expr, $($kind:ident),*) => {$(
            for (j, &k) in $task.joints.$kind.drain(..).zip(&$task.joint_slots.$kind) {
                let frame = joints.$kind[k].frame;
                joints.$kind[k] = j;
                joints.$kind[k].frame = frame;
            }
        )*};
    }
    for mut task in tasks {
        for (l, &i) in task.bodies[..task.moving].iter().enumerate() {
            s.copy_from(i, &task.states, l);
        }
        scatter_joints!(task, ball, hinge, universal, fixed, slider, spring);
        for (mut pair, &(k, a, b)) in task.pairs.into_iter().zip(&task.pair_slots) {
            pair.a = a;
            pair.b = b;
            pairs[k] = pair;
        }
    }
}
