//! Scene description (the seam between file formats and methods) and its readers.
//!
//! - [`desc`]: `SceneDesc` and everything in it, plain data.
//! - [`mass`]: mass properties from shapes, shared by both methods.
//! - `lexer` and `file_error`: the tokens of Doom 3's text formats with their positions,
//!   and [`AfError`], the positioned error, shared by the four readers below (which
//!   depend on these two and not on each other's internals).
//! - [`af`]: the Doom 3 articulated-figure reader with our extensions.
//! - [`md5mesh`]: `.md5mesh` skeletons (the bind pose `joint("name")` reads) and meshes.
//! - [`md5anim`]: `.md5anim` animations and their frames' joint poses.
//! - [`decl`]: Doom 3 `.def` declarations: entities, models, where figures are.
//! - [`rig`]: skeleton joints from body poses (how a figure's bodies move its mesh).
//! - [`skin`]: the skinned mesh on the CPU, segment casts against it, the body a hit
//!   pushes.
//! - `rolling`: rolling resistance, the contact material's one definition for every
//!   solver ([`ROLLING_RESISTANCE`], [`Shape::rolling_radius`], [`rolling_arm`]).
//! - [`takeover`]: a figure placed on an animation with the animation's velocities.
//! - `transform`: moving a whole scene (or one body, one joint) by a rigid transform,
//!   and putting its bodies in a new pose with the joints re-expressed (`repose`).

pub mod af;
pub mod collider;
pub mod decl;
pub mod desc;
mod file_error;
pub(crate) mod lexer;
pub mod mass;
pub mod md5anim;
pub mod md5mesh;
mod pyramid;
pub mod rig;
mod rolling;
pub mod skin;
pub mod takeover;
mod transform;
mod validate;

pub use collider::{BodyCollider, Collider};
pub use desc::*;
pub use file_error::AfError;
pub use mass::{MassProps, collider, mass_props, scene_mass_props};
pub use pyramid::pyramid_sides;
pub use rolling::{ROLLING_RESISTANCE, rolling_arm};
pub use validate::validate;

use thiserror::Error;

/// Why a `SceneDesc` cannot be simulated. The file readers have their own positioned
/// error type, [`AfError`]; this one is for descriptions built in code or after reading.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SceneError {
    /// A body's shape or mass is unusable.
    #[error("body \"{body}\" is degenerate: {what}")]
    Degenerate {
        /// Body name.
        body: String,
        /// What is wrong.
        what: String,
    },
    /// A constraint is unusable.
    #[error("constraint \"{constraint}\" is invalid: {what}")]
    BadConstraint {
        /// Constraint name.
        constraint: String,
        /// What is wrong.
        what: String,
    },
    /// A setting is out of range.
    #[error("setting {setting} is invalid: {what}")]
    BadSetting {
        /// Setting name.
        setting: &'static str,
        /// What is wrong.
        what: String,
    },
}
