//! Picking and shooting through the cursor, as the window does it: a box resting on the
//! ground, written here from its description (a 30 cm cube of 10 kg), seen by the scene's
//! camera; the pixel it projects to in either half gives a ray that picks it in both
//! methods, and a box shot along that ray hits it in both worlds (it moves), where a
//! shot at the camera's target, 1.5 m to its side, leaves it alone.

use glam::{Vec2, Vec3};
use ragdoll_lab::cli::{ParticleSolverArg, SceneArgs};
use ragdoll_lab::picking::cursor_ray;
use ragdoll_lab::render::camera::OrbitCamera;
use ragdoll_lab::render::{Viewport, split};
use ragdoll_lab::scenes;
use ragdoll_lab::session::{Session, ShotSettings};
use ragdoll_sim::BodyState;

const SCENE: &str = r#"
settings {
	name "target"
	units "m"
	up "y"
}

camera {
	eye ( 0, 1.2, 4 )
	target ( -1.5, 0.3, 0 )
}

body "target" {
	model box( ( -0.15, -0.15, -0.15 ), ( 0.15, 0.15, 0.15 ) )
	origin ( 0, 0.15, 0 )
	mass 10
}
"#;

fn session(tag: &str) -> (Session, OrbitCamera) {
    let dir = std::env::temp_dir().join(format!("ragdoll-lab-shoot-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("target.af");
    std::fs::write(&path, SCENE).unwrap();
    let loaded = scenes::load(&SceneArgs {
        af: Some(path),
        ..Default::default()
    })
    .unwrap();
    let camera = OrbitCamera::from_desc(&loaded.desc.settings.camera);
    let mut s = Session::new(loaded, ParticleSolverArg::RigidFrames).unwrap();
    // Let it settle on the ground.
    for _ in 0..30 {
        s.step();
    }
    let _ = std::fs::remove_dir_all(dir);
    (s, camera)
}

fn halves() -> [Viewport; 2] {
    split(Viewport {
        x: 300.0,
        y: 0.0,
        width: 980.0,
        height: 720.0,
    })
}

fn positions(s: &Session) -> [Vec3; 2] {
    [0, 1].map(|i| {
        let mut states: Vec<BodyState> = Vec::new();
        s.methods[i].body_states(&mut states);
        states[0].com
    })
}

#[test]
fn a_click_on_a_body_in_either_half_picks_it_in_both_methods() {
    let (s, camera) = session("pick");
    let vps = halves();
    let centre = positions(&s)[0];
    for (side, vp) in vps.iter().enumerate() {
        let pixel = vp.project(&camera, centre).unwrap();
        let ray = cursor_ray(&camera, &vps, pixel).unwrap();
        assert_eq!(ray.side, side);
        for (m, method) in s.methods.iter().enumerate() {
            let hit = method.raycast(ray.origin, ray.dir);
            assert_eq!(
                hit.map(|h| h.body.index()),
                Some(0),
                "pixel {pixel} of half {side}: method {m} does not pick the box"
            );
        }
        // A pixel of sky beside it picks nothing.
        let sky = cursor_ray(&camera, &vps, Vec2::new(pixel.x, vp.y + 5.0)).unwrap();
        assert!(s.methods[side].raycast(sky.origin, sky.dir).is_none());
    }
}

#[test]
fn a_box_shot_through_the_cursor_hits_in_both_worlds_from_either_half() {
    let shot = ShotSettings::default();
    for side in 0..2 {
        let (mut s, camera) = session(&format!("shoot{side}"));
        let vps = halves();
        let before = positions(&s);
        let pixel = vps[side].project(&camera, before[0]).unwrap();
        let ray = cursor_ray(&camera, &vps, pixel).unwrap();
        s.shoot(ray.origin, ray.dir, &shot);
        for _ in 0..40 {
            s.step();
        }
        let after = positions(&s);
        for m in 0..2 {
            let moved = after[m].distance(before[m]);
            assert!(
                moved > 0.05,
                "shot through half {side}: the box in method {m} moved {moved} m"
            );
        }
    }
    // The old aim, at the camera's target, misses it.
    let (mut s, camera) = session("miss");
    let before = positions(&s);
    let eye = camera.eye();
    s.shoot(eye, (camera.target - eye).normalize(), &shot);
    for _ in 0..40 {
        s.step();
    }
    let after = positions(&s);
    for m in 0..2 {
        assert!(after[m].distance(before[m]) < 0.01, "method {m} was hit");
    }
}
