//! The impulse-based multibody method (right, red): maximal coordinates, rigid bodies,
//! joints and contacts solved with impulses by Box2D v3's soft step.
//!
//! - `body`: hot body arrays (SoA) and cold body data.
//! - `integrate`: semi-implicit Euler, the gyroscopic term by an implicit midpoint
//!   rule, bodies without a contact turned with their angular momentum held.
//! - `soft`: soft-constraint coefficients.
//! - `joint`: building blocks every joint is made of; `limits`: swing, twist, ranges.
//! - `ball`, `hinge`, `universal`, `fixed`, `slider`, `spring`: one file per
//!   joint type; `joint_set`: the arrays of them; `joint_tree`: the point rows of a
//!   tree of joints across a large mass ratio, solved exactly (Baraff 1996).
//! - `contact`: collision detection (with [`crate::broadphase`]) and the contact
//!   cache; `contact_solver`: the contact constraints of one step, over dense arrays;
//!   `contact_rows`: the rows, written once for one pair and four at a time (graph
//!   colouring, SIMD lanes).
//! - `impulse`: what acts on bodies from outside (an impulse, a new pose) and the
//!   wake it brings.
//! - `kinematic`: bodies moved by the game along a path, infinite mass to the solver.
//! - `island`: islands and sleeping; `solver`: the step; `project`: the position
//!   projection after it; `parallel`: islands solved on all cores.
//! - `world`: [`MultibodyWorld`], the `Method`, the one public item.
//!
//! Everything but [`MultibodyWorld`] is crate-private: the app, the benchmarks and
//! the tests build and drive the method through it and the `Method` trait.

mod ball;
mod body;
mod contact;
mod contact_rows;
mod contact_solver;
mod fixed;
mod hinge;
mod impulse;
mod integrate;
mod island;
mod joint;
mod joint_rows;
mod joint_set;
mod joint_tree;
mod joint_wide;
mod kinematic;
mod limits;
mod parallel;
mod project;
mod slider;
mod soft;
mod solver;
mod spring;
mod substeps;
mod universal;
mod world;

pub use world::MultibodyWorld;
