//! `ragdoll-lab stats --anim NAME --at FRAME`: both methods start from the animation's
//! frame with its velocities, and the mistakes a user can make are one-line errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ragdoll-lab"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

const ENTITY: [&str; 5] = [
    "stats",
    "--doom3",
    "assets/doom3",
    "--entity",
    "monster_lab_human",
];

/// The mean x velocity (m/s, mass-weighted) of the first traced frame per method, and
/// the frame's largest body speed.
fn first_frame_velocity(trace: &Path) -> Vec<(String, f64)> {
    let text = std::fs::read_to_string(trace).unwrap();
    let mut lines = text.lines();
    let header: serde_json::Value = serde_json::from_str(lines.next().unwrap()).unwrap();
    let masses: Vec<f64> = header["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["mass"].as_f64().unwrap())
        .collect();
    let total: f64 = masses.iter().sum();
    let mut out: Vec<(String, f64)> = Vec::new();
    for line in lines {
        let f: serde_json::Value = serde_json::from_str(line).unwrap();
        let method = f["method"].as_str().unwrap().to_string();
        if out.iter().any(|(m, _)| *m == method) {
            continue;
        }
        let vx: f64 = f["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .zip(&masses)
            .map(|(b, m)| b["linear_velocity"][0].as_f64().unwrap() * m)
            .sum::<f64>()
            / total;
        out.push((method, vx));
    }
    out
}

#[test]
fn stats_from_a_walk_frame_starts_both_methods_walking_forward() {
    let dir = std::env::temp_dir().join(format!("ragdoll-lab-anim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let trace = dir.join("walk.jsonl");
    let mut args = ENTITY.to_vec();
    let trace_s = trace.display().to_string();
    args.extend([
        "--anim",
        "walk",
        "--at",
        "6",
        "--seconds",
        "0.05",
        "--trace",
        &trace_s,
    ]);
    let out = run(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for m in ["particle", "multibody"] {
        assert_eq!(json["methods"][m]["finite"], true, "{m}");
        assert_eq!(json["methods"][m]["bodies"], 11, "{m}");
    }
    // The walk moves its root at 1.59 m/s along +X; one frame later both methods still
    // carry nearly all of it.
    let v = first_frame_velocity(&trace);
    assert_eq!(v.len(), 2, "{v:?}");
    for (m, vx) in &v {
        assert!(*vx > 1.2 && *vx < 1.8, "{m}: {vx} m/s");
    }
    // Without --anim the figure starts at rest.
    let still = dir.join("still.jsonl");
    let still_s = still.display().to_string();
    let mut args = ENTITY.to_vec();
    args.extend(["--seconds", "0.05", "--trace", &still_s]);
    let out = run(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    for (m, vx) in first_frame_velocity(&still) {
        assert!(vx.abs() < 0.05, "{m}: {vx} m/s");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `stats` with `extra` after the entity and returns its one error line.
fn error(extra: &[&str]) -> String {
    let mut args = ENTITY.to_vec();
    args.extend(extra);
    args.extend(["--seconds", "0"]);
    let out = run(&args);
    assert!(!out.status.success(), "{extra:?} succeeded");
    let err = text(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn an_unknown_anim_or_frame_is_an_error_that_says_what_there_is() {
    let e = error(&["--anim", "run"]);
    assert!(
        e.contains("no anim \"run\"") && e.contains("af_pose, walk"),
        "{e}"
    );
    let e = error(&["--anim", "Walk"]);
    assert!(e.contains("compare exactly"), "{e}");
    let e = error(&["--anim", "walk", "--at", "25"]);
    assert!(
        e.contains("frame 25") && e.contains("frames 0 to 24"),
        "{e}"
    );
}

#[test]
fn an_anim_file_of_another_skeleton_is_refused() {
    let dir = std::env::temp_dir().join(format!("ragdoll-lab-anim-h-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let walk = root().join("assets/doom3/models/md5/lab_human/walk.md5anim");
    let text_in = std::fs::read_to_string(&walk).unwrap();
    let bad = dir.join("other.md5anim");
    std::fs::write(&bad, text_in.replace("\"Chest\"", "\"Spine\"")).unwrap();
    let mesh = root().join("assets/doom3/models/md5/lab_human/lab_human.md5mesh");
    let af = root().join("assets/doom3/af/lab_human.af");
    let (af, mesh) = (af.display().to_string(), mesh.display().to_string());
    // The file route: --af, --mesh and --anim FILE.
    let good = run(&[
        "stats",
        "--af",
        &af,
        "--mesh",
        &mesh,
        "--anim",
        &walk.display().to_string(),
        "--at",
        "3",
        "--seconds",
        "0.1",
    ]);
    assert!(good.status.success(), "{}", text(&good.stderr));
    let out = run(&[
        "stats",
        "--af",
        &af,
        "--mesh",
        &mesh,
        "--anim",
        &bad.display().to_string(),
        "--seconds",
        "0",
    ]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(
        err.contains("does not fit the mesh") && err.contains("Spine"),
        "{err}"
    );
    // --anim with --af but no skeleton to animate.
    let out = run(&[
        "stats",
        "--af",
        &af,
        "--anim",
        "x.md5anim",
        "--seconds",
        "0",
    ]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("--mesh"),
        "{}",
        text(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
