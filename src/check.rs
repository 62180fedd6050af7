//! `ragdoll-lab check FILE.af [--mesh M]` (or `--doom3 BASE --entity NAME`): reads a file, every variant of it, and prints
//! a summary — bodies by shape, constraints by type, total mass, ignored keys — or the
//! first error as `FILE:LINE:COL: error: ...`.

use crate::AppError;
use crate::cli::CheckArgs;
use ragdoll_sim::scene::af::{self, AfOptions, AfScene, FigureSource};
use ragdoll_sim::scene::{MassSpec, SceneDesc};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Prints a summary of the file or its first error.
pub fn run(args: CheckArgs) -> Result<(), AppError> {
    let opts = AfOptions {
        variant: 1,
        mesh: args.mesh.clone(),
        count: None,
    };
    if let (Some(base), Some(entity)) = (&args.doom3, &args.entity) {
        let (scene, c) = crate::scenes::load_entity(base, entity, &opts)?;
        let mut out = summary(&c.af_file.display().to_string(), &scene);
        let _ = writeln!(
            out,
            "entity \"{}\": figure \"{}\", mesh {}, pose {}, skin {}, anims: {}",
            c.entity.name,
            c.figure,
            c.mesh
                .as_ref()
                .map_or("none".into(), |p| p.display().to_string()),
            c.af_pose
                .as_ref()
                .map_or("bind pose".into(), |p| format!("af_pose {}", p.display())),
            c.skin.as_deref().unwrap_or("none"),
            if c.anims.is_empty() {
                "none".into()
            } else {
                c.anims
                    .iter()
                    .map(|(n, _)| n.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            },
        );
        print!("{out}");
        return Ok(());
    }
    let Some(file) = &args.file else {
        return Err(AppError::Usage(
            "check needs an .af file, or --doom3 BASE --entity NAME".into(),
        ));
    };
    let source = FigureSource {
        base: args.doom3.clone(),
        ..FigureSource::default()
    };
    let scene =
        af::load_figure(file, &opts, &source).map_err(|e| AppError::Scene(e.to_string()))?;
    // Every variant must build too; a broken override is an error in the file.
    for v in scene.desc.variants.iter().filter(|v| v.number != 1) {
        let o = AfOptions {
            variant: v.number,
            ..opts.clone()
        };
        af::load_figure(file, &o, &source).map_err(|e| AppError::Scene(e.to_string()))?;
    }
    print!("{}", summary(&file.display().to_string(), &scene));
    Ok(())
}

/// The summary `check` prints.
pub fn summary(file: &str, scene: &AfScene) -> String {
    let d: &SceneDesc = &scene.desc;
    let mut out = String::new();
    let _ = writeln!(out, "{file}: ok, scene \"{}\"", d.name);
    if !d.variants.is_empty() {
        let v: Vec<String> = d
            .variants
            .iter()
            .map(|v| format!("{} \"{}\"", v.number, v.name))
            .collect();
        let _ = writeln!(out, "variants: {}", v.join(", "));
    }
    let st = &d.settings;
    let ground = match st.ground {
        Some(g) => format!("ground top at {} m", g.height),
        None => "no ground".into(),
    };
    let _ = writeln!(
        out,
        "settings: timestep {:.4} s, {} iterations{}, {} substeps{}, {ground}",
        st.timestep,
        st.iterations,
        st.multibody_iterations
            .map_or(String::new(), |n| format!(" ({n} multibody)")),
        st.substeps,
        st.multibody_substeps
            .map_or(String::new(), |n| format!(" ({n} multibody)"))
    );
    let mut shapes: BTreeMap<&str, usize> = BTreeMap::new();
    for b in &d.bodies {
        *shapes.entry(b.shape.kind_name()).or_default() += 1;
    }
    let fixed = d.bodies.iter().filter(|b| b.is_fixed()).count();
    let _ = writeln!(
        out,
        "bodies: {} ({} dynamic, {} fixed): {}",
        d.bodies.len(),
        d.bodies.len() - fixed,
        fixed,
        counts(&shapes)
    );
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    for c in &d.constraints {
        *kinds.entry(c.kind.keyword()).or_default() += 1;
    }
    let _ = writeln!(
        out,
        "constraints: {}{}{}",
        d.constraints.len(),
        if kinds.is_empty() { "" } else { ": " },
        counts(&kinds)
    );
    let total: f32 = d
        .bodies
        .iter()
        .filter(|b| !b.is_fixed())
        .map(|b| match b.mass {
            MassSpec::Mass(m) => m,
            MassSpec::Density(_) => 0.0,
        })
        .sum();
    let _ = writeln!(out, "total mass: {total:.2} kg (dynamic bodies)");
    if let Some(rig) = &scene.rig {
        // Which body a shot at the mesh pushes, per joint (`containedJoints`).
        let contained: usize = d.bodies.iter().map(|b| b.contained_joints.len()).sum();
        let _ = writeln!(
            out,
            "skeleton: {} joints, {contained} contained by a body (containedJoints)",
            rig.joints.len()
        );
    }
    if scene.ignored.is_empty() {
        let _ = writeln!(out, "ignored: nothing");
    } else {
        let _ = writeln!(out, "ignored: {} key(s)", scene.ignored.len());
        for i in &scene.ignored {
            let _ = writeln!(
                out,
                "  {file}:{}:{}: `{}`: {}",
                i.line, i.col, i.key, i.reason
            );
        }
    }
    out
}

fn counts(m: &BTreeMap<&str, usize>) -> String {
    m.iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}
