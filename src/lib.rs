//! The ragdoll-lab app: command line, scene registry, window, renderer, offscreen
//! capture, stats and benchmarks. The physics lives in the `ragdoll-sim` crate; the app
//! drives it only through `ragdoll_sim::Method` and draws only `RenderSnapshot`s.

pub mod app_state;
pub mod bench;
pub mod capture;
pub mod check;
pub mod cli;
pub mod compose;
pub mod error;
pub mod impacts;
pub mod input;
pub mod inspect;
pub mod methods;
pub mod picking;
pub mod readback;
pub mod render;
pub mod scenes;
pub mod session;
pub mod stats;
pub mod ui;
pub mod view;

pub use error::AppError;
