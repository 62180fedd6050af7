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
use parry3d::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};

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

/// A tree reused by the detections of one step: the particle method detects four times
/// a frame, each time with boxes that moved a little. The first call builds the tree;
/// later calls with as many boxes move its leaves and refit the nodes above them,
/// bottom up (parry's `refit_without_opt`), about a tenth of a build. A refitted tree is
/// looser than a fresh one, so its traversal tests more nodes, but the overlapping pairs
/// are the boxes' own: the same pairs, in the same sorted order, as from a new tree.
///
/// It lives for one step and is dropped after it: kept between steps, the tree and its
/// workspace would cost about 144 bytes per body, a third of the memory goal.
#[derive(Default)]
pub struct Reused {
    tree: Option<Bvh>,
    workspace: BvhWorkspace,
}

impl Reused {
    /// [`overlapping_pairs`] of `aabbs`, on the tree refitted to them when it has as
    /// many leaves, else on a new one.
    pub fn overlapping_pairs(&mut self, aabbs: &[Aabb], out: &mut Vec<(u32, u32)>) {
        self.overlapping_pairs_where(aabbs, |_, _| true, out);
    }

    /// [`Self::overlapping_pairs`] that `keep(i, j)` accepts, judged as the traversal
    /// reaches them: a pile mostly asleep overlaps mostly between sleeping bodies, pairs
    /// nobody wants, and sorting them cost as much as finding them.
    pub fn overlapping_pairs_where(
        &mut self,
        aabbs: &[Aabb],
        keep: impl Fn(u32, u32) -> bool,
        out: &mut Vec<(u32, u32)>,
    ) {
        let start = out.len();
        if aabbs.len() >= 2 {
            let tree = match &mut self.tree {
                Some(tree) if tree.leaf_count() as usize == aabbs.len() => {
                    for (i, aabb) in aabbs.iter().enumerate() {
                        tree.update_partially_if_present(*aabb, i as u32, 0.0);
                    }
                    tree.refit_without_opt();
                    tree
                }
                slot => slot.insert(Bvh::from_leaves(BvhBuildStrategy::Binned, aabbs)),
            };
            tree.traverse_bvtt_single_tree::<false>(&mut self.workspace, &mut |a, b| {
                let pair = (a.min(b), a.max(b));
                if keep(pair.0, pair.1) {
                    out.push(pair);
                }
            });
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
}
