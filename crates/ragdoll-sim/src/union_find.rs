//! Union–find over dense indices (bodies, bones): how both methods find islands, the
//! bodies linked by joints or touching contacts, for sleeping and for dealing work to
//! threads (`rigid::island`, `particle::islands`, `particle::sleeping`,
//! `particle::xpbd::sleeping`).
//!
//! Invariant: the root of a set is its lowest index. [`UnionFind::union`] makes the
//! smaller of the two roots the root of both, so a set's root does not depend on the
//! order its links were added in — islands named by their roots, and walked in the
//! order of their roots, come out the same however the links were listed, which the
//! methods' determinism across thread counts relies on. [`UnionFind::find`] halves
//! the path on the way up (each node visited points to its grandparent after), which
//! changes the shape of a tree and never its root.

/// Disjoint sets over `0..len()`, each index at first a set of its own.
#[derive(Clone, Debug, Default)]
pub(crate) struct UnionFind {
    /// Per index: its parent, itself at a root.
    parent: Vec<u32>,
}

impl UnionFind {
    /// `n` sets of one index each.
    pub(crate) fn new(n: usize) -> UnionFind {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }

    /// The number of indices.
    pub(crate) fn len(&self) -> usize {
        self.parent.len()
    }

    /// Adds index `len()` as a set of its own.
    pub(crate) fn push(&mut self) {
        self.parent.push(self.parent.len() as u32);
    }

    /// Makes every index a set of its own again, keeping the length.
    pub(crate) fn reset(&mut self) {
        for (i, p) in self.parent.iter_mut().enumerate() {
            *p = i as u32;
        }
    }

    /// The root of `i`'s set (its lowest index), halving the path on the way.
    pub(crate) fn find(&mut self, i: usize) -> usize {
        let mut i = i as u32;
        while self.parent[i as usize] != i {
            let up = self.parent[self.parent[i as usize] as usize];
            self.parent[i as usize] = up;
            i = up;
        }
        i as usize
    }

    /// Joins the sets of `a` and `b`; the lower of the two roots stays the root.
    pub(crate) fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            self.parent[hi] = lo as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::UnionFind;

    /// The root is the lowest index of the set whatever the order of the unions, and
    /// sets not joined stay apart.
    #[test]
    fn the_root_is_the_lowest_index_in_any_link_order() {
        let links = [(5, 3), (3, 7), (7, 1), (2, 6), (8, 6)];
        let mut forward = UnionFind::new(9);
        links.iter().for_each(|&(a, b)| forward.union(a, b));
        let mut backward = UnionFind::new(9);
        links.iter().rev().for_each(|&(a, b)| backward.union(b, a));
        let expected = [0, 1, 2, 1, 4, 1, 2, 1, 2];
        for (i, &root) in expected.iter().enumerate() {
            assert_eq!(forward.find(i), root, "index {i}, links in order");
            assert_eq!(backward.find(i), root, "index {i}, links reversed");
        }
    }

    /// `reset` and `push` give sets of one index each.
    #[test]
    fn reset_and_push_make_single_sets() {
        let mut u = UnionFind::new(3);
        u.union(0, 2);
        u.push();
        assert_eq!((u.len(), u.find(2), u.find(3)), (4, 0, 3));
        u.union(3, 1);
        u.reset();
        assert!((0..4).all(|i| u.find(i) == i));
    }
}
