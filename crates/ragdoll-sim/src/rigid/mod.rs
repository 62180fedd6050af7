//! The impulse-based multibody method (right, red): maximal coordinates, rigid bodies,
//! joints and contacts solved with impulses by Box2D v3's soft step.
//!
//! - [`body`]: hot body arrays (SoA) and cold body data.
//! - [`integrate`]: semi-implicit Euler with the implicit gyroscopic term.
//! - [`soft`]: soft-constraint coefficients.
//! - [`joint`]: building blocks every joint is made of; [`limits`]: swing, twist, ranges.
//! - [`ball`], [`hinge`], [`universal`], [`fixed`], [`slider`], [`spring`]: one file per
//!   joint type; [`joint_set`]: the arrays of them.
//! - [`contact`]: collision detection (with [`crate::broadphase`]) and the contact
//!   cache; [`contact_solver`]: the contact rows of one step, over dense arrays;
//!   [`contact_wide`]: the same rows four pairs at a time (graph colouring, SIMD).
//! - [`island`]: islands and sleeping; [`solver`]: the step; [`project`]: the position
//!   projection after it; [`parallel`]: islands solved on all cores.
//! - [`world`]: [`MultibodyWorld`], the `Method`.

pub mod ball;
pub mod body;
pub mod contact;
pub mod contact_solver;
pub mod contact_wide;
pub mod fixed;
pub mod hinge;
pub mod integrate;
pub mod island;
pub mod joint;
pub mod joint_set;
pub mod joint_wide;
pub mod limits;
pub mod parallel;
pub mod project;
pub mod slider;
pub mod soft;
pub mod solver;
pub mod spring;
pub mod universal;
pub mod world;

pub use world::MultibodyWorld;
