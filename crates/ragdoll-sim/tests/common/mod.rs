//! What the test files share: the solvers under test, scene builders (boxes, joints),
//! the shipped scenes' loader, energies computed from the states a method reports; the
//! particle solvers' shared checks (`particle`) and the readers' fuzzing mutations
//! (`mutation`).

#![allow(dead_code)]

pub mod mutation;
pub mod particle;

use ragdoll_sim::glam::{Mat3, Vec3};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::af::{AfOptions, AfScene, load};
use ragdoll_sim::scene::*;
use ragdoll_sim::{BodyState, Method};
use std::path::PathBuf;

/// A solver's constructor: builds a method from a scene.
pub type Make = fn(&SceneDesc) -> Box<dyn Method>;

/// The impulse-based multibody solver.
pub fn multibody(sc: &SceneDesc) -> Box<dyn Method> {
    Box::new(MultibodyWorld::new(sc).unwrap_or_else(|e| panic!("{e}")))
}

/// The particle method's rigid-frames solver.
pub fn rigid_frames(sc: &SceneDesc) -> Box<dyn Method> {
    Box::new(ParticleWorld::new(sc, ParticleSolver::RigidFrames).unwrap_or_else(|e| panic!("{e}")))
}

/// The particle method's XPBD solver.
pub fn xpbd(sc: &SceneDesc) -> Box<dyn Method> {
    Box::new(ParticleWorld::new(sc, ParticleSolver::Xpbd).unwrap_or_else(|e| panic!("{e}")))
}

/// `body_states` into a fresh vector.
pub trait States {
    /// The kinematic state of every body now.
    fn body_states_vec(&self) -> Vec<BodyState>;
}

impl States for Box<dyn Method> {
    fn body_states_vec(&self) -> Vec<BodyState> {
        let mut out = Vec::new();
        self.body_states(&mut out);
        out
    }
}

/// A dynamic box of half extents `half` centred at `pos`.
pub fn boxed(name: &str, half: Vec3, pos: Vec3, mass: f32) -> BodyDesc {
    BodyDesc::new(
        name,
        Shape::Box { half_extents: half },
        Pose::from_position(pos),
        MassSpec::Mass(mass),
    )
}

/// A dynamic cube of half size `half` centred at `pos`.
pub fn cube(name: &str, half: f32, pos: Vec3, mass: f32) -> BodyDesc {
    boxed(name, Vec3::splat(half), pos, mass)
}

/// A scene of `bodies` with default settings and the given ground, no air friction.
pub fn scene(bodies: Vec<BodyDesc>, ground: Option<Ground>) -> SceneDesc {
    SceneDesc {
        name: "closed form".into(),
        bodies,
        settings: Settings {
            ground,
            ..Settings::default()
        },
        ..SceneDesc::default()
    }
}

/// A scene of `bodies` and `constraints` without ground and under `gravity`, the
/// other settings default.
pub fn free_scene(
    bodies: Vec<BodyDesc>,
    constraints: Vec<ConstraintDesc>,
    gravity: Vec3,
) -> SceneDesc {
    SceneDesc {
        name: "free".into(),
        bodies,
        constraints,
        settings: Settings {
            gravity,
            ground: None,
            ..Settings::default()
        },
        ..SceneDesc::default()
    }
}

fn body2(parent: Option<usize>) -> BodyRef {
    parent.map_or(BodyRef::World, |p| BodyRef::Body(BodyId(p as u32)))
}

/// A frictionless hinge from body `body` to `parent` (or the world).
pub fn hinge(
    name: &str,
    body: usize,
    parent: Option<usize>,
    anchor: Vec3,
    axis: Vec3,
    limit: Option<AngleRange>,
) -> ConstraintDesc {
    ConstraintDesc {
        name: name.into(),
        body1: BodyId(body as u32),
        body2: body2(parent),
        kind: JointKind::Hinge {
            anchor,
            axis,
            limit,
        },
        friction: 0.0,
    }
}

/// A frictionless, unlimited ball-and-socket joint.
pub fn ball(name: &str, body: usize, parent: Option<usize>, anchor: Vec3) -> ConstraintDesc {
    ConstraintDesc {
        name: name.into(),
        body1: BodyId(body as u32),
        body2: body2(parent),
        kind: JointKind::BallAndSocket {
            anchor,
            swing: None,
            twist: None,
            limit_style: LimitStyle::Hard,
        },
        friction: 0.0,
    }
}

/// Every body's inertia about its centre of mass in its shape frame (boxes: the centre
/// of mass is the shape frame's origin).
pub fn inertias(sc: &SceneDesc) -> Vec<Mat3> {
    sc.bodies
        .iter()
        .map(|b| mass_props(b).unwrap_or_else(|e| panic!("{e}")).inertia)
        .collect()
}

/// Total energy ½mv² + ½ωᵀIω + m g y of the dynamic bodies (J), from the states.
pub fn energy(states: &[BodyState], sc: &SceneDesc, inertia: &[Mat3]) -> f64 {
    let g = -sc.settings.gravity;
    let mut e = 0.0f64;
    for (i, (s, b)) in states.iter().zip(&sc.bodies).enumerate() {
        if b.is_fixed() {
            continue;
        }
        let m = match b.mass {
            MassSpec::Mass(m) => m,
            MassSpec::Density(_) => mass_props(b).unwrap().mass,
        };
        let r = Mat3::from_quat(s.orientation);
        let iw = r * inertia[i] * r.transpose();
        e += 0.5 * (m * s.linear_velocity.length_squared()) as f64
            + 0.5 * s.angular_velocity.dot(iw * s.angular_velocity) as f64
            + (m * g.dot(s.com)) as f64;
    }
    e
}

/// A scene shipped in assets/scenes, default variant.
pub fn shipped_scene(name: &str) -> SceneDesc {
    shipped_variant(name, 1)
}

/// A scene shipped in assets/scenes, in one of its variants (`AfOptions::variant`).
pub fn shipped_variant(name: &str, variant: u32) -> SceneDesc {
    let opts = AfOptions {
        variant,
        ..Default::default()
    };
    shipped_with(name, &opts).desc
}

/// The pile scene (assets/scenes/pile.af) with `count` humans.
pub fn shipped_pile(count: u32) -> SceneDesc {
    let opts = AfOptions {
        count: Some(count),
        ..Default::default()
    };
    shipped_with("pile", &opts).desc
}

/// The path of `file` (with its extension) in assets/scenes.
pub fn shipped_path(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/scenes")
        .join(file)
}

/// The scene file `name` of assets/scenes read with `opts`: the one loader of the
/// tests that read shipped scenes; a file that does not load fails the test with its
/// `FILE:LINE:COL` message.
pub fn shipped_with(name: &str, opts: &AfOptions) -> AfScene {
    load(&shipped_path(&format!("{name}.af")), opts).unwrap_or_else(|e| panic!("{e}"))
}

/// Our own Doom 3 test mod (assets/doom3, made by scripts/make_doom3_mod.py).
pub fn lab_mod_base() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/doom3")
}

/// The variable naming a real Doom 3 base folder for the tests that read id's files.
pub const DOOM3_BASE_ENV: &str = "RAGDOLL_LAB_DOOM3_BASE";

/// The real Doom 3 base folder named by [`DOOM3_BASE_ENV`], or `None` when it is unset,
/// after a note that `what` is skipped.
pub fn real_doom3_base(what: &str) -> Option<PathBuf> {
    match std::env::var_os(DOOM3_BASE_ENV) {
        Some(p) if !p.is_empty() => Some(PathBuf::from(p)),
        _ => {
            println!("note: {DOOM3_BASE_ENV} is not set; skipping {what}");
            None
        }
    }
}
