//! The Doom 3-style mod under `assets/doom3/` (written by `scripts/make_doom3_mod.py`):
//! its declarations resolve as the engine resolves them, its mesh and animations read,
//! the figure is built from the `af_pose` frame, and both methods (the particle method
//! with its rigid-frames and its XPBD solver) run it within the scene thresholds.
//!
//! Gaps a method does not yet close are listed in `KNOWN_GAPS` with the figure measured
//! when the list was written; the test fails when a listed gap starts passing.

use ragdoll_sim::Method;
use ragdoll_sim::metrics::{MethodStats, MetricsRecorder};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::SceneDesc;
use ragdoll_sim::scene::af::{AfOptions, AfScene, FigureSource, load_figure};
use ragdoll_sim::scene::decl::{Doom3Base, Doom3Character};
use ragdoll_sim::scene::{Pose, scene_mass_props};
use ragdoll_sim::scene::{md5anim, md5mesh};

mod common;

use common::lab_mod_base as base_dir;

fn character() -> Doom3Character {
    let base = Doom3Base::open(&base_dir()).unwrap_or_else(|e| panic!("{e}"));
    assert!(base.warnings.is_empty(), "{:?}", base.warnings);
    base.character("Monster_Lab_Human")
        .unwrap_or_else(|e| panic!("{e}"))
}

fn figure(pose: bool) -> SceneDesc {
    scene(pose).desc
}

fn scene(pose: bool) -> AfScene {
    let c = character();
    let source = FigureSource {
        figure: Some(c.figure.clone()),
        pose_anim: if pose { c.af_pose.clone() } else { None },
        base: Some(base_dir()),
    };
    let opts = AfOptions {
        mesh: c.mesh.clone(),
        ..Default::default()
    };
    load_figure(&c.af_file, &opts, &source).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_entity_resolves_through_inherit_and_the_model_declaration() {
    let c = character();
    // The child's own keys win; the figure comes from the parent.
    assert_eq!(c.entity.get("classname"), Some("monster_lab_human"));
    assert_eq!(c.entity.get("RAGDOLL"), Some("lab_human"));
    assert_eq!(c.skin.as_deref(), Some("skins/lab_human_red"));
    assert_eq!(c.figure, "lab_human");
    assert!(c.af_file.ends_with("af/lab_human.af"));
    assert!(c.mesh.as_ref().unwrap().ends_with("lab_human.md5mesh"));
    assert!(c.af_pose.as_ref().unwrap().ends_with("af_pose.md5anim"));
    let names: Vec<&str> = c.anims.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["walk"]);
    let m = c.model.unwrap();
    assert_eq!(m.anim("walk").unwrap().files.len(), 1);
    assert!(m.anim("Walk").is_none(), "anim names compare exactly");
}

#[test]
fn the_mesh_and_animations_read_and_fit_each_other() {
    let c = character();
    let mesh = md5mesh::load(c.mesh.as_ref().unwrap()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.skeleton.joints.len(), 20);
    assert!(mesh.skeleton.joint("RUPARM").is_some());
    let sub = &mesh.meshes[0];
    assert!(sub.vertices.len() >= 200, "{}", sub.vertices.len());
    // The bind pose skins every vertex to where the script put it: inside the figure's
    // height, nothing below the ground.
    let p = sub.skin(&mesh.skeleton.poses());
    let (lo, hi) = p
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), v| (l.min(v.z), h.max(v.z)));
    assert!(lo > -0.01 && hi < 73.0, "{lo} {hi}");
    for (_, path) in &c.anims {
        let a = md5anim::load(path).unwrap_or_else(|e| panic!("{e}"));
        a.check_hierarchy(&mesh.skeleton).unwrap();
        // A cycle: the last frame equals the first but for the root motion, which
        // carries the walk forward (+X, the way the figure faces).
        let (mut first, mut last) = (a.local_poses(0), a.local_poses(a.frame_count() - 1));
        let travel = last[0].position - first[0].position;
        assert!(
            travel.x > 30.0 && travel.y.abs() + travel.z.abs() < 1e-4,
            "{travel}"
        );
        first[0].position = glam::Vec3::ZERO;
        last[0].position = glam::Vec3::ZERO;
        let (first, last) = (a.compose(&first), a.compose(&last));
        for (f, l) in first.iter().zip(&last) {
            assert!((f.position - l.position).length() < 1e-4);
        }
        // The walk moves the legs between frames.
        let mid = a.frame_poses(a.frame_count() / 4);
        let knee = mesh.skeleton.index("lloleg").unwrap();
        assert!((mid[knee].position - first[knee].position).length() > 1.0);
    }
    let pose = md5anim::load(c.af_pose.as_ref().unwrap()).unwrap();
    pose.check_hierarchy(&mesh.skeleton).unwrap();
}

#[test]
fn the_figure_is_built_from_the_af_pose_frame() {
    let posed = figure(true);
    let bind = figure(false);
    assert_eq!((posed.bodies.len(), posed.constraints.len()), (11, 10));
    let body = |d: &SceneDesc, n: &str| d.bodies.iter().find(|b| b.name == n).unwrap().pose;
    // af_pose turns the upper arms away from the sides; the legs are as bound.
    let arm = (body(&posed, "luparm").position - body(&bind, "luparm").position).length();
    assert!(arm > 0.01, "the upper arm moved {arm} m");
    let leg = (body(&posed, "lloleg").position - body(&bind, "lloleg").position).length();
    assert!(leg < 1e-5, "{leg}");
    // The shins end on the ground (Y up after conversion; ground top at 0).
    let lowest = posed
        .bodies
        .iter()
        .map(|b| b.pose.position.y - b.shape.local_half_extents().length())
        .fold(f32::MAX, f32::min);
    assert!(lowest < 0.02, "{lowest}");
}

/// (method, metric, measured when written) over the threshold.
///
/// What happens: the figure folds onto its left knee, which reaches the top of its range
/// (86°) within 0.35 s and stays pressed there under the torso's weight with the shin on
/// the ground; the right knee follows; later the figure rolls onto its side and the chest
/// (25 kg) comes down on an upper arm (2 kg), whose bone model reaches 5 cm past the
/// chest's side at the shoulder.
///
/// Rigid-frames holds the thresholds at this start: the ground's contact on a shin (or
/// an upper arm) and the joints behind it, the heavy torso's, fight over the light limb
/// each Gauss–Seidel pass, and with two passes what they left was pushed out in the next
/// substep as a velocity; five passes settle it (`rigid_frames::PASSES`).
///
/// Multibody: it keeps its energy, limits, contacts and joints at this start (the knee
/// pressed at its stop stays closed: the position projection ends with a pass of the
/// point rows, `rigid::project`).
///
/// One start says little on a landing this chaotic; over 72 starts shifted by 0–23 mm
/// (`cargo run --release -p ragdoll-sim --example ensemble -- lab-human [--multibody]`),
/// median (worst): rigid-frames energy gain 0.3 % (11.1 %), joint gap 1.6 mm (3.3),
/// penetration 1.4 mm (5.1), asleep in 72 of 72; multibody energy gain 0.3 % (2.4 %),
/// joint gap 0.8 mm (1.8), penetration 8.1 mm (8.1), asleep in 72 of 72.
///
/// XPBD brings the knee in as rigid frames does (`xpbd::step::close_start_slack`) and
/// keeps its energy, contacts, joints and limits at this start. Over the 72 starts
/// (`ensemble -- lab-human --xpbd`) median (worst): energy gain 0.5 % (4.2 %), joint
/// gap 1.0 mm (4.7), penetration 0.1 mm (2.1), asleep in 72 of 72.
const KNOWN_GAPS: [(&str, &str, f64); 0] = [];

/// Runs 10 s from the load pose, which is recorded too (as `stats` does): energy the
/// first step puts in counts. The limit excess is the largest after the start, the
/// start's own excess being the file's (the test checks it separately).
fn run(w: &mut dyn Method, sc: &SceneDesc) -> MethodStats {
    let mut rec = MetricsRecorder::new(sc).unwrap();
    rec.record(w.time(), &w.sample());
    let mut limit = 0.0f32;
    let steps = (10.0 / sc.settings.timestep).round() as usize;
    for _ in 0..steps {
        w.step();
        let s = w.sample();
        limit = limit.max(s.max_limit_violation_deg);
        rec.record(w.time(), &s);
    }
    MethodStats {
        max_limit_violation_deg: limit,
        ..rec.stats()
    }
}

#[test]
fn both_methods_hold_the_scene_thresholds_on_the_mod_humanoid() {
    let sc = figure(true);
    let mut failures = Vec::new();
    let mut report = Vec::new();
    let methods: [(&str, Box<dyn Method>, f64, f64); 3] = [
        (
            "particle",
            Box::new(ParticleWorld::new(&sc, ParticleSolver::RigidFrames).unwrap()),
            0.005,
            3.0,
        ),
        (
            "xpbd",
            Box::new(ParticleWorld::new(&sc, ParticleSolver::Xpbd).unwrap()),
            0.005,
            3.0,
        ),
        (
            "multibody",
            Box::new(MultibodyWorld::new(&sc).unwrap()),
            0.002,
            2.0,
        ),
    ];
    for (name, mut w, gap, limit) in methods {
        // The left knee's limit starts 4° from the rest pose (the script's design, as
        // real id figures start); both methods must see the same geometry.
        let start = w.sample().max_limit_violation_deg;
        report.push(format!("{name}: limit excess at the start = {start:.2}°"));
        if (start - 4.0).abs() > 0.25 {
            failures.push(format!(
                "{name}: starts {start}° outside a limit, expected 4°"
            ));
        }
        let st = run(w.as_mut(), &sc);
        assert!(st.finite, "{name}: not finite");
        for (metric, value, max) in [
            ("energy_gain", st.energy_gain, 0.02),
            ("max_penetration_m", st.max_penetration_m as f64, 0.01),
            ("max_joint_gap_m", st.max_joint_gap_m as f64, gap),
            (
                "max_limit_violation_deg",
                st.max_limit_violation_deg as f64,
                limit,
            ),
        ] {
            report.push(format!("{name}: {metric} = {value:.4} (threshold {max})"));
            let known = KNOWN_GAPS.iter().any(|&(m, k, _)| m == name && k == metric);
            if known && value <= max {
                failures.push(format!(
                    "{name}: {metric} = {value} now meets {max}; remove it from KNOWN_GAPS"
                ));
            } else if !known && value > max {
                failures.push(format!("{name}: {metric} = {value} > {max}"));
            }
        }
    }
    println!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{failures:#?}\n{}", report.join("\n"));
}

/// The figure comes to rest and falls asleep under the multibody, by the file's own
/// `suspendSpeed` and `noMoveTime` (the scene threshold: a figure must sleep). Its limbs
/// are bone models, thin across, and their joints have friction: a friction couple that
/// turned them about their centres of mass, or that answered what the hard rows after it
/// were about to take out, kept their spins changing faster than `suspendSpeed` allows.
#[test]
fn the_multibody_puts_the_mod_humanoid_to_sleep() {
    let sc = figure(true);
    let mut w = MultibodyWorld::new(&sc).unwrap();
    let st = run(&mut w, &sc);
    assert!(st.asleep_at_s.is_some(), "still awake after 10 s");
}

/// The shape-frame poses of a method's bodies (the frame the rig's load poses use).
fn shape_frames(w: &dyn Method, sc: &SceneDesc) -> Vec<Pose> {
    let props = scene_mass_props(sc).unwrap();
    let mut states = Vec::new();
    w.body_states(&mut states);
    states
        .iter()
        .zip(&props)
        .map(|(s, m)| Pose {
            position: s.com - s.orientation * m.local_com,
            rotation: s.orientation,
        })
        .collect()
}

#[test]
fn the_bodies_drive_the_skeleton_and_skin_the_mesh() {
    let af = scene(true);
    let rig = af.rig.as_ref().expect("a figure built on a mesh has a rig");
    let sc = &af.desc;
    let mesh = md5mesh::load(character().mesh.as_ref().unwrap()).unwrap();
    assert_eq!(rig.joints.len(), mesh.skeleton.joints.len());
    // The body driving each joint is the one the .af names, in any case.
    let driver = |joint: &str| {
        let j = rig.joints.iter().find(|j| j.name == joint).unwrap();
        sc.bodies[j.driver.unwrap().body].name.clone()
    };
    assert_eq!(driver("Neck"), "head");
    assert_eq!(driver("Ruparm"), "ruparm");
    assert_eq!(
        driver("Body"),
        "waist",
        "the origin body drives joint origin's first child"
    );
    let mut w = MultibodyWorld::new(sc).unwrap();
    // At load the bodies give back the af_pose skeleton.
    for (p, r) in rig.joint_poses(&shape_frames(&w, sc)).iter().zip(&rig.rest) {
        assert!((p.position - r.position).length() < 1e-4, "{p:?} {r:?}");
    }
    for _ in 0..90 {
        w.step();
    }
    let bodies = shape_frames(&w, sc);
    let poses = rig.joint_poses(&bodies);
    // A driven joint keeps its rotation relative to its body (mod orientation).
    let lloleg = mesh.skeleton.index("Lloleg").unwrap();
    let body = rig.joints[lloleg].driver.unwrap().body;
    let rel_rest = sc.bodies[body].pose.rotation.inverse() * rig.rest[lloleg].rotation;
    let rel_now = bodies[body].rotation.inverse() * poses[lloleg].rotation;
    assert!(
        rel_rest.dot(rel_now).abs() > 1.0 - 1e-5,
        "the shin joint turns with its body"
    );
    // The fall moved the figure: the skeleton differs from the load pose.
    let moved = poses
        .iter()
        .zip(&rig.rest)
        .map(|(p, r)| (p.position - r.position).length())
        .fold(0.0f32, f32::max);
    assert!(moved > 0.05, "{moved}");
}
