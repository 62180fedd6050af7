//! The built-in scene table: numbers, names, embedded files, variants, `--af`, `--count`.

use ragdoll_lab::AppError;
use ragdoll_lab::cli::SceneArgs;
use ragdoll_lab::scenes::{builtin_scenes, find_builtin, load};
use std::path::PathBuf;

fn args(scene: &str) -> SceneArgs {
    SceneArgs {
        scene: Some(scene.into()),
        ..Default::default()
    }
}

#[test]
fn the_table_of_design_md() {
    let names: Vec<(u32, &str)> = builtin_scenes()
        .iter()
        .map(|s| (s.number, s.name))
        .collect();
    assert_eq!(
        names,
        [
            (1, "collision"),
            (2, "ball-chain"),
            (3, "hinge-chain"),
            (4, "box-masses"),
            (5, "ball-limits"),
            (6, "hinge-limits"),
            (7, "spider"),
            (8, "human"),
            (9, "capsule-human"),
            (10, "pile")
        ]
    );
    // Variants the paper names: tests 2, 3 (three), 4.
    for (n, variants) in [(2, 2), (3, 3), (4, 2), (1, 0), (8, 0)] {
        let s = load(&args(&n.to_string())).unwrap();
        assert_eq!(s.desc.variants.len(), variants, "scene {n}");
    }
}

#[test]
fn embedded_text_is_the_file_on_disk() {
    for s in builtin_scenes() {
        let disk = std::fs::read_to_string(s.asset_path()).unwrap();
        assert_eq!(disk, s.text, "{} is stale in the binary", s.file);
    }
    let on_disk: usize =
        std::fs::read_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes"))
            .unwrap()
            .count();
    assert_eq!(
        on_disk,
        builtin_scenes().len(),
        "every file in assets/scenes is a built-in scene"
    );
}

#[test]
fn by_number_or_name_with_variants_default_human() {
    for s in builtin_scenes() {
        let by_number = load(&args(&s.number.to_string())).unwrap();
        let by_name = load(&args(&s.name.to_uppercase())).unwrap();
        assert_eq!(by_number.desc, by_name.desc);
        assert_eq!(by_number.desc.name, s.name);
    }
    let default = load(&SceneArgs::default()).unwrap();
    assert_eq!(default.desc.name, "human");
    assert_eq!(default.desc.bodies.len(), 16);
    let v3 = load(&SceneArgs {
        variant: Some(3),
        ..args("hinge-chain")
    })
    .unwrap();
    assert_eq!(v3.desc.settings.iterations, 20);
    let bad = load(&SceneArgs {
        variant: Some(3),
        ..args("ball-chain")
    })
    .unwrap_err();
    assert!(
        matches!(&bad, AppError::Scene(m) if m.starts_with("assets/scenes/ball-chain.af:") && m.contains("variant 3 does not exist")),
        "{bad}"
    );
}

#[test]
fn unknown_scene_lists_the_table() {
    assert_eq!(find_builtin(" Pile ").map(|s| s.number), Some(10));
    let e = load(&args("11")).unwrap_err();
    assert!(
        matches!(&e, AppError::Usage(m) if m.contains("10 pile")),
        "{e}"
    );
}

#[test]
fn af_file_mesh_and_count() {
    let figures = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/figures");
    let s = load(&SceneArgs {
        af: Some(figures.join("doom-figure.af")),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(s.desc.bodies.len(), 10);
    assert!(s.ignored.iter().any(|i| i.contains("frictionDirection")));
    let pile = load(&SceneArgs {
        count: Some(1000),
        ..args("pile")
    })
    .unwrap();
    assert_eq!(pile.desc.bodies.len(), 16_000);
    let spiders = load(&SceneArgs {
        count: Some(3),
        ..args("spider")
    })
    .unwrap();
    assert_eq!(spiders.desc.bodies.len(), 27, "--count copies any scene");
}
