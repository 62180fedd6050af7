//! `ragdoll-lab check FILE.af [--mesh M]`: reads a file, every variant of it, and prints
//! a summary — bodies by shape, constraints by type, total mass, ignored keys — or the
//! first error as `FILE:LINE:COL: error: ...`.

use crate::AppError;
use crate::cli::CheckArgs;
use ragdoll_sim::scene::af::{self, AfOptions, AfScene};
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
    let scene = af::load(&args.file, &opts).map_err(|e| AppError::Scene(e.to_string()))?;
    // Every variant must build too; a broken override is an error in the file.
    for v in scene.desc.variants.iter().filter(|v| v.number != 1) {
        let o = AfOptions {
            variant: v.number,
            ..opts.clone()
        };
        af::load(&args.file, &o).map_err(|e| AppError::Scene(e.to_string()))?;
    }
    print!("{}", summary(&args.file.display().to_string(), &scene));
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
        "settings: timestep {:.4} s, {} iterations, {} substeps{}, {ground}",
        st.timestep,
        st.iterations,
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
