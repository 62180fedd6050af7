//! What bones of one kind share, kept once: the shape ([`BoneShape`]), where the
//! shape and the particles sit in the bone frame ([`Placement`]), and the contact and
//! air materials ([`Material`]).
//!
//! A bone's motion and sleep state are its own ([`Bone`]); its shape, the shape frame
//! in the bone frame, the rest corners (a function of the shape and its mass
//! distribution, [`placement`](super::placement)) and its materials are the same for
//! every bone built from the same body description. A pile of a thousand humans has
//! sixteen kinds, one per limb, each bone naming its kind and material by index, instead
//! of a thousand copies of each.
//!
//! Placements and shapes are equal when their fields are bit for bit equal (the shape
//! as described and its centre of mass; the rest corners and the shape frame), so
//! sharing one changes no number a solver reads. The paper solver's bones measure their
//! rest corners and shape frame from the world particles they placed, and rounding makes
//! those of two bones differ: each such bone keeps a placement of its own (80 bytes)
//! and shares its shape with every bone of the same description.

use super::bone::Bone;
use crate::scene::{BodyCollider, Pose, Shape};
use glam::{Quat, Vec3};
use std::collections::HashMap;

/// A bone's kind as the code reads it ([`BoneKinds::of`]): its placement's rest corners
/// and shape frame, and its shape's collider, centre of mass and drawn shape. The cold
/// data of a bone, read at collision detection, drawing and measurement, never in the
/// substeps but for a capsule's rolled contact point (`bone::rolled_point`).
#[derive(Clone, Copy)]
pub(crate) struct BoneKind<'a> {
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
    pub shape: &'a BodyCollider,
    /// Centre of mass in the shape frame.
    pub shape_com: Vec3,
    /// The shape as described, for drawing.
    pub drawn: &'a Shape,
}

/// What every bone of one shape holds alike: built from the body's description alone.
#[derive(Clone)]
pub(crate) struct BoneShape {
    /// Collision shape, in the shape frame.
    pub shape: BodyCollider,
    /// Centre of mass in the shape frame.
    pub shape_com: Vec3,
    /// The shape as described, for drawing.
    pub drawn: Shape,
}

/// Where a bone's particles and shape sit in its frame, and which shape it has: 80
/// bytes (the shape frame kept as its two parts, so the shape's index packs beside its
/// 12-byte position instead of padding a [`Pose`] to 32).
#[derive(Clone)]
pub(crate) struct Placement {
    /// Particle positions in the bone frame at rest ([`BoneKind::rest`]).
    pub rest: [Vec3; 4],
    /// The shape frame's origin in the bone frame.
    shape_at: Vec3,
    /// Index of its [`BoneShape`].
    shape: u32,
    /// The shape frame's orientation in the bone frame.
    shape_turn: Quat,
}

const _: () = assert!(std::mem::size_of::<Placement>() == 80);

impl Placement {
    /// The shape frame expressed in the bone frame.
    #[inline]
    pub fn shape_in_bone(&self) -> Pose {
        Pose {
            position: self.shape_at,
            rotation: self.shape_turn,
        }
    }

    /// Sets the shape frame expressed in the bone frame.
    pub fn set_shape_in_bone(&mut self, p: Pose) {
        self.shape_at = p.position;
        self.shape_turn = p.rotation;
    }
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

/// The kinds and materials of a world's bones, each kept once ([`Bone::kind`] indexes
/// the placements, each placement its shape; [`Bone::material`] the materials).
#[derive(Default)]
pub(crate) struct BoneKinds {
    placements: Vec<Placement>,
    shapes: Vec<BoneShape>,
    materials: Vec<Material>,
    /// While the world is built: each placement's, shape's and material's bits to its
    /// index, so that equal ones are kept once. Dropped by [`BoneKinds::seal`]: a body
    /// added later (a projectile) gets a kind and a material of its own.
    index: Option<Index>,
}

/// The bits of the placements, shapes and materials kept so far, to their indices.
#[derive(Default)]
struct Index {
    placements: HashMap<Vec<u32>, u32>,
    shapes: HashMap<Vec<u32>, u32>,
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
        self.placements.shrink_to_fit();
        self.shapes.shrink_to_fit();
        self.materials.shrink_to_fit();
    }

    /// The kind of bone `b`.
    #[inline]
    pub fn of(&self, b: &Bone) -> BoneKind<'_> {
        let p = &self.placements[b.kind as usize];
        let s = &self.shapes[p.shape as usize];
        BoneKind {
            rest: p.rest,
            shape_in_bone: p.shape_in_bone(),
            shape: &s.shape,
            shape_com: s.shape_com,
            drawn: &s.drawn,
        }
    }

    /// The placement of bone `b`, to change: only for one no other bone shares, one
    /// added after [`BoneKinds::seal`].
    pub fn of_mut(&mut self, b: &Bone) -> &mut Placement {
        debug_assert!(self.index.is_none(), "a kind shared while building");
        &mut self.placements[b.kind as usize]
    }

    /// The materials of bone `b`.
    #[inline]
    pub fn material(&self, b: &Bone) -> &Material {
        &self.materials[b.material as usize]
    }

    /// The index of the kind with rest corners `rest`, shape frame `shape_in_bone` and
    /// shape `shape`: an equal one's while building (placement and shape each), else
    /// a new one.
    pub fn kind(&mut self, rest: [Vec3; 4], shape_in_bone: Pose, shape: BoneShape) -> u32 {
        let next = self.shapes.len() as u32;
        let shape_index = match &mut self.index {
            Some(ix) => *ix.shapes.entry(shape_bits(&shape)).or_insert(next),
            None => next,
        };
        if shape_index == next {
            self.shapes.push(shape);
        }
        let placement = Placement {
            rest,
            shape_at: shape_in_bone.position,
            shape: shape_index,
            shape_turn: shape_in_bone.rotation,
        };
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

/// Every bit of a placement that tells it from another: the floats of the rest
/// corners and shape frame, and its shape's index.
fn placement_bits(p: &Placement) -> Vec<u32> {
    let mut bits: Vec<u32> = Vec::with_capacity(20);
    for r in &p.rest {
        bits.extend(r.to_array().map(f32::to_bits));
    }
    bits.extend(p.shape_at.to_array().map(f32::to_bits));
    bits.extend(p.shape_turn.to_array().map(f32::to_bits));
    bits.push(p.shape);
    bits
}

/// Every bit of a shape that tells it from another: the shape as described (its
/// collider is built from it) and the centre of mass.
fn shape_bits(k: &BoneShape) -> Vec<u32> {
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
        assert_eq!(w.kinds.placements.len(), kinds.len());
        assert!(w.kinds.shapes.len() <= kinds.len());
        assert_eq!(w.kinds.materials.len(), materials.len());
        assert!(w.kinds.index.is_none(), "the index outlives the build");
    }

    /// The paper solver's bones of two humans of the pile: each second human's bone
    /// names the shape of the first human's same limb, and the table keeps only the
    /// first human's shapes, however many placements the rounding of the placed
    /// particles makes.
    #[test]
    fn paper_bones_share_shapes() {
        use super::super::{ParticleSolver, ParticleWorld};
        use crate::scene::af::{AfOptions, parse};
        let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/scenes/pile.af");
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
        let opts = AfOptions {
            count: Some(2),
            ..AfOptions::default()
        };
        let scene = parse(&text, &path, &opts)
            .unwrap_or_else(|e| panic!("{e}"))
            .desc;
        let w = ParticleWorld::new(&scene, ParticleSolver::Paper).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(w.bones.len(), 32);
        let shape = |b: &super::Bone| w.kinds.placements[b.kind as usize].shape;
        let (first, second) = w.bones.split_at(16);
        for (i, (a, b)) in first.iter().zip(second).enumerate() {
            assert_eq!(shape(a), shape(b), "bone {i}: a shape of its own");
        }
        let shapes: HashSet<u32> = first.iter().map(shape).collect();
        assert_eq!(w.kinds.shapes.len(), shapes.len());
        println!(
            "{} placements, {} shapes for 32 bones",
            w.kinds.placements.len(),
            w.kinds.shapes.len()
        );
    }
}
