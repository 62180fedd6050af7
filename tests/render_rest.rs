//! The renderer alone, on a scene built in code at its rest pose (no method involved):
//! colours per half, bodies where the scene puts them, shadows on the ground.
//!
//! Runs on whatever adapter `capture` would pick; in CI that is llvmpipe (software).

use glam::{Quat, Vec3};
use ragdoll_lab::capture::{Image, Offscreen};
use ragdoll_lab::render::camera::OrbitCamera;
use ragdoll_lab::render::{Frame, ShowOptions, SideView, Viewport, split};
use ragdoll_sim::scene::{BodyDesc, CameraDesc, MassSpec, Pose, SceneDesc, Shape};
use ragdoll_sim::{MethodKind, RenderSnapshot};

const W: u32 = 320;
const H: u32 = 180;

/// A pixel is "blue" when blue beats both other channels by 40 of 255, "red" likewise.
/// Background (grey-blue sky, grey ground, dark shadows) never differs by that much;
/// lit and unlit faces of the palette's blues and reds always do.
const MARGIN: i32 = 40;

fn is_blue(p: [u8; 4]) -> bool {
    let [r, g, b, _] = p.map(i32::from);
    b - r.max(g) > MARGIN
}

fn is_red(p: [u8; 4]) -> bool {
    let [r, g, b, _] = p.map(i32::from);
    r - g.max(b) > MARGIN
}

/// Counts (blue, red) pixels in columns `x0..x1`.
fn count(img: &Image, x0: u32, x1: u32) -> (usize, usize) {
    let (mut blue, mut red) = (0, 0);
    for y in 0..img.height {
        for x in x0..x1 {
            let p = img.pixel(x, y);
            blue += is_blue(p) as usize;
            red += is_red(p) as usize;
        }
    }
    (blue, red)
}

fn scene() -> SceneDesc {
    let cube = BodyDesc::new(
        "cube",
        Shape::Box {
            half_extents: Vec3::splat(0.3),
        },
        Pose {
            position: Vec3::new(-0.9, 0.3, 0.0),
            rotation: Quat::from_rotation_y(0.4),
        },
        MassSpec::Mass(1.0),
    );
    let capsule = BodyDesc::new(
        "capsule",
        Shape::Capsule {
            half_height: 0.3,
            radius: 0.15,
        },
        Pose::from_position(Vec3::new(0.9, 1.2, 0.0)),
        MassSpec::Mass(1.0),
    );
    let mut desc = SceneDesc {
        name: "two shapes".into(),
        bodies: vec![cube, capsule],
        ..Default::default()
    };
    desc.settings.camera = CameraDesc {
        eye: Vec3::new(0.0, 1.2, 5.0),
        target: Vec3::new(0.0, 0.6, 0.0),
    };
    desc
}

#[test]
fn rest_pose_renders_blue_left_red_right_with_bodies_in_place() {
    let desc = scene();
    let snap = RenderSnapshot::from_scene_rest(&desc);
    let camera = OrbitCamera::from_desc(&desc.settings.camera);
    let halves = split(Viewport {
        x: 0.0,
        y: 0.0,
        width: W as f32,
        height: H as f32,
    });
    let sides = [
        SideView {
            kind: MethodKind::Particle,
            snapshot: &snap,
            viewport: halves[0],
        },
        SideView {
            kind: MethodKind::Multibody,
            snapshot: &snap,
            viewport: halves[1],
        },
    ];
    let frame = Frame {
        camera: &camera,
        ground: desc.settings.ground,
        sides: &sides,
        show: ShowOptions::default(),
    };
    let mut target = Offscreen::new(W, H).expect("an adapter (llvmpipe in CI)");
    let img = target.render_scene(&frame).expect("render");
    if let Ok(dir) = std::env::var("RAGDOLL_LAB_TEST_OUT") {
        img.write_png(&std::path::Path::new(&dir).join("render_rest.png"))
            .unwrap();
    }

    let half = W / 2;
    let (left_blue, left_red) = count(&img, 0, half);
    let (right_blue, right_red) = count(&img, half, W);
    // The cube alone covers ~0.6 m of a ~4 m wide half-view: well over 1 % of its pixels.
    let min_body = (half * H / 100) as usize;
    assert!(left_blue > min_body, "left half blue pixels: {left_blue}");
    assert!(right_red > min_body, "right half red pixels: {right_red}");
    assert!(
        left_red * 20 < left_blue,
        "left: {left_red} red vs {left_blue} blue"
    );
    assert!(
        right_blue * 20 < right_red,
        "right: {right_blue} blue vs {right_red} red"
    );

    // Where the bodies are: the cube (x = −0.9, low) is in the left part of each half,
    // the capsule (x = +0.9, high) in the right part, above the cube's centre.
    for (x0, pred) in [(0, is_blue as fn([u8; 4]) -> bool), (half, is_red)] {
        let (mut lo, mut hi) = ((0.0, 0.0, 0usize), (0.0, 0.0, 0usize));
        for y in 0..H {
            for x in x0..x0 + half {
                if pred(img.pixel(x, y)) {
                    let acc = if x - x0 < half / 2 { &mut lo } else { &mut hi };
                    acc.0 += x as f64;
                    acc.1 += y as f64;
                    acc.2 += 1;
                }
            }
        }
        assert!(
            lo.2 > 100 && hi.2 > 50,
            "both bodies visible: {} {}",
            lo.2,
            hi.2
        );
        let cube_y = lo.1 / lo.2 as f64;
        let capsule_y = hi.1 / hi.2 as f64;
        assert!(
            capsule_y < cube_y - 10.0,
            "capsule above cube: {capsule_y} vs {cube_y}"
        );
    }

    // Shadows: some ground pixels under the bodies are much darker than the open ground.
    let ground = img.pixel(half / 2, H - 5);
    let darkest = (0..H)
        .flat_map(|y| (0..half).map(move |x| (x, y)))
        .map(|(x, y)| img.pixel(x, y))
        .filter(|p| !is_blue(*p) && !is_red(*p))
        .map(|p| p[0] as u32 + p[1] as u32 + p[2] as u32)
        .min()
        .unwrap();
    let ground_sum = ground[0] as u32 + ground[1] as u32 + ground[2] as u32;
    assert!(
        darkest * 10 < ground_sum * 7,
        "a shadow darker than ground: {darkest} vs {ground_sum}"
    );
}
