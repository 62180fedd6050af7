//! A shot at the skinned mesh, as B fires one in the window: the mod humanoid
//! (`assets/doom3`, entity `monster_lab_human`) standing in its af_pose, a 1 cm box of
//! 0.2 kg at 15 m/s shot forward through the left forearm's mesh four fifths of the way
//! from the elbow to the hand, 3.5 cm off the bone's axis. There the mesh (a tube 4 cm in
//! radius) stands outside the collision shape (Doom 3's `bone` model, 1.8 cm from the
//! axis there), so only the mesh lies on the shot's path. With mesh hits on, the hit
//! pushes the forearm (the body containing the hand joint, the nearest) along the shot
//! with the shot's whole momentum; the upper arm, sharing the elbow, follows less, and
//! the other bodies barely move. With mesh hits off, the same shot passes by. Both
//! methods, each on its own side.

use glam::Vec3;
use ragdoll_lab::cli::{ParticleSolverArg, SceneArgs};
use ragdoll_lab::scenes;
use ragdoll_lab::session::{Session, ShotSettings};
use ragdoll_sim::BodyState;
use ragdoll_sim::scene::{BodyId, MassSpec};
use std::path::PathBuf;

fn session() -> Session {
    let loaded = scenes::load(&SceneArgs {
        doom3: Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/doom3")),
        entity: Some("monster_lab_human".into()),
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{e}"));
    Session::new(loaded, ParticleSolverArg::RigidFrames).unwrap_or_else(|e| panic!("{e}"))
}

fn states(s: &Session, side: usize) -> Vec<BodyState> {
    let mut out = Vec::new();
    s.methods[side].body_states(&mut out);
    out
}

/// A 1 cm box of 0.2 kg at 15 m/s: 3 N·s.
const SHOT: ShotSettings = ShotSettings {
    edge: 0.01,
    speed: 15.0,
    density: 0.2 / (0.01 * 0.01 * 0.01),
};

/// Where the shot is aimed and along which direction: the forearm's mesh four fifths of
/// the way from the elbow joint to the hand joint, 3.5 cm off the axis outward.
fn aim(s: &Session) -> (Vec3, Vec3) {
    let skin = s
        .loaded
        .skin
        .as_ref()
        .expect("the entity has a skinned mesh");
    let joint = |name: &str| {
        let j = skin.rig.joints.iter().position(|j| j.name == name).unwrap();
        skin.rig.rest[j].position
    };
    let (elbow, hand, chest) = (joint("Lloarm"), joint("Lhand"), joint("Chest"));
    let axis = (hand - elbow).normalize();
    // Across the arm, horizontal; the shot flies along the third direction.
    let out = {
        let side = elbow - chest;
        (side - axis * side.dot(axis)).normalize()
    };
    let dir = axis.cross(out).normalize();
    let target = elbow + (hand - elbow) * 0.8 + out * 0.035;
    (target, dir)
}

/// Sides whose forearm a shot passing 1.2 cm beside its collision shape still pushes by
/// more than half a mesh hit's push (measured when written: multibody 1.29 m/s against
/// the hit's 2.29). The multibody makes a shot's contacts once a step, at its start,
/// within the distance the shot may travel (25 cm at 15 m/s), with the normal it has
/// there; the speculative rows then stop an approach along that normal that never
/// happens as the shot flies past (a ghost contact). The test fails when a listed side
/// starts passing.
const NUDGED_SIDES: [usize; 1] = [1];

fn body(s: &Session, name: &str) -> BodyId {
    let i = s
        .loaded
        .desc
        .bodies
        .iter()
        .position(|b| b.name == name)
        .unwrap();
    BodyId(i as u32)
}

#[test]
fn a_shot_through_the_forearm_mesh_pushes_the_forearm_on_both_sides() {
    let mut control = session();
    let mut hit = session();
    let mut missed = session();
    missed.mesh_shots = false;
    let (target, dir) = aim(&hit);
    // Shot from 0.15 m before the target (Session::shoot starts the box 0.3 m and one
    // edge along the ray), so its first step crosses the mesh.
    let origin = target - dir * (0.15 + 0.3 + SHOT.edge);
    // No collision shape of either method lies on the path of the shot's centre or of
    // its faces' centres.
    for side in 0..2 {
        let n = hit.loaded.desc.bodies.len();
        for ray in [-0.005f32, 0.005] {
            for offset in [Vec3::new(0.0, ray, 0.0), Vec3::new(0.0, 0.0, ray)] {
                let o = origin + offset;
                assert!(
                    hit.methods[side]
                        .raycast(o, dir)
                        .is_none_or(|h| h.body.index() >= n),
                    "side {side}: the shot's path at {offset} meets a collision shape"
                );
            }
        }
    }
    hit.shoot(origin, dir, &SHOT);
    missed.shoot(origin, dir, &SHOT);
    // The control fires the same shot 5 m to the side, so the three worlds hold the same
    // bodies and differ only by what the shot hits.
    control.shoot(origin + Vec3::new(0.0, 0.0, -5.0), dir, &SHOT);
    // Step until both sides have hit: the first step, as the shot starts 15 cm away.
    let mut steps = 0;
    while hit.mesh_impacts.len() < 2 && steps < 30 {
        for s in [&mut control, &mut hit, &mut missed] {
            s.step();
        }
        steps += 1;
    }
    let forearm = body(&hit, "lloarm");
    let momentum = SHOT.mass() * SHOT.speed;
    let n = hit.loaded.desc.bodies.len();
    for side in 0..2 {
        let impact = hit
            .mesh_impacts
            .iter()
            .find(|i| i.side == side)
            .unwrap_or_else(|| panic!("side {side}: no hit on the mesh in {steps} steps"));
        // The hand joint is the nearest; the forearm contains it ("*Lloarm").
        let skin = hit.loaded.skin.as_ref().unwrap();
        assert_eq!(skin.rig.joints[impact.joint].name, "Lhand", "side {side}");
        assert_eq!(impact.body, Some(forearm), "side {side}: {impact:?}");
        assert!(
            (impact.impulse - dir * momentum).length() < 1e-3 * momentum,
            "side {side}: the whole momentum along the shot: {impact:?}"
        );
        assert!(
            impact.point.distance(target) < 0.02,
            "side {side}: hit {} from the aim",
            impact.point.distance(target)
        );
        let (c, h, m) = (
            states(&control, side),
            states(&hit, side),
            states(&missed, side),
        );
        let dv = |i: usize| h[i].linear_velocity - c[i].linear_velocity;
        let along = dv(forearm.index()).dot(dir);
        let MassSpec::Mass(mass) = hit.loaded.desc.bodies[forearm.index()].mass else {
            panic!("masses are resolved when the figure is read")
        };
        // A free forearm would take J/m along the shot; through the elbow it takes less,
        // but the largest push of all.
        let free = momentum / mass;
        println!("side {side}: forearm dv along the shot {along:.3} m/s (free body: {free:.3})");
        let upper = body(&hit, "luparm");
        let mut others = Vec::new();
        for i in (0..n).filter(|&i| i != forearm.index()) {
            others.push((hit.loaded.desc.bodies[i].name.clone(), dv(i).length()));
        }
        println!("side {side}: other bodies' |dv|: {others:?}");
        assert!(
            along > 0.5 * free,
            "side {side}: the forearm moved {along} m/s along the shot (free: {free})"
        );
        // The upper arm shares the elbow, and a hit away from the forearm's centre of
        // percussion (about the middle of a bone model) pulls the elbow along: it moves,
        // less than the forearm. The bodies not jointed to the forearm barely move.
        for (i, (name, v)) in (0..n).filter(|&i| i != forearm.index()).zip(&others) {
            let bound = if i == upper.index() { 1.0 } else { 0.25 };
            assert!(
                *v < bound * along,
                "side {side}: {name} changed by {v} m/s, the forearm by {along}"
            );
        }
        // The same shot with mesh hits off passes beside the forearm's bone; no
        // collision shape lies on its path (checked above), but the methods' speculative
        // contacts may still nudge the forearm as it flies by. The mesh hit's push is
        // more than twice that nudge.
        let nudge =
            (m[forearm.index()].linear_velocity - c[forearm.index()].linear_velocity).length();
        println!("side {side}: with mesh hits off the forearm changed by {nudge:.3} m/s");
        if NUDGED_SIDES.contains(&side) {
            assert!(
                nudge >= 0.5 * along,
                "side {side}: the passing shot's nudge {nudge} m/s is now under half the hit's \
                 {along}; remove the side from NUDGED_SIDES"
            );
        } else {
            assert!(
                nudge < 0.5 * along,
                "side {side}: the shot passing by changed the forearm by {nudge} m/s, the hit by {along}"
            );
        }
    }
}

#[test]
fn a_shot_from_afar_hits_the_same_forearm_with_its_whole_momentum() {
    // From 1.5 m, as from the camera: the shot drops under gravity on its way (the
    // impulse gains m·g·t downward) but hits the same forearm, on both sides, with its
    // whole momentum along the shot.
    let mut s = session();
    let (target, dir) = aim(&s);
    s.shoot(target - dir * (1.5 + 0.3 + SHOT.edge), dir, &SHOT);
    let mut steps = 0;
    while s.mesh_impacts.len() < 2 && steps < 30 {
        s.step();
        steps += 1;
    }
    let forearm = body(&s, "lloarm");
    let momentum = SHOT.mass() * SHOT.speed;
    for side in 0..2 {
        let impact = s
            .mesh_impacts
            .iter()
            .find(|i| i.side == side)
            .unwrap_or_else(|| panic!("side {side}: no hit on the mesh in {steps} steps"));
        assert_eq!(impact.body, Some(forearm), "side {side}: {impact:?}");
        assert!(
            (impact.impulse.dot(dir) - momentum).abs() < 1e-3 * momentum,
            "side {side}: {impact:?}"
        );
    }
}
