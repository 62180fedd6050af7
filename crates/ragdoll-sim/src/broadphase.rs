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

/// Appends to `out` every pair `(i, j)`, `i < j`, of overlapping boxes, sorted.
pub fn overlapping_pairs(aabbs: &[Aabb], out: &mut Vec<(u32, u32)>) {
    let start = out.len();
    if aabbs.len() >= 2 {
        let tree = Bvh::from_leaves(BvhBuildStrategy::Binned, aabbs);
        let mut workspace = BvhWorkspace::default();
        tree.traverse_bvtt_single_tree::<false>(&mut workspace, &mut |a, b| {
            out.push((a.min(b), a.max(b)));
        });
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
    }
}
