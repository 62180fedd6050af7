//! Islands, and the improved solver's substeps on all cores, deterministically.
//!
//! Between two collision detections the contacts are fixed. Bones linked by a joint or
//! a contact, both moving, form an island; static bones (fixed or asleep) take no
//! correction, so two islands that touch the same static bone still never interact. An
//! island's substeps are therefore the same operations on the same numbers whether the
//! other islands run before it, after it or beside it — provided every Gauss–Seidel
//! loop meets its contacts and joints in the same relative order. So each batch of
//! islands is gathered into dense arrays of its own (bones renumbered, contacts and
//! joints kept in world order, a manifold's points still consecutive), stepped by the
//! very code that steps the whole world (`rigid_frames::run_substeps`, handed in as
//! `substeps` so this file does not depend on the solver), and scattered back:
//! the serial result bit for bit, on any number of threads.

use super::ParticleWorld;
use super::bone::{Bone, Side};
use super::bone_kinds::BoneKinds;
use super::contacts::{BONES_PER_TASK, ContactPoint, Manifold, point_runs, range, ranges};
use super::joint_lanes::{Entry, Lockstep};
use super::joints::JointSet;
use crate::method::Grab;
use crate::scene::Settings;
use crate::union_find::UnionFind;
use glam::Vec3A;
use rayon::prelude::*;
use std::ops::Range;

/// Batches per thread: a few, so that rayon's work stealing evens out islands of
/// unequal cost, but not so many that gathering dominates small islands.
const BATCHES_PER_THREAD: usize = 4;

/// Below this much work (bones + contact points + joints) a frame's chunk is stepped in
/// place: gathering and waking threads would cost more than they save.
const MIN_PARALLEL_WORK: usize = 256;

/// A chunk is gathered even without parallel work when at most 1 / this of its bones
/// move.
const COMPACT_FRACTION: usize = 4;

/// "No index": a static bone's island, an unused local index.
const NONE: u32 = u32::MAX;

/// What one batch holds, by world index, each list ascending.
#[derive(Default)]
struct Members {
    bones: Vec<u32>,
    manifolds: Vec<u32>,
    joints: Vec<u32>,
}

/// The islands of one detection chunk, grouped into batches of similar work.
pub(super) struct Plan {
    batches: Vec<Members>,
    /// Each moving bone's index in its batch (`NONE` for static bones).
    local: Vec<u32>,
    /// Each moving bone's batch (`NONE` for static bones).
    bone_batch: Vec<u32>,
    /// Each manifold's batch and index in it (`NONE`: between static bones only).
    manifold_at: Vec<(u32, u32)>,
}

impl Plan {
    /// Islands from the world's joints and current contacts, cut into batches for
    /// `threads` threads; `None` when stepping the world in place is cheaper (one
    /// island or too little work, with most bones moving).
    pub fn new(w: &ParticleWorld, threads: usize) -> Option<Plan> {
        let bones = &w.bones;
        let n = bones.len();
        // On one thread only compaction can pay: with most bones moving, the island
        // search below would be done for nothing, once per detection.
        if threads == 1 && bones.iter().filter(|b| !b.is_static()).count() * COMPACT_FRACTION > n {
            return None;
        }
        // The bones' static flags in a dense array of their own: the joints and contacts
        // below ask them of bones all over the world's array, one cache miss each in
        // the 352-byte bones (most of the island search on a 1000-human pile).
        let is_static: Vec<bool> = bones.iter().map(Bone::is_static).collect();
        let moving = |s: Side| s.filter(|&i| !is_static[i]);
        let mut sets = UnionFind::new(n);
        let links = w.links.iter().map(|l| l.sides());
        let touching = w.contacts.manifolds.iter().map(|m| (Some(m.a()), m.b()));
        for (a, b) in links.chain(touching) {
            if let (Some(a), Some(b)) = (moving(a), moving(b)) {
                sets.union(a, b);
            }
        }
        // Each moving bone's island, named by its root; a constraint's is that of its
        // moving side (it has at most one island: both moving sides were joined).
        let root: Vec<u32> = (0..n)
            .map(|i| {
                if is_static[i] {
                    NONE
                } else {
                    sets.find(i) as u32
                }
            })
            .collect();
        let side_root = |s: Side| s.map_or(NONE, |i| root[i]);
        let pair_root = |a: Side, b: Side| match side_root(a) {
            NONE => side_root(b),
            r => r,
        };
        let manifold_root: Vec<u32> = w
            .contacts
            .manifolds
            .iter()
            .map(|m| pair_root(Some(m.a()), m.b()))
            .collect();
        let joint_root: Vec<u32> = w
            .links
            .iter()
            .map(|l| {
                let (a, b) = l.sides();
                pair_root(a, b)
            })
            .collect();

        // Work per island, at its root: per substep a bone, a contact point and a joint
        // cost about the same.
        let mut work = vec![0usize; n];
        for &r in root.iter().chain(&joint_root) {
            if r != NONE {
                work[r as usize] += 1;
            }
        }
        let (manifolds, points) = (&w.contacts.manifolds, &w.contacts.points);
        for (run, &r) in ranges(manifolds, points.len()).zip(&manifold_root) {
            if r != NONE {
                work[r as usize] += run.len();
            }
        }
        let total: usize = work.iter().sum();
        // Gathering also pays on its own when most bones are static (a pile mostly or
        // wholly asleep): a batch's substeps never visit the static bones, which the
        // in-place loops reset and skip on every substep, a cost that grows with the
        // pile while there is nothing to move.
        let moving = root.iter().filter(|&&r| r != NONE).count();
        let compacts = moving * COMPACT_FRACTION <= n;
        // Islands in the order of their roots (every root has work: its own bone),
        // dealt into runs of about equal work.
        let wanted = if threads > 1 {
            threads * BATCHES_PER_THREAD
        } else {
            1
        };
        let roots: Vec<usize> = (0..n).filter(|&r| work[r] > 0).collect();
        let island_work: Vec<usize> = roots.iter().map(|&r| work[r]).collect();
        let dealt = crate::batches::deal(&island_work, wanted);
        let count = dealt.last().map_or(0, |&b| b + 1);
        let mut batch_of = vec![NONE; n];
        for (&r, &b) in roots.iter().zip(&dealt) {
            batch_of[r] = b;
        }
        let parallel = threads > 1 && count >= 2 && total >= MIN_PARALLEL_WORK;
        if !parallel && !compacts {
            return None;
        }

        let mut batches: Vec<Members> = (0..count).map(|_| Members::default()).collect();
        let mut local = vec![NONE; n];
        let mut bone_batch = vec![NONE; n];
        for (i, &r) in root.iter().enumerate() {
            if r != NONE {
                let b = batch_of[r as usize];
                let m = &mut batches[b as usize];
                local[i] = m.bones.len() as u32;
                bone_batch[i] = b;
                m.bones.push(i as u32);
            }
        }
        let mut manifold_at = vec![(NONE, NONE); manifold_root.len()];
        for (k, &r) in manifold_root.iter().enumerate() {
            if r != NONE {
                let b = batch_of[r as usize];
                let m = &mut batches[b as usize].manifolds;
                manifold_at[k] = (b, m.len() as u32);
                m.push(k as u32);
            }
        }
        for (k, &r) in joint_root.iter().enumerate() {
            if r != NONE {
                batches[batch_of[r as usize] as usize].joints.push(k as u32);
            }
        }
        Some(Plan {
            batches,
            local,
            bone_batch,
            manifold_at,
        })
    }
}

/// A batch of islands in dense arrays of its own: its moving bones first, then copies
/// of the static bones its constraints read; its contacts and joints in world order,
/// their bones renumbered.
#[derive(Default)]
pub(super) struct Batch {
    /// Each of `bones`' world index.
    ids: Vec<u32>,
    /// How many of `bones` move (the first ones).
    moving: usize,
    /// Its moving bones (written back, [`scatter`]), then the static ones its
    /// constraints read.
    bones: Vec<Bone>,
    /// Its manifolds, their points rebased onto `points`.
    manifolds: Vec<Manifold>,
    points: Vec<ContactPoint>,
    /// Each joint's world index and its two sides in the batch.
    joints: Vec<(u32, Side, Side)>,
}

impl Batch {
    /// Copies a batch's share of the world into `self`, a batch of the frame's last
    /// detection chunk (or an empty one). Returns whether its joints stayed the same.
    ///
    /// Its bones are copied only if they are the same bones as before, the same ones
    /// moving: a moving bone's copy there is the one whose motion was written back to
    /// the world ([`scatter`]), a static one's holds still as the world's does, and
    /// nothing else about a bone changes between two chunks of a frame. A bone that
    /// woke between them moves now, so the count of moving bones tells it even when it
    /// was the batch's static bone before; and the caller drops its kept batches when a
    /// chunk is stepped in place. The islands seldom change within a frame: on a
    /// 1000-human pile this skips most of the copying of 16 000 bones (352 bytes each)
    /// three times a frame.
    fn gather(&mut self, m: &Members, local: &[u32], w: &ParticleWorld) -> bool {
        let is_static = |i: usize| w.bones[i].is_static();
        let contact_sides = m.manifolds.iter().flat_map(|&k| {
            let c = &w.contacts.manifolds[k as usize];
            [Some(c.a()), c.b()]
        });
        let joint_sides = m.joints.iter().flat_map(|&k| {
            let (a, b) = w.links[k as usize].sides();
            [a, b]
        });
        let mut statics: Vec<u32> = contact_sides
            .chain(joint_sides)
            .flatten()
            .filter(|&i| is_static(i))
            .map(|i| i as u32)
            .collect();
        statics.sort_unstable();
        statics.dedup();
        let moving = m.bones.len();
        let local_of = |i: usize| {
            if is_static(i) {
                let k = statics.binary_search(&(i as u32));
                moving + k.expect("every static bone read was gathered")
            } else {
                local[i] as usize
            }
        };
        let renumber = |s: Side| s.map(local_of);

        let ids = m.bones.iter().chain(&statics);
        if self.moving != moving || self.ids.iter().ne(ids.clone()) {
            self.moving = moving;
            self.ids.clear();
            self.ids.extend(ids);
            self.bones.clear();
            self.bones
                .extend(self.ids.iter().map(|&i| w.bones[i as usize].clone()));
        }
        // Debug builds and the unit tests (release ones too) check the kept copies.
        if cfg!(any(debug_assertions, test)) {
            assert!(
                self.ids
                    .iter()
                    .zip(&self.bones)
                    .all(|(&i, b)| same_motion(b, &w.bones[i as usize])),
                "a kept bone differs from the world's"
            );
        }
        self.manifolds.clear();
        self.points.clear();
        let (manifolds, points) = (&w.contacts.manifolds, &w.contacts.points);
        for &k in &m.manifolds {
            let c = manifolds[k as usize];
            let start = self.points.len() as u32;
            self.points
                .extend_from_slice(&points[range(manifolds, k as usize, points.len())]);
            let sides = (local_of(c.a()), renumber(c.b()));
            self.manifolds.push(c.renumbered(sides, start));
        }
        let joints = m.joints.iter().map(|&k| {
            let (a, b) = w.links[k as usize].sides();
            (k, renumber(a), renumber(b))
        });
        let same_joints = self.joints.iter().copied().eq(joints.clone());
        if !same_joints {
            self.joints.clear();
            self.joints.extend(joints);
        }
        same_joints
    }
}

/// Whether two copies of a bone are in the same state, to the bit (the check of the
/// kept copies in debug builds and unit tests).
fn same_motion(a: &Bone, b: &Bone) -> bool {
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let state = |b: &Bone| {
        let mut v = Vec::new();
        for x in [b.com, b.dcom, b.lin_vel, b.ang_vel] {
            v.extend(x.to_array());
        }
        for q in [b.rot, b.prev_rot] {
            v.extend(q.to_array());
        }
        (bits(&v), b.is_static())
    };
    state(a) == state(b)
}

/// Writes the batches' moving bones' motion and their contacts' multipliers back, on
/// all threads: each world bone and each manifold's points fetch their batch's copy (a
/// gather by the plan's maps, so every write has one owner). Copied in turn, whole
/// bones batch by batch, this was a serial thirtieth of a 1000-human frame on two
/// threads.
fn scatter(w: &mut ParticleWorld, plan: &Plan, stepped: &[&Batch]) {
    w.bones
        .par_iter_mut()
        .with_min_len(BONES_PER_TASK)
        .zip(&plan.bone_batch)
        .zip(&plan.local)
        .for_each(|((bone, &b), &i)| {
            if b != NONE {
                bone.take_motion(&stepped[b as usize].bones[i as usize]);
            }
        });
    let runs: Vec<&mut [ContactPoint]> =
        point_runs(&w.contacts.manifolds, &mut w.contacts.points).collect();
    runs.into_par_iter()
        .with_min_len(BONES_PER_TASK)
        .zip(&plan.manifold_at)
        .for_each(|(run, &(b, k))| {
            if b != NONE {
                let batch = &stepped[b as usize];
                let (manifolds, points) = (&batch.manifolds, &batch.points);
                run.copy_from_slice(&points[range(manifolds, k as usize, points.len())]);
            }
        });
}

/// What the substeps between two collision detections read and write: the world's
/// own arrays, or a batch of islands gathered into arrays of its own ([`Batch`]). Every
/// index — a contact's bones, a joint's sides — is into these.
///
/// There are no particle arrays: a bone's four particles sit rigidly in its frame at
/// the end of every substep, at `world(rest_k)` with velocity `lin_vel + ω × (R rest_k)`
/// (`Bone::corner`, `Bone::corner_velocity`), so they are evaluated where a substep
/// needs them instead of being stored three times over (positions, previous positions,
/// velocities: 144 B a bone, and the traffic of writing them every substep).
pub(super) struct Part<'a> {
    pub bones: &'a mut [Bone],
    /// What the bones share by kind (a capsule's rolled point, the grab's point, the
    /// air friction): the world's table, which batches do not copy.
    pub kinds: &'a BoneKinds,
    /// Contact manifolds as detected, and their points (`Manifold::range`).
    pub manifolds: &'a [Manifold],
    pub points: &'a mut [ContactPoint],
    /// Its joints in the world's order, with their sides in `bones`
    /// ([`JointSet::entries`]), and the joint pass over them.
    pub joints: &'a [Entry<'a>],
    pub lockstep: &'a Lockstep,
    /// The mouse grab; it acts only where its bone is (see `grab_improved`).
    pub grab: Option<Grab>,
}

/// A batch stepped in a detection chunk of a frame and the joint pass over its
/// joints, kept for the next chunk ([`Batch::gather`]).
pub(super) type Kept = (Batch, Lockstep);

/// Runs the frame's substeps `subs` of length `h` (`substeps`, the solver's kernel over a
/// [`Part`]),
/// each of the plan's batches on its own rayon task.
/// `kept` holds the batches of the frame's last chunk and their joint passes: the
/// batch at the same place here is gathered into the kept one (its bones not copied
/// again if they are the same bones) and reuses its pass if its joints are the same
/// (the same joints give the same pass), and `kept` is left holding this chunk's.
pub(super) fn run_substeps(
    w: &mut ParticleWorld,
    plan: &Plan,
    subs: Range<u32>,
    h: f32,
    s: &Settings,
    kept: &mut Vec<Kept>,
    substeps: impl Fn(&mut Part, Range<u32>, f32, &Settings) + Sync,
) {
    // What the substeps do to a static bone, once: its frame holds still and its
    // velocity is zero. The copies in the batches get the same; this covers the static
    // bones no constraint reads. On all threads: it is a pass over every bone, which on
    // one thread would be a large serial part of a big pile's step.
    w.bones
        .par_iter_mut()
        .with_min_len(BONES_PER_TASK)
        .filter(|b| b.is_static())
        .for_each(|b| {
            b.prev_rot = b.rot;
            b.dturn = glam::Quat::IDENTITY;
            b.dcom = Vec3A::ZERO;
            b.lin_vel = Vec3A::ZERO;
            b.ang_vel = Vec3A::ZERO;
        });
    let world = &*w;
    let mut previous = std::mem::take(kept).into_iter();
    let before: Vec<Option<Kept>> = plan.batches.iter().map(|_| previous.next()).collect();
    *kept = plan
        .batches
        .par_iter()
        .zip(before)
        .map(|(m, before)| {
            let (mut batch, pass) = match before {
                Some((batch, pass)) => (batch, Some(pass)),
                None => (Batch::default(), None),
            };
            let same_joints = batch.gather(m, &plan.local, world);
            let joints =
                JointSet::Batch(&world.joints, &world.joint_kinds, &batch.joints).entries();
            let lockstep = match pass {
                Some(pass) if same_joints => pass,
                _ => Lockstep::new(&joints, &batch.bones),
            };
            let mut part = Part {
                bones: &mut batch.bones,
                kinds: &world.kinds,
                manifolds: &batch.manifolds,
                points: &mut batch.points,
                joints: &joints,
                lockstep: &lockstep,
                grab: world.grab,
            };
            substeps(&mut part, subs.clone(), h, s);
            (batch, lockstep)
        })
        .collect();
    let stepped: Vec<&Batch> = kept.iter().map(|(batch, _)| batch).collect();
    scatter(w, plan, &stepped);
}

#[cfg(test)]
mod tests {
    use super::super::text_world;
    use crate::method::Method;

    /// A box thrown up lands on a sleeping one beside another sleeping one: the first
    /// wakes their figures between two detection chunks of a frame, and the one it
    /// woke second was the batch's static neighbour in the chunk before, with the same
    /// bones in the batch. Its copy there was still asleep; `Batch::gather` must copy
    /// it again (the check of the kept copies, active in unit tests, fails otherwise,
    /// as it did when only the bones' indices were compared), on any number of threads.
    #[test]
    fn a_bone_that_woke_between_chunks_is_copied_again() {
        let text = include_str!("../../tests/data/islands_wake_chain.af");
        let path = std::path::Path::new("islands_wake_chain.af");
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut w = text_world(text, path, None);
                for _ in 0..150 {
                    w.step();
                }
                let thrown = &w.bones[0];
                assert!(
                    thrown.com.y < 1.0,
                    "{threads} threads: the box never came down"
                );
            });
        }
    }
}
