//! Rolling resistance: a property of the contact material, the same for every solver
//! that offers it (the multibody and both improved particle solvers; the paper's solver
//! stays as the paper wrote it, without).
//!
//! A contact of a round body resists the relative rotation of its two sides with an
//! angular impulse of at most `ρ r λₙ`: ρ = [`ROLLING_RESISTANCE`], r the rolling radius
//! of the round side ([`Shape::rolling_radius`], the larger of the two where both roll)
//! and λₙ the contact's normal impulse (Box2D v3's `rollingResistance`, there in 2D;
//! here the whole relative angular velocity is resisted, as a 3D rolling-and-pivoting
//! friction). It stands for the deformation of real contacts, which a rigid round body
//! lacks: without it a capsule on a level floor never stops rolling and its island
//! never sleeps.
//!
//! A body rolling without slipping on a level floor then decelerates uniformly: with the
//! floor's friction `f` and the resisting torque `ρ r m g`, `m a = −f` and
//! `I α = f r − ρ r m g` with `a = α r` give `a = −ρ g / (1 + I / (m r²))`, I the
//! moment of inertia about the rolling axis through the centre of mass.

use super::collider::BodyCollider;
use super::desc::Shape;

/// Rolling resistance coefficient (dimensionless): the lever arm of the resisting
/// torque over the rolling radius. 0.005 is between a steel wheel on rail (0.001) and
/// a tyre on concrete (0.01–0.02): it stops scene 9's rolling head and obstacle within
/// seconds; on the multibody, larger values (0.01–0.03, measured) let the limbs land
/// differently enough that a hard limit is pushed past 2°.
pub const ROLLING_RESISTANCE: f32 = 0.005;

/// Rolling radius of a round body of `radius` and `half_height` along its axis: its
/// smallest half extent, the radius of "resting on its flattest side" (a cylinder
/// flatter than it is wide rests on a face, and its half height is the lever).
fn round(half_height: f32, radius: f32) -> f32 {
    radius.min(half_height)
}

impl Shape {
    /// The radius the shape rolls on: a capsule's radius, a cylinder's or cone's
    /// smallest half extent; 0 for a box or hull, which do not roll (their rotation on
    /// a contact is resisted by its points' friction).
    pub fn rolling_radius(&self) -> f32 {
        match *self {
            Shape::Capsule { radius, .. } => radius,
            Shape::Cylinder {
                half_height,
                radius,
                ..
            }
            | Shape::Cone {
                half_height,
                radius,
                ..
            } => round(half_height, radius),
            Shape::Box { .. } | Shape::ConvexHull { .. } => 0.0,
        }
    }
}

impl BodyCollider {
    /// [`Shape::rolling_radius`] of the shape this collider was made from.
    pub fn rolling_radius(&self) -> f32 {
        match self {
            BodyCollider::Capsule { radius, .. } => *radius,
            BodyCollider::Cylinder(c) => round(c.half_height, c.radius),
            BodyCollider::Cone(c) => round(c.half_height, c.radius),
            BodyCollider::Cuboid(_) | BodyCollider::Shared(_) => 0.0,
        }
    }
}

/// `ρ r` of a contact between sides of rolling radii `radius_a` and `radius_b` (0 for
/// a side that does not roll, and for the ground): the most angular impulse the
/// contact resists rolling with, per unit of its normal impulse (m).
pub fn rolling_arm(radius_a: f32, radius_b: f32) -> f32 {
    ROLLING_RESISTANCE * radius_a.max(radius_b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{BodyDesc, MassSpec, Pose};
    use glam::Vec3;

    /// Shape and collider agree on every primitive, and the round ones roll on what
    /// their half extents say.
    #[test]
    fn shape_and_collider_give_the_same_rolling_radius() {
        let shapes = [
            (
                Shape::Box {
                    half_extents: Vec3::new(0.1, 0.2, 0.3),
                },
                0.0,
            ),
            (
                Shape::Capsule {
                    half_height: 0.25,
                    radius: 0.07,
                },
                0.07,
            ),
            (
                Shape::Cylinder {
                    half_height: 0.3,
                    radius: 0.1,
                    sides: 0,
                },
                0.1,
            ),
            (
                Shape::Cylinder {
                    half_height: 0.02,
                    radius: 0.1,
                    sides: 0,
                },
                0.02,
            ),
            (
                Shape::Cone {
                    half_height: 0.3,
                    radius: 0.1,
                    sides: 0,
                },
                0.1,
            ),
        ];
        for (shape, radius) in shapes {
            let desc = BodyDesc::new("b", shape.clone(), Pose::IDENTITY, MassSpec::Mass(1.0));
            let held = BodyCollider::new(&desc).expect("a primitive is held");
            assert_eq!(shape.rolling_radius(), radius, "{shape:?}");
            assert_eq!(held.rolling_radius(), radius, "{shape:?}");
            if radius > 0.0 {
                assert_eq!(
                    radius,
                    shape.local_half_extents().min_element(),
                    "{shape:?}"
                );
            }
        }
        assert_eq!(rolling_arm(0.07, 0.0), ROLLING_RESISTANCE * 0.07);
        assert_eq!(rolling_arm(0.0, 0.0), 0.0);
    }
}
