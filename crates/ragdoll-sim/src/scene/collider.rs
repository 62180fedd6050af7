//! A body's parry collider as the methods hold it between queries: a primitive by its
//! dimensions, made on the spot for each query, and a shape that must be built once
//! (a convex hull) kept and shared.
//!
//! A parry `SharedShape` is an `Arc<dyn Shape>`: 16 bytes in the body and a 32-byte
//! allocation behind it for a box. Made on the spot, a primitive costs a few stores per
//! query and no memory; [`BodyCollider`] holds one in 24 bytes.

use super::SceneError;
use super::desc::{BodyDesc, Shape};
use parry3d::shape::{Capsule, Cone, Cuboid, Cylinder, Shape as ParryShape, SharedShape};

/// A body's collider for one query: a primitive by value or a shape built once (a
/// hull, the ground's half-space); [`Collider::shape`] is what parry's queries take.
pub enum Collider<'a> {
    /// A box.
    Cuboid(Cuboid),
    /// A Y-aligned capsule.
    Capsule(Capsule),
    /// A Y-aligned cylinder.
    Cylinder(Cylinder),
    /// A Y-aligned cone.
    Cone(Cone),
    /// A shape built once and shared: a convex hull, the ground's half-space.
    Shared(&'a SharedShape),
}

impl Collider<'_> {
    /// The shape for parry's queries.
    pub fn shape(&self) -> &dyn ParryShape {
        match self {
            Collider::Cuboid(c) => c,
            Collider::Capsule(c) => c,
            Collider::Cylinder(c) => c,
            Collider::Cone(c) => c,
            Collider::Shared(h) => &***h,
        }
    }

    /// The parry primitive of a scene shape, made by the same constructor as
    /// [`super::collider()`] with the same floats; `None` for a convex hull, which is
    /// built once and kept.
    pub fn primitive(shape: &Shape) -> Option<Collider<'static>> {
        Some(match *shape {
            Shape::Box { half_extents } => Collider::Cuboid(Cuboid::new(half_extents)),
            Shape::Capsule {
                half_height,
                radius,
            } => Collider::Capsule(Capsule::new_y(half_height, radius)),
            Shape::Cylinder {
                half_height,
                radius,
                ..
            } => Collider::Cylinder(Cylinder::new(half_height, radius)),
            Shape::Cone {
                half_height,
                radius,
                ..
            } => Collider::Cone(Cone::new(half_height, radius)),
            Shape::ConvexHull { .. } => return None,
        })
    }
}

/// A body's collider as a body holds it, in 24 bytes: a primitive's dimensions, or the
/// built shape of anything else. [`BodyCollider::get`] gives the shape for a query.
#[derive(Clone)]
pub enum BodyCollider {
    /// A box, by its half extents.
    Cuboid(Cuboid),
    /// A Y-aligned capsule, by its half height and radius (a parry capsule keeps its
    /// two end points: 28 bytes).
    Capsule {
        /// Half the length of the inner segment (m).
        half_height: f32,
        /// Radius (m).
        radius: f32,
    },
    /// A Y-aligned cylinder.
    Cylinder(Cylinder),
    /// A Y-aligned cone.
    Cone(Cone),
    /// A shape built once: a convex hull.
    Shared(SharedShape),
}

impl BodyCollider {
    /// The collider of a body: its primitive's dimensions, or the shape
    /// [`super::collider()`] builds (which fails, naming the body, for a convex hull parry
    /// cannot build).
    pub fn new(body: &BodyDesc) -> Result<BodyCollider, SceneError> {
        Ok(match body.shape {
            Shape::Box { half_extents } => BodyCollider::Cuboid(Cuboid::new(half_extents)),
            Shape::Capsule {
                half_height,
                radius,
            } => BodyCollider::Capsule {
                half_height,
                radius,
            },
            Shape::Cylinder {
                half_height,
                radius,
                ..
            } => BodyCollider::Cylinder(Cylinder::new(half_height, radius)),
            Shape::Cone {
                half_height,
                radius,
                ..
            } => BodyCollider::Cone(Cone::new(half_height, radius)),
            Shape::ConvexHull { .. } => BodyCollider::Shared(super::collider(body)?),
        })
    }

    /// The shape for a query.
    pub fn get(&self) -> Collider<'_> {
        match *self {
            BodyCollider::Cuboid(c) => Collider::Cuboid(c),
            BodyCollider::Capsule {
                half_height,
                radius,
            } => Collider::Capsule(Capsule::new_y(half_height, radius)),
            BodyCollider::Cylinder(c) => Collider::Cylinder(c),
            BodyCollider::Cone(c) => Collider::Cone(c),
            BodyCollider::Shared(ref s) => Collider::Shared(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{MassSpec, Pose, collider};
    use glam::Vec3;

    /// A held primitive gives the very shape `collider` builds: same type, same floats.
    #[test]
    fn held_primitives_match_the_built_shapes() {
        let shapes = [
            Shape::Box {
                half_extents: Vec3::new(0.1, 0.2, 0.3),
            },
            Shape::Capsule {
                half_height: 0.25,
                radius: 0.07,
            },
            Shape::Cylinder {
                half_height: 0.3,
                radius: 0.1,
                sides: 0,
            },
            Shape::Cone {
                half_height: 0.3,
                radius: 0.1,
                sides: 0,
            },
        ];
        for shape in shapes {
            let desc = BodyDesc::new("b", shape.clone(), Pose::IDENTITY, MassSpec::Mass(1.0));
            let built = collider(&desc).expect("a primitive builds");
            let held = BodyCollider::new(&desc).expect("a primitive is held");
            assert!(
                !matches!(held, BodyCollider::Shared(_)),
                "{shape:?} is held by value"
            );
            let (a, b) = (held.get(), built);
            let (a, b) = (a.shape(), b.as_ref());
            assert_eq!(a.shape_type(), b.shape_type());
            assert_eq!(a.compute_local_aabb(), b.compute_local_aabb(), "{shape:?}");
            assert_eq!(a.mass_properties(1.0), b.mass_properties(1.0), "{shape:?}");
        }
    }
}
