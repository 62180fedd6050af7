//! The ragdoll taking over from an animation, on the mod under `assets/doom3/` (written
//! by `scripts/make_doom3_mod.py`): the walk's velocities, the figure placed where the
//! build would place it, and both methods carrying the walk forward after the take-over.

use glam::Vec3;
use ragdoll_sim::Method;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::af::{AfOptions, AfScene, load_character};
use ragdoll_sim::scene::decl::{Doom3Base, Doom3Character};
use ragdoll_sim::scene::takeover::{Takeover, TakeoverError};
use ragdoll_sim::scene::{SceneDesc, md5anim, md5mesh, scene_mass_props};

mod common;

use common::lab_mod_base as base_dir;

fn character() -> Doom3Character {
    let base = Doom3Base::open(&base_dir()).unwrap_or_else(|e| panic!("{e}"));
    base.character("monster_lab_human")
        .unwrap_or_else(|e| panic!("{e}"))
}

fn figure(c: &Doom3Character) -> AfScene {
    load_character(c, &base_dir(), &AfOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn takeover(anim_name: &str) -> Takeover {
    let c = character();
    let scene = figure(&c);
    let mesh = md5mesh::load(c.mesh.as_ref().unwrap()).unwrap_or_else(|e| panic!("{e}"));
    let path = if anim_name == "af_pose" {
        c.af_pose.clone().unwrap()
    } else {
        c.anims
            .iter()
            .find(|(n, _)| n == anim_name)
            .map(|(_, p)| p.clone())
            .unwrap()
    };
    let anim = md5anim::load(&path).unwrap_or_else(|e| panic!("{e}"));
    Takeover::new(
        &scene.desc,
        scene.rig.as_ref(),
        &mesh.skeleton,
        anim,
        anim_name,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Total mass and the mass-weighted mean of the bodies' (centre-of-mass) velocities.
fn momentum_velocity(scene: &SceneDesc) -> Vec3 {
    let props = scene_mass_props(scene).unwrap();
    let m: f32 = props.iter().map(|p| p.mass).sum();
    scene
        .bodies
        .iter()
        .zip(&props)
        .map(|(b, p)| b.linear_velocity * p.mass)
        .sum::<Vec3>()
        / m
}

fn centre_of_mass(m: &dyn Method, scene: &SceneDesc) -> Vec3 {
    let props = scene_mass_props(scene).unwrap();
    let mut states = Vec::new();
    m.body_states(&mut states);
    let total: f32 = props.iter().map(|p| p.mass).sum();
    states
        .iter()
        .zip(&props)
        .map(|(s, p)| s.com * p.mass)
        .sum::<Vec3>()
        / total
}

#[test]
fn the_build_pose_sampled_as_the_build_samples_it_gives_the_figure_back() {
    // The figure is built from af_pose at 1 ms; placing its bodies on af_pose by the
    // engine's rule at that instant must put every body where the build did.
    let t = takeover("af_pose");
    let scene = t.scene_at(0.001);
    for (a, b) in scene.bodies.iter().zip(&t.figure().bodies) {
        assert!(
            a.pose.position.distance(b.pose.position) < 1e-5,
            "{}: {} vs {}",
            a.name,
            a.pose.position,
            b.pose.position
        );
        // 2·asin |xyz| of the relative rotation (acos of the dot loses ~1e-3 rad near 0).
        let d = a.pose.rotation * b.pose.rotation.inverse();
        let turn = 2.0 * Vec3::new(d.x, d.y, d.z).length().asin();
        assert!(turn < 1e-4, "{}: {turn} rad", a.name);
    }
}

#[test]
fn velocities_from_the_walk_are_finite_and_point_the_way_it_walks() {
    let t = takeover("walk");
    let dir = t.root_motion().expect("the walk moves its root");
    // The figure faces +X (the .af's forward), which stays +X in our axes.
    assert!(dir.dot(Vec3::X) > 0.99, "{dir}");
    // The root's speed: its travel over the animation's length.
    let a = t.anim();
    let travel = (a.local_poses(a.frame_count() - 1)[0].position - a.local_poses(0)[0].position)
        .length()
        * 0.0254;
    let root_speed = travel / a.duration();
    for frame in [0, 5, 12, 24] {
        let scene = t.scene_at(t.frame_time(frame).unwrap());
        for b in &scene.bodies {
            assert!(
                b.linear_velocity.is_finite() && b.angular_velocity.is_finite(),
                "{}",
                b.name
            );
        }
        let v = momentum_velocity(&scene);
        let along = v.dot(dir);
        println!(
            "frame {frame}: mean velocity {v} ({along:.3} m/s along the walk, root {root_speed:.3} m/s)"
        );
        // The swinging limbs move with and against the walk; the figure as a whole
        // moves with the root.
        assert!(
            along > 0.5 * root_speed && along < 1.5 * root_speed,
            "frame {frame}: {along} m/s along the walk, root {root_speed} m/s"
        );
        assert!(
            (v - dir * along).length() < 0.25 * root_speed,
            "frame {frame}: {v}"
        );
    }
}

#[test]
fn after_the_take_over_the_figure_moves_the_way_it_walked_on_both_methods() {
    let t = takeover("walk");
    let dir = t.root_motion().unwrap();
    let scene = t.scene_at(t.frame_time(6).unwrap());
    let v0 = momentum_velocity(&scene).dot(dir);
    let methods: [(&str, Box<dyn Method>); 3] = [
        ("multibody", Box::new(MultibodyWorld::new(&scene).unwrap())),
        (
            "rigid-frames",
            Box::new(ParticleWorld::new(&scene, ParticleSolver::RigidFrames).unwrap()),
        ),
        (
            "xpbd",
            Box::new(ParticleWorld::new(&scene, ParticleSolver::Xpbd).unwrap()),
        ),
    ];
    for (name, mut m) in methods {
        let start = centre_of_mass(m.as_ref(), &scene);
        let steps = (0.3 / scene.settings.timestep).round() as usize;
        for _ in 0..steps {
            m.step();
        }
        let moved = centre_of_mass(m.as_ref(), &scene) - start;
        let along = moved.dot(dir);
        let across = (moved - dir * along - Vec3::Y * moved.y).length();
        println!(
            "{name}: centre of mass moved {moved} in 0.3 s ({along:.3} m along the walk; v0 {v0:.3} m/s)"
        );
        // Free flight at v0 would carry it v0 · 0.3 s; the feet's friction slows it.
        assert!(along > 0.25 * v0 * 0.3, "{name}: {along} m along the walk");
        assert!(across < 0.5 * along, "{name}: {across} m across the walk");
    }
}

#[test]
fn an_animation_of_another_skeleton_is_refused() {
    let c = character();
    let scene = figure(&c);
    let mesh = md5mesh::load(c.mesh.as_ref().unwrap()).unwrap();
    let mut anim = md5anim::load(&c.anims[0].1).unwrap();
    anim.joints[3].name = "Spine".into();
    let e = Takeover::new(
        &scene.desc,
        scene.rig.as_ref(),
        &mesh.skeleton,
        anim,
        "walk",
    )
    .unwrap_err();
    assert!(matches!(e, TakeoverError::Hierarchy { .. }), "{e}");
    assert!(e.to_string().contains("Spine"), "{e}");
    // A figure built without a skeleton has nothing to animate.
    let anim = md5anim::load(&c.anims[0].1).unwrap();
    let e = Takeover::new(&scene.desc, None, &mesh.skeleton, anim, "walk").unwrap_err();
    assert!(matches!(e, TakeoverError::NoSkeleton { .. }), "{e}");
}
