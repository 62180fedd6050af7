//! `containedJoints` resolved as Doom 3 resolves them (dhewm3
//! `idDeclModelDef::GetJointList`, `idAF::Load`): on a small figure written here, whose
//! skeleton lists one joint out of its parent's run, and on the mod under
//! `assets/doom3`.

use ragdoll_sim::scene::SceneDesc;
use ragdoll_sim::scene::af::{AfOptions, AfScene, load, load_character};
use ragdoll_sim::scene::decl::Doom3Base;
use std::path::PathBuf;

/// Eight joints, Z up, inches. "Finger" (a child of "Hand") comes after "Leg", so
/// `*Arm` stops before it: the run after a joint ends at the first joint whose parent
/// comes before it.
const MESH: &str = r#"MD5Version 10
commandline ""
numJoints 8
numMeshes 0
joints {
	"origin" -1 ( 0 0 0 ) ( 0 0 0 )
	"Hips"    0 ( 0 0 40 ) ( 0 0 0 )
	"Spine"   1 ( 0 0 50 ) ( 0 0 0 )
	"Head"    2 ( 0 0 65 ) ( 0 0 0 )
	"Arm"     2 ( 0 10 55 ) ( 0 0 0 )
	"Hand"    4 ( 0 20 55 ) ( 0 0 0 )
	"Leg"     1 ( 0 0 20 ) ( 0 0 0 )
	"Finger"  5 ( 0 24 55 ) ( 0 0 0 )
}
"#;

const FIGURE: &str = r#"settings {
	mesh "small.md5mesh"
}
body "pelvis" {
	joint "origin"
	model box( ( -4, -4, -4 ), ( 4, 4, 4 ) )
	origin joint( "Hips" )
	containedJoints "origin *hips -*spine -*LEG"
}
body "torso" {
	joint "Spine"
	model box( ( -4, -4, -4 ), ( 4, 4, 4 ) )
	origin joint( "spine" )
	containedJoints "*SPINE -*arm"
}
body "arm" {
	joint "Arm"
	model box( ( -2, -2, -2 ), ( 2, 2, 2 ) )
	origin joint( "Arm" )
	containedJoints "*Arm"
}
body "hand" {
	joint "Hand"
	model box( ( -2, -2, -2 ), ( 2, 2, 2 ) )
	origin joint( "Hand" )
	containedJoints "Hand  finger"
}
body "leg" {
	joint "Leg"
	model box( ( -2, -2, -2 ), ( 2, 2, 2 ) )
	origin joint( "Leg" )
	containedJoints "Leg"
}
"#;

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ragdoll-contained-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("small.md5mesh"), MESH).unwrap();
    d
}

fn read(tag: &str, figure: &str) -> (Result<AfScene, String>, PathBuf) {
    let dir = scratch(tag);
    let path = dir.join("small.af");
    std::fs::write(&path, figure).unwrap();
    let out = load(&path, &AfOptions::default()).map_err(|e| e.to_string());
    let _ = std::fs::remove_dir_all(&dir);
    (out, path)
}

fn contained(desc: &SceneDesc, body: &str) -> Vec<u32> {
    desc.bodies
        .iter()
        .find(|b| b.name == body)
        .unwrap_or_else(|| panic!("no body {body}"))
        .contained_joints
        .clone()
}

#[test]
fn lists_resolve_left_to_right_with_runs_removals_and_later_claims() {
    let (scene, _) = read("rules", FIGURE);
    let scene = scene.unwrap_or_else(|e| panic!("{e}"));
    let d = &scene.desc;
    // pelvis: origin, *hips = Hips..Finger (every later parent is at or after Hips),
    // -*spine = Spine, Head, Arm, Hand (Leg's parent Hips is before Spine),
    // -*LEG = Leg alone (Finger's parent Hand is before Leg): origin, Hips, Finger —
    // then "hand", later in the file, takes Finger.
    assert_eq!(contained(d, "pelvis"), [0, 1]);
    assert_eq!(contained(d, "torso"), [2, 3], "*SPINE -*arm");
    assert_eq!(
        contained(d, "arm"),
        [4],
        "*Arm is Arm, Hand; hand takes Hand"
    );
    assert_eq!(contained(d, "hand"), [5, 7]);
    assert_eq!(contained(d, "leg"), [6]);
    // Both later claims are noted, naming the joint and both bodies.
    let notes: Vec<&str> = scene
        .ignored
        .iter()
        .filter(|i| i.key == "containedJoints")
        .map(|i| i.reason.as_str())
        .collect();
    assert_eq!(notes.len(), 2, "{notes:?}");
    assert!(
        notes
            .iter()
            .any(|n| n.contains("\"Hand\"") && n.contains("\"arm\""))
    );
    assert!(
        notes
            .iter()
            .any(|n| n.contains("\"Finger\"") && n.contains("\"pelvis\""))
    );
}

#[test]
fn a_body_without_the_key_contains_everything_from_origin_down() {
    // Doom 3's default is "*origin"; last in the file, it takes every joint.
    let figure = format!(
        "{FIGURE}body \"cloak\" {{\n\tjoint \"Head\"\n\tmodel box( ( -1, -1, -1 ), ( 1, 1, 1 ) )\n\torigin joint( \"Head\" )\n}}\n"
    );
    let (scene, _) = read("default", &figure);
    let d = scene.unwrap_or_else(|e| panic!("{e}")).desc;
    assert_eq!(contained(&d, "cloak"), (0..8).collect::<Vec<u32>>());
    for b in ["pelvis", "torso", "arm", "hand", "leg"] {
        assert!(contained(&d, b).is_empty(), "{b}");
    }
}

#[test]
fn an_unknown_joint_is_an_error_at_its_name() {
    let figure = FIGURE.replace("\"*SPINE -*arm\"", "\"*SPINE -*tail\"");
    let (scene, path) = read("unknown", &figure);
    let err = scene.expect_err("tail is no joint");
    // Line 14 is the torso's containedJoints; the quote is at column 18 (after a tab
    // and `containedJoints `), "-*tail" starts at column 26, its name at 28.
    let want = format!(
        "{}:14:28: error: containedJoints: the mesh has no joint \"tail\"",
        path.display()
    );
    assert!(err.starts_with(&want), "{err}\nwanted {want}");
    let bare = FIGURE.replace("\"Leg\"\n}", "\"Leg -*\"\n}");
    let (scene, _) = read("bare", &bare);
    let err = scene.expect_err("a bare modifier names no joint");
    assert!(err.contains("a joint name after `-` or `*`"), "{err}");
}

#[test]
fn without_a_mesh_the_key_is_listed_as_ignored() {
    let figure = "body \"b\" {\n\tmodel box( ( -1, -1, -1 ), ( 1, 1, 1 ) )\n\tcontainedJoints \"*origin\"\n}\n";
    let (scene, _) = read("nomesh", figure);
    let scene = scene.unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.desc.bodies[0].contained_joints.is_empty());
    let i = scene
        .ignored
        .iter()
        .find(|i| i.key == "containedJoints")
        .expect("listed");
    assert_eq!((i.line, i.col), (3, 2));
}

mod common;

use common::lab_mod_base as mod_base;

#[test]
fn every_joint_of_the_mod_humanoid_belongs_to_the_body_its_file_names() {
    let base = mod_base();
    let decls = Doom3Base::open(&base).unwrap_or_else(|e| panic!("{e}"));
    let c = decls
        .character("monster_lab_human")
        .unwrap_or_else(|e| panic!("{e}"));
    let scene = load_character(&c, &base, &AfOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let mesh = ragdoll_sim::scene::md5mesh::load(c.mesh.as_ref().unwrap()).unwrap();
    let names = |body: &str| -> Vec<String> {
        contained(&scene.desc, body)
            .iter()
            .map(|&j| mesh.skeleton.joints[j as usize].name.clone())
            .collect()
    };
    assert_eq!(names("waist"), ["origin", "Body"]);
    assert_eq!(names("chest"), ["Waist", "Chest"]);
    assert_eq!(names("head"), ["Neck", "Head"]);
    assert_eq!(names("luparm"), ["Luparm"]);
    assert_eq!(names("lloarm"), ["Lloarm", "Lhand"]);
    assert_eq!(names("rloarm"), ["Rloarm", "Rhand"]);
    assert_eq!(names("lloleg"), ["Lloleg", "Lankle", "Lsole"]);
    assert_eq!(names("rupleg"), ["Rupleg"]);
    // Each of the 20 joints belongs to exactly one body, and nothing is noted.
    let mut all: Vec<u32> = scene
        .desc
        .bodies
        .iter()
        .flat_map(|b| b.contained_joints.iter().copied())
        .collect();
    all.sort_unstable();
    assert_eq!(all, (0..20).collect::<Vec<u32>>());
    assert!(
        !scene.ignored.iter().any(|i| i.key == "containedJoints"),
        "{:?}",
        scene.ignored
    );
}
