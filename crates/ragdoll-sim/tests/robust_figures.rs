//! Robustness of both methods on the articulated scenes (spider, human, capsule human):
//! timesteps from 1/1000 to 1/10 s and 1 to 40 iterations give no NaN and no explosion,
//! and neither do combinations of timestep, iterations and substeps for the multibody,
//! rigid-frames and XPBD solvers.
//!
//! "No explosion" is measured as a bound on every body's speed. The figures start at
//! most about a metre up: free fall from there is √(2 g h) ≈ 4.5 m/s, and a limb
//! whipping about its joint as the figure lands reaches about twice that (7.9 m/s for
//! the human's fist, measured); 15 m/s leaves room for that and none for energy
//! entering the figure. The paper's solver gains energy by design (its finding, section
//! 5.1.9, reproduced by `particle_scenes`), so it is held to no NaN only.

use ragdoll_sim::method::BodyState;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::{Method, SceneDesc};

const FIGURES: [&str; 3] = ["spider", "human", "capsule-human"];
const MAX_SPEED: f32 = 15.0;

mod common;

use common::shipped_scene as scene;

/// The settings tried, with the simulated time each runs (s): the small timestep and
/// the many iterations are the expensive ones, and show their trouble early.
fn variations(base: &SceneDesc) -> Vec<(String, SceneDesc, f32)> {
    let mut out = Vec::new();
    for (dt, seconds) in [(0.001, 1.5), (0.1, 10.0)] {
        let mut s = base.clone();
        s.settings.timestep = dt;
        out.push((format!("dt {dt}"), s, seconds));
    }
    for it in [1, 40] {
        let mut s = base.clone();
        s.settings.iterations = it;
        s.settings.multibody_iterations = Some(it);
        out.push((format!("{it} iterations"), s, 2.0));
    }
    out
}

/// Steps `w` for `seconds` and returns the largest body speed seen, or panics on NaN.
fn fastest(w: &mut dyn Method, seconds: f32, what: &str) -> f32 {
    let frames = (seconds / w.settings().timestep).ceil() as usize;
    let mut states: Vec<BodyState> = Vec::new();
    let mut top = 0.0f32;
    for f in 0..frames {
        w.step();
        w.body_states(&mut states);
        for b in &states {
            let ok = b.com.is_finite() && b.linear_velocity.is_finite();
            assert!(ok, "{what}: not finite at frame {f}");
            top = top.max(b.linear_velocity.length());
        }
        assert!(w.sample().energy.is_finite(), "{what}: energy NaN");
    }
    top
}

#[test]
fn figures_stay_finite_and_bounded_across_timesteps_and_iterations() {
    let mut report = Vec::new();
    for name in FIGURES {
        for (label, s, seconds) in variations(&scene(name)) {
            let mut methods: Vec<(&str, Box<dyn Method>, bool)> = vec![
                (
                    "particle rigid frames",
                    Box::new(ParticleWorld::new(&s, ParticleSolver::RigidFrames).unwrap()),
                    true,
                ),
                (
                    "particle paper",
                    Box::new(ParticleWorld::new(&s, ParticleSolver::Paper).unwrap()),
                    false,
                ),
                (
                    "multibody",
                    Box::new(MultibodyWorld::new(&s).unwrap()),
                    true,
                ),
            ];
            for (method, w, bounded) in &mut methods {
                let what = format!("{name}, {label}, {method}");
                let top = fastest(w.as_mut(), seconds, &what);
                report.push(format!("{what}: top speed {top:.1} m/s"));
                assert!(
                    !*bounded || top <= MAX_SPEED,
                    "{what}: a body reached {top} m/s"
                );
            }
        }
    }
    println!("{}", report.join("\n"));
}

/// The multibody solver over combinations of timestep, iterations and substeps (a
/// covering set, [`COMBINATIONS`]): each figure stays finite with no body above 15 m/s.
#[test]
fn multibody_figures_stay_bounded_across_timestep_iteration_and_substep_combinations() {
    let mut report = Vec::new();
    for name in FIGURES {
        let base = scene(name);
        for (dt, iterations, substeps, seconds) in COMBINATIONS {
            let mut s = base.clone();
            s.settings.timestep = dt;
            s.settings.iterations = iterations;
            s.settings.multibody_iterations = Some(iterations);
            s.settings.substeps = substeps;
            s.settings.multibody_substeps = Some(substeps);
            let what = format!("{name}, dt {dt}, {iterations} iterations, {substeps} substeps");
            let mut w = MultibodyWorld::new(&s).unwrap();
            let top = fastest(&mut w, seconds, &what);
            report.push(format!("{what}: top speed {top:.1} m/s"));
            assert!(top <= MAX_SPEED, "{what}: a body reached {top} m/s");
        }
    }
    println!("{}", report.join("\n"));
}

/// The rigid-frames solver over the same covering set of timestep, iterations and
/// substeps ([`COMBINATIONS`]), and over the corner where the capsule human once
/// reached 32.9 m/s (1/20 s, 200 iterations, 50 substeps: the solver's substeps are
/// iterations × substeps, capped at 1000 a frame). Each figure stays finite with no
/// body above 15 m/s.
#[test]
fn rigid_frames_figures_stay_bounded_across_timestep_iteration_and_substep_combinations() {
    let extra = (0.05, 200, 50, 3.0);
    let combinations: Vec<_> = COMBINATIONS.into_iter().chain([extra]).collect();
    let (mut report, mut failures) = (Vec::new(), Vec::new());
    for name in FIGURES {
        let (r, f) = particle_top_speeds(name, ParticleSolver::RigidFrames, &combinations);
        report.extend(r);
        failures.extend(f);
    }
    println!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The XPBD particle solver over the covering set of timestep, iterations and
/// substeps ([`XPBD_COMBINATIONS`]): each figure stays finite with no body above
/// 15 m/s.
fn xpbd_figure_stays_bounded_across_timestep_iteration_and_substep_combinations(name: &str) {
    let (report, failures) = particle_top_speeds(name, ParticleSolver::Xpbd, &XPBD_COMBINATIONS);
    println!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Runs the figure `name` with a particle `solver` at each (timestep, iterations,
/// substeps, simulated seconds) of `combinations`: a report line per run, and a failure
/// per run in which a body went above [`MAX_SPEED`].
fn particle_top_speeds(
    name: &str,
    solver: ParticleSolver,
    combinations: &[(f32, u32, u32, f32)],
) -> (Vec<String>, Vec<String>) {
    let (mut report, mut failures) = (Vec::new(), Vec::new());
    let base = scene(name);
    for &(dt, iterations, substeps, seconds) in combinations {
        let mut s = base.clone();
        s.settings.timestep = dt;
        s.settings.iterations = iterations;
        s.settings.substeps = substeps;
        let what = format!("{name}, dt {dt}, {iterations} iterations, {substeps} substeps");
        let mut w = ParticleWorld::new(&s, solver).unwrap();
        let top = fastest(&mut w, seconds, &what);
        report.push(format!("{what}: top speed {top:.1} m/s"));
        if top > MAX_SPEED {
            failures.push(format!("{what}: a body reached {top} m/s"));
        }
    }
    (report, failures)
}

#[test]
fn xpbd_spider_stays_bounded_across_timestep_iteration_and_substep_combinations() {
    xpbd_figure_stays_bounded_across_timestep_iteration_and_substep_combinations("spider");
}

#[test]
fn xpbd_human_stays_bounded_across_timestep_iteration_and_substep_combinations() {
    xpbd_figure_stays_bounded_across_timestep_iteration_and_substep_combinations("human");
}

#[test]
fn xpbd_capsule_human_stays_bounded_across_timestep_iteration_and_substep_combinations() {
    xpbd_figure_stays_bounded_across_timestep_iteration_and_substep_combinations("capsule-human");
}

/// Combinations of timestep (1/1000–1/10 s), iterations (1–200) and substeps (1–50):
/// every corner of the three ranges that costs little to run, the expensive corners
/// (small timestep with many iterations and substeps) over fewer simulated seconds, and
/// a middle point. Ten of the 27 combinations of {1/1000, 1/60, 1/10} × {1, 40, 200} ×
/// {1, 10, 50}, chosen so that every pair of values of two settings appears at least
/// once (a pairwise covering set), keep the tests within seconds:
/// (timestep, iterations, substeps, simulated seconds).
const COMBINATIONS: [(f32, u32, u32, f32); 10] = [
    (0.001, 1, 1, 1.5),
    (0.001, 40, 10, 0.5),
    (0.001, 200, 50, 0.2),
    (1.0 / 60.0, 1, 10, 3.0),
    (1.0 / 60.0, 40, 50, 1.0),
    (1.0 / 60.0, 200, 1, 2.0),
    (0.1, 1, 50, 10.0),
    (0.1, 40, 1, 10.0),
    (0.1, 200, 10, 5.0),
    (0.1, 200, 50, 3.0),
];

/// [`COMBINATIONS`] for the XPBD solver, whose substeps are iterations × substeps
/// (capped at 1000 a frame), each a full round of constraint passes: the same ten (every pair of
/// values of two settings), the expensive ones over fewer simulated seconds. At
/// 1/1000 s, 400 substeps a frame for 0.35 s, past each figure's first landing
/// (0.18–0.32 s), and 1000 (substeps of 1 µs) for 0.05 s; at 1/60 s, 1000 substeps for
/// 0.5 s; at 1/10 s, 1000 substeps for 3 s, and once more (the same substeps) for 1 s.
/// Then the corner none of the ten reaches, where one substep is a whole 1/10 s frame,
/// the solver's longest (1 iteration × 1 substep).
const XPBD_COMBINATIONS: [(f32, u32, u32, f32); 11] = [
    (0.001, 1, 1, 1.5),
    (0.001, 40, 10, 0.35),
    (0.001, 200, 50, 0.05),
    (1.0 / 60.0, 1, 10, 3.0),
    (1.0 / 60.0, 40, 50, 0.5),
    (1.0 / 60.0, 200, 1, 2.0),
    (0.1, 1, 50, 10.0),
    (0.1, 40, 1, 10.0),
    (0.1, 200, 10, 3.0),
    (0.1, 200, 50, 1.0),
    (0.1, 1, 1, 10.0),
];
