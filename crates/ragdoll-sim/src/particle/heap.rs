//! Where a particle world's heap bytes go: each array it keeps between steps, by owner,
//! as `capacity × size_of::<T>()` plus what its elements own in turn (a joint's angle
//! limits, a parry manifold's points; not a convex hull's parry shape, behind an `Arc`). Bytes
//! a step allocates and frees within itself are not held and not listed. The memory
//! bench counts what the allocator hands out; the difference from this list's sum is
//! what no array here owns (allocator rounding is in neither).

use super::ParticleWorld;
use parry3d::query::{ContactManifold, TrackedContact};
use std::mem::size_of;

/// The bytes a `Vec`'s buffer holds (its capacity) and uses (its length).
pub(crate) fn vec<T>(v: &Vec<T>) -> Bytes {
    Bytes {
        held: v.capacity() * size_of::<T>(),
        used: v.len() * size_of::<T>(),
    }
}

/// Heap bytes held (allocated) and used (in elements) by one or more arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Bytes {
    pub held: usize,
    pub used: usize,
}

impl std::ops::Add for Bytes {
    type Output = Bytes;
    fn add(self, o: Bytes) -> Bytes {
        Bytes {
            held: self.held + o.held,
            used: self.used + o.used,
        }
    }
}

impl std::iter::Sum for Bytes {
    fn sum<I: Iterator<Item = Bytes>>(it: I) -> Bytes {
        it.fold(Bytes::default(), |a, b| a + b)
    }
}

/// A kept list of parry manifolds and the point arrays they own.
pub(crate) fn manifolds(v: &Vec<ContactManifold<(), ()>>) -> Bytes {
    vec(v)
        + v.iter()
            .map(|m| Bytes {
                held: m.points.capacity() * size_of::<TrackedContact<()>>(),
                used: m.points.len() * size_of::<TrackedContact<()>>(),
            })
            .sum::<Bytes>()
}

/// One owner's bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HeapOwner {
    /// The array, by its field path in the world.
    pub name: &'static str,
    /// Heap bytes it holds (its buffer's capacity and what its elements own).
    pub bytes: usize,
    /// Of those, the bytes its elements fill (its length); the rest is room.
    pub used: usize,
}

impl ParticleWorld {
    /// The world's heap bytes by owner, largest first ([module doc](self)): what the
    /// memory bench's total is made of, so that the largest owners can be cut.
    pub fn heap_owners(&self) -> Vec<HeapOwner> {
        let mut out = Vec::new();
        let mut add = |name: &'static str, b: Bytes| {
            if b.held > 0 {
                out.push(HeapOwner {
                    name,
                    bytes: b.held,
                    used: b.used,
                });
            }
        };
        add("shapes", vec(&self.shapes));
        add("bones", vec(&self.bones));
        add("frame_starts", vec(&self.frame_starts));
        add("joints", vec(&self.joints));
        add(
            "joints.angle_limits",
            self.joints
                .iter()
                .map(|j| vec(&j.angle_limits))
                .sum::<Bytes>(),
        );
        add("links", vec(&self.links));
        add("filter", self.filter.heap_bytes());
        add("contacts.manifolds", vec(&self.contacts.manifolds));
        add("contacts.points", vec(&self.contacts.points));
        add("pairs", vec(&self.pairs));
        add("manifolds (parry scratch)", manifolds(&self.manifolds));
        add("kinematic", vec(&self.kinematic));
        add("motors", vec(&self.motors));
        let p = &self.particles;
        add(
            "particles",
            vec(&p.x)
                + vec(&p.x_prev)
                + vec(&p.frame_start)
                + vec(&p.mass)
                + vec(&p.inv_mass)
                + vec(&p.joint)
                + vec(&p.of_bone),
        );
        if let Some(st) = &self.paper {
            add("paper.sticks", vec(&st.sticks));
            add("paper.first_stick", vec(&st.first_stick));
            add("paper.hinges", vec(&st.hinges));
            add("paper.cones", vec(&st.cones));
        }
        if let Some(st) = &self.xpbd {
            let p = &st.particles;
            add("xpbd.particles.x", vec(&p.x));
            add("xpbd.particles.x_prev", vec(&p.x_prev));
            add("xpbd.particles.v", vec(&p.v));
            add("xpbd.particles.mass+w", vec(&p.mass) + vec(&p.w));
            add("xpbd.particles.start.centre", vec(&p.start.centre));
            add("xpbd.particles.start.arm", vec(&p.start.arm));
            add(
                "xpbd.particles.start.inv_inertia",
                vec(&p.start.inv_inertia),
            );
            add("xpbd.rest_inv", vec(&st.rest_inv));
            add("xpbd.anchors", vec(&st.anchors));
            add("xpbd.joint_start", vec(&st.joint_start));
            add("xpbd.contacts", vec(&st.contacts));
            add("xpbd.rest", vec(&st.rest));
            for (name, bytes) in st.scratch.heap_owners() {
                add(name, bytes);
            }
        }
        out.sort_by(|a, b| b.bytes.cmp(&a.bytes).then(a.name.cmp(b.name)));
        out
    }
}
