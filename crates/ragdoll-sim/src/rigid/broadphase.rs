//! Sort-and-sweep broad phase on parry3d AABBs: O(n log n), deterministic, no
//! allocation once the arrays have grown.
//!
//! Bodies are sorted by the lower x bound of their (loosened) AABB; a sweep reports
//! every pair whose intervals overlap on x and whose boxes overlap on y and z. The
//! ground is an infinite plane and is tested against every body separately.

use parry3d::bounding_volume::{Aabb, BoundingVolume};

/// Reusable broad-phase arrays.
#[derive(Clone, Debug, Default)]
pub struct BroadPhase {
    order: Vec<u32>,
}

impl BroadPhase {
    /// Appends to `out` every pair `(i, j)`, `i < j`, of overlapping boxes, sorted.
    pub fn pairs(&mut self, aabbs: &[Aabb], out: &mut Vec<(u32, u32)>) {
        self.order.clear();
        self.order.extend(0..aabbs.len() as u32);
        // Ties broken by index: the order, hence the pair list, is reproducible.
        self.order.sort_unstable_by(|&i, &j| {
            aabbs[i as usize]
                .mins
                .x
                .total_cmp(&aabbs[j as usize].mins.x)
                .then(i.cmp(&j))
        });
        let start = out.len();
        for (k, &i) in self.order.iter().enumerate() {
            let a = &aabbs[i as usize];
            for &j in &self.order[k + 1..] {
                let b = &aabbs[j as usize];
                if b.mins.x > a.maxs.x {
                    break;
                }
                if a.intersects(b) {
                    out.push((i.min(j), i.max(j)));
                }
            }
        }
        out[start..].sort_unstable();
    }
}
