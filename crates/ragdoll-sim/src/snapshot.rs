//! The render snapshot: what a method shows, the same way for both methods.
//!
//! The app draws only this. A method fills it each frame from its own state; the
//! vectors are reused between frames (`clear` then push), so drawing allocates nothing
//! in steady state.

use crate::scene::{BodyId, Pose, Shape};
use glam::Vec3;

/// What a drawn body is, for colouring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyRole {
    /// A moving body.
    Dynamic,
    /// A fixed body.
    Fixed,
    /// A dynamic body that is asleep.
    Asleep,
    /// A body the user is dragging.
    Grabbed,
    /// A box shot from the camera (`B`).
    Projectile,
}

/// One body to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyInstance {
    /// The body (scene bodies first, then projectiles in the order they were added).
    pub body: BodyId,
    /// Its shape, in the shape frame.
    pub shape: Shape,
    /// World pose of the shape frame.
    pub pose: Pose,
    /// Role, for colouring.
    pub role: BodyRole,
}

/// What a particle is, for colouring (the paper's figure 31: green shared, red internal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParticleRole {
    /// Shared by two bones or tied to another bone's joint point.
    Joint,
    /// Internal to one bone.
    Internal,
    /// Belongs to a fixed bone.
    Fixed,
}

/// One particle to draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleInstance {
    /// World position.
    pub position: Vec3,
    /// Role, for colouring.
    pub role: ParticleRole,
}

/// What a stick is, for colouring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StickRole {
    /// One of a bone's six tetrahedron edges.
    Bone,
    /// A joint coupling.
    Joint,
    /// A limit stick (paper mode), drawn only when active.
    Limit,
}

/// One stick to draw, as a line segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StickInstance {
    /// First end.
    pub a: Vec3,
    /// Second end.
    pub b: Vec3,
    /// Role.
    pub role: StickRole,
}

/// One contact point to draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactInstance {
    /// World point.
    pub point: Vec3,
    /// Normal (unit, from the first shape to the second).
    pub normal: Vec3,
    /// Penetration depth (m, ≥ 0 when overlapping).
    pub depth: f32,
}

/// A joint limit to draw (the Doom 3 seed's `af_showLimits`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LimitShape {
    /// No limit.
    None,
    /// A cone of `half_angle` around `axis` at the anchor.
    Cone {
        /// World axis.
        axis: Vec3,
        /// Half-angle (radians).
        half_angle: f32,
    },
    /// A hinge range: the arc from `min` to `max` radians about `axis`, starting from
    /// `reference` (a world direction perpendicular to the axis, angle zero).
    Arc {
        /// World hinge axis.
        axis: Vec3,
        /// World direction of angle zero.
        reference: Vec3,
        /// Lower bound (radians).
        min: f32,
        /// Upper bound (radians).
        max: f32,
    },
}

/// One joint to draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointInstance {
    /// Anchor as seen from body1 (world).
    pub anchor: Vec3,
    /// Anchor as seen from body2 or the world; differs from `anchor` by the joint gap.
    pub anchor2: Vec3,
    /// The limit, if any.
    pub limit: LimitShape,
}

/// Everything a method shows in one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderSnapshot {
    /// Bodies as lit shapes.
    pub bodies: Vec<BodyInstance>,
    /// Particles (particle method only).
    pub particles: Vec<ParticleInstance>,
    /// Sticks (particle method only).
    pub sticks: Vec<StickInstance>,
    /// Contacts of the last step.
    pub contacts: Vec<ContactInstance>,
    /// Joints with their limits.
    pub joints: Vec<JointInstance>,
}

impl RenderSnapshot {
    /// Empties every list, keeping the allocations.
    pub fn clear(&mut self) {
        self.bodies.clear();
        self.particles.clear();
        self.sticks.clear();
        self.contacts.clear();
        self.joints.clear();
    }
}

impl RenderSnapshot {
    /// The scene's bodies at their rest pose, as a method would show them before its first
    /// step: fixed bodies as [`BodyRole::Fixed`], the rest as [`BodyRole::Dynamic`]. No
    /// particles, sticks, contacts or joints: those belong to a method.
    pub fn from_scene_rest(scene: &crate::SceneDesc) -> RenderSnapshot {
        let bodies = scene
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| BodyInstance {
                body: BodyId(i as u32),
                shape: b.shape.clone(),
                pose: b.pose,
                role: if b.is_fixed() {
                    BodyRole::Fixed
                } else {
                    BodyRole::Dynamic
                },
            })
            .collect();
        RenderSnapshot {
            bodies,
            ..RenderSnapshot::default()
        }
    }
}
