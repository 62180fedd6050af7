//! Bad input gives one error at the mistake, never a panic or a half-built scene.

use ragdoll_sim::scene::af::{AfError, AfOptions, load, parse};
use std::path::{Path, PathBuf};

fn figures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/figures")
}

const GOOD: &str = r#"settings {
	units "m"
	up "y"
}
body "a" {
	model box( ( -0.1, -0.1, -0.1 ), ( 0.1, 0.1, 0.1 ) )
	origin ( 0, 1, 0 )
	density 1000
}
body "b" {
	model box( ( -0.1, -0.1, -0.1 ), ( 0.1, 0.1, 0.1 ) )
	origin ( 0, 1.2, 0 )
	density 1000
}
hinge "h" {
	body1 "b"
	body2 "a"
	anchor ( 0, 1.1, 0 )
	axis ( 0, 0, 1 )
}
"#;

fn err(text: &str) -> AfError {
    parse(text, Path::new("t.af"), &AfOptions::default()).expect_err("should fail")
}

/// Replaces `from` by `to` in the good file and expects an error at (line, col) whose
/// message contains `says`.
fn check(from: &str, to: &str, line: u32, col: u32, says: &str) {
    assert!(GOOD.contains(from), "{from}");
    let e = err(&GOOD.replacen(from, to, 1));
    assert_eq!((e.line, e.col), (line, col), "{e}");
    assert!(e.message.contains(says), "{e}");
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("t.af:{line}:{col}: error: ")),
        "{shown}"
    );
    assert_eq!(shown.lines().count(), 1, "one line: {shown}");
}

#[test]
fn the_good_file_is_good() {
    let s = parse(GOOD, Path::new("t.af"), &AfOptions::default()).unwrap();
    assert_eq!((s.desc.bodies.len(), s.desc.constraints.len()), (2, 1));
}

#[test]
fn truncated_file() {
    let cut = &GOOD[..GOOD.find("axis").unwrap()];
    let e = err(cut);
    assert_eq!(e.line, 19, "{e}");
    assert!(
        e.message
            .contains("ends inside the `hinge` block opened at line 15"),
        "{e}"
    );
    let e = err("body \"a\" {\n model box( ( -1, -1, -1 ), ( 1, 1");
    assert!(e.message.contains("expected `)`"), "{e}");
}

#[test]
fn wrong_tokens() {
    check(
        "origin ( 0, 1, 0 )",
        "origin ( 0, 1, 0 ) }",
        8,
        2,
        "`density` is not a block",
    );
    check(
        "density 1000\n}\nbody \"b\"",
        "density 1000\n}\nbody \"b\" =",
        10,
        10,
        "unexpected character",
    );
    check(
        "axis ( 0, 0, 1 )",
        "axis { 0, 0, 1 }",
        19,
        7,
        "a value for `axis`",
    );
    check("origin ( 0, 1, 0 )", "origin 7", 7, 9, "expected a vector");
    check("origin ( 0, 1, 0 )", "origin ( 0, 1 )", 7, 9, "3 numbers");
    check(
        "density 1000",
        "density \"heavy\"",
        8,
        10,
        "expected a number",
    );
    check("hinge \"h\"", "hing \"h\"", 15, 1, "`hing` is not a block");
    check(
        "axis ( 0, 0, 1 )",
        "axle ( 0, 0, 1 )",
        19,
        2,
        "unknown key `axle`",
    );
    check(
        "axis ( 0, 0, 1 )",
        "axis ( 0, 0, 1 )\n\tshafts ( 0, 0, 1 ), ( 0, 0, 1 )",
        20,
        2,
        "does not apply to a hinge",
    );
    check("units \"m\"", "units \"furlong\"", 2, 8, "unknown unit");
}

#[test]
fn unknown_and_reserved_bodies() {
    check("body1 \"b\"", "body1 \"c\"", 16, 8, "unknown body \"c\"");
    check("body2 \"a\"", "body2 \"A\"", 17, 8, "unknown body \"A\"");
    check(
        "body1 \"b\"",
        "body1 \"world\"",
        16,
        8,
        "body1 cannot be the world",
    );
    check(
        "body \"b\"",
        "body \"world\"",
        10,
        6,
        "may not be named \"world\"",
    );
    check(
        "body \"b\"",
        "body \"Origin\"",
        10,
        6,
        "may not be named \"origin\"",
    );
    check("body2 \"a\"", "body2 \"b\"", 15, 1, "to itself");
    check("\tbody2 \"a\"\n", "", 15, 1, "missing `body2`");
    check("\tanchor ( 0, 1.1, 0 )\n", "", 15, 1, "missing `anchor`");
}

#[test]
fn duplicate_names() {
    check(
        "body \"b\"",
        "body \"a\"",
        10,
        6,
        "already defined at line 5",
    );
    let twice = format!(
        "{GOOD}hinge \"h\" {{ body1 \"a\" body2 \"b\" anchor ( 0, 1, 0 ) axis ( 1, 0, 0 ) }}\n"
    );
    let e = err(&twice);
    assert_eq!((e.line, e.col), (21, 7), "{e}");
    assert!(
        e.message
            .contains("constraint named \"h\" is already defined")
    );
}

#[test]
fn nan_infinite_and_negative_sizes() {
    check(
        "( 0.1, 0.1, 0.1 ) )\n\torigin ( 0, 1, 0 )",
        "( nan, 0.1, 0.1 ) )\n\torigin ( 0, 1, 0 )",
        6,
        37,
        "expected a number for x",
    );
    check(
        "origin ( 0, 1, 0 )",
        "origin ( 0, 1e99, 0 )",
        7,
        14,
        "finite",
    );
    check(
        "( 0.1, 0.1, 0.1 ) )\n\torigin ( 0, 1, 0 )",
        "( 0.1, -0.2, 0.1 ) )\n\torigin ( 0, 1, 0 )",
        6,
        35,
        "must exceed its min",
    );
    check(
        "density 1000\n}\nbody \"b\"",
        "density -5\n}\nbody \"b\"",
        8,
        10,
        "density must be positive",
    );
    check(
        "density 1000\n}\nbody \"b\"",
        "density 0\n}\nbody \"b\"",
        8,
        10,
        "density must be positive",
    );
    check("axis ( 0, 0, 1 )", "axis ( 0, 0, 0 )", 19, 7, "zero length");
}

#[test]
fn joint_names_and_meshes() {
    let with_mesh = |mesh_line: &str, origin: &str| {
        GOOD.replace("up \"y\"", &format!("up \"y\"\n\t{mesh_line}"))
            .replacen("origin ( 0, 1, 0 )", origin, 1)
    };
    let at = figures().join("t.af");
    let run = |text: &str, opts: &AfOptions| parse(text, &at, opts);
    // Resolves against the mesh named relative to the file.
    let ok = run(
        &with_mesh("mesh \"doom-figure.md5mesh\"", "origin joint( \"Head\" )"),
        &AfOptions::default(),
    )
    .unwrap();
    assert!(
        (ok.desc.bodies[0].pose.position.z - 64.0).abs() < 1e-4,
        "a Y-up file in metres keeps the mesh's (0, 0, 64)"
    );
    // Unresolved joint name: points at the name and lists the mesh's joints.
    let e = run(
        &with_mesh("mesh \"doom-figure.md5mesh\"", "origin joint( \"Skull\" )"),
        &AfOptions::default(),
    )
    .unwrap_err();
    assert_eq!((e.line, e.col), (8, 16), "{e}");
    assert!(
        e.message.contains("no joint \"Skull\"") && e.message.contains("Head"),
        "{e}"
    );
    // No mesh at all: says how to give one.
    let e = run(
        &with_mesh("", "origin bonecenter( \"Neck\", \"Head\" )"),
        &AfOptions::default(),
    )
    .unwrap_err();
    assert_eq!((e.line, e.col), (8, 21), "{e}");
    assert!(
        e.message.contains("--mesh") && e.message.contains("bonecenter(\"Neck\")"),
        "{e}"
    );
    // --mesh supplies it.
    let opts = AfOptions {
        mesh: Some(figures().join("doom-figure.md5mesh")),
        ..Default::default()
    };
    assert!(
        run(
            &with_mesh("", "origin bonecenter( \"Neck\", \"Head\" )"),
            &opts
        )
        .is_ok()
    );
    // A missing mesh file: the error points at the `mesh` key's path.
    let e = run(
        &with_mesh("mesh \"nowhere.md5mesh\"", "origin joint( \"Head\" )"),
        &AfOptions::default(),
    )
    .unwrap_err();
    assert_eq!((e.line, e.col), (4, 7), "{e}");
    assert!(e.message.contains("nowhere.md5mesh"), "{e}");
    // An unused missing mesh is fine (real Doom 3 files name meshes in the game's tree).
    assert!(
        run(
            &with_mesh("mesh \"nowhere.md5mesh\"", "origin ( 0, 1, 0 )"),
            &AfOptions::default()
        )
        .is_ok()
    );
}

#[test]
fn variants_and_copies() {
    let v = format!("{GOOD}variant 2 \"heavier\" {{ body \"a\" {{ density 2000 }} }}\n");
    let opts = |variant| AfOptions {
        variant,
        ..Default::default()
    };
    let one = parse(&v, Path::new("t.af"), &opts(1)).unwrap().desc;
    let two = parse(&v, Path::new("t.af"), &opts(2)).unwrap().desc;
    assert_eq!(one.variants.len(), 2);
    assert!(format!("{:?}", two.bodies[0].mass) != format!("{:?}", one.bodies[0].mass));
    let e = parse(&v, Path::new("t.af"), &opts(3)).unwrap_err();
    assert!(
        e.message.contains("variant 3 does not exist") && e.message.contains("1, 2"),
        "{e}"
    );
    let bad = format!("{GOOD}variant 2 \"x\" {{ spring \"h\" {{ }} }}\n");
    assert!(
        parse(&bad, Path::new("t.af"), &opts(2))
            .unwrap_err()
            .message
            .contains("may only override keys")
    );
    let e = parse(
        GOOD,
        Path::new("t.af"),
        &AfOptions {
            count: Some(0),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.message.contains("number of copies"), "{e}");
    let e = parse(
        GOOD,
        Path::new("t.af"),
        &AfOptions {
            count: Some(1_000_000),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.message.contains("number of copies"), "{e}");
}

#[test]
fn validation_errors_point_at_the_body() {
    // Values the reader passes on but validate() rejects still point at their block.
    let bouncy = GOOD.replacen("density 1000", "density 1000\n\trestitution 2", 2);
    let e = err(&bouncy);
    assert_eq!((e.line, e.col), (5, 6), "{e}");
    assert!(e.message.contains("restitution"), "{e}");
    let spring = format!(
        "{GOOD}spring \"s\" {{ body1 \"a\" body2 \"world\" anchor1 ( 0, 0, 0 ) anchor2 ( 0, 1, 0 ) }}\n"
    );
    assert!(parse(&spring, Path::new("t.af"), &AfOptions::default()).is_ok());
    let e = err(&GOOD.replace("up \"y\"", "up \"y\"\n\ttimestep 5"));
    assert!(e.message.contains("timestep"), "{e}");
    assert_eq!((e.line, e.col), (1, 1), "{e}");
}

#[test]
fn missing_file() {
    let e = load(Path::new("/no/such/file.af"), &AfOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/no/such/file.af:1:1: error: cannot read the file"),
        "{e}"
    );
}

#[test]
fn the_doom_figure_uses_everything_and_reports_ignored_keys() {
    let s = load(&figures().join("doom-figure.af"), &AfOptions::default()).unwrap();
    let d = &s.desc;
    assert_eq!(d.name, "doom_figure");
    // totalMass 60 over dynamic bodies.
    let total: f32 = d
        .bodies
        .iter()
        .map(|b| match b.mass {
            ragdoll_sim::scene::MassSpec::Mass(m) => m,
            _ => 0.0,
        })
        .sum();
    assert!((total - 60.0).abs() < 1e-3);
    // Inches, Z up: the head joint at z = 64 in becomes y = 1.6256 m.
    let leash = d.constraints.iter().find(|c| c.name == "leash").unwrap();
    let ragdoll_sim::scene::JointKind::Spring { anchor1, .. } = leash.kind else {
        panic!()
    };
    assert!((anchor1.y - 64.0 * 0.0254).abs() < 1e-5);
    assert_eq!(leash.body2, ragdoll_sim::scene::BodyRef::World);
    // suspendSpeed 20 in/s, noMoveRotation 10 deg.
    assert!((d.settings.sleep.linear_velocity - 20.0 * 0.0254).abs() < 1e-6);
    assert!((d.settings.sleep.rotation - 10f32.to_radians()).abs() < 1e-6);
    // Every kind of key Doom 3 has that we do not use is listed, in file order.
    for key in [
        "skin",
        "anim",
        "contents",
        "clipMask",
        "mod",
        "frictionDirection",
        "contactMotorDirection",
    ] {
        assert!(s.ignored.iter().any(|i| i.key == key), "{key}");
    }
    assert!(s.ignored.iter().any(|i| i.key.starts_with("custom(")));
    // containedJoints are resolved against the mesh, not ignored: each of its 18 joints
    // belongs to one body.
    assert!(!s.ignored.iter().any(|i| i.key == "containedJoints"));
    let mut owned: Vec<u32> = d
        .bodies
        .iter()
        .flat_map(|b| b.contained_joints.clone())
        .collect();
    owned.sort_unstable();
    assert_eq!(owned, (0..18).collect::<Vec<u32>>());
    // Hinge `limit centre, width, shaft` = 45, 90, 0: body1 may turn shaft − centre
    // ± width/2 = −90..0 degrees about `( 0, 0, 1 )`, the T-posed left forearm (+Y)
    // swinging forward (+X), as an elbow does.
    let find = |n: &str| &d.constraints.iter().find(|c| c.name == n).unwrap().kind;
    let ragdoll_sim::scene::JointKind::Hinge { limit: Some(l), .. } = find("l_elbow") else {
        panic!()
    };
    assert!((l.min + 90f32.to_radians()).abs() < 1e-6 && l.max.abs() < 1e-6);
    // Universal: Doom 3's shafts along the bones become the cross's two axes, each
    // perpendicular to its shaft and to the other; the cone keeps shaft 1.
    let ragdoll_sim::scene::JointKind::Universal {
        shaft1,
        shaft2,
        swing,
        ..
    } = find("neck")
    else {
        panic!()
    };
    let up = ragdoll_sim::glam::Vec3::Y; // bonedir(Neck, Head) in Z-up inches is our +Y
    assert!(
        shaft1.dot(*shaft2).abs() < 1e-6
            && shaft1.dot(up).abs() < 1e-6
            && shaft2.dot(up).abs() < 1e-6
    );
    let Some(ragdoll_sim::scene::SwingLimit::Cone {
        shaft, half_angle, ..
    }) = swing
    else {
        panic!()
    };
    assert!((*shaft - up).length() < 1e-6 && (half_angle - 30f32.to_radians()).abs() < 1e-6);
    assert!(
        s.ignored
            .windows(2)
            .all(|w| (w[0].line, w[0].col) <= (w[1].line, w[1].col))
    );
}

#[test]
fn the_seeds_comma_less_suspend_speed_reads_as_the_comma_form() {
    // The seed documents `suspendSpeed <lv> <av> <la> <aa>` with blanks; id's files write
    // commas. Both mean the same; a value that is not a number still ends the entry.
    let with = |line: &str| {
        let text = GOOD.replacen("\tup \"y\"\n", &format!("\tup \"y\"\n\t{line}\n"), 1);
        parse(&text, Path::new("t.af"), &AfOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
            .desc
            .settings
            .sleep
    };
    let blanks = with("suspendSpeed 20 30 40 60");
    assert_eq!(blanks, with("suspendSpeed 20, 30, 40, 60"));
    assert!((blanks.linear_velocity - 20.0).abs() < 1e-6);
    assert!((blanks.angular_acceleration - 60f32.to_radians()).abs() < 1e-6);
    check(
        "\tup \"y\"\n",
        "\tup \"y\"\n\tsuspendSpeed 20 30 \"x\" 60\n",
        4,
        21,
        "key",
    );
}
