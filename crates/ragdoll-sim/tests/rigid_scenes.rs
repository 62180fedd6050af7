//! The multibody method over the scene table (scenes 1–9 with every variant, 10 s each):
//! the quality bounds of docs/results.md. One binary, one run per scene, so CI stays
//! short.
//!
//! Scenes and metrics that do not yet meet a threshold are listed in `KNOWN_GAPS` with
//! the figure measured when the list was written; the test checks everything else at the
//! thresholds, and fails when a listed gap starts passing, so the list cannot go
//! stale.

use ragdoll_sim::Method;
use ragdoll_sim::metrics::{MethodStats, MetricsRecorder};
use ragdoll_sim::rigid::MultibodyWorld;

const SCENES: [(&str, u32); 13] = [
    ("collision", 1),
    ("ball-chain", 1),
    ("ball-chain", 2),
    ("hinge-chain", 1),
    ("hinge-chain", 2),
    ("hinge-chain", 3),
    ("box-masses", 1),
    ("box-masses", 2),
    ("ball-limits", 1),
    ("hinge-limits", 1),
    ("spider", 1),
    ("human", 1),
    ("capsule-human", 1),
];

/// (scene, variant, metric) measured over their threshold, with the measured value.
/// `asleep_at_s` entries mean "never slept in 10 s" (the value is unused). None at
/// present: the human's fist-in-head overlap (16–20 mm) went with the step's extra
/// detections for fast-turning contacts (`rigid/solver.rs`).
const KNOWN_GAPS: [(&str, u32, &str, f64); 0] = [];

mod common;

use common::shipped_variant as scene;

/// Runs a scene for 10 s; also checks scene 4's "nothing sinks, nothing is launched".
fn run(name: &str, variant: u32) -> MethodStats {
    let sc = scene(name, variant);
    let mut w = MultibodyWorld::new(&sc).unwrap();
    let mut rec = MetricsRecorder::new(&sc).unwrap();
    let steps = (10.0 / sc.settings.timestep).round() as usize;
    let mut lowest: Vec<Option<f32>> = vec![None; sc.bodies.len()];
    let mut states = Vec::new();
    for _ in 0..steps {
        w.step();
        rec.record(w.time(), &w.sample());
        if name == "box-masses" {
            w.body_states(&mut states);
            for (i, s) in states.iter().enumerate() {
                let b = &sc.bodies[i];
                if b.is_fixed() {
                    continue;
                }
                // Height of the box's lowest corner: a box that tumbles over an edge
                // raises its centre by up to (√2 − 1) of its half size while its lowest
                // corner stays on the ground; a launched box lifts that corner.
                let m = ragdoll_sim::glam::Mat3::from_quat(s.orientation);
                let down = m.transpose() * ragdoll_sim::glam::Vec3::Y;
                let h = s.com.y - down.abs().dot(b.shape.local_half_extents());
                match &mut lowest[i] {
                    Some(low) => {
                        assert!(
                            h <= *low + 0.01,
                            "{name} v{variant}: {} rose from {low} to {h}",
                            b.name
                        );
                        *low = low.min(h);
                    }
                    None if h < 0.02 => lowest[i] = Some(h),
                    None => {}
                }
            }
        }
    }
    rec.stats()
}

fn metrics(st: &MethodStats) -> [(&'static str, f64, f64); 4] {
    [
        ("energy_gain", st.energy_gain, 0.02),
        ("max_penetration_m", st.max_penetration_m as f64, 0.01),
        ("max_joint_gap_m", st.max_joint_gap_m as f64, 0.002),
        (
            "max_limit_violation_deg",
            st.max_limit_violation_deg as f64,
            2.0,
        ),
    ]
}

fn known(name: &str, variant: u32, metric: &str) -> bool {
    KNOWN_GAPS
        .iter()
        .any(|&(s, v, m, _)| s == name && v == variant && m == metric)
}

#[test]
fn scene_table_meets_the_thresholds() {
    let mut failures = Vec::new();
    let mut gaps = Vec::new();
    for (name, variant) in SCENES {
        let st = run(name, variant);
        assert!(st.finite, "{name}: not finite");
        for (metric, value, limit) in metrics(&st) {
            if known(name, variant, metric) && metric != "asleep_at_s" {
                gaps.push((name, variant, metric, value, limit));
            } else if value > limit {
                failures.push(format!("{name} v{variant}: {metric} = {value} > {limit}"));
            }
        }
        if ["spider", "human", "capsule-human"].contains(&name) {
            match (st.asleep_at_s, known(name, variant, "asleep_at_s")) {
                (None, false) => failures.push(format!("{name}: never slept")),
                (Some(t), true) => {
                    failures.push(format!("{name}: slept at {t} s; remove it from KNOWN_GAPS"))
                }
                _ => {}
            }
        }
    }
    for (name, variant, metric, value, limit) in &gaps {
        // Still open: must be over the threshold, or the entry is stale.
        if value <= limit {
            failures.push(format!(
                "{name} v{variant}: {metric} = {value} now meets {limit}; remove it from KNOWN_GAPS"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
