//! The particle method on the scene files (assets/scenes, the README's scene table):
//! the quality bounds (docs/results.md) for the rigid-frames solver across scenes 1–9,
//! the paper solver on every scene without NaN, and the paper's own expectations
//! (section 5.1), measured.
//!
//! One binary, each scene simulated once per solver (10 s at the scene's timestep):
//! about two seconds of release-mode CPU in all.

mod common;

use common::particle::{SCENES, run_scene as run, scene_failures};
use common::{shipped_pile, shipped_variant as scene};
use ragdoll_sim::glam::Vec3;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::Pose;
use ragdoll_sim::snapshot::{RenderSnapshot, StickRole};
use ragdoll_sim::{Method, SceneDesc};

/// The rigid-frames solver on every variant of scenes 1–9 against the scene thresholds,
/// the state's own energy gain bounded too (`common::particle::scene_failures`).
#[test]
fn improved_solver_meets_the_issue_thresholds_on_scenes_1_to_9_every_variant() {
    let mut failures = Vec::new();
    for n in 1..=9 {
        failures.extend(scene_failures(ParticleSolver::RigidFrames, n, None, true));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Resting limbs do not creep. Joint corrections after friction left a few micrometres
/// of slip a substep, a creep of about 1 cm/s that kept piles awake for seconds; static
/// friction takes back half of a contact's small drift
/// (`particle::friction::ANCHOR_PULL`), the contact velocity pass never pulls
/// (`particle::friction::solve_velocities`), and each point's friction reads the normal
/// load its point carries after the manifold's block (`rigid_frames::ManifoldSolve`).
/// One pile's sleep time is chaotic (the last island decides), so four piles are
/// averaged: 2.15, 2.22, 2.93 and 3.12 s, mean 2.60 s; 3.54 s with an unbounded velocity
/// block and no top-up, 5.30 s with the bound alone.
#[test]
fn resting_piles_stop_creeping_and_sleep_sooner() {
    let mut times = Vec::new();
    for humans in [4, 8, 14, 26] {
        let s = shipped_pile(humans);
        let (st, _, _) = run(&s, ParticleSolver::RigidFrames, 6.0);
        times.push(st.asleep_at_s.unwrap_or(f64::INFINITY));
    }
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    assert!(mean <= 2.8, "piles asleep at {times:?} s, mean {mean:.2} s");
}

#[test]
fn paper_solver_runs_every_scene_without_nan() {
    for (k, name) in SCENES.iter().enumerate() {
        let s = scene(name, 1);
        let variants = s.variants.len().max(1) as u32;
        for v in 1..=variants {
            let s = scene(name, v);
            // The pile is many humans: 3 s show it settles without blowing up.
            let seconds = if *name == "pile" { 3.0 } else { 10.0 };
            let (st, _, w) = run(&s, ParticleSolver::Paper, seconds);
            let mut x = Vec::new();
            w.particle_positions(&mut x);
            assert!(
                st.finite && x.iter().all(|p| p.is_finite()),
                "scene {} {name} v{v}: NaN",
                k + 1
            );
            println!(
                "paper, scene {} {name} v{v}: energy_gain {:.4}",
                k + 1,
                st.energy_gain
            );
        }
    }
}

/// Section 5.1.8–5.1.9: the paper's particle spider and human "gain too much energy";
/// ours must not.
///
/// How much the paper's solver gains is chaotic: dropped from twelve heights 1 mm apart,
/// the human gains 0.18-1.63 of its energy scale (default build), 0.10-1.72 when built
/// with `-C target-cpu=native`, whose fused multiply-adds round differently; a single
/// start at the threshold failed there. The paper's finding is about the method, so its
/// gain is judged by the mean over `PAPER_STARTS` heights (human: 1.19 default, 0.41
/// native; spider: 1.53, 2.46).
#[test]
fn paper_finding_articulated_figures_gain_energy_in_paper_mode_only() {
    const PAPER_STARTS: u32 = 8;
    for name in ["spider", "human"] {
        let s = scene(name, 1);
        let gains: Vec<f64> = (0..PAPER_STARTS)
            .map(|mm| {
                let dropped = raised(s.clone(), mm as f32 * 1e-3);
                run(&dropped, ParticleSolver::Paper, 10.0).0.energy_gain
            })
            .collect();
        let paper = gains.iter().sum::<f64>() / gains.len() as f64;
        let (improved, _, _) = run(&s, ParticleSolver::RigidFrames, 10.0);
        println!(
            "{name}: energy_gain paper {paper:.3} (mean of {gains:.3?}), improved {:.4}",
            improved.energy_gain
        );
        assert!(
            paper > 0.2,
            "{name}: the paper's energy gain did not reproduce (mean {paper:.3} of {gains:.3?})"
        );
        assert!(improved.energy_gain <= 0.02);
    }
}

/// `s` with every body and joint anchor raised by `dy` metres.
fn raised(mut s: SceneDesc, dy: f32) -> SceneDesc {
    s.transform(&Pose::from_position(Vec3::new(0.0, dy, 0.0)));
    s
}

/// The capsule human dropped from 24 heights 1 mm apart: its energy never rises by
/// more than 2 %, whichever way it lands. The shoulder's twist limit (±45°) is reached
/// with the arm swung far (130°); corrected by turning the upper arm about its own axis,
/// on which it has almost no inertia, it fought the elbow every substep and spun the arm
/// up (state energy +30 % at one of these heights, 6 of 24 over 2 % by the frame
/// measure). Corrected along the twist angle's gradient it measures at most 0.6 %.
#[test]
fn capsule_human_keeps_its_energy_from_any_drop_height() {
    let base = scene("capsule-human", 1);
    let mut worst = (0.0f64, 0);
    for mm in 0..24 {
        let (_, state_gain, _) = run(
            &raised(base.clone(), mm as f32 * 1e-3),
            ParticleSolver::RigidFrames,
            10.0,
        );
        if state_gain > worst.0 {
            worst = (state_gain, mm);
        }
    }
    println!(
        "capsule human: largest state energy rise {:.4} (raised {} mm)",
        worst.0, worst.1
    );
    assert!(
        worst.0 <= 0.02,
        "state energy rose by {:.4} when raised {} mm",
        worst.0,
        worst.1
    );
}

fn com(w: &ParticleWorld, body: usize) -> (Vec3, Vec3) {
    let mut s = Vec::new();
    w.body_states(&mut s);
    (s[body].com, s[body].linear_velocity)
}

#[test]
fn scene_4_big_box_keeps_its_speed_and_pushes_the_small_one_away() {
    // Section 5.1.5: "we expect the big box to dominate, and push the small box away
    // loosing only little speed". Measured 5 frames after the boxes first touch.
    for solver in [ParticleSolver::Paper, ParticleSolver::RigidFrames] {
        let s = scene("box-masses", 1);
        let (small, big) = (
            s.body_id("small").unwrap().index(),
            s.body_id("big").unwrap().index(),
        );
        let mut w = ParticleWorld::new(&s, solver).unwrap();
        let mut before = None;
        let mut touched_at = None;
        let mut last = (0.0, 0.0);
        for f in 0..120 {
            let (ps, vs) = com(&w, small);
            let (pb, vb) = com(&w, big);
            // Half extents 0.125 and 0.25: touching when the centres are 0.375 apart;
            // "before" is the frame before that.
            if touched_at.is_none() && (pb.x - ps.x) < 0.375 + 0.02 {
                touched_at = Some(f);
                before = Some(last);
            }
            last = (vs.x, vb.x);
            if touched_at.is_some_and(|t| f == t + 5) {
                let (vs0, vb0) = before.unwrap();
                println!(
                    "{solver:?}: small {vs0:.2} → {:.2} m/s, big {vb0:.2} → {:.2} m/s",
                    vs.x, vb.x
                );
                assert!(
                    vb.x < 0.0 && vb.x.abs() > 0.5 * vb0.abs(),
                    "{solver:?}: big box lost most of its speed ({vb0} → {})",
                    vb.x
                );
                assert!(
                    vs.x < 0.0,
                    "{solver:?}: small box not pushed back ({vs0} → {})",
                    vs.x
                );
                break;
            }
            w.step();
        }
        assert!(touched_at.is_some(), "{solver:?}: the boxes never met");
    }
}

/// Each body's four particles, from the render snapshot: a bone's first three sticks
/// are p0–p1, p0–p2, p0–p3.
fn body_particles(w: &ParticleWorld) -> Vec<[Vec3; 4]> {
    let mut snap = RenderSnapshot::default();
    w.snapshot(&mut snap);
    let bone_sticks: Vec<_> = snap
        .sticks
        .iter()
        .filter(|s| s.role == StickRole::Bone)
        .collect();
    bone_sticks
        .chunks(6)
        .map(|c| [c[0].a, c[0].b, c[1].b, c[2].b])
        .collect()
}

/// Scene 2 over 10 s in paper mode: the largest distance of a chain link's centre (the
/// mean of its four particles) from the chain's plane (z = 0), m. The centre, not single
/// particles: variant 2 starts its internal particles off the plane on purpose.
fn chain_out_of_plane(variant: u32) -> f32 {
    let s = scene("ball-chain", variant);
    let links: Vec<usize> = (0..6)
        .filter_map(|i| s.body_id(&format!("link{i}")))
        .map(|b| b.index())
        .collect();
    assert_eq!(links.len(), 6);
    let mut w = ParticleWorld::new(&s, ParticleSolver::Paper).unwrap();
    let mut dist = 0.0f32;
    for _ in 0..600 {
        w.step();
        let p = body_particles(&w);
        for &l in &links {
            let centre = p[l].iter().sum::<Vec3>() / 4.0;
            dist = dist.max(centre.z.abs());
        }
    }
    dist
}

#[test]
fn scene_2_aligned_particles_keep_the_chain_in_its_plane_and_tetrahedra_free_it() {
    // Section 5.1.3: with all of a box's particles at the same depth, a vertical hit
    // moves them only within that plane — "regardless of weights, they stay aligned" —
    // and the pendulum acts "much like hinge joints" (variant 1). Variant 2 gives the
    // boxes proper tetrahedra, and the hit turns the chain out of its plane: we ask for
    // at least 1 cm, a visible swing for 30 cm links (a chain kept in plane by symmetry
    // alone would stay below float noise, ~1e-6 m).
    let v1 = chain_out_of_plane(1);
    let v2 = chain_out_of_plane(2);
    println!("chain links off the chain's plane: variant 1 {v1:.2e} m, variant 2 {v2:.2e} m");
    assert!(v1 < 1e-3, "variant 1: the chain left its plane by {v1} m");
    assert!(
        v2 > 0.01,
        "variant 2: the chain stayed in its plane ({v2} m)"
    );
}

#[test]
fn scene_3_more_iterations_give_a_stiffer_hinge() {
    // Section 5.1.4 and figure 21: 2, 5 and 20 iterations (variants 2, 1, 3). Stiffness
    // measured as the largest joint gap and bone stretch over the run.
    let mut rows = Vec::new();
    for (variant, iterations) in [(2, 2), (1, 5), (3, 20)] {
        let (st, _, _) = run(&scene("hinge-chain", variant), ParticleSolver::Paper, 10.0);
        let stretch = st.max_bone_stretch.unwrap_or(0.0);
        println!(
            "{iterations} iterations: joint gap {:.4} m, stretch {:.4}",
            st.max_joint_gap_m, stretch
        );
        rows.push((st.max_joint_gap_m, stretch));
    }
    for w in rows.windows(2) {
        assert!(
            w[1].0 < w[0].0 && w[1].1 < w[0].1,
            "more iterations were not stiffer: {rows:?}"
        );
    }
}
