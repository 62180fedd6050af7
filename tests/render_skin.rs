//! The skinned md5 mesh of a Doom 3 figure, captured offscreen (llvmpipe in CI): with the
//! bodies hidden the mesh alone draws the figure, blue on the left and red on the
//! right; the CPU skin that shots are cast against lies where the GPU drew it; hiding the
//! mesh too leaves neither colour; after a fall the mesh is not where the bind pose put
//! it.

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
const MARGIN: i32 = 40;

/// (blue pixels in the left half, red pixels in the right half).
fn colours(img: &Image) -> (usize, usize) {
    let (mut blue, mut red) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            let [r, g, b, _] = img.pixel(x, y).map(i32::from);
            if x < W / 2 && b - r.max(g) > MARGIN {
                blue += 1;
            }
            if x >= W / 2 && r - g.max(b) > MARGIN {
                red += 1;
            }
        }
    }
    (blue, red)
}

#[test]
fn the_skinned_mesh_is_drawn_on_both_sides_and_follows_the_fall() {
    let loaded = scenes::load(&SceneArgs {
        doom3: Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/doom3")),
        entity: Some("monster_lab_human".into()),
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        loaded.skin.is_some(),
        "the entity's mesh is loaded for skinning"
    );
    // Close enough that the 1.7 m figure fills most of each half's height.
    let camera = OrbitCamera::from_desc(&CameraDesc {
        eye: Vec3::new(2.6, 1.1, 1.2),
        target: Vec3::new(0.0, 0.8, 0.0),
    });
    let mut state = AppState::new(None, 1, camera);
    state.show.particles = false;
    state.show.sticks = false;
    state.show.bodies = false;
    let mut session = Session::new(loaded, ParticleSolverArg::RigidFrames).unwrap();
    let mut target = Offscreen::new(W, H).unwrap();

    let mesh_only = target.render(&state, &session).unwrap();
    let (blue, red) = colours(&mesh_only);
    assert!(
        blue > 200 && red > 200,
        "mesh: {blue} blue, {red} red pixels"
    );

    // The CPU skin (what shots are cast against) lies where the GPU drew the mesh: the
    // middles of its triangles, projected into each half, land on that half's tint; the
    // same points 0.4 m to the side mostly do not.
    let layout = target.last_layout().expect("rendered").view;
    let halves = ragdoll_lab::ui::viewports(layout, 1.0, state.layout);
    let skin = session.loaded.skin.clone().expect("loaded above");
    for (side, half) in halves.iter().enumerate() {
        let posed = skin.skinned.posed(&session.joint_poses[side]);
        let p = posed.positions();
        let on_tint = |shift: Vec3| {
            let mut inside = 0;
            let mut total = 0;
            for t in &skin.skinned.triangles {
                let centre = (p[t[0] as usize] + p[t[1] as usize] + p[t[2] as usize]) / 3.0;
                let Some(px) = half.project(&state.camera, centre + shift) else {
                    continue;
                };
                total += 1;
                // A pixel of the 3×3 around it: small triangles' middles fall on
                // antialiased edges, blended with the background.
                let (x, y) = (px.x.round() as i64, px.y.round() as i64);
                let tinted = (-1..=1).any(|dy| {
                    (-1..=1).any(|dx| {
                        let (x, y) = (x + dx, y + dy);
                        if x < 0 || y < 0 || x >= W as i64 || y >= H as i64 {
                            return false;
                        }
                        let [r, g, b, _] = mesh_only.pixel(x as u32, y as u32).map(i32::from);
                        let tint = if side == 0 {
                            b - r.max(g)
                        } else {
                            r - g.max(b)
                        };
                        tint > MARGIN
                    })
                });
                inside += tinted as usize;
            }
            inside as f32 / total.max(1) as f32
        };
        let (here, beside) = (on_tint(Vec3::ZERO), on_tint(Vec3::new(0.0, 0.0, 0.4)));
        assert!(
            here > 0.9 && beside < 0.5,
            "side {side}: {here} of the CPU skin's triangles on the drawn mesh, {beside} when moved aside"
        );
    }

    state.show.mesh = false;
    state.show.bodies = false;
    let nothing = target.render(&state, &session).unwrap();
    // With neither box ticked the bodies are drawn (the toggles never hide the figure
    // altogether): the collision shapes cover other pixels than the skin does.
    let mut differ = 0;
    for y in 0..H {
        for x in 0..W {
            let (a, b) = (mesh_only.pixel(x, y), nothing.pixel(x, y));
            differ += (0..3).any(|c| (a[c] as i32 - b[c] as i32).abs() > 30) as usize;
        }
    }
    assert!(
        differ > 100,
        "bodies and mesh draw differently: {differ} pixels"
    );

    state.show.mesh = true;
    for _ in 0..120 {
        session.step();
    }
    session.refresh();
    let fallen = target.render(&state, &session).unwrap();
    let mut changed = 0;
    for y in 0..H {
        for x in 0..W {
            let (a, b) = (mesh_only.pixel(x, y), fallen.pixel(x, y));
            changed += (0..3).any(|c| (a[c] as i32 - b[c] as i32).abs() > 30) as usize;
        }
    }
    assert!(
        changed > 200,
        "only {changed} pixels changed after the fall"
    );
    let (blue, red) = colours(&fallen);
    assert!(
        blue > 50 && red > 50,
        "fallen mesh: {blue} blue, {red} red pixels"
    );
}
