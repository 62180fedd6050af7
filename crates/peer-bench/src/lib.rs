//! Side-by-side benchmark of ragdoll-lab against Rapier.
//!
//! Everything lives in `benches/pile.rs` so that Rapier stays a dev-dependency: it
//! builds the same pile of humans in Rapier (same boxes and masses, spherical and
//! revolute joints with the same limits, no contacts between jointed bodies, the same
//! timestep and solver budget) and in both of our methods, runs them in turn in one
//! process and prints milliseconds per frame and the ratios.
//!
//! ```text
//! cargo bench -p peer-bench --bench pile                 # 1, 10, 100, 270, 1000 humans
//! cargo bench -p peer-bench --bench pile -- 100 --frames 300
//! cargo bench -p peer-bench --bench pile -- 100 1000 --no-sleep --frames 180
//! cargo bench -p peer-bench --bench rain                 # humans dropped at a steady rate
//! ```
//!
//! `benches/rain.rs` does the same for the rain (`ragdoll_lab::bench::rain`).
