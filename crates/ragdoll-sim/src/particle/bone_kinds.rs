//! What bones share, kept once: the shape (a [`BoneKind`]), where the particles and
//! the shape sit in the bone frame (a [`Placement`]), and the contact and air materials
//! (a [`Material`]).
//!
//! A bone's motion and sleep state are its own ([`Bone`]); its shape and materials are
//! the same for every bone built from the same body description, and so are its rest
//! corners and shape frame where they are functions of the shape and its mass
//! distribution ([`placement`](super::placement)). A pile of a thousand humans has
//! sixteen kinds and sixteen placements, one per limb, each bone naming its kind,
//! placement and material by index, instead of a thousand copies of each.
//!
//! Kinds, placements and materials are equal when their fields are bit for bit equal,
//! so sharing one changes no number a solver reads. The paper solver's bones measure
//! their rest corners and shape frame from the world particles they placed, and
//! rounding makes those of two bones differ: each such bone keeps a placement of its
//! own (80 bytes) and shares its kind with every bone of the same description. A bone
//! names its kind and its placement apart, so a reader of either reads one dense
//! array at the bone's index into it.

use super::bone::Bone;
use crate::scene::{BodyCollider, Pose, Shape};
use glam::Vec3;
use std::collections::HashMap;

/// What every bone of one kind holds alike, built from the body's description alone:
/// the cold data of a bone, read at collision detection, drawing and measurement,
/// never in the substeps but for a capsule's rolled contact point
/// (`bone::rolled_point`).
#[derive(Clone)]
pub(crate) struct BoneKind {
    /// Collision shape, in the shape frame.
    pub shape: BodyCollider,
    /// Centre of mass in the shape frame.
    pub shape_com: Vec3,
    /// The shape as described, for drawing.
    pub drawn: Shape,
}

/// Where a bone's particles and shape sit in its frame: 80 bytes.
#[derive(Clone)]
pub(crate) struct Placement {
    /// Particle positions in the bone frame at rest. Its particles' indices and its
    /// sticks' rest lengths are not kept here: the paper solver keeps its own
    /// ([`Particles::of_bone`](super::particles::Particles::of_bone) and
    /// [`paper::PaperState`](super::paper::PaperState)), XPBD's are `4i..4i + 4`, and the
    /// rigid-frames solver's four corners are evaluated from `rest`, whose distances
    /// are its sticks' lengths ([`Bone::rest_stick_lengths`]).
    pub rest: [Vec3; 4],
    /// The shape frame expressed in the bone frame.
    pub shape_in_bone: Pose,
}

const _: () = assert!(std::mem::size_of::<Placement>() == 80);

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

/// The kinds, placements and materials of a world's bones, each kept once
/// ([`Bone::kind`], [`Bone::placement`], [`Bone::material`] index them).
#[derive(Default)]
pub(crate) struct BoneKinds {
    kinds: Vec<BoneKind>,
    placements: Vec<Placement>,
    materials: Vec<Material>,
    /// While the world is built: each kind's, placement's and material's bits to its
    /// index, so that equal ones are kept once. Dropped by [`BoneKinds::seal`]: a body
    /// added later (a projectile) gets a kind, a placement and a material of its own.
    index: Option<Index>,
}

/// The bits of the kinds, placements and materials kept so far, to their indices.
#[derive(Default)]
struct Index {
    kinds: HashMap<Vec<u32>, u32>,
    placements: HashMap<[u32; PLACEMENT_FLOATS], u32>,
    materials: HashMap<[u32; 4], u32>,
}

/// The floats of a placement: four rest corners, the shape frame's origin and
/// orientation.
const PLACEMENT_FLOATS: usize = 4 * 3 + 3 + 4;

impl BoneKinds {
    /// An empty table that shares equal kinds, placements and materials until
    /// [`BoneKinds::seal`].
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
        self.placements.shrink_to_fit();
        self.materials.shrink_to_fit();
    }

    /// The kind of bone `b`.
    #[inline]
    pub fn of(&self, b: &Bone) -> &BoneKind {
        &self.kinds[b.kind as usize]
    }

    /// The placement of bone `b`: its rest corners and shape frame.
    #[inline]
    pub fn placement(&self, b: &Bone) -> &Placement {
        &self.placements[b.placement as usize]
    }

    /// The placement of bone `b`, to change: only for one no other bone shares, one
    /// added after [`BoneKinds::seal`].
    pub fn placement_mut(&mut self, b: &Bone) -> &mut Placement {
        debug_assert!(self.index.is_none(), "a placement shared while building");
        &mut self.placements[b.placement as usize]
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

    /// The index of `placement`: an equal one's while building, else a new one.
    pub fn placement_index(&mut self, placement: Placement) -> u32 {
        let next = self.placements.len() as u32;
        let index = match &mut self.index {
            Some(ix) => *ix
                .placements
                .entry(placement_bits(&placement))
                .or_insert(next),
            None => next,
        };
        if index == next {
            self.placements.push(placement);
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

/// Every bit of a placement: the floats of its rest corners and shape frame.
fn placement_bits(p: &Placement) -> [u32; PLACEMENT_FLOATS] {
    let s = &p.shape_in_bone;
    let mut bits = [0u32; PLACEMENT_FLOATS];
    let floats = p.rest.iter().flat_map(|r| r.to_array());
    let floats = floats
        .chain(s.position.to_array())
        .chain(s.rotation.to_array());
    for (b, f) in bits.iter_mut().zip(floats) {
        *b = f.to_bits();
    }
    bits
}

/// Every bit of a kind that tells it from another: the shape as described (its
/// collider is built from it) and the centre of mass.
fn kind_bits(k: &BoneKind) -> Vec<u32> {
    let mut bits: Vec<u32> = Vec::with_capacity(8);
    bits.extend(k.shape_com.to_array().map(f32::to_bits));
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

    /// Two humans of the pile keep one human's kinds, placements and materials: the
    /// second's bones name the first's, limb by limb, and the tables hold no more than
    /// the first human's distinct ones.
    #[test]
    fn humans_of_a_pile_share_kinds_and_materials() {
        let w = scene_world("pile.af", Some(2));
        assert_eq!(w.bones.len(), 32);
        let (first, second) = w.bones.split_at(16);
        for (i, (a, b)) in first.iter().zip(second).enumerate() {
            assert_eq!(a.kind, b.kind, "bone {i}: a kind of its own");
            assert_eq!(a.placement, b.placement, "bone {i}: a placement of its own");
            assert_eq!(a.material, b.material, "bone {i}: a material of its own");
        }
        let kinds: HashSet<u32> = first.iter().map(|b| b.kind).collect();
        let placements: HashSet<u32> = first.iter().map(|b| b.placement).collect();
        let materials: HashSet<u32> = first.iter().map(|b| b.material).collect();
        assert_eq!(w.kinds.kinds.len(), kinds.len());
        assert_eq!(w.kinds.placements.len(), placements.len());
        assert_eq!(w.kinds.materials.len(), materials.len());
        assert!(w.kinds.index.is_none(), "the index outlives the build");
    }

    /// The paper solver's bones of two humans of the pile: each second human's bone
    /// names the kind of the first human's same limb, and the table keeps only the
    /// first human's kinds, however many placements the rounding of the placed
    /// particles makes; each placement holds the rest corners its bone was built with.
    #[test]
    fn paper_bones_share_kinds() {
        use super::super::ParticleSolver;
        let w = super::super::solver_scene_world("pile.af", Some(2), ParticleSolver::Paper);
        assert_eq!(w.bones.len(), 32);
        let (first, second) = w.bones.split_at(16);
        for (i, (a, b)) in first.iter().zip(second).enumerate() {
            assert_eq!(a.kind, b.kind, "bone {i}: a kind of its own");
        }
        let kinds: HashSet<u32> = first.iter().map(|b| b.kind).collect();
        assert_eq!(w.kinds.kinds.len(), kinds.len());
        for (i, b) in w.bones.iter().enumerate() {
            let x = &w.particles.x;
            let frame = crate::scene::Pose {
                position: glam::Vec3::from(b.com),
                rotation: b.rot,
            };
            let rest = w.particles.of_bone[i].map(|p| frame.inverse_transform_point(x[p as usize]));
            assert!(w.kinds.placement(b).rest == rest, "bone {i}: rest corners");
        }
        println!(
            "{} placements, {} kinds for 32 bones",
            w.kinds.placements.len(),
            w.kinds.kinds.len()
        );
    }
}
