//! Fuzzing the md5mesh, md5anim and `.def` readers the way `af_fuzz` fuzzes the `.af`
//! reader: mutated files never panic; they either read or give one positioned error on
//! one line, inside the text.

mod common;

use common::mutation::Mutation;
use proptest::prelude::*;
use ragdoll_sim::scene::af::AfError;
use ragdoll_sim::scene::decl::Doom3Base;
use ragdoll_sim::scene::{md5anim, md5mesh};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every md5 file we ship, with its text.
fn sources(ext: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut dirs = vec![root().join("assets")];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == ext) {
                out.push((
                    p.display().to_string(),
                    std::fs::read_to_string(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    assert!(!out.is_empty(), "no .{ext} files under assets/");
    out
}

const TOKENS: &[&str] = &[
    "{",
    "}",
    "(",
    ")",
    "\"",
    "/*",
    "//",
    "\n",
    "-",
    "0",
    "-1",
    "1e39",
    "nan",
    "1e-40",
    "64",
    "99999999",
    "MD5Version",
    "numJoints",
    "numMeshes",
    "joints",
    "mesh",
    "shader",
    "numverts",
    "vert",
    "numtris",
    "tri",
    "numweights",
    "weight",
    "numFrames",
    "frameRate",
    "hierarchy",
    "bounds",
    "baseframe",
    "frame",
    "numAnimatedComponents",
    "\"origin\"",
    "inherit",
    "anim",
    "model",
    "entityDef",
    "\u{feff}",
    "é",
    "\u{0}",
];

/// A mutation over this reader's tokens.
fn mutation() -> impl Strategy<Value = Mutation> {
    common::mutation::strategy(TOKENS.len())
}

/// Applies mutations on char boundaries.
fn mutate(text: &str, muts: &[Mutation]) -> String {
    common::mutation::apply(text, muts, TOKENS)
}

/// The error contract: inside the text, one line, named file.
fn check_error(file: &str, text: &str, e: &AfError) {
    let lines = text.lines().count() as u32 + 1;
    assert!(e.line >= 1 && e.line <= lines.max(1), "{e}");
    assert!(e.col >= 1, "{e}");
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("{file}:{}:{}: error: ", e.line, e.col)),
        "{shown}"
    );
    assert!(!e.message.chars().any(char::is_control), "{shown:?}");
}

fn check_mesh(file: &str, text: &str) {
    match md5mesh::parse(text, file) {
        Ok(m) => {
            // Whatever reads can be skinned without a panic.
            let poses = m.skeleton.poses();
            for sub in &m.meshes {
                assert!(sub.skin(&poses).len() == sub.vertices.len());
            }
        }
        Err(e) => check_error(file, text, &e),
    }
}

fn check_anim(file: &str, text: &str) {
    match md5anim::parse(text, file) {
        Ok(a) => {
            for f in 0..a.frame_count() {
                assert_eq!(a.frame_poses(f).len(), a.joints.len());
            }
            let _ = a.compose(&a.local_poses_at(0.3));
        }
        Err(e) => check_error(file, text, &e),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_meshes_never_panic(which in any::<usize>(), muts in prop::collection::vec(mutation(), 1..4)) {
        let srcs = sources("md5mesh");
        let (file, text) = &srcs[which % srcs.len()];
        check_mesh(file, &mutate(text, &muts));
    }

    #[test]
    fn mutated_animations_never_panic(which in any::<usize>(), muts in prop::collection::vec(mutation(), 1..4)) {
        let srcs = sources("md5anim");
        let (file, text) = &srcs[which % srcs.len()];
        check_anim(file, &mutate(text, &muts));
    }

    #[test]
    fn arbitrary_text_never_panics(text in "[ -~\n\t]{0,200}") {
        check_mesh("fuzz.md5mesh", &text);
        check_anim("fuzz.md5anim", &text);
    }
}

/// Mutated declaration files: the lookups either resolve or return an error.
#[test]
fn mutated_declarations_never_panic() {
    let src = root().join("assets/doom3");
    let def = std::fs::read_to_string(src.join("def/lab_human.def")).unwrap();
    let af = std::fs::read_to_string(src.join("af/lab_human.af")).unwrap();
    let dir = std::env::temp_dir().join(format!("ragdoll-lab-def-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("def")).unwrap();
    std::fs::create_dir_all(dir.join("af")).unwrap();
    std::fs::write(dir.join("af/lab_human.af"), &af).unwrap();
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig {
        cases: 300,
        ..ProptestConfig::default()
    });
    runner
        .run(&(prop::collection::vec(mutation(), 1..4)), |muts| {
            std::fs::write(dir.join("def/lab_human.def"), mutate(&def, &muts)).unwrap();
            match Doom3Base::open(&dir) {
                Ok(base) => {
                    let _ = base.character("monster_lab_human");
                    let _ = base.model("lab_human");
                }
                Err(e) => assert!(e.line >= 1 && e.col >= 1),
            }
            Ok(())
        })
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn inheritance_loops_end_in_an_error() {
    let dir = std::env::temp_dir().join(format!("ragdoll-lab-def-loop-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("def")).unwrap();
    std::fs::write(
        dir.join("def/loop.def"),
        "entityDef a { \"inherit\" \"b\" }\nentityDef b { \"inherit\" \"a\" }\nmodel m { inherit m }\n",
    )
    .unwrap();
    let base = Doom3Base::open(&dir).unwrap();
    assert!(
        base.entity("a")
            .unwrap_err()
            .message
            .contains("inherits too deeply")
    );
    assert!(
        base.model("m")
            .unwrap_err()
            .message
            .contains("inherits too deeply")
    );
    let _ = std::fs::remove_dir_all(&dir);
    let _ = Path::new("");
}

#[test]
fn model_keywords_may_be_quoted_and_entity_keys_must_be() {
    let dir = std::env::temp_dir().join(format!("ragdoll-lab-def-quotes-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("def")).unwrap();
    // A quoted model keyword, as id's env.def writes `"skin"`; an entity key that is a
    // bare number, as id's monster_boss_cyberdemon.def has after `"knockback" "180" 0`.
    std::fs::write(
        dir.join("def/quotes.def"),
        "model m {\n\t\"skin\"\t\"skins/x.skin\"\n\tmesh\tm.md5mesh\n}\n\
         entityDef e {\n\t\"knockback\"\t\"180\" 0\n\t\"push\"\t\"5\"\n}\n",
    )
    .unwrap();
    let base = Doom3Base::open(&dir).unwrap();
    let m = base.model("m").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.skin.as_deref(), Some("skins/x.skin"));
    assert_eq!(m.mesh.as_deref(), Some("m.md5mesh"));
    let e = base.entity("e").unwrap_err();
    assert_eq!((e.line, e.col), (6, 20), "{e}");
    assert!(e.message.contains("expected a quoted key"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_mesh_is_reported_at_its_model_declaration() {
    let dir = std::env::temp_dir().join(format!("ragdoll-lab-def-missing-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("def")).unwrap();
    std::fs::write(
        dir.join("def/m.def"),
        "// a model whose mesh the folder lacks\nmodel m {\n\tmesh\tmodels/none.md5mesh\n}\n",
    )
    .unwrap();
    let base = Doom3Base::open(&dir).unwrap();
    let e = base.model_files("m").unwrap_err();
    assert!(e.file.ends_with("m.def"), "{e}");
    assert_eq!(e.line, 2, "{e}");
    assert!(
        e.message
            .contains("\"models/none.md5mesh\" is not in the base folder"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
