//! The broad phase both methods share: which bodies' (loosened) bounding boxes
//! overlap, from parry3d's bounding volume hierarchy.
//!
//! The tree is built from the boxes (a binned SAH build, O(n log n)), or kept from the
//! last step and refitted to the new boxes (O(n), [`KeptTrees`]), and traversed against
//! itself (the bounding volume test tree), so the cost follows the
//! number of bodies and of overlaps wherever the bodies are: a sort-and-sweep along one
//! axis visits every pair that overlaps on that axis, O(n √n) for a pile laid out in a
//! grid whose columns all span the same x. The pairs come out sorted, so what follows
//! does not depend on the tree's traversal order.
//!
//! Bodies at rest (asleep or fixed) need no pairs with each other, and in a pile that
//! is settling most bodies are: only the moving boxes go into trees, and each box at
//! rest is looked up in them ([`moving_pairs_where`]). The trees' cost then follows
//! the number of moving bodies, not of all bodies, and a pile that is mostly asleep
//! costs little to detect.

use glam::Vec3;
use parry3d::bounding_volume::Aabb;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use rayon::prelude::*;

/// Distance within which both methods create contacts before touching, beyond what a
/// pair can close over the time detected for (m).
///
/// Box2D v3 creates contacts within a fixed 2 cm (four linear slops) and leaves faster
/// approaches to continuous collision. Here each pair's margin also grows by how far its
/// points can approach at the start velocities, `(|v_a − v_b| + |ω_a| r_a + |ω_b| r_b) dt`
/// (each method's detection), so the constant only covers what that misses: gravity's
/// `g dt²` ([`speculative_margin`]) and velocity the other constraints give a body
/// meanwhile. Smaller than Box2D's constant, it keeps fewer speculative rows in the
/// solver; it is enough because a pair's own approach is already in its margin.
pub const SPECULATIVE_DISTANCE: f32 = 0.005;

/// The speculative margin of a detection covering `dt` under gravity `g` (m/s²): what
/// gravity alone closes in that time, `g dt²`, and [`SPECULATIVE_DISTANCE`].
pub fn speculative_margin(g: f32, dt: f32) -> f32 {
    g * dt * dt + SPECULATIVE_DISTANCE
}

/// How far a box lies above a plane (through `origin`, unit `normal`): the height of
/// its lowest corner along the normal, `n·(c − o) − |n|·e` over its centre `c` and half
/// extents `e`; negative when the box reaches below the plane. Both methods find the
/// bodies near the ground by it, with no broad phase for the plane.
pub fn box_height_above_plane(aabb: &Aabb, normal: Vec3, origin: Vec3) -> f32 {
    normal.dot(aabb.center() - origin) - normal.abs().dot(aabb.half_extents())
}

/// Appends to `out` every pair `(i, j)`, `i < j`, of overlapping boxes, sorted.
pub fn overlapping_pairs(aabbs: &[Aabb], out: &mut Vec<(u32, u32)>) {
    overlapping_pairs_where(aabbs, |_, _| true, out);
}

/// [`overlapping_pairs`] that `keep(i, j)` accepts, judged as the traversal reaches
/// them: a pile mostly asleep overlaps mostly between sleeping bodies, pairs nobody
/// wants, and sorting them cost as much as finding them. One detection; a step that
/// detects several times keeps its work in a [`Reused`].
pub fn overlapping_pairs_where(
    aabbs: &[Aabb],
    keep: impl Fn(u32, u32) -> bool + Sync,
    out: &mut Vec<(u32, u32)>,
) {
    moving_pairs_where(aabbs, |_| false, keep, out);
}

/// [`overlapping_pairs_where`] without the pairs of two boxes at rest (`resting(i)`):
/// trees are built over the moving boxes only and each box at rest is looked up in
/// them. In a pile that is mostly asleep that is a fraction of the work of
/// one tree over every box, whose traversal meets every pair of sleeping neighbours
/// only for `keep` to drop it.
pub fn moving_pairs_where(
    aabbs: &[Aabb],
    resting: impl Fn(u32) -> bool,
    keep: impl Fn(u32, u32) -> bool + Sync,
    out: &mut Vec<(u32, u32)>,
) {
    if aabbs.len() >= 2 {
        Split::new(aabbs.len(), resting).build(aabbs, aabbs, &keep, out);
    }
}

/// The boxes of one detection cut into those that move and those at rest, each list
/// ascending. Only the moving boxes go into trees; the trees' leaves count along
/// `moving`, so a leaf's box index is `moving[leaf]`.
#[derive(Default)]
struct Split {
    moving: Vec<u32>,
    resting: Vec<u32>,
}

/// Boxes at rest per task when they are looked up in the moving boxes' trees.
const RESTING_PER_TASK: usize = 1024;

impl Split {
    /// The `n` boxes split by `resting(i)`.
    fn new(n: usize, resting: impl Fn(u32) -> bool) -> Split {
        let (resting, moving) = (0..n as u32).partition(|&i| resting(i));
        Split { moving, resting }
    }

    /// Whether this is the split of `n` boxes by `resting(i)`.
    fn is_split_of(&self, n: usize, resting: impl Fn(u32) -> bool) -> bool {
        if self.moving.len() + self.resting.len() != n {
            return false;
        }
        let (mut m, mut r) = (
            self.moving.iter().peekable(),
            self.resting.iter().peekable(),
        );
        (0..n as u32).all(|i| {
            let list = if resting(i) { &mut r } else { &mut m };
            list.next_if_eq(&&i).is_some()
        })
    }

    /// Trees over the moving boxes of `tree_boxes` (see [`traverse_runs`]), and
    /// the pairs `keep` accepts appended to `out`, sorted: moving boxes of `tree_boxes`
    /// that overlap each other, and boxes at rest, as `query_boxes` has them, that
    /// overlap a moving one of `tree_boxes`. A step that detects again builds its trees
    /// from loosened boxes (`tree_boxes`) while the boxes at rest, which do not move
    /// until they wake, need none.
    fn build(
        &self,
        tree_boxes: &[Aabb],
        query_boxes: &[Aabb],
        keep: &(impl Fn(u32, u32) -> bool + Sync),
        out: &mut Vec<(u32, u32)>,
    ) -> Vec<Part> {
        let mut parts = Vec::new();
        self.find(&mut parts, Trees::Build, tree_boxes, query_boxes, keep, out);
        parts
    }

    /// [`Split::build`] with the trees in `parts`: built anew, or the trees of an
    /// earlier call over the same moving boxes refitted to the boxes as they are now
    /// ([`Trees`]).
    fn find(
        &self,
        parts: &mut Vec<Part>,
        trees: Trees,
        tree_boxes: &[Aabb],
        query_boxes: &[Aabb],
        keep: &(impl Fn(u32, u32) -> bool + Sync),
        out: &mut Vec<(u32, u32)>,
    ) {
        let moving = &self.moving;
        if self.resting.is_empty() {
            traverse_runs(parts, trees, tree_boxes, keep, out);
            return;
        }
        if moving.is_empty() {
            parts.clear();
            return;
        }
        let start = out.len();
        let boxes: Vec<Aabb> = moving.iter().map(|&i| tree_boxes[i as usize]).collect();
        let mut among = Vec::new();
        traverse_runs(
            parts,
            trees,
            &boxes,
            &|a, b| keep(moving[a as usize], moving[b as usize]),
            &mut among,
        );
        // `moving` ascends, so the pairs stay sorted.
        out.extend(
            among
                .into_iter()
                .map(|(a, b)| (moving[a as usize], moving[b as usize])),
        );
        let with_resting: Vec<Vec<(u32, u32)>> = self
            .resting
            .par_chunks(RESTING_PER_TASK)
            .map(|chunk| {
                let mut found = Vec::new();
                for &r in chunk {
                    let query = &query_boxes[r as usize];
                    // parry tests every node on the way, the leaf's own box too.
                    for part in parts.iter() {
                        for leaf in part.tree.intersect_aabb(query) {
                            let m = moving[(part.start + leaf) as usize];
                            let pair = (r.min(m), r.max(m));
                            if keep(pair.0, pair.1) {
                                found.push(pair);
                            }
                        }
                    }
                }
                found
            })
            .collect();
        if with_resting.iter().any(|f| !f.is_empty()) {
            out.reserve_exact(with_resting.iter().map(Vec::len).sum());
            for found in &with_resting {
                out.extend_from_slice(found);
            }
            out[start..].sort_unstable();
        }
    }
}

/// The broad phase of one step's detections: the particle method detects four times a
/// frame, the multibody once per detection window of a step whose contacts turn fast,
/// each time with boxes that moved a little.
///
/// The first call builds trees from the moving boxes loosened by `fat`
/// ([`Reused::fattened`]) and keeps the pairs that `keep` accepts of two moving boxes
/// whose fat boxes overlap and of a box at rest (as it is) and a moving one whose fat
/// box it overlaps: the candidates. A later call needs no tree
/// traversal while the boxes stay inside their fat boxes, as most do (Box2D's enlarged
/// AABBs): two boxes that overlap now and stay inside their fat boxes have overlapping
/// fat boxes, so their pair is a candidate, and the call's pairs are the candidates
/// whose boxes overlap now. A box that left its fat box is looked up in the trees (its
/// partners that stayed are found by their fat boxes), against the boxes at rest (a
/// tree of their own, built the first time it is needed: in a settling pile boxes
/// seldom leave their fat boxes) and against the other boxes that left (a small tree
/// of their own). The pairs are the boxes' own, sorted: the same as from new trees.
/// When more than one in 16 of the moving boxes left (`ESCAPED_FOR_REBUILD`), the
/// trees are built again around the boxes as they are. Within a frame few boxes leave
/// a fat box (about one in a hundred in a pile's busiest second, none once it settles),
/// so querying the trees with those few costs much less than refitting and traversing
/// every tree again at each detection.
///
/// Many boxes are cut into runs of consecutive indices, a tree each, two runs per
/// thread ([`run_count`]): the trees are built and traversed against themselves on all
/// threads, then against each other. parry builds a tree on one thread, and at 16 000
/// bones building and traversing one tree was the largest serial part of a particle
/// frame. A scene's bodies are numbered figure by figure and its figures placed in
/// order, so runs of indices tend to be regions of space and the cross traversals stay
/// short (they are correct either way). Which trees found a pair does not matter: the
/// pairs are sorted.
///
/// `keep` must judge a pair the same way at every call: a caller whose judgement changes
/// (a body woke) calls [`Reused::forget`] first.
///
/// It lives for one step and is dropped after it: kept between steps, the trees alone
/// would hold about 80 bytes per body (parry's `heap_memory_size`) and the fat boxes 24
/// more, a fifth of what a whole body costs (`docs/benchmarks.md`, memory).
#[derive(Default)]
pub struct Reused {
    parts: Vec<Part>,
    /// How much the boxes the trees are built from are loosened (m).
    fat: f32,
    /// The boxes the trees were built from: the first call's, loosened by `fat`.
    fat_boxes: Vec<Aabb>,
    /// The pairs of overlapping fat boxes `keep` accepted, sorted.
    candidates: Vec<(u32, u32)>,
    /// Which boxes moved at the first call: the trees hold those, their fat boxes.
    split: Split,
    /// The boxes at rest, in a tree of their own once a moving box leaves its fat box.
    resting_tree: Option<Bvh>,
}

/// One run of boxes and its tree.
struct Part {
    /// Index of the run's first box; the tree's leaves count from it.
    start: u32,
    tree: Bvh,
}

/// Boxes from which [`Reused`] cuts them into runs, a tree each, on one thread: there
/// the runs only serve the cache, and below this one tree is cheaper.
const BOXES_TO_CUT: usize = 4096;

/// Boxes from which the runs are cut on more threads than one: the trees are then built
/// at once, where one tree over every box would be built on one thread while the others
/// wait: in a 100-human pile's multibody step that is about a twelfth of the work, the
/// largest part left serial. Below this a tree costs less than waking a thread.
const BOXES_TO_CUT_SHARED: usize = 1024;

/// The share of boxes (1 / this) that may leave their fat boxes before [`Reused`]
/// builds its trees again: each box that left is a query of the trees.
const ESCAPED_FOR_REBUILD: usize = 16;

/// How many runs [`Reused`] cuts `n` boxes into on this thread pool: two per thread, at
/// most eight (the trees' cross traversals grow with the square of their number). With
/// one run per thread, two threads would have a single cross traversal, run on one of
/// them; two runs per thread give two threads six cross traversals to share. The pairs
/// do not depend on the runs (they are sorted), so neither does any result.
fn run_count(n: usize) -> usize {
    let threads = rayon::current_num_threads();
    let cut_from = if threads > 1 {
        BOXES_TO_CUT_SHARED
    } else {
        BOXES_TO_CUT
    };
    if n < cut_from {
        1
    } else {
        (2 * threads).clamp(1, 8)
    }
}

impl Part {
    /// The run `start..end` of `aabbs`, in a new tree.
    fn build(aabbs: &[Aabb], start: usize, end: usize) -> Part {
        Part {
            start: start as u32,
            tree: Bvh::from_leaves(BvhBuildStrategy::Binned, &aabbs[start..end]),
        }
    }

    /// The run's tree fitted to the run's boxes in `aabbs` as they are now: each leaf
    /// takes its box, then every inner node the union of its children's, bottom up. The
    /// tree's shape is kept, so it bounds the boxes exactly but may be looser than a new
    /// tree's nodes (more nodes visited, the same pairs found).
    fn refit(&mut self, aabbs: &[Aabb]) {
        let start = self.start as usize;
        let end = start + self.tree.leaf_count() as usize;
        for (leaf, aabb) in aabbs[start..end].iter().enumerate() {
            self.tree
                .update_partially_if_present(*aabb, leaf as u32, 0.0);
        }
        self.tree.refit_without_opt();
    }

    /// The run's overlapping pairs `keep` accepts, by box index, into `out`.
    fn self_pairs(&self, keep: &impl Fn(u32, u32) -> bool, out: &mut Vec<(u32, u32)>) {
        let start = self.start;
        self.tree
            .traverse_bvtt_single_tree::<false>(&mut BvhWorkspace::default(), &mut |a, b| {
                let pair = (start + a.min(b), start + a.max(b));
                if keep(pair.0, pair.1) {
                    out.push(pair);
                }
            });
    }

    /// The pairs of a box of this run and one of `other`'s (a later run) that overlap
    /// and `keep` accepts.
    fn cross_pairs(
        &self,
        other: &Part,
        aabbs: &[Aabb],
        keep: &impl Fn(u32, u32) -> bool,
    ) -> Vec<(u32, u32)> {
        self.tree
            .leaf_pairs(&other.tree, |a, b| a.intersects(b))
            .map(|(a, b)| (self.start + a, other.start + b))
            // `leaf_pairs` does not test the pair it starts from.
            .filter(|&(a, b)| aabbs[a as usize].intersects(&aabbs[b as usize]) && keep(a, b))
            .collect()
    }
}

/// The broad phase of a method that detects once a step: its trees, kept from one step to
/// the next and refitted to the boxes of the next (Rapier's and Box2D's dynamic trees are
/// kept likewise), built anew when the boxes that move are not the same ones or after
/// [`REFITS_PER_BUILD`] refits. A refit visits every node once, O(n); a new tree sorts the
/// boxes into bins level by level, O(n log n). A refitted tree's nodes grow looser as its
/// boxes move relative to each other, so its traversal visits more nodes; a new tree every
/// few steps bounds that. The pairs are those of the boxes either way (sorted), so no
/// result depends on when the trees are built.
///
/// The trees hold about 80 bytes per moving box (parry's `heap_memory_size`) between
/// steps; [`KeptTrees::release`] gives them back, as a world at rest does.
#[derive(Default)]
pub struct KeptTrees {
    /// The moving and resting boxes the trees were built for.
    split: Split,
    parts: Vec<Part>,
    /// Refits since the trees were built.
    refits: u32,
}

/// Steps a [`KeptTrees`] refits its trees before building them again.
const REFITS_PER_BUILD: u32 = 32;

impl KeptTrees {
    /// Drops the trees: the next call builds them again.
    pub fn release(&mut self) {
        *self = KeptTrees::default();
    }

    /// The free [`moving_pairs_where`], with the trees kept from the last call when the
    /// same boxes move (see [`KeptTrees`]).
    pub fn moving_pairs_where(
        &mut self,
        aabbs: &[Aabb],
        resting: impl Fn(u32) -> bool,
        keep: impl Fn(u32, u32) -> bool + Sync,
        out: &mut Vec<(u32, u32)>,
    ) {
        if aabbs.len() < 2 {
            self.release();
            return;
        }
        let same = !self.parts.is_empty()
            && self.refits < REFITS_PER_BUILD
            && self.split.is_split_of(aabbs.len(), &resting)
            && self.parts.len() == run_count(self.split.moving.len());
        let trees = if same {
            self.refits += 1;
            Trees::Refit
        } else {
            self.split = Split::new(aabbs.len(), resting);
            self.refits = 0;
            Trees::Build
        };
        self.split
            .find(&mut self.parts, trees, aabbs, aabbs, &keep, out);
    }
}

impl Reused {
    /// Trees built from the boxes loosened by `fat` (m), for a step that detects
    /// several times ([`Reused`]); the default, no fat, suits a single detection.
    pub fn fattened(fat: f32) -> Reused {
        Reused {
            fat,
            ..Reused::default()
        }
    }

    /// Whether the trees are built from loosened boxes, for several detections.
    pub fn is_fattened(&self) -> bool {
        self.fat > 0.0
    }

    /// Drops the trees and candidates: the next call builds them again.
    pub fn forget(&mut self) {
        self.parts.clear();
        self.resting_tree = None;
        self.fat_boxes.clear();
        self.candidates.clear();
    }

    /// [`overlapping_pairs`] of `aabbs` (see [`Reused`] for how a later call with as
    /// many boxes reuses the first one's work).
    pub fn overlapping_pairs(&mut self, aabbs: &[Aabb], out: &mut Vec<(u32, u32)>) {
        self.overlapping_pairs_where(aabbs, |_, _| true, out);
    }

    /// [`Self::overlapping_pairs`] that `keep(i, j)` accepts (see the free
    /// [`overlapping_pairs_where`]).
    pub fn overlapping_pairs_where(
        &mut self,
        aabbs: &[Aabb],
        keep: impl Fn(u32, u32) -> bool + Sync,
        out: &mut Vec<(u32, u32)>,
    ) {
        self.moving_pairs_where(aabbs, |_| false, keep, out);
    }

    /// [`Self::overlapping_pairs_where`] without the pairs of two boxes at rest
    /// (`resting(i)`; see the free [`moving_pairs_where`]). Which boxes are at rest is
    /// read when the trees are built: until [`Reused::forget`] the same boxes must be
    /// at rest, and a box at rest may shrink (the particle step loosens its boxes less
    /// as the frame goes on) but not move out of where it was.
    pub fn moving_pairs_where(
        &mut self,
        aabbs: &[Aabb],
        resting: impl Fn(u32) -> bool,
        keep: impl Fn(u32, u32) -> bool + Sync,
        out: &mut Vec<(u32, u32)>,
    ) {
        if aabbs.len() < 2 {
            return;
        }
        if self.fat == 0.0 {
            // Without fat nothing would outlast a call.
            moving_pairs_where(aabbs, resting, keep, out);
            return;
        }
        if self.fat_boxes.len() == aabbs.len() {
            let escaped: Vec<u32> = self
                .split
                .moving
                .iter()
                .copied()
                .filter(|&i| !self.fat_boxes[i as usize].contains(&aabbs[i as usize]))
                .collect();
            if escaped.len() * ESCAPED_FOR_REBUILD <= self.split.moving.len() {
                self.pairs_since(aabbs, &escaped, &keep, out);
                return;
            }
        }
        self.split = Split::new(aabbs.len(), resting);
        self.resting_tree = None;
        self.fat_boxes.clear();
        self.fat_boxes
            .extend(aabbs.iter().map(|b| b.loosened(self.fat)));
        let mut candidates = std::mem::take(&mut self.candidates);
        candidates.clear();
        self.parts = self
            .split
            .build(&self.fat_boxes, aabbs, &keep, &mut candidates);
        self.candidates = candidates;
        out.extend(self.overlapping_candidates(aabbs));
    }

    /// The candidates whose boxes overlap in `aabbs`.
    fn overlapping_candidates<'a>(
        &'a self,
        aabbs: &'a [Aabb],
    ) -> impl Iterator<Item = (u32, u32)> + 'a {
        self.candidates
            .iter()
            .copied()
            .filter(|&(i, j)| aabbs[i as usize].intersects(&aabbs[j as usize]))
    }

    /// A later call's pairs: the candidates', then those of the moving boxes that left
    /// their fat boxes (`escaped`, ascending), with the moving boxes that stayed (found
    /// by their fat boxes in the trees), with each other and with the boxes at rest
    /// (in a tree of their own, built the first time a box escapes).
    fn pairs_since(
        &mut self,
        aabbs: &[Aabb],
        escaped: &[u32],
        keep: &impl Fn(u32, u32) -> bool,
        out: &mut Vec<(u32, u32)>,
    ) {
        let start = out.len();
        out.extend(self.overlapping_candidates(aabbs));
        if escaped.is_empty() {
            return;
        }
        let left = |i: u32| escaped.binary_search(&i).is_ok();
        let Split { moving, resting } = &self.split;
        let mut found = Vec::new();
        for &e in escaped {
            for part in &self.parts {
                found.extend(
                    part.tree
                        .intersect_aabb(&aabbs[e as usize])
                        .map(|leaf| moving[(leaf + part.start) as usize])
                        .filter(|&j| !left(j))
                        .map(|j| (e.min(j), e.max(j))),
                );
            }
        }
        if !resting.is_empty() {
            let tree = self.resting_tree.get_or_insert_with(|| {
                let boxes: Vec<Aabb> = resting.iter().map(|&r| aabbs[r as usize]).collect();
                Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes)
            });
            for &e in escaped {
                found.extend(
                    tree.intersect_aabb(&aabbs[e as usize])
                        .map(|leaf| resting[leaf as usize])
                        .map(|r| (e.min(r), e.max(r))),
                );
            }
        }
        let moved: Vec<Aabb> = escaped.iter().map(|&e| aabbs[e as usize]).collect();
        let mut among = Vec::new();
        overlapping_pairs(&moved, &mut among);
        found.extend(
            among
                .into_iter()
                .map(|(a, b)| (escaped[a as usize], escaped[b as usize])),
        );
        out.extend(
            found
                .into_iter()
                .filter(|&(i, j)| aabbs[i as usize].intersects(&aabbs[j as usize]) && keep(i, j)),
        );
        out[start..].sort_unstable();
        // A pair of an escaped box and one that stayed may also be a candidate.
        dedup_from(out, start);
    }
}

/// Removes repeated pairs from the sorted `out[start..]`, in place.
fn dedup_from(out: &mut Vec<(u32, u32)>, start: usize) {
    let mut kept = start;
    for k in start..out.len() {
        if kept == start || out[k] != out[kept - 1] {
            out[kept] = out[k];
            kept += 1;
        }
    }
    out.truncate(kept);
}

/// Whether [`traverse_runs`] builds its trees anew or refits those it is given.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Trees {
    Build,
    Refit,
}

/// The trees of `parts` over `aabbs` (a run each, see [`run_count`]), built anew or
/// refitted (`Trees::Refit`: `parts` holds the trees of an earlier call over as many boxes,
/// cut into as many runs), and their overlapping pairs that `keep` accepts appended to
/// `out`, sorted. The pairs are those of the boxes whatever the trees' shape: a tree only
/// decides which nodes are visited, every leaf pair reported is tested on the leaves' own
/// boxes.
fn traverse_runs(
    parts: &mut Vec<Part>,
    trees: Trees,
    aabbs: &[Aabb],
    keep: &(impl Fn(u32, u32) -> bool + Sync),
    out: &mut Vec<(u32, u32)>,
) {
    let start = out.len();
    let n = aabbs.len();
    let k = run_count(n);
    debug_assert!(trees == Trees::Build || parts.len() == k);
    if k == 1 {
        match trees {
            Trees::Build => *parts = vec![Part::build(aabbs, 0, n)],
            Trees::Refit => parts[0].refit(aabbs),
        }
        parts[0].self_pairs(keep, out);
    } else {
        let run = |p: usize| (n * p / k, n * (p + 1) / k);
        // Each run's tree and the pairs within it, in one task.
        let found: Vec<Vec<(u32, u32)>> = match trees {
            Trees::Build => {
                let (built, found): (Vec<Part>, Vec<Vec<(u32, u32)>>) = (0..k)
                    .into_par_iter()
                    .map(|p| {
                        let (s, e) = run(p);
                        let part = Part::build(aabbs, s, e);
                        let mut pairs = Vec::new();
                        part.self_pairs(keep, &mut pairs);
                        (part, pairs)
                    })
                    .unzip();
                *parts = built;
                found
            }
            Trees::Refit => parts
                .par_iter_mut()
                .map(|part| {
                    part.refit(aabbs);
                    let mut pairs = Vec::new();
                    part.self_pairs(keep, &mut pairs);
                    pairs
                })
                .collect(),
        };
        let parts = &*parts;
        let crossing: Vec<Vec<(u32, u32)>> = (0..k)
            .flat_map(|p| (p + 1..k).map(move |q| (p, q)))
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|(p, q)| parts[p].cross_pairs(&parts[q], aabbs, keep))
            .collect();
        // Room for all of them at once: `out` is kept between steps at its largest
        // size, and growing it run by run would leave it up to twice that.
        out.reserve_exact(found.iter().chain(&crossing).map(Vec::len).sum());
        for pairs in found.iter().chain(&crossing) {
            out.extend_from_slice(pairs);
        }
    }
    out[start..].sort_unstable();
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use parry3d::bounding_volume::BoundingVolume;

    /// Against the quadratic answer on a grid of boxes, some touching, some apart, some
    /// stacked in columns (the layout that made the old x sweep slow).
    #[test]
    fn finds_exactly_the_overlapping_pairs() {
        let mut aabbs = Vec::new();
        for i in 0..12 {
            for j in 0..5 {
                for k in 0..4 {
                    let c = Vec3::new(i as f32 * 0.9, k as f32 * 0.45, j as f32 * 1.7);
                    let h = Vec3::new(0.5, 0.25 + 0.01 * ((i + j + k) % 3) as f32, 0.4);
                    aabbs.push(Aabb::new(c - h, c + h));
                }
            }
        }
        let mut fast = Vec::new();
        overlapping_pairs(&aabbs, &mut fast);
        let mut slow = Vec::new();
        for a in 0..aabbs.len() {
            for b in a + 1..aabbs.len() {
                if aabbs[a].intersects(&aabbs[b]) {
                    slow.push((a as u32, b as u32));
                }
            }
        }
        assert!(!slow.is_empty());
        assert_eq!(fast, slow);

        // The same fat trees asked again with boxes moved apart, into each other and
        // across the grid: still exactly the overlapping pairs.
        let mut reused = Reused::fattened(0.1);
        let mut first = Vec::new();
        reused.overlapping_pairs(&aabbs, &mut first);
        assert_eq!(first, slow);
        for step in 1..4 {
            let moved: Vec<Aabb> = aabbs
                .iter()
                .enumerate()
                .map(|(n, b)| {
                    let shift = Vec3::new(
                        ((n * 7 + step) % 5) as f32 * 0.3 * step as f32,
                        -0.2 * step as f32 * (n % 3) as f32,
                        ((n * 3) % 4) as f32 * 0.4 - 0.6,
                    );
                    Aabb::new(b.mins + shift, b.maxs + shift)
                })
                .collect();
            let mut again = Vec::new();
            reused.overlapping_pairs(&moved, &mut again);
            let mut fresh = Vec::new();
            overlapping_pairs(&moved, &mut fresh);
            assert_ne!(fresh, slow, "step {step} moved nothing that matters");
            assert_eq!(again, fresh, "step {step}");
        }
    }

    /// `n` boxes on a 0.5 m grid of 20 x 20 x ~13 cells, numbered in an order that
    /// scatters them, each touching its neighbours; `shift` moves two thirds of them
    /// along x, one third each way.
    fn scattered(n: usize, shift: f32) -> Vec<Aabb> {
        (0..n)
            .map(|k| {
                let s = (k * 7919) % n; // a scattered cell of a 20 x 20 x ~13 grid
                let c = Vec3::new(
                    (s % 20) as f32 * 0.5 + shift * ((k % 3) as f32 - 1.0),
                    ((s / 20) % 20) as f32 * 0.5,
                    (s / 400) as f32 * 0.5 + 0.1 * (k % 5) as f32,
                );
                let h = Vec3::splat(0.26 + 0.02 * (k % 4) as f32);
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    /// The pairs `keep_some` accepts, by testing every pair.
    fn slow(aabbs: &[Aabb]) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for a in 0..aabbs.len() {
            for b in a + 1..aabbs.len() {
                if aabbs[a].intersects(&aabbs[b]) && keep_some(a as u32, b as u32) {
                    out.push((a as u32, b as u32));
                }
            }
        }
        out
    }

    /// A `keep` that drops some pairs.
    fn keep_some(a: u32, b: u32) -> bool {
        !(a + b).is_multiple_of(7)
    }

    /// A pool of `threads` threads.
    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    /// Enough boxes to be cut into runs, a tree each: on pools of one, two and three threads,
    /// fresh and asked again after most boxes moved (so built again), the same pairs as
    /// one tree on one thread and as the quadratic answer, with a `keep` that drops some.
    /// The runs' trees overlap (the boxes are numbered in an order that scatters them)
    /// so the cross traversals find pairs.
    #[test]
    fn trees_cut_into_runs_find_the_same_pairs() {
        let n = BOXES_TO_CUT + 700;
        let keep = keep_some;
        let (first, moved) = (scattered(n, 0.0), scattered(n, 0.3));
        let (want_first, want_moved) = (slow(&first), slow(&moved));
        assert!(want_first.len() > n && want_first != want_moved);
        for threads in [1, 2, 3] {
            pool(threads).install(|| {
                assert_eq!(run_count(n), 2 * threads);
                // Fewer boxes are cut only when the runs' trees are built at once.
                let fewer = BOXES_TO_CUT_SHARED + 100;
                assert_eq!(run_count(fewer), if threads == 1 { 1 } else { 2 * threads });
                let mut reused = Reused::fattened(0.01);
                let (mut a, mut b) = (Vec::new(), Vec::new());
                reused.overlapping_pairs_where(&first, keep, &mut a);
                reused.overlapping_pairs_where(&moved, keep, &mut b);
                assert_eq!(a, want_first, "{threads} threads, built");
                assert_eq!(b, want_moved, "{threads} threads, built again");
                let mut single = Vec::new();
                overlapping_pairs_where(&moved, keep, &mut single);
                assert_eq!(single, want_moved, "{threads} threads, one detection");
            });
        }
    }

    /// A later call without new trees: every box moved a little, within its fat box,
    /// and a few (one in 25) left theirs for one corner of the grid, where they meet
    /// each other and boxes that stayed. The pairs are the quadratic answer's, on one
    /// tree and on trees cut into runs, and the trees were not built again. Fails if
    /// the boxes that left are not looked up in the trees or not tested against each
    /// other.
    #[test]
    fn boxes_leaving_their_fat_boxes_find_their_new_pairs() {
        let fat = 0.05;
        for (n, threads) in [(1200, 1), (1200, 2), (BOXES_TO_CUT + 700, 2)] {
            let first = scattered(n, 0.0);
            let mut moved = scattered(n, 0.03);
            let corner = Vec3::new(0.1, 0.2, 0.3);
            let mut left = 0;
            for (k, b) in moved.iter_mut().enumerate().filter(|(k, _)| k % 25 == 3) {
                let shift = corner + Vec3::splat(0.05 * (k % 9) as f32) - b.center();
                *b = Aabb::new(b.mins + shift, b.maxs + shift);
                left += 1;
            }
            let want = slow(&moved);
            assert!(want.iter().any(|&(a, b)| a % 25 == 3 && b % 25 == 3));
            assert!(want.iter().any(|&(a, b)| (a % 25 == 3) != (b % 25 == 3)));
            assert!(left * ESCAPED_FOR_REBUILD <= n);
            pool(threads).install(|| {
                let mut reused = Reused::fattened(fat);
                let (mut a, mut b) = (Vec::new(), Vec::new());
                reused.overlapping_pairs_where(&first, keep_some, &mut a);
                assert_eq!(a, slow(&first), "{n} boxes, first");
                let built = reused.fat_boxes.clone();
                reused.overlapping_pairs_where(&moved, keep_some, &mut b);
                assert_eq!(reused.fat_boxes, built, "{n} boxes: built again");
                assert_eq!(b, want, "{n} boxes, after moving");
            });
        }
    }

    /// Trees kept from call to call and refitted: after the boxes moved (so far that a
    /// refitted node bounds boxes a new tree would not put together), after a change
    /// of the boxes at rest (built again) and on trees cut into runs, the pairs are the
    /// quadratic answer's less those of two boxes at rest. Fails if a refit leaves a
    /// node short of a moved box, or keeps trees built for other moving boxes.
    #[test]
    fn kept_trees_refitted_find_the_same_pairs() {
        for (n, threads) in [(1200, 1), (1200, 2), (BOXES_TO_CUT + 700, 2)] {
            pool(threads).install(|| {
                let mut kept = KeptTrees::default();
                let calls = [(0.0, 0), (0.3, 0), (0.6, 0), (0.9, 3), (1.2, 3), (0.0, 3)];
                for (call, &(shift, every)) in calls.iter().enumerate() {
                    let boxes = scattered(n, shift);
                    let resting = |i: u32| every != 0 && i % every == 1;
                    let want: Vec<(u32, u32)> = slow(&boxes)
                        .into_iter()
                        .filter(|&(a, b)| !(resting(a) && resting(b)))
                        .collect();
                    let mut found = Vec::new();
                    kept.moving_pairs_where(&boxes, resting, keep_some, &mut found);
                    assert_eq!(found, want, "{n} boxes, {threads} threads, call {call}");
                    let refitted = !matches!(call, 0 | 3);
                    assert_eq!(kept.refits > 0, refitted, "call {call}");
                }
            });
        }
    }

    /// Boxes at rest (one in three, the ones `scattered` does not shift) are looked up
    /// in the moving boxes' trees, not put in them: the pairs are the quadratic
    /// answer's less those of two boxes at rest, in one detection and in a later call
    /// after a few moving boxes left their fat boxes for a corner of the grid, where
    /// they meet boxes at rest (found in the tree of those). Fails if boxes at rest are
    /// left out of either lookup, or their pairs with each other are reported.
    #[test]
    fn boxes_at_rest_pair_only_with_moving_ones() {
        let resting = |i: u32| i % 3 == 1;
        let want = |aabbs: &[Aabb]| -> Vec<(u32, u32)> {
            let all = slow(aabbs);
            assert!(all.iter().any(|&(a, b)| resting(a) && resting(b)));
            all.into_iter()
                .filter(|&(a, b)| !(resting(a) && resting(b)))
                .collect()
        };
        for (n, threads) in [(1200, 1), (1200, 2), (BOXES_TO_CUT + 700, 2)] {
            let first = scattered(n, 0.0);
            let mut moved = scattered(n, 0.03);
            let corner = Vec3::new(0.1, 0.2, 0.3);
            for (k, b) in moved.iter_mut().enumerate() {
                if resting(k as u32) {
                    assert_eq!(*b, first[k], "a box at rest moved");
                } else if k % 25 == 3 {
                    let shift = corner + Vec3::splat(0.05 * (k % 9) as f32) - b.center();
                    *b = Aabb::new(b.mins + shift, b.maxs + shift);
                }
            }
            let (want_first, want_moved) = (want(&first), want(&moved));
            let escaped = |&(a, b): &(u32, u32)| {
                let left = |i: u32| i % 25 == 3 && !resting(i);
                (left(a) && resting(b)) || (resting(a) && left(b))
            };
            assert!(want_moved.iter().any(escaped));
            pool(threads).install(|| {
                let mut once = Vec::new();
                moving_pairs_where(&first, resting, keep_some, &mut once);
                assert_eq!(once, want_first, "{n} boxes, one detection");
                let mut reused = Reused::fattened(0.05);
                let (mut a, mut b) = (Vec::new(), Vec::new());
                reused.moving_pairs_where(&first, resting, keep_some, &mut a);
                assert_eq!(a, want_first, "{n} boxes, first");
                let built = reused.fat_boxes.clone();
                reused.moving_pairs_where(&moved, resting, keep_some, &mut b);
                assert_eq!(reused.fat_boxes, built, "{n} boxes: built again");
                assert!(reused.resting_tree.is_some());
                assert_eq!(b, want_moved, "{n} boxes, after moving");
            });
        }
        // One box moving among boxes at rest: a tree of one leaf.
        let boxes = scattered(300, 0.0);
        let lone = |i: u32| i != 17;
        let mut found = Vec::new();
        moving_pairs_where(&boxes, lone, |_, _| true, &mut found);
        let touching: Vec<u32> = (0..300)
            .filter(|&j| j != 17 && boxes[j as usize].intersects(&boxes[17]))
            .collect();
        assert!(!touching.is_empty());
        let want: Vec<(u32, u32)> = touching.iter().map(|&j| (j.min(17), j.max(17))).collect();
        assert_eq!(found, want, "one moving box");
    }
}
