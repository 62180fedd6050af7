//! The XPBD solver drops the Doom 3-style mod's humanoid (assets/doom3, entity
//! `monster_lab_human`, from its `af_pose` frame) onto flat ground from starts shifted
//! sideways by a few millimetres: the same fall, so each gains no more than a small
//! fraction of its energy scale. It holds only if the limit rows measure a swing
//! limit's breach exactly (by `atan2`; through f32 `acos` a breach is resolved in steps
//! of 3.4e-4 rad) and push each pyramid face along its own gradient: otherwise which
//! start gains how much is a matter of rounding, and the start shifted 7 mm gains 2.7 %.

use ragdoll_sim::Method;
use ragdoll_sim::glam::Vec3;
use ragdoll_sim::metrics::MetricsRecorder;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::Pose;
use ragdoll_sim::scene::SceneDesc;
use ragdoll_sim::scene::af::{AfOptions, load_character};
use ragdoll_sim::scene::decl::Doom3Base;

mod common;

use common::lab_mod_base as base_dir;

fn figure() -> SceneDesc {
    let base = Doom3Base::open(&base_dir()).unwrap_or_else(|e| panic!("{e}"));
    let c = base
        .character("Monster_Lab_Human")
        .unwrap_or_else(|e| panic!("{e}"));
    load_character(&c, &base_dir(), &AfOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .desc
}

/// The energy gain (docs/metrics.md, a fraction of the energy scale) over 10 s.
fn gain(sc: &SceneDesc) -> f64 {
    let mut w = ParticleWorld::new(sc, ParticleSolver::Xpbd).unwrap_or_else(|e| panic!("{e}"));
    let mut rec = MetricsRecorder::new(sc).unwrap_or_else(|e| panic!("{e}"));
    rec.record(w.time(), &w.sample());
    let steps = (10.0 / sc.settings.timestep).round() as usize;
    for _ in 0..steps {
        w.step();
        rec.record(w.time(), &w.sample());
    }
    rec.stats().energy_gain
}

#[test]
fn xpbd_lab_humanoid_shifted_sideways_gains_under_a_percent() {
    let base = figure();
    let mut failures = Vec::new();
    for d in [
        Vec3::ZERO,
        Vec3::new(0.007, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.011),
        Vec3::new(0.0, 0.0, 0.023),
    ] {
        let mut sc = base.clone();
        sc.transform(&Pose::from_position(d));
        let g = gain(&sc);
        eprintln!("shift {d}: energy gain {:.3} %", g * 100.0);
        if g > 0.01 {
            failures.push(format!("shift {d}: gained {:.3} %", g * 100.0));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
