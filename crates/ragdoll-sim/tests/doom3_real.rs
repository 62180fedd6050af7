//! Real Doom 3 figures, read from a Doom 3 base folder the way `ragdoll-lab stats
//! --doom3 BASE --entity NAME` reads them, and run on every improved solver (rigid
//! frames, XPBD, the multibody).
//!
//! id Software's files are not part of this repository: the tests run only when
//! `RAGDOLL_LAB_DOOM3_BASE` names a base folder (one holding `def/`, `af/`,
//! `models/`), and print a note and pass otherwise. Every `entityDef` whose figure,
//! mesh and `af_pose` the folder holds is run; entities that name no figure, or files
//! the folder lacks (a partial copy), are listed and skipped. Nothing here knows any
//! figure's results: each is held to the same bounds as the shipped scenes.

use ragdoll_sim::Method;
use ragdoll_sim::metrics::{MethodStats, MetricsRecorder};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::SceneDesc;
use ragdoll_sim::scene::af::{AfOptions, load_character};
use ragdoll_sim::scene::decl::Doom3Base;
use std::collections::BTreeMap;
use std::path::PathBuf;

mod common;

/// The real Doom 3 base folder, or `None` (with a note) when it is not given.
fn base_dir() -> Option<PathBuf> {
    common::real_doom3_base("the real Doom 3 figures")
}

/// Whether a character's error only says the folder lacks something, the entity is not
/// a character, or its declaration is one Doom 3 itself refuses (a key that is not a
/// quoted string: the engine warns and uses an empty default): skipped, not failed.
fn is_absent(message: &str) -> bool {
    message.contains("is not in the base folder")
        || message.contains("names no figure")
        || message.contains("which does not exist")
        || message.contains("expected a quoted key")
        || message.starts_with("no ")
}

/// Every figure the folder holds, once per (figure, mesh, pose): the entities sharing
/// it, and its scene. A figure that fails to load for another reason is an error.
fn figures(base: &std::path::Path) -> Vec<(Vec<String>, SceneDesc)> {
    let decls = Doom3Base::open(base).unwrap_or_else(|e| panic!("{e}"));
    let mut seen: BTreeMap<(String, Option<PathBuf>, Option<PathBuf>), usize> = BTreeMap::new();
    let mut out: Vec<(Vec<String>, SceneDesc)> = Vec::new();
    let mut skipped = 0;
    let mut errors = Vec::new();
    for name in decls.names("entityDef") {
        let c = match decls.character(name) {
            Ok(c) => c,
            Err(e) if is_absent(&e.message) => {
                if !e.message.contains("names no figure") {
                    println!("skipped {name}: {}", e.message);
                }
                skipped += 1;
                continue;
            }
            Err(e) => {
                errors.push(format!("{name}: {e}"));
                continue;
            }
        };
        let key = (
            c.figure.to_ascii_lowercase(),
            c.mesh.clone(),
            c.af_pose.clone(),
        );
        if let Some(&i) = seen.get(&key) {
            out[i].0.push(name.to_string());
            continue;
        }
        match load_character(&c, base, &AfOptions::default()) {
            Ok(sc) => {
                seen.insert(key, out.len());
                out.push((vec![name.to_string()], sc.desc));
            }
            Err(e) if is_absent(&e.message) => {
                println!("skipped {name}: {}", e.message);
                skipped += 1;
            }
            Err(e) => errors.push(format!("{name}: {e}")),
        }
    }
    println!(
        "{} figures from {} ({skipped} entities skipped)",
        out.len(),
        base.display()
    );
    assert!(
        errors.is_empty(),
        "figures that do not load:\n{}",
        errors.join("\n")
    );
    out
}

/// Runs `w` for 10 s from the load pose, which is recorded too (as `stats` does):
/// energy the first step puts in counts. The limit excess is the largest after the
/// start: id's figures start a few degrees outside some limits, which is the file's
/// doing, not the method's (`limit excess at the start` is printed beside it).
fn run(mut w: Box<dyn Method>, sc: &SceneDesc) -> (MethodStats, f32) {
    let mut rec = MetricsRecorder::new(sc).unwrap();
    let start = w.sample();
    rec.record(w.time(), &start);
    let mut states = Vec::new();
    let mut limit = 0.0f32;
    for _ in 0..(10.0 / sc.settings.timestep).round() as usize {
        w.step();
        let s = w.sample();
        limit = limit.max(s.max_limit_violation_deg);
        rec.record(w.time(), &s);
        w.body_states(&mut states);
        rec.record_speeds(&states);
    }
    let stats = MethodStats {
        max_limit_violation_deg: limit,
        ..rec.stats()
    };
    (stats, start.max_limit_violation_deg)
}

/// Every improved solver on every figure: (entities, method, stats). The particle
/// method runs both its improved solvers, rigid frames and XPBD.
fn measure(figs: &[(Vec<String>, SceneDesc)]) -> Vec<(String, &'static str, MethodStats)> {
    let mut out = Vec::new();
    for (names, sc) in figs {
        let label = names.join(", ");
        for (solver, name) in [
            (ParticleSolver::RigidFrames, "rigid frames"),
            (ParticleSolver::Xpbd, "xpbd"),
        ] {
            let p = ParticleWorld::new(sc, solver).unwrap_or_else(|e| panic!("{label}: {e}"));
            let (st, start) = run(Box::new(p), sc);
            out.push((label.clone(), name, st, start));
        }
        let m = MultibodyWorld::new(sc).unwrap_or_else(|e| panic!("{label}: {e}"));
        let (st, start) = run(Box::new(m), sc);
        out.push((label, "multibody", st, start));
    }
    for (label, method, s, start) in &out {
        println!(
            "{label} | {method} | gain {:.4} | penetration {:.1} mm | joint gap {:.1} mm | \
             limit excess {:.2}° (at the start {start:.2}°) | top speed {:.2} m/s | asleep {}",
            s.energy_gain,
            1e3 * s.max_penetration_m,
            1e3 * s.max_joint_gap_m,
            s.max_limit_violation_deg,
            s.max_body_speed_mps,
            s.asleep_at_s.map_or("no".into(), |t| format!("{t:.2} s")),
        );
    }
    out.into_iter().map(|(l, m, s, _)| (l, m, s)).collect()
}

/// Every real figure builds on every improved solver, stays finite and no body exceeds
/// 15 m/s (a figure dropped from standing falls well below that).
#[test]
fn real_figures_load_and_stay_finite_and_bounded() {
    let Some(base) = base_dir() else { return };
    let figs = figures(&base);
    let mut failures = Vec::new();
    for (label, method, s) in measure(&figs) {
        if !s.finite {
            failures.push(format!("{label} | {method}: not finite"));
        } else if s.max_body_speed_mps > 15.0 {
            failures.push(format!(
                "{label} | {method}: a body reached {:.1} m/s",
                s.max_body_speed_mps
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Every real figure holds the scene thresholds on every improved solver: energy gain ≤ 2 %,
/// penetration ≤ 1 cm, joint gap ≤ 5 mm (particle) / 2 mm (multibody), limit excess
/// ≤ 3° / 2°.
#[test]
fn real_figures_hold_the_scene_thresholds() {
    let Some(base) = base_dir() else { return };
    let figs = figures(&base);
    let mut failures = Vec::new();
    for (label, method, s) in measure(&figs) {
        let (gap, limit) = if method == "multibody" {
            (0.002, 2.0)
        } else {
            (0.005, 3.0)
        };
        for (metric, value, max) in [
            ("energy gain", s.energy_gain, 0.02),
            ("penetration (m)", s.max_penetration_m as f64, 0.01),
            ("joint gap (m)", s.max_joint_gap_m as f64, gap),
            ("limit excess (°)", s.max_limit_violation_deg as f64, limit),
        ] {
            if value.is_nan() || value > max {
                failures.push(format!("{label} | {method}: {metric} {value:.4} > {max}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
