//! The skinned mesh on the CPU (`scene::skin`), which the GPU pass draws from the same
//! vertex records: on the mod humanoid (`assets/doom3`) after a fall in each method, a
//! vertex weighted to one joint moves exactly with the body that places that joint, and
//! a rigid motion of every body moves every vertex rigidly.

use glam::{Quat, Vec3};
use ragdoll_sim::Method;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::Pose;
use ragdoll_sim::scene::af::{AfOptions, AfScene, load_character};
use ragdoll_sim::scene::decl::Doom3Base;
use ragdoll_sim::scene::md5mesh;
use ragdoll_sim::scene::skin::SkinnedMesh;
use ragdoll_sim::snapshot::RenderSnapshot;
use std::path::Path;

fn figure() -> (AfScene, SkinnedMesh) {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/doom3");
    let decls = Doom3Base::open(&base).unwrap_or_else(|e| panic!("{e}"));
    let c = decls
        .character("monster_lab_human")
        .unwrap_or_else(|e| panic!("{e}"));
    let scene = load_character(&c, &base, &AfOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let mesh = md5mesh::load(c.mesh.as_ref().unwrap()).unwrap_or_else(|e| panic!("{e}"));
    let skin = SkinnedMesh::new(&mesh, scene.rig.as_ref().unwrap(), &scene.desc.bodies);
    (scene, skin)
}

/// Every body's shape frame as the method draws it.
fn poses(m: &dyn Method, n: usize) -> Vec<Pose> {
    let mut snap = RenderSnapshot::default();
    m.snapshot(&mut snap);
    let mut out = vec![Pose::IDENTITY; n];
    for b in snap.bodies.iter().filter(|b| b.body.index() < n) {
        out[b.body.index()] = b.pose;
    }
    out
}

/// Vertices whose one weight is on joint `name`.
fn single(scene: &AfScene, skin: &SkinnedMesh, name: &str) -> Vec<usize> {
    let rig = scene.rig.as_ref().unwrap();
    let j = rig.joints.iter().position(|j| j.name == name).unwrap() as u32;
    let v: Vec<usize> = (0..skin.vertices.len())
        .filter(|&i| {
            let v = &skin.vertices[i];
            v.joints[0] == j && v.biases[0] == 1.0 && v.biases[1..].iter().all(|b| *b == 0.0)
        })
        .collect();
    assert!(!v.is_empty(), "the mesh has vertices on {name} alone");
    v
}

fn body(scene: &AfScene, name: &str) -> usize {
    scene
        .desc
        .bodies
        .iter()
        .position(|b| b.name == name)
        .unwrap()
}

#[test]
fn a_vertex_on_one_joint_moves_with_its_body_through_a_fall() {
    let (scene, skin) = figure();
    let rig = scene.rig.as_ref().unwrap();
    let n = scene.desc.bodies.len();
    let methods: [Box<dyn Method>; 2] = [
        Box::new(ParticleWorld::new(&scene.desc, ParticleSolver::RigidFrames).unwrap()),
        Box::new(MultibodyWorld::new(&scene.desc).unwrap()),
    ];
    for mut m in methods {
        let rest_bodies = poses(m.as_ref(), n);
        let mut rest = Vec::new();
        skin.positions(&rig.joint_poses(&rest_bodies), &mut rest);
        for _ in 0..90 {
            m.step();
        }
        let now_bodies = poses(m.as_ref(), n);
        let mut now = Vec::new();
        skin.positions(&rig.joint_poses(&now_bodies), &mut now);
        // Where a point fixed to body b at rest is now.
        let carried = |b: usize, p: Vec3| {
            now_bodies[b].transform_point(rest_bodies[b].inverse_transform_point(p))
        };
        // Joint "Body" is placed by the origin body ("waist") alone: its entity carries
        // joint "origin", and the waist turns "Body" about it. Exact to rounding.
        let waist = body(&scene, "waist");
        let moved = now_bodies[waist]
            .position
            .distance(rest_bodies[waist].position);
        assert!(moved > 0.1, "{:?}: the waist fell {moved} m", m.kind());
        for &v in &single(&scene, &skin, "Body") {
            let off = now[v].distance(carried(waist, rest[v]));
            assert!(
                off < 2e-5,
                "{:?}: vertex {v} is {off} m off the waist",
                m.kind()
            );
        }
        // "Lloarm" turns with the forearm but sits where the chain waist → chest →
        // upper arm puts it, so its vertices stay on the forearm to within the gaps of
        // the three joints on that chain.
        let gap = m.sample().max_joint_gap;
        let forearm = body(&scene, "lloarm");
        let worst = single(&scene, &skin, "Lloarm")
            .iter()
            .map(|&v| now[v].distance(carried(forearm, rest[v])))
            .fold(0.0f32, f32::max);
        assert!(
            worst <= 3.0 * gap + 2e-5,
            "{:?}: forearm vertices {worst} m off, joint gaps up to {gap} m",
            m.kind()
        );
    }
}

#[test]
fn moving_every_body_rigidly_moves_every_vertex_with_them() {
    let (scene, skin) = figure();
    let rig = scene.rig.as_ref().unwrap();
    let rest_bodies: Vec<Pose> = scene.desc.bodies.iter().map(|b| b.pose).collect();
    let t = Pose {
        position: Vec3::new(0.4, -0.2, 1.3),
        rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.8, -0.3, 1.9),
    };
    let moved: Vec<Pose> = rest_bodies
        .iter()
        .map(|b| Pose {
            position: t.transform_point(b.position),
            rotation: t.rotation * b.rotation,
        })
        .collect();
    let (mut before, mut after) = (Vec::new(), Vec::new());
    skin.positions(&rig.joint_poses(&rest_bodies), &mut before);
    skin.positions(&rig.joint_poses(&moved), &mut after);
    let worst = before
        .iter()
        .zip(&after)
        .map(|(b, a)| t.transform_point(*b).distance(*a))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "{worst} m");
    // Casts go against the moved vertices: a short segment through the middle of a
    // moved triangle hits it there.
    let joints = rig.joint_poses(&moved);
    let posed = skin.posed(&joints);
    let tri = skin.triangles[0];
    let corner = |k: usize| after[tri[k] as usize];
    let centre = (corner(0) + corner(1) + corner(2)) / 3.0;
    let normal = (corner(1) - corner(0))
        .cross(corner(2) - corner(0))
        .normalize();
    let hit = posed
        .cast_segment(centre + normal * 0.01, centre - normal * 0.01)
        .expect("the segment crosses the triangle");
    assert!(hit.point.distance(centre) < 1e-4, "{hit:?} vs {centre}");
    assert!((hit.fraction - 0.5).abs() < 1e-2, "{hit:?}");
}
