//! The broad phase both methods share: which bodies' (loosened) bounding boxes
//! overlap, from parry3d's bounding volume hierarchy.
//!
//! The tree is built afresh from the boxes each time (a binned SAH build, O(n log n))
//! and traversed against itself (the bounding volume test tree), so the cost follows the
//! number of bodies and of overlaps wherever the bodies are: a sort-and-sweep along one
//! axis visits every pair that overlaps on that axis, O(n √n) for a pile laid out in a
//! grid whose columns all span the same x. The pairs come out sorted, so what follows
//! does not depend on the tree's traversal order.

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
/// meanwhile. Measured on the multibody method against 2 cm: scenes 1–9 agree to their
/// printed digits but for the spider's first sleep (2.55 → 2.40 s), the 100-human
/// pile's step takes 6.5 % fewer instructions (fewer speculative rows), and over 72
/// shifted starts the figures' worst figures and sleeping starts are the same.
pub const SPECULATIVE_DISTANCE: f32 = 0.005;

/// The speculative margin of a detection covering `dt` under gravity `g` (m/s²): what
/// gravity alone closes in that time, `g dt²`, and [`SPECULATIVE_DISTANCE`].
pub fn speculative_margin(g: f32, dt: f32) -> f32 {
    g * dt * dt + SPECULATIVE_DISTANCE
}

/// Appends to `out` every pair `(i, j)`, `i < j`, of overlapping boxes, sorted.
pub fn overlapping_pairs(aabbs: &[Aabb], out: &mut Vec<(u32, u32)>) {
    Reused::default().overlapping_pairs(aabbs, out);
}

/// Trees reused by the detections of one step: the particle method detects four times
/// a frame, each time with boxes that moved a little. The first call builds the trees;
/// later calls with as many boxes move their leaves and refit the nodes above them,
/// bottom up (parry's `refit_without_opt`), about a tenth of a build. A refitted tree is
/// looser than a fresh one, so its traversal tests more nodes, but the overlapping pairs
/// are the boxes' own: the same pairs, in the same sorted order, as from a new tree.
///
/// On a pool of several threads, many boxes are cut into runs of consecutive indices,
/// a tree each ([`parts`]): the trees are built and traversed against themselves on all
/// threads, then against each other. parry builds a tree on one thread, and at 16 000
/// bones building and traversing one tree was the largest serial part of a particle
/// frame. A scene's bodies are numbered figure by figure and its figures placed in
/// order, so runs of indices tend to be regions of space and the cross traversals stay
/// short (they are correct either way). Which trees found a pair does not matter: the
/// pairs are sorted.
///
/// It lives for one step and is dropped after it: kept between steps, the tree and its
/// workspace would cost about 144 bytes per body, a third of the memory goal.
#[derive(Default)]
pub struct Reused {
    parts: Vec<Part>,
}

/// One run of boxes and its tree.
struct Part {
    /// Index of the run's first box; the tree's leaves count from it.
    start: u32,
    tree: Bvh,
    workspace: BvhWorkspace,
}

/// Boxes from which [`Reused`] cuts them into runs, a tree each.
const BOXES_TO_CUT: usize = 4096;

/// How many runs [`Reused`] cuts `n` boxes into on this thread pool: one per thread, at
/// most eight (the trees' cross traversals grow with the square of their number).
fn parts(n: usize) -> usize {
    if n < BOXES_TO_CUT {
        1
    } else {
        rayon::current_num_threads().clamp(1, 8)
    }
}

impl Part {
    /// The run `start..end` of `aabbs`, in a new tree.
    fn build(aabbs: &[Aabb], start: usize, end: usize) -> Part {
        Part {
            start: start as u32,
            tree: Bvh::from_leaves(BvhBuildStrategy::Binned, &aabbs[start..end]),
            workspace: BvhWorkspace::default(),
        }
    }

    /// Moves the leaves to the run's boxes in `aabbs` (as many as the tree has) and
    /// refits the tree.
    fn refit(&mut self, aabbs: &[Aabb]) {
        let start = self.start as usize;
        let run = &aabbs[start..start + self.tree.leaf_count() as usize];
        for (i, aabb) in run.iter().enumerate() {
            self.tree.update_partially_if_present(*aabb, i as u32, 0.0);
        }
        self.tree.refit_without_opt();
    }

    /// The run's overlapping pairs `keep` accepts, by box index, into `out`.
    fn self_pairs(&mut self, keep: &impl Fn(u32, u32) -> bool, out: &mut Vec<(u32, u32)>) {
        let start = self.start;
        self.tree
            .traverse_bvtt_single_tree::<false>(&mut self.workspace, &mut |a, b| {
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

impl Reused {
    /// [`overlapping_pairs`] of `aabbs`, on the trees refitted to them when the boxes
    /// and the pool's threads cut them into the same runs as last time, else on new
    /// ones.
    pub fn overlapping_pairs(&mut self, aabbs: &[Aabb], out: &mut Vec<(u32, u32)>) {
        self.overlapping_pairs_where(aabbs, |_, _| true, out);
    }

    /// [`Self::overlapping_pairs`] that `keep(i, j)` accepts, judged as the traversal
    /// reaches them: a pile mostly asleep overlaps mostly between sleeping bodies, pairs
    /// nobody wants, and sorting them cost as much as finding them.
    pub fn overlapping_pairs_where(
        &mut self,
        aabbs: &[Aabb],
        keep: impl Fn(u32, u32) -> bool + Sync,
        out: &mut Vec<(u32, u32)>,
    ) {
        let start = out.len();
        let n = aabbs.len();
        if n < 2 {
            return;
        }
        let k = parts(n);
        let run = |p: usize| (n * p / k, n * (p + 1) / k);
        let reusable = self.parts.len() == k
            && (0..k).all(|p| {
                let (s, e) = run(p);
                self.parts[p].start as usize == s
                    && self.parts[p].tree.leaf_count() as usize == e - s
            });
        if k == 1 {
            if reusable {
                self.parts[0].refit(aabbs);
            } else {
                self.parts = vec![Part::build(aabbs, 0, n)];
            }
            self.parts[0].self_pairs(&keep, out);
        } else {
            // Each run's tree, refitted or built, and the pairs within it, in one task.
            let own = |part: &mut Part| {
                let mut pairs = Vec::new();
                part.self_pairs(&keep, &mut pairs);
                pairs
            };
            let found: Vec<Vec<(u32, u32)>> = if reusable {
                self.parts
                    .par_iter_mut()
                    .map(|part| {
                        part.refit(aabbs);
                        own(part)
                    })
                    .collect()
            } else {
                let (parts, found) = (0..k)
                    .into_par_iter()
                    .map(|p| {
                        let (s, e) = run(p);
                        let mut part = Part::build(aabbs, s, e);
                        let pairs = own(&mut part);
                        (part, pairs)
                    })
                    .unzip();
                self.parts = parts;
                found
            };
            let parts = &self.parts;
            let crossing: Vec<Vec<(u32, u32)>> = (0..k)
                .flat_map(|p| (p + 1..k).map(move |q| (p, q)))
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|(p, q)| parts[p].cross_pairs(&parts[q], aabbs, &keep))
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

        // The same tree refitted to boxes moved apart, into each other and across
        // the grid: still exactly the overlapping pairs.
        let mut reused = Reused::default();
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
            let mut refitted = Vec::new();
            reused.overlapping_pairs(&moved, &mut refitted);
            let mut fresh = Vec::new();
            overlapping_pairs(&moved, &mut fresh);
            assert_ne!(fresh, slow, "step {step} moved nothing that matters");
            assert_eq!(refitted, fresh, "step {step}");
        }
    }

    /// Enough boxes to be cut into runs, a tree each: on pools of two and three threads,
    /// fresh and refitted, the same pairs as one tree on one thread and as the quadratic
    /// answer, with a `keep` that drops some. The runs' trees overlap (the boxes are
    /// numbered in an order that scatters them) so the cross traversals find pairs.
    #[test]
    fn trees_cut_into_runs_find_the_same_pairs() {
        let n = BOXES_TO_CUT + 700;
        let boxes = |shift: f32| -> Vec<Aabb> {
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
        };
        let keep = |a: u32, b: u32| !(a + b).is_multiple_of(7);
        let slow = |aabbs: &[Aabb]| {
            let mut out = Vec::new();
            for a in 0..aabbs.len() {
                for b in a + 1..aabbs.len() {
                    if aabbs[a].intersects(&aabbs[b]) && keep(a as u32, b as u32) {
                        out.push((a as u32, b as u32));
                    }
                }
            }
            out
        };
        let (first, moved) = (boxes(0.0), boxes(0.3));
        let (want_first, want_moved) = (slow(&first), slow(&moved));
        assert!(want_first.len() > n && want_first != want_moved);
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                assert_eq!(parts(n), threads);
                let mut reused = Reused::default();
                let (mut a, mut b) = (Vec::new(), Vec::new());
                reused.overlapping_pairs_where(&first, keep, &mut a);
                reused.overlapping_pairs_where(&moved, keep, &mut b);
                assert_eq!(a, want_first, "{threads} threads, built");
                assert_eq!(b, want_moved, "{threads} threads, refitted");
            });
        }
    }
}
