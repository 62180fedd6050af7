//! The benches' scenes, built as `SceneDesc` in code so their size can be any number.
//!
//! The paper (section 5.2) describes its performance scenes in one sentence each; these
//! follow the sentences:
//! - test 9: "small bones, placed above each other with space in between them";
//! - test 10: "three bones, connected with one hinge joint and one ball joint";
//! - test 11: the same figure repeated, "two joints for every three bones";
//! - test 12: "the number of boxes are 9": three such figures dropped onto each other, so
//!   the iterations have joints and contacts to work on.
//!
//! Sleeping is off in all of them (see `base_scene`). The pile of humans for the scale
//! table is the built-in `pile` scene (scene 10), with its own settings.

use glam::{Quat, Vec3};
use ragdoll_sim::SceneDesc;
use ragdoll_sim::scene::{
    BodyDesc, BodyId, BodyRef, ConstraintDesc, JointKind, LimitStyle, MassSpec, Pose, Settings,
    Shape,
};

/// Half extents of a test 9 box: a 10 cm cube.
const SMALL_BOX_HALF: f32 = 0.05;
/// Vertical space between two stacked test 9 boxes (m).
const STACK_GAP: f32 = 0.05;
/// Boxes per test 9 column; more bones make more columns, in a square grid.
const STACK_HEIGHT: usize = 16;

/// Half extents of a bone of the three-bone figure: 30 × 10 × 10 cm.
const BONE_HALF: Vec3 = Vec3::new(0.15, 0.05, 0.05);
/// Distance between the centres of neighbouring bones of a figure: 2 cm between faces,
/// the joint anchor in the middle of the gap.
const BONE_PITCH: f32 = 0.32;
/// Mass of a figure's bone (kg).
const BONE_MASS: f32 = 1.0;

/// Test 9: `bones` small boxes stacked in columns with a gap between each two, no joints.
pub fn stacked_boxes(bones: usize) -> SceneDesc {
    let columns = bones.div_ceil(STACK_HEIGHT);
    let side = (columns as f64).sqrt().ceil() as usize;
    let pitch_y = 2.0 * SMALL_BOX_HALF + STACK_GAP;
    let pitch_xz = 6.0 * SMALL_BOX_HALF;
    let mut scene = base_scene(format!("bench-stack-{bones}"), Settings::default());
    for i in 0..bones {
        let (column, level) = (i / STACK_HEIGHT, i % STACK_HEIGHT);
        let (cx, cz) = (column % side, column / side);
        let position = Vec3::new(
            cx as f32 * pitch_xz,
            SMALL_BOX_HALF + STACK_GAP + level as f32 * pitch_y,
            cz as f32 * pitch_xz,
        );
        scene.bodies.push(BodyDesc::new(
            format!("box{i}"),
            Shape::Box {
                half_extents: Vec3::splat(SMALL_BOX_HALF),
            },
            Pose::from_position(position),
            MassSpec::Mass(0.1),
        ));
    }
    scene
}

/// Test 10: one three-bone figure (a hinge and a ball joint) falling onto the ground,
/// stepped at `timestep`.
pub fn three_bones(timestep: f32) -> SceneDesc {
    figures(1, timestep, 5)
}

/// Test 11: `count` three-bone figures (3·count bones, two joints per three bones) in a
/// grid, far enough apart that each falls onto the ground on its own, stepped at
/// `timestep` with `iterations`.
pub fn figures(count: usize, timestep: f32, iterations: u32) -> SceneDesc {
    // The paper's N for both methods: the multibody's velocity iterations follow it.
    let settings = Settings {
        timestep,
        iterations,
        multibody_iterations: None,
        ..Settings::default()
    };
    let mut scene = base_scene(format!("bench-figures-{}", 3 * count), settings);
    let side = (count as f64).sqrt().ceil() as usize;
    for i in 0..count {
        let (gx, gz) = ((i % side) as f32, (i / side) as f32);
        // A small tilt so one end lands first and the joints have something to do.
        let rotation = Quat::from_rotation_z(0.2);
        let pose = Pose {
            position: Vec3::new(1.5 * gx, 0.6, 0.6 * gz),
            rotation,
        };
        add_figure(&mut scene, &format!("f{i}"), pose);
    }
    scene
}

/// Test 12: nine boxes, three three-bone figures dropped crosswise onto each other so
/// contacts and joints both need the iterations.
pub fn nine_boxes(iterations: u32) -> SceneDesc {
    // The swept iterations for both methods: the multibody's follow them.
    let settings = Settings {
        timestep: 0.01,
        iterations,
        multibody_iterations: None,
        ..Settings::default()
    };
    let mut scene = base_scene("bench-nine-boxes".into(), settings);
    for i in 0..3 {
        let pose = Pose {
            position: Vec3::new(0.0, 0.3 + 0.4 * i as f32, 0.0),
            rotation: Quat::from_rotation_y(i as f32 * std::f32::consts::FRAC_PI_3)
                * Quat::from_rotation_z(0.1),
        };
        add_figure(&mut scene, &format!("f{i}"), pose);
    }
    scene
}

/// A scene with sleeping off: the paper's methods never slept, and a figure asleep
/// after its first second would make the realtime tables time nothing.
fn base_scene(name: String, mut settings: Settings) -> SceneDesc {
    settings.sleep.disable();
    SceneDesc {
        name,
        settings,
        variant: 1,
        ..SceneDesc::default()
    }
}

/// Adds three bones along the figure's local X, a hinge (about local Z) between the
/// first two and an unlimited ball joint between the last two. Anchors and axes are
/// world space at the rest pose, as `SceneDesc` wants them.
fn add_figure(scene: &mut SceneDesc, prefix: &str, pose: Pose) {
    let first = scene.bodies.len() as u32;
    for j in 0..3 {
        let local = Pose::from_position(Vec3::new((j as f32 - 1.0) * BONE_PITCH, 0.0, 0.0));
        scene.bodies.push(BodyDesc::new(
            format!("{prefix}_bone{j}"),
            Shape::Box {
                half_extents: BONE_HALF,
            },
            pose.mul_pose(&local),
            MassSpec::Mass(BONE_MASS),
        ));
    }
    let anchor = |x: f32| pose.transform_point(Vec3::new(x, 0.0, 0.0));
    scene.constraints.push(ConstraintDesc {
        name: format!("{prefix}_hinge"),
        body1: BodyId(first),
        body2: BodyRef::Body(BodyId(first + 1)),
        kind: JointKind::Hinge {
            anchor: anchor(-0.5 * BONE_PITCH),
            axis: pose.transform_vector(Vec3::Z),
            limit: None,
        },
        friction: 0.0,
    });
    scene.constraints.push(ConstraintDesc {
        name: format!("{prefix}_ball"),
        body1: BodyId(first + 2),
        body2: BodyRef::Body(BodyId(first + 1)),
        kind: JointKind::BallAndSocket {
            anchor: anchor(0.5 * BONE_PITCH),
            swing: None,
            twist: None,
            limit_style: LimitStyle::Hard,
        },
        friction: 0.0,
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use ragdoll_sim::scene::validate;

    #[test]
    fn every_bench_scene_is_valid_and_has_the_asked_size() {
        for n in [2, 17, 256] {
            let s = stacked_boxes(n);
            validate(&s).unwrap();
            assert_eq!(s.bodies.len(), n);
            assert!(s.constraints.is_empty());
        }
        let s = three_bones(0.001);
        validate(&s).unwrap();
        assert_eq!((s.bodies.len(), s.constraints.len()), (3, 2));
        let s = figures(40, 0.01, 5);
        validate(&s).unwrap();
        assert_eq!((s.bodies.len(), s.constraints.len()), (120, 80));
        let s = nine_boxes(7);
        validate(&s).unwrap();
        assert_eq!((s.bodies.len(), s.settings.iterations), (9, 7));
    }

    #[test]
    fn stacked_boxes_do_not_touch_each_other_or_the_ground() {
        let s = stacked_boxes(40);
        for (i, a) in s.bodies.iter().enumerate() {
            assert!(a.pose.position.y - SMALL_BOX_HALF > 0.0);
            for b in &s.bodies[i + 1..] {
                let d = (a.pose.position - b.pose.position).abs();
                assert!(
                    d.max_element() > 2.0 * SMALL_BOX_HALF + 1e-4,
                    "{} {}",
                    a.name,
                    b.name
                );
            }
        }
    }

    #[test]
    fn figure_joints_sit_between_their_bones() {
        let s = three_bones(0.01);
        for c in &s.constraints {
            let a = c.kind.anchor().unwrap();
            let p1 = s.body(c.body1).pose.position;
            let p2 = s.body(c.body2.body().unwrap()).pose.position;
            assert!((a - 0.5 * (p1 + p2)).length() < 1e-5, "{}", c.name);
        }
    }
}
