//! Every scene file loads, and its counts, masses, sizes, limits and placements are
//! those the paper (section 5.1, appendix A) and the PyODE tutorial give.

use ragdoll_sim::glam::{Quat, Vec3};
use ragdoll_sim::scene::af::{AfOptions, load};
use ragdoll_sim::scene::{
    BodyDesc, BodyRef, JointKind, LimitStyle, MassSpec, SceneDesc, Shape, SwingLimit, validate,
};

mod common;

use common::{shipped_path, shipped_variant as scene};

fn body<'a>(s: &'a SceneDesc, name: &str) -> &'a BodyDesc {
    &s.bodies[s
        .body_id(name)
        .unwrap_or_else(|| panic!("no body {name}"))
        .index()]
}

fn kg(b: &BodyDesc) -> f32 {
    match b.mass {
        MassSpec::Mass(m) => m,
        MassSpec::Density(_) => panic!("mass of {} not resolved", b.name),
    }
}

fn joint<'a>(s: &'a SceneDesc, name: &str) -> &'a JointKind {
    &s.constraints
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no joint {name}"))
        .kind
}

fn assert_close(a: f32, b: f32, tol: f32, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

/// Lowest point of a body's world bounding box.
fn bottom(b: &BodyDesc) -> f32 {
    let m = glam_abs(b.pose.rotation);
    b.pose.position.y - (m * b.shape.local_half_extents()).y
}

fn glam_abs(q: Quat) -> ragdoll_sim::glam::Mat3 {
    let m = ragdoll_sim::glam::Mat3::from_quat(q);
    ragdoll_sim::glam::Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
}

#[test]
fn every_scene_and_variant_loads_validated_above_the_ground_with_masses_in_kg() {
    let mut n = 0;
    for e in std::fs::read_dir(shipped_path("")).unwrap() {
        let path = e.unwrap().path();
        let first = load(&path, &AfOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let variants: Vec<u32> = first.desc.variants.iter().map(|v| v.number).collect();
        for v in variants.iter().copied().chain([1]) {
            let s = load(
                &path,
                &AfOptions {
                    variant: v,
                    ..Default::default()
                },
            )
            .unwrap()
            .desc;
            validate(&s).unwrap();
            assert_eq!(s.variant, v);
            let ground = s.settings.ground.expect("every scene has a ground").height;
            for b in &s.bodies {
                assert!(kg(b) > 0.0);
                assert!(
                    bottom(b) > ground,
                    "{}: {} starts below the ground",
                    path.display(),
                    b.name
                );
            }
        }
        n += 1;
    }
    assert_eq!(n, 10, "scenes 1-10 ship as files");
}

/// Test 8 / appendix A: 16 bones, table 5 sizes, 15 joints of table 6 types placed at
/// the touching faces, table 7 hinge ranges, table 8 cone half-angles.
#[test]
fn human_is_the_papers_appendix_a() {
    let s = scene("human", 1);
    assert_eq!(s.bodies.len(), 16);
    assert_eq!(s.constraints.len(), 15);
    // Table 5 (cm): height (our y), width (x), depth (our z).
    let table5 = [
        ("head", 20.0, 15.7, 20.0),
        ("neck", 12.3, 10.9, 10.9),
        ("chest", 40.9, 39.2, 25.0),
        ("hip", 14.5, 35.8, 14.3),
        ("left_upper_arm", 8.8, 36.6, 8.8),
        ("right_forearm", 8.5, 28.8, 8.5),
        ("left_fist", 8.9, 8.9, 8.9),
        ("right_thigh", 51.2, 16.9, 16.9),
        ("left_calf", 30.5, 10.6, 10.6),
        ("right_foot", 13.9, 9.9, 27.3),
    ];
    for (name, h, w, d) in table5 {
        let b = body(&s, name);
        let Shape::Box { half_extents } = b.shape else {
            panic!("{name} is a box")
        };
        let size = half_extents * 200.0; // cm
        assert!(
            (size - Vec3::new(w, h, d)).abs().max_element() < 1e-3,
            "{name}: {size}"
        );
        // Mass from size at 1000 kg/m³.
        assert_close(kg(b), 1000.0 * w * h * d * 1e-6, 1e-3 * kg(b), name);
    }
    // Table 6 types.
    let hinges = [
        "head_neck",
        "right_elbow",
        "left_elbow",
        "right_wrist",
        "left_wrist",
        "right_knee",
        "left_knee",
        "right_ankle",
        "left_ankle",
    ];
    let balls = [
        "neck_chest",
        "chest_hip",
        "right_shoulder",
        "left_shoulder",
        "right_hip",
        "left_hip",
    ];
    for h in hinges {
        assert!(
            matches!(joint(&s, h), JointKind::Hinge { .. }),
            "{h} is a hinge"
        );
    }
    for b in balls {
        assert!(
            matches!(joint(&s, b), JointKind::BallAndSocket { .. }),
            "{b} is a ball joint"
        );
    }
    // Table 7: hinge ranges in degrees.
    let table7 = [
        ("head_neck", -45.0, 45.0),
        ("left_elbow", 0.0, 135.0),
        ("right_wrist", -90.0, 90.0),
        ("left_knee", 0.0, 135.0),
        ("right_ankle", 0.0, 90.0),
    ];
    for (name, lo, hi) in table7 {
        let JointKind::Hinge { limit: Some(l), .. } = joint(&s, name) else {
            panic!("{name} limited")
        };
        assert_close(l.min.to_degrees(), lo, 1e-3, name);
        assert_close(l.max.to_degrees(), hi, 1e-3, name);
    }
    // Table 8: cone half-angles; the shaft starts on the axis (rest pose inside).
    for (name, deg) in [
        ("neck_chest", 45.0),
        ("chest_hip", 45.0),
        ("left_shoulder", 90.0),
        ("right_hip", 45.0),
    ] {
        let JointKind::BallAndSocket {
            swing:
                Some(SwingLimit::Cone {
                    axis,
                    half_angle,
                    shaft,
                }),
            ..
        } = joint(&s, name)
        else {
            panic!("{name} has a cone")
        };
        assert_close(half_angle.to_degrees(), deg, 1e-3, name);
        assert!(axis.dot(*shaft) > 0.9999);
    }
    // Placements: the paper's appendix C centres (cm, Z up) relative to the head, mapped
    // (x, y, z) → (x, z, -y) and carried by the file's transform (read off the head).
    let head = body(&s, "head").pose;
    let world = |p: Vec3| head.position + head.rotation * Vec3::new(p.x, p.z, -p.y) * 0.01;
    for (name, c) in [
        ("chest", Vec3::new(0.0, 0.0, -42.75)),
        ("right_upper_arm", Vec3::new(-37.9, 0.0, -26.7)),
        ("left_fist", Vec3::new(89.45, 0.0, -26.7)),
        ("right_foot", Vec3::new(-9.45, -5.2, -166.45)),
    ] {
        assert!(
            (body(&s, name).pose.position - world(c)).length() < 1e-4,
            "{name}"
        );
    }
    for (name, a) in [
        ("left_hip", Vec3::new(9.45, 0.0, -77.7)),
        ("right_knee", Vec3::new(-9.45, 0.0, -128.9)),
        ("left_ankle", Vec3::new(9.45, 0.0, -159.4)),
    ] {
        assert!(
            (joint(&s, name).anchor().unwrap() - world(a)).length() < 1e-4,
            "{name}"
        );
    }
    // The right hand is at -X of the figure, which faces +Z: a right-handed mapping.
    let right = head.rotation.inverse() * (body(&s, "right_fist").pose.position - head.position);
    let toes = head.rotation.inverse()
        * (body(&s, "left_foot").pose.position - body(&s, "left_calf").pose.position);
    assert!(right.x < 0.0 && toes.z > 0.0);
    // It starts tilted, so it falls and tumbles rather than standing.
    assert!(head.rotation.angle_between(Quat::IDENTITY) > 0.3);
}

/// Test 4: the big box has twice the edge and eight times the mass; variant 2 divides
/// the masses by ten and makes the floor three times thicker.
#[test]
fn box_masses_ratio_and_variant() {
    let a = scene("box-masses", 1);
    let b = scene("box-masses", 2);
    for s in [&a, &b] {
        assert_close(
            kg(body(s, "big")) / kg(body(s, "small")),
            8.0,
            1e-4,
            "mass ratio",
        );
        let (Shape::Box { half_extents: hb }, Shape::Box { half_extents: hs }) =
            (&body(s, "big").shape, &body(s, "small").shape)
        else {
            panic!()
        };
        assert_close(hb.x / hs.x, 2.0, 1e-6, "edge ratio");
    }
    assert_close(
        kg(body(&a, "big")) / kg(body(&b, "big")),
        10.0,
        1e-3,
        "masses / 10",
    );
    let (ga, gb) = (a.settings.ground.unwrap(), b.settings.ground.unwrap());
    assert_close(gb.thickness / ga.thickness, 3.0, 1e-6, "floor 3x thicker");
    // They are thrown at each other.
    assert!(body(&a, "small").linear_velocity.x > 0.0 && body(&a, "big").linear_velocity.x < 0.0);
}

/// Test 2: six boxes on ball joints, the top fixed, five raised, a seventh dropped;
/// variant 1 aligns every box's particles at one depth, variant 2 fixes the dropped one.
#[test]
fn ball_chain_particles_per_variant() {
    let s = scene("ball-chain", 1);
    assert_eq!(s.bodies.len(), 7);
    assert_eq!(
        s.constraints
            .iter()
            .filter(|c| matches!(c.kind, JointKind::BallAndSocket { .. }))
            .count(),
        5
    );
    assert_eq!(s.bodies.iter().filter(|b| b.is_fixed()).count(), 1);
    assert!(body(&s, "link0").is_fixed());
    let top = body(&s, "link0").pose.position.y;
    for i in 1..6 {
        // Raised: level with the fixed top, not hanging below it.
        assert_close(
            body(&s, &format!("link{i}")).pose.position.y,
            top,
            1e-5,
            "raised",
        );
    }
    for b in &s.bodies {
        let p = b.particles.expect("variant 1 gives every box particles");
        assert!(
            p.iter().all(|q| q.z.abs() < 1e-6),
            "{}: aligned depth",
            b.name
        );
    }
    let v2 = scene("ball-chain", 2);
    let p = body(&v2, "dropper").particles.unwrap();
    let vol = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])).abs() / 6.0;
    assert!(
        vol > 1e-4,
        "corrected particles span a tetrahedron ({vol} m³)"
    );
    // Ball joints' anchors touch the two links they join.
    for c in &s.constraints {
        let a = c.kind.anchor().unwrap();
        let b1 = &s.bodies[c.body1.index()];
        assert_close((a - b1.pose.position).length(), 0.15, 1e-5, &c.name);
    }
}

/// Test 3: the same chain with hinges; variants are 5, 2 and 20 iterations.
#[test]
fn hinge_chain_iterations_per_variant() {
    for (v, it) in [(1, 5), (2, 2), (3, 20)] {
        let s = scene("hinge-chain", v);
        assert_eq!(s.settings.iterations, it);
        assert_eq!(
            s.constraints
                .iter()
                .filter(|c| matches!(c.kind, JointKind::Hinge { limit: None, .. }))
                .count(),
            5
        );
    }
    assert_eq!(scene("hinge-chain", 1).variants.len(), 3);
}

/// Tests 5 and 6: four fixed boxes with a box on a joint limited to 0, 45, 90, 135°.
#[test]
fn limit_scenes_have_the_four_limits() {
    let ball = scene("ball-limits", 1);
    let hinge = scene("hinge-limits", 1);
    for s in [&ball, &hinge] {
        assert_eq!(s.bodies.len(), 8);
        assert_eq!(s.bodies.iter().filter(|b| b.is_fixed()).count(), 4);
        assert_eq!(s.constraints.len(), 4);
    }
    for deg in [0.0f32, 45.0, 90.0, 135.0] {
        let JointKind::BallAndSocket {
            swing: Some(SwingLimit::Cone { half_angle, .. }),
            ..
        } = joint(&ball, &format!("limit{deg}"))
        else {
            panic!()
        };
        assert_close(half_angle.to_degrees(), deg, 1e-3, "cone half-angle");
        let JointKind::Hinge { limit: Some(l), .. } = joint(&hinge, &format!("limit{deg}")) else {
            panic!()
        };
        assert_close(l.max.to_degrees(), deg, 1e-3, "hinge limit");
        assert_close(l.min.to_degrees(), -deg, 1e-3, "hinge limit");
    }
    // From the top down: 0° highest, 135° lowest.
    assert!(body(&ball, "base0").pose.position.y > body(&ball, "base135").pose.position.y);
}

/// Test 7: cube body, 4 upper legs on ball joints, 4 lower legs on hinges, no limits.
#[test]
fn spider_is_a_cube_with_eight_legs_unlimited() {
    let s = scene("spider", 1);
    assert_eq!(s.bodies.len(), 9);
    let balls = s
        .constraints
        .iter()
        .filter(|c| {
            matches!(
                c.kind,
                JointKind::BallAndSocket {
                    swing: None,
                    twist: None,
                    ..
                }
            )
        })
        .count();
    let hinges = s
        .constraints
        .iter()
        .filter(|c| matches!(c.kind, JointKind::Hinge { limit: None, .. }))
        .count();
    assert_eq!((balls, hinges), (4, 4));
    let Shape::Box { half_extents } = body(&s, "body").shape else {
        panic!()
    };
    assert!(
        (half_extents - Vec3::splat(half_extents.x)).length() < 1e-6,
        "a cube"
    );
}

/// Scene 9: the PyODE tutorial's measurements, joints, stops and obstacle.
#[test]
fn capsule_human_is_the_pyode_tutorial() {
    let s = scene("capsule-human", 1);
    assert_eq!(s.bodies.len(), 17, "16 parts and the obstacle");
    assert!(
        s.bodies
            .iter()
            .all(|b| matches!(b.shape, Shape::Capsule { .. }))
    );
    // Radii and the half-radius overlap: an upper arm spans shoulder to elbow (0.30 m)
    // with a cylinder of 0.30 - r.
    let Shape::Capsule {
        half_height,
        radius,
    } = body(&s, "right_upper_arm").shape
    else {
        panic!()
    };
    assert_close(radius, 0.08, 1e-6, "arm radius");
    assert_close(2.0 * half_height, 0.30 - 0.08, 1e-4, "arm cylinder");
    let Shape::Capsule { radius, .. } = body(&s, "chest").shape else {
        panic!()
    };
    assert_close(radius, 0.13, 1e-6, "chest radius");
    // Density 500.
    let b = body(&s, "belly");
    let Shape::Capsule {
        half_height,
        radius,
    } = b.shape
    else {
        panic!()
    };
    let vol = std::f32::consts::PI * radius * radius * (2.0 * half_height + 4.0 / 3.0 * radius);
    assert_close(kg(b), 500.0 * vol, 1e-3 * kg(b), "density 500");
    // Joints: fixed spine, universal hips with stops, hinges with stops, soft balls.
    let count = |f: fn(&JointKind) -> bool| s.constraints.iter().filter(|c| f(&c.kind)).count();
    assert_eq!(count(|k| matches!(k, JointKind::Fixed)), 2);
    assert_eq!(
        count(|k| matches!(
            k,
            JointKind::Universal {
                axis_ranges: Some(_),
                ..
            }
        )),
        2
    );
    assert_eq!(
        count(|k| matches!(k, JointKind::Hinge { limit: Some(_), .. })),
        8
    );
    assert_eq!(
        count(|k| matches!(
            k,
            JointKind::BallAndSocket {
                swing: Some(_),
                twist: Some(_),
                limit_style: LimitStyle::Soft { .. },
                ..
            }
        )),
        3
    );
    let JointKind::Hinge {
        anchor,
        axis,
        limit: Some(l),
    } = joint(&s, "left_knee")
    else {
        panic!()
    };
    assert!((*anchor - Vec3::new(0.14, 0.48 + 0.9, 0.0)).length() < 1e-5);
    // The tutorial: leftAxis, 0..0.75π with (thigh, calf); ours (calf, thigh) negates the axis.
    assert_eq!(*axis, Vec3::X);
    assert_close(l.max, 0.75 * std::f32::consts::PI, 1e-4, "knee stop");
    let JointKind::BallAndSocket {
        swing: Some(SwingLimit::Cone { half_angle, .. }),
        twist: Some(t),
        ..
    } = joint(&s, "right_shoulder")
    else {
        panic!()
    };
    assert_close(*half_angle, std::f32::consts::FRAC_PI_2, 1e-4, "flex limit");
    assert_close(t.max, std::f32::consts::FRAC_PI_4, 1e-4, "twist limit");
    let JointKind::Universal { shaft1, shaft2, .. } = joint(&s, "left_hip") else {
        panic!()
    };
    assert!(
        shaft1.dot(*shaft2).abs() < 1e-6,
        "a universal joint's axes are perpendicular"
    );
    // The obstacle at the tutorial's fixed position.
    let o = body(&s, "obstacle");
    assert!((o.pose.position - Vec3::new(0.274, 0.2, 0.1753)).length() < 1e-3);
}

/// Scene 10: N humans in a grid; `--count` overrides N, and 1000 humans build.
#[test]
fn pile_replicates_the_human() {
    let human = scene("human", 1);
    let s = scene("pile", 1);
    assert_eq!(s.bodies.len(), 4 * 16);
    assert_eq!(s.constraints.len(), 4 * 15);
    let big = common::shipped_pile(1000);
    assert_eq!(big.bodies.len(), 16_000);
    assert_eq!(big.constraints.len(), 15_000);
    let names: std::collections::HashSet<&str> =
        big.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names.len(), 16_000, "unique names");
    // Every copy is the human: same masses, joints on its own bodies.
    let human_mass: f32 = human.bodies.iter().map(kg).sum();
    for copy in big.bodies.chunks(16) {
        assert_close(
            copy.iter().map(kg).sum::<f32>(),
            human_mass,
            1e-3,
            "copy mass",
        );
    }
    for (i, c) in big.constraints.iter().enumerate() {
        let copy = (i / 15) as u32;
        assert_eq!(c.body1.0 / 16, copy);
        if let BodyRef::Body(b) = c.body2 {
            assert_eq!(b.0 / 16, copy);
        }
    }
    // Copies do not start inside each other: the chests are at least a chest apart.
    let chests: Vec<Vec3> = big
        .bodies
        .iter()
        .filter(|b| b.name.starts_with("chest"))
        .map(|b| b.pose.position)
        .collect();
    for (i, a) in chests.iter().enumerate().take(50) {
        for b in &chests[i + 1..] {
            assert!((*a - *b).length() > 0.4);
        }
    }
}

#[test]
fn collision_scene_has_two_falling_boxes() {
    let s = scene("collision", 1);
    assert_eq!((s.bodies.len(), s.constraints.len()), (2, 0));
    assert!(s.bodies.iter().all(|b| !b.is_fixed() && bottom(b) > 0.1));
}

/// The parry3d shape of a body, for the overlap test.
fn parry_shape(s: &Shape) -> Box<dyn parry3d::shape::Shape> {
    use parry3d::shape as ps;
    match s {
        Shape::Box { half_extents } => Box::new(ps::Cuboid::new(*half_extents)),
        Shape::Capsule {
            half_height,
            radius,
        } => Box::new(ps::Capsule::new_y(*half_height, *radius)),
        Shape::Cylinder {
            half_height,
            radius,
            ..
        } => Box::new(ps::Cylinder::new(*half_height, *radius)),
        Shape::Cone {
            half_height,
            radius,
            ..
        } => Box::new(ps::Cone::new(*half_height, *radius)),
        Shape::ConvexHull { points } => {
            Box::new(ps::ConvexPolyhedron::from_convex_hull(points).unwrap())
        }
    }
}

/// Bodies that do not share a joint must not start inside each other: contacts would
/// push them apart with energy the scene never had. (Jointed neighbours may touch or,
/// as in the PyODE tutorial, overlap; both methods skip their contacts.)
#[test]
fn no_scene_starts_with_unjointed_bodies_overlapping() {
    for e in std::fs::read_dir(shipped_path("")).unwrap() {
        let path = e.unwrap().path();
        let s = load(&path, &AfOptions::default()).unwrap().desc;
        let jointed = |a: usize, b: usize| {
            s.constraints.iter().any(|c| {
                let (x, y) = (c.body1.index(), c.body2.body().map(|b| b.index()));
                (x == a && y == Some(b)) || (x == b && y == Some(a))
            })
        };
        let shapes: Vec<_> = s.bodies.iter().map(|b| parry_shape(&b.shape)).collect();
        let poses: Vec<_> = s
            .bodies
            .iter()
            .map(|b| parry3d::math::Pose::from_parts(b.pose.position, b.pose.rotation))
            .collect();
        for i in 0..s.bodies.len() {
            for j in i + 1..s.bodies.len() {
                if jointed(i, j) || (s.bodies[i].is_fixed() && s.bodies[j].is_fixed()) {
                    continue;
                }
                let c =
                    parry3d::query::contact(&poses[i], &*shapes[i], &poses[j], &*shapes[j], 0.0)
                        .unwrap();
                if let Some(c) = c {
                    assert!(
                        c.dist > -1e-3,
                        "{}: {} and {} overlap by {} m",
                        path.display(),
                        s.bodies[i].name,
                        s.bodies[j].name,
                        -c.dist
                    );
                }
            }
        }
    }
}

#[test]
fn max_push_out_speed_is_read_in_file_units_per_second() {
    use ragdoll_sim::scene::af::parse;
    let text = |units: &str| {
        format!(
            "settings {{ units \"{units}\" maxPushOutSpeed 2 }}\n\
             body \"b\" {{ model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin ( 0, 0, 5 ) mass 1 }}"
        )
    };
    let read = |units: &str| {
        parse(
            &text(units),
            std::path::Path::new("t.af"),
            &AfOptions::default(),
        )
        .unwrap_or_else(|e| panic!("{e}"))
        .desc
        .settings
        .max_push_out_speed
    };
    assert_close(read("m"), 2.0, 1e-6, "2 m/s");
    assert_close(read("inch"), 2.0 * 0.0254, 1e-6, "2 in/s");
    assert_eq!(
        ragdoll_sim::scene::Settings::default().max_push_out_speed,
        3.0,
        "Box2D's 3 m/s by default"
    );
}
