//! `ragdoll-lab check`: accepts every scene and the hand-written Doom 3 figure; every
//! broken file gives exactly one `FILE:LINE:COL: error: ...` line and exit status 1.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn check(args: &[&Path]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ragdoll-lab"));
    c.arg("check");
    for a in args {
        c.arg(a);
    }
    c.output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn accepts_every_scene_with_a_summary() {
    for e in std::fs::read_dir(root().join("assets/scenes")).unwrap() {
        let p = e.unwrap().path();
        let out = check(&[&p]);
        let stdout = text(&out.stdout);
        assert!(
            out.status.success(),
            "{}: {}",
            p.display(),
            text(&out.stderr)
        );
        for line in ["bodies: ", "constraints: ", "total mass: ", "ignored: "] {
            assert!(stdout.contains(line), "{}: {stdout}", p.display());
        }
    }
    let human = text(&check(&[&root().join("assets/scenes/human.af")]).stdout);
    assert!(
        human.contains("bodies: 16 (16 dynamic, 0 fixed): 16 box"),
        "{human}"
    );
    assert!(
        human.contains("constraints: 15: 6 ballAndSocketJoint, 9 hinge"),
        "{human}"
    );
}

#[test]
fn accepts_the_doom_figure_and_lists_what_it_ignores() {
    let fig = root().join("assets/figures/doom-figure.af");
    let out = check(&[&fig]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("total mass: 60.00 kg"), "{stdout}");
    assert!(
        stdout.contains("1 slider") && stdout.contains("2 spring") && stdout.contains("1 fixed"),
        "{stdout}"
    );
    assert!(
        stdout.contains("`frictionDirection`") && stdout.contains("custom(\""),
        "{stdout}"
    );
}

/// A scratch directory for broken files.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ragdoll-lab-check-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn mesh_flag_resolves_joint_references() {
    let dir = scratch("mesh");
    let fig = std::fs::read_to_string(root().join("assets/figures/doom-figure.af")).unwrap();
    let no_key = dir.join("figure.af");
    std::fs::write(&no_key, fig.replace("model \"doom-figure.md5mesh\"", "")).unwrap();
    let out = check(&[&no_key]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("--mesh"), "{err}");
    let mesh = root().join("assets/figures/doom-figure.md5mesh");
    let out = check(&[&no_key, Path::new("--mesh"), &mesh]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

#[test]
fn broken_files_give_one_positioned_error_and_exit_1() {
    let dir = scratch("broken");
    let human = std::fs::read_to_string(root().join("assets/scenes/human.af")).unwrap();
    let cases: Vec<(&str, String)> = vec![
        ("truncated", human[..human.len() / 2].to_string()),
        (
            "wrong-token",
            human.replacen("density 0.001", "density = 0.001", 1),
        ),
        (
            "unknown-body",
            human.replacen("body2 \"neck\"", "body2 \"nek\"", 1),
        ),
        (
            "duplicate",
            human.replacen("body \"neck\"", "body \"head\"", 1),
        ),
        (
            "world",
            human.replacen("body \"neck\"", "body \"world\"", 1),
        ),
        (
            "nan",
            human.replacen("origin ( 0, 0, -16.15 )", "origin ( 0, nan, -16.15 )", 1),
        ),
        (
            "negative",
            human.replacen("( -7.85, -10, -10 )", "( 7.85, -10, -10 )", 1),
        ),
        (
            "unresolved",
            human.replacen("origin ( 0, 0, -16.15 )", "origin joint( \"neck\" )", 1),
        ),
        (
            "missing-mesh",
            human
                .replacen("up \"z\"", "up \"z\"\n\tmesh \"gone.md5mesh\"", 1)
                .replacen("origin ( 0, 0, -16.15 )", "origin joint( \"neck\" )", 1),
        ),
        ("empty", String::new()),
        ("binary", "\u{0}\u{1}body".to_string()),
    ];
    for (name, body) in cases {
        assert_ne!(body, human, "{name}: the mutation applied");
        let p = dir.join(format!("{name}.af"));
        std::fs::write(&p, &body).unwrap();
        let out = check(&[&p]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(out.stdout.is_empty(), "{name}: no summary of a broken file");
        assert_eq!(err.lines().count(), 1, "{name}: exactly one line: {err}");
        let prefix = format!("{}:", p.display());
        let rest = err
            .strip_prefix(&prefix)
            .unwrap_or_else(|| panic!("{name}: {err}"));
        let mut parts = rest.splitn(3, ':');
        let line: u32 = parts
            .next()
            .unwrap()
            .parse()
            .unwrap_or_else(|_| panic!("{name}: {err}"));
        let col: u32 = parts
            .next()
            .unwrap()
            .parse()
            .unwrap_or_else(|_| panic!("{name}: {err}"));
        assert!(line >= 1 && col >= 1);
        assert!(
            parts.next().unwrap().starts_with(" error: "),
            "{name}: {err}"
        );
    }
    let missing = check(&[&dir.join("does-not-exist.af")]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(text(&missing.stderr).contains("does-not-exist.af:1:1: error: cannot read the file"));
}

#[test]
fn the_mod_entity_has_every_joint_contained_by_a_body() {
    let base = root().join("assets/doom3");
    let out = check(&[
        Path::new("--doom3"),
        &base,
        Path::new("--entity"),
        Path::new("monster_lab_human"),
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        stdout.contains("skeleton: 20 joints, 20 contained by a body (containedJoints)"),
        "{stdout}"
    );
}
