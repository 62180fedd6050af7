//! What bones of one kind share, kept once: the shape and where its particles sit in
//! the bone frame (a [`BoneKind`]), and the contact and air materials (a [`Material`]).
//!
//! A bone's motion and sleep state are its own ([`Bone`]); its shape, the shape frame
//! in the bone frame, the rest corners (a function of the shape and its mass
//! distribution, [`placement`](super::placement)) and its materials are the same for
//! every bone built from the same body description. A pile of a thousand humans has
//! sixteen kinds, one per limb, each bone naming its kind and material by index, instead
//! of a thousand copies of each.
//!
//! Kinds are equal when their fields are bit for bit equal (the shape as described, the
//! rest corners, the shape frame, the centre of mass), so sharing one changes no number
//! a solver reads. The paper solver's bones measure their rest corners from the world
//! particles they placed, and rounding makes those of two bones differ: it shares
//! a kind only where the bits agree.

use super::bone::Bone;
use crate::scene::{BodyCollider, Pose, Shape};
use glam::Vec3;
use std::collections::HashMap;

/// What every bone of one kind holds alike: the cold data of a bone, read at collision
/// detection, drawing and measurement, never in the substeps but for a capsule's
/// rolled contact point (`bone::rolled_point`).
#[derive(Clone)]
pub(crate) struct BoneKind {
    /// Particle positions in the bone frame at rest. Its particles' indices and its
    /// sticks' rest lengths are not kept here: the paper solver keeps its own
    /// ([`Particles::of_bone`](super::particles::Particles::of_bone) and
    /// [`paper::PaperState`](super::paper::PaperState)), XPBD's are `4i..4i + 4`, and the
    /// rigid-frames solver's four corners are evaluated from `rest`, whose distances
    /// are its sticks' lengths ([`Bone::rest_stick_lengths`]).
    pub rest: [Vec3; 4],
    /// The shape frame expressed in the bone frame.
    pub shape_in_bone: Pose,
    /// Collision shape, in the shape frame.
    pub shape: BodyCollider,
    /// Centre of mass in the shape frame.
    pub shape_com: Vec3,
    /// The shape as described, for drawing.
    pub drawn: Shape,
}

/// A body's contact and air materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Material {
    /// Contact friction μ.
    pub friction: f32,
    /// Restitution.
    pub restitution: f32,
    /// Air friction per second (linear, angular).
    pub air: (f32, f32),
}

/// The kinds and materials of a world's bones, each kept once ([`Bone::kind`],
/// [`Bone::material`] index them).
#[derive(Default)]
pub(crate) struct BoneKinds {
    kinds: Vec<BoneKind>,
    materials: Vec<Material>,
    /// While the world is built: each kind's and material's bits to its index, so that
    /// equal ones are kept once. Dropped by [`BoneKinds::seal`]: a body added later
    /// (a projectile) gets a kind and a material of its own.
    index: Option<Index>,
}

/// The bits of the kinds and materials kept so far, to their indices.
#[derive(Default)]
struct Index {
    kinds: HashMap<Vec<u32>, u32>,
    materials: HashMap<[u32; 4], u32>,
}

impl BoneKinds {
    /// An empty table that shares equal kinds and materials until [`BoneKinds::seal`].
    pub fn building() -> BoneKinds {
        BoneKinds {
            index: Some(Index::default()),
            ..BoneKinds::default()
        }
    }

    /// Stops sharing (drops the index) and gives back the room the arrays do not use.
    pub fn seal(&mut self) {
        self.index = None;
        self.kinds.shrink_to_fit();
        self.materials.shrink_to_fit();
    }

    /// The kind of bone `b`.
    #[inline]
    pub fn of(&self, b: &Bone) -> &BoneKind {
        &self.kinds[b.kind as usize]
    }

    /// The kind of bone `b`, to change: only for a kind no other bone shares, one
    /// added after [`BoneKinds::seal`].
    pub fn of_mut(&mut self, b: &Bone) -> &mut BoneKind {
        debug_assert!(self.index.is_none(), "a kind shared while building");
        &mut self.kinds[b.kind as usize]
    }

    /// The materials of bone `b`.
    #[inline]
    pub fn material(&self, b: &Bone) -> &Material {
        &self.materials[b.material as usize]
    }

    /// The index of `kind`: an equal one's while building, else a new one.
    pub fn kind(&mut self, kind: BoneKind) -> u32 {
        let next = self.kinds.len() as u32;
        let index = match &mut self.index {
            Some(ix) => *ix.kinds.entry(kind_bits(&kind)).or_insert(next),
            None => next,
        };
        if index == next {
            self.kinds.push(kind);
        }
        index
    }

    /// The index of `material`: an equal one's while building, else a new one.
    pub fn material_index(&mut self, material: Material) -> u32 {
        let next = self.materials.len() as u32;
        let bits = [
            material.friction,
            material.restitution,
            material.air.0,
            material.air.1,
        ]
        .map(f32::to_bits);
        let index = match &mut self.index {
            Some(ix) => *ix.materials.entry(bits).or_insert(next),
            None => next,
        };
        if index == next {
            self.materials.push(material);
        }
        index
    }
}

/// Every bit of a kind that tells it from another: the shape as described (its
/// collider is built from it) and the floats of the rest corners, shape frame and
/// centre of mass.
fn kind_bits(k: &BoneKind) -> Vec<u32> {
    let mut bits: Vec<u32> = Vec::with_capacity(32);
    let mut floats = |v: &[f32]| bits.extend(v.iter().map(|x| x.to_bits()));
    for r in &k.rest {
        floats(&r.to_array());
    }
    floats(&k.shape_in_bone.position.to_array());
    floats(&k.shape_in_bone.rotation.to_array());
    floats(&k.shape_com.to_array());
    match &k.drawn {
        Shape::Box { half_extents } => {
            bits.push(0);
            bits.extend(half_extents.to_array().map(f32::to_bits));
        }
        Shape::Capsule {
            half_height,
            radius,
        } => bits.extend([1, half_height.to_bits(), radius.to_bits()]),
        Shape::Cylinder {
            half_height,
            radius,
            sides,
        } => bits.extend([2, half_height.to_bits(), radius.to_bits(), *sides]),
        Shape::Cone {
            half_height,
            radius,
            sides,
        } => bits.extend([3, half_height.to_bits(), radius.to_bits(), *sides]),
        Shape::ConvexHull { points } => {
            bits.push(4);
            for p in points.iter() {
                bits.extend(p.to_array().map(f32::to_bits));
            }
        }
    }
    bits
}

#[cfg(test)]
mod tests {
    use super::super::scene_world;
    use std::collections::HashSet;

    /// Two humans of the pile keep one human's kinds and materials: the second's bones
    /// name the first's, limb by limb, and the tables hold no more than the first
    /// human's distinct ones.
    #[test]
    fn humans_of_a_pile_share_kinds_and_materials() {
        let w = scene_world("pile.af", Some(2));
        assert_eq!(w.bones.len(), 32);
        let (first, second) = w.bones.split_at(16);
        for (i, (a, b)) in first.iter().zip(second).enumerate() {
            assert_eq!(a.kind, b.kind, "bone {i}: a kind of its own");
            assert_eq!(a.material, b.material, "bone {i}: a material of its own");
        }
        let kinds: HashSet<u32> = first.iter().map(|b| b.kind).collect();
        let materials: HashSet<u32> = first.iter().map(|b| b.material).collect();
        assert_eq!(w.kinds.kinds.len(), kinds.len());
        assert_eq!(w.kinds.materials.len(), materials.len());
        assert!(w.kinds.index.is_none(), "the index outlives the build");
    }
}
