//! The ragdoll taking over from an animation, captured offscreen (llvmpipe in CI): the
//! figure at frame 0 of the walk is not the figure in its `af_pose`, and after K and a
//! fall it is neither.

use glam::Vec3;
use ragdoll_lab::app_state::AppState;
use ragdoll_lab::capture::{Image, Offscreen};
use ragdoll_lab::cli::{ParticleSolverArg, SceneArgs};
use ragdoll_lab::render::camera::OrbitCamera;
use ragdoll_lab::scenes;
use ragdoll_lab::session::Session;
use ragdoll_sim::scene::CameraDesc;
use std::path::PathBuf;

const W: u32 = 320;
const H: u32 = 180;

fn load(anim: Option<&str>) -> scenes::LoadedScene {
    scenes::load(&SceneArgs {
        doom3: Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/doom3")),
        entity: Some("monster_lab_human".into()),
        anim: anim.map(String::from),
        at: anim.map(|_| 0),
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Pixels whose colour differs by more than 30 in a channel.
fn differing(a: &Image, b: &Image) -> usize {
    let mut n = 0;
    for y in 0..H {
        for x in 0..W {
            let (p, q) = (a.pixel(x, y), b.pixel(x, y));
            n += (0..3).any(|c| (p[c] as i32 - q[c] as i32).abs() > 30) as usize;
        }
    }
    n
}

/// Pixels tinted like either side's figure (blue or red over the grey ground).
fn figure_pixels(img: &Image) -> usize {
    let mut n = 0;
    for y in 0..H {
        for x in 0..W {
            let [r, g, b, _] = img.pixel(x, y).map(i32::from);
            n += (b - r.max(g) > 40 || r - g.max(b) > 40) as usize;
        }
    }
    n
}

#[test]
fn the_walk_frame_and_the_fall_after_k_are_captured_as_they_differ() {
    let camera = OrbitCamera::from_desc(&CameraDesc {
        eye: Vec3::new(0.6, 1.1, 3.0),
        target: Vec3::new(0.2, 0.8, 0.0),
    });
    let mut state = AppState::new(None, 1, camera);
    state.show.particles = false;
    state.show.sticks = false;
    state.show.bodies = false;
    let mut target = Offscreen::new(W, H).unwrap();

    let af_pose = Session::new(load(None), ParticleSolverArg::RigidFrames).unwrap();
    let posed = target.render(&state, &af_pose).unwrap();
    // What `capture --anim walk --at 0` starts from: the ragdoll on the walk's frame 0.
    let walk = load(Some("walk")).taken_over();
    let mut session = Session::new(walk, ParticleSolverArg::RigidFrames).unwrap();
    let frame0 = target.render(&state, &session).unwrap();
    let n = differing(&posed, &frame0);
    println!("af_pose vs walk frame 0: {n} pixels differ");
    assert!(figure_pixels(&frame0) > 400, "{}", figure_pixels(&frame0));
    // The walk holds the arms at the sides where af_pose spreads them 12°.
    assert!(n > 30, "{n} pixels differ");

    // The window's way: the walk plays, K at frame 0, then a second of falling.
    let mut playing = Session::new(load(Some("walk")), ParticleSolverArg::RigidFrames).unwrap();
    assert!(playing.take_over().unwrap());
    for _ in 0..60 {
        playing.step();
        session.step();
    }
    playing.refresh();
    session.refresh();
    let fallen = target.render(&state, &playing).unwrap();
    let n = differing(&frame0, &fallen);
    println!("walk frame 0 vs a second after K: {n} pixels differ");
    assert!(n > 400, "{n} pixels differ");
    // K at frame 0 and `capture --anim walk --at 0` start the same ragdoll.
    let captured = target.render(&state, &session).unwrap();
    assert!(
        differing(&fallen, &captured) < 20,
        "{}",
        differing(&fallen, &captured)
    );
}
