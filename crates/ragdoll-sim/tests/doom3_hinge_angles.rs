//! The sense of a Doom 3 hinge `limit c, w, s`, derived from the engine's source (see
//! `hinge_limit_range` in the `.af` reader), held end to end: a hand-written rod on every
//! solver, and the hinge angles id Software's own walks and runs give real figures.
//!
//! id's files are not part of this repository: the walks run only when
//! `RAGDOLL_LAB_DOOM3_BASE` names a base folder and print a note otherwise.
//!
//! Walks: for every character with limited hinges and every animation of its model
//! whose name says walk or run, each frame's skeleton (model space, converted to our
//! axes as the rig converts the `af_pose`) turns each body as its driving joint turns:
//! `R_b = R_j R_rel`, with `R_rel` the body's rotation relative to its joint at load.
//! The hinge angle is then measured as the multibody's gauge measures it: body1's
//! rotation relative to body2 since load, right-handed about the axis. A frame is
//! inside a range when the angle is. Animations are not held to limits (they are
//! authored, not simulated), so neither reading need hold every frame; the engine's
//! reading must hold more of them than its mirror image, or the derivation is wrong.

use glam::{Quat, Vec3};
use ragdoll_sim::Method;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::af::{AfOptions, load_character, parse};
use ragdoll_sim::scene::decl::Doom3Base;
use ragdoll_sim::scene::md5anim;
use ragdoll_sim::scene::rig::Rig;
use ragdoll_sim::scene::{AngleRange, BodyRef, JointKind, SceneDesc};
use std::collections::BTreeSet;
use std::path::PathBuf;

mod common;

/// The real Doom 3 base folder, or `None` (with a note) when it is not given.
fn base_dir() -> Option<PathBuf> {
    common::real_doom3_base("the real Doom 3 animations")
}

/// A limited hinge between two bodies that joints drive.
struct Hinge {
    name: String,
    /// Body1's and body2's driving joint and rotation relative to it.
    drivers: [(usize, Quat); 2],
    /// Body2's rest rotation inverse times body1's: `q₀`.
    rest_rel: Quat,
    /// The axis in body2's frame.
    axis_b: Vec3,
    range: AngleRange,
}

fn hinges(sc: &SceneDesc, rig: &Rig) -> Vec<Hinge> {
    let driver = |body: usize| {
        rig.joints
            .iter()
            .enumerate()
            .find_map(|(j, rj)| match rj.driver {
                Some(d) if d.body == body => Some((j, d.relative)),
                _ => None,
            })
    };
    let mut out = Vec::new();
    for c in &sc.constraints {
        let (
            JointKind::Hinge {
                axis,
                limit: Some(range),
                ..
            },
            BodyRef::Body(b2),
        ) = (&c.kind, c.body2)
        else {
            continue;
        };
        let (a, b) = (c.body1.index(), b2.index());
        let (Some(da), Some(db)) = (driver(a), driver(b)) else {
            continue;
        };
        let (qa, qb) = (sc.bodies[a].pose.rotation, sc.bodies[b].pose.rotation);
        out.push(Hinge {
            name: c.name.clone(),
            drivers: [da, db],
            rest_rel: qb.inverse() * qa,
            axis_b: qb.inverse() * *axis,
            range: *range,
        });
    }
    out
}

/// The hinge angle (degrees) for joints' world rotations `joints` (our axes).
fn angle(h: &Hinge, joints: &[Quat]) -> f32 {
    let qa = joints[h.drivers[0].0] * h.drivers[0].1;
    let qb = joints[h.drivers[1].0] * h.drivers[1].1;
    let mut d = qb.inverse() * qa * h.rest_rel.inverse();
    if d.w < 0.0 {
        d = -d;
    }
    (2.0 * d.xyz().dot(h.axis_b).atan2(d.w)).to_degrees()
}

fn inside(r: AngleRange, deg: f32) -> bool {
    (r.min.to_degrees()..=r.max.to_degrees()).contains(&deg)
}

fn mirrored(r: AngleRange) -> AngleRange {
    AngleRange {
        min: -r.max,
        max: -r.min,
    }
}

#[test]
fn real_walks_keep_their_hinges_inside_the_engine_reading_of_limit() {
    let Some(base) = base_dir() else { return };
    let decls = Doom3Base::open(&base).unwrap_or_else(|e| panic!("{e}"));
    let mut seen = BTreeSet::new();
    let (mut frames, mut in_ours, mut in_mirror) = (0usize, 0usize, 0usize);
    let mut runs = 0;
    for name in decls.names("entityDef") {
        let Ok(c) = decls.character(name) else {
            continue;
        };
        let Ok(sc) = load_character(&c, &base, &AfOptions::default()) else {
            continue;
        };
        let Some(rig) = &sc.rig else { continue };
        let hs = hinges(&sc.desc, rig);
        if hs.is_empty() {
            continue;
        }
        let axes = rig.file_axes;
        for (anim_name, path) in &c.anims {
            let lower = anim_name.to_ascii_lowercase();
            if !(lower.contains("walk") || lower.contains("run")) {
                continue;
            }
            // One animation file per figure once, whichever entities share them.
            if !seen.insert((c.figure.to_ascii_lowercase(), path.clone())) {
                continue;
            }
            let Ok(anim) = md5anim::load(path) else {
                continue;
            };
            let same = anim.joints.len() == rig.joints.len()
                && anim
                    .joints
                    .iter()
                    .zip(&rig.joints)
                    .all(|(a, r)| a.name == r.name);
            if !same {
                continue;
            }
            runs += 1;
            let per_frame: Vec<Vec<Quat>> = (0..anim.frame_count())
                .map(|f| {
                    anim.frame_poses(f)
                        .iter()
                        .map(|p| (axes * p.rotation * axes.inverse()).normalize())
                        .collect()
                })
                .collect();
            for h in &hs {
                let angles: Vec<f32> = per_frame.iter().map(|j| angle(h, j)).collect();
                let ours = angles.iter().filter(|&&a| inside(h.range, a)).count();
                let mirror = angles
                    .iter()
                    .filter(|&&a| inside(mirrored(h.range), a))
                    .count();
                let lo = angles.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = angles.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                println!(
                    "{} {anim_name} {}: angle {lo:.0}..{hi:.0}°, range [{:.0}, {:.0}]°: \
                     inside {ours}/{n}, mirrored {mirror}/{n}",
                    c.figure,
                    h.name,
                    h.range.min.to_degrees(),
                    h.range.max.to_degrees(),
                    n = angles.len(),
                );
                frames += angles.len();
                in_ours += ours;
                in_mirror += mirror;
            }
        }
    }
    println!(
        "{runs} walks and runs, {frames} hinge-frames: inside the reader's ranges {in_ours}, \
         inside the mirrored ranges {in_mirror}"
    );
    if runs == 0 {
        println!(
            "note: no walk or run animation in {} plays on a figure with limited hinges",
            base.display()
        );
        return;
    }
    assert!(
        in_ours > in_mirror,
        "the walks keep {in_ours} of {frames} hinge-frames inside the reader's hinge ranges \
         and {in_mirror} inside the mirrored ones"
    );
}

/// A rod hanging from a world hinge about Doom's `( 0, 1, 0 )` (Z up) with `limit 0, 30,
/// 45`: the engine's cone axis is left `( −1, 0, 0 )` turned 0°, the shaft left turned
/// −45° right-handed about +Y, so body1 may turn φ with `|φ − 45°| ≤ 15°`. The rod starts
/// hanging (φ = 0, 30° outside); a right-handed turn φ about +Y takes its downward
/// direction `( 0, 0, −1 )` to `( −sin φ, 0, −cos φ )`. Every solver must bring it to
/// the nearer bound and gravity hold it there: the rod 30° off the vertical, its centre
/// towards Doom −X (ours −X too: Z-up `( x, y, z )` is ours `( x, z, −y )`).
#[test]
fn a_rod_on_a_doom_hinge_rests_on_the_side_the_engine_allows() {
    let text = "body \"rod\" { model box( ( -1, -1, -20 ), ( 1, 1, 20 ) ) origin ( 0, 0, 60 ) }\n\
                hinge \"h\" { body1 \"rod\" body2 \"world\" anchor ( 0, 0, 80 ) axis ( 0, 1, 0 ) limit 0, 30, 45 }\n";
    let sc = parse(text, std::path::Path::new("rod.af"), &AfOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .desc;
    let anchor = Vec3::new(0.0, 80.0 * 0.0254, 0.0);
    let methods: [(&str, Box<dyn Method>); 4] = [
        ("multibody", Box::new(MultibodyWorld::new(&sc).unwrap())),
        (
            "rigid-frames",
            Box::new(ParticleWorld::new(&sc, ParticleSolver::RigidFrames).unwrap()),
        ),
        (
            "paper",
            Box::new(ParticleWorld::new(&sc, ParticleSolver::Paper).unwrap()),
        ),
        (
            "xpbd",
            Box::new(ParticleWorld::new(&sc, ParticleSolver::Xpbd).unwrap()),
        ),
    ];
    let mut states = Vec::new();
    for (name, mut w) in methods {
        for _ in 0..(3.0 / sc.settings.timestep).round() as usize {
            w.step();
        }
        w.body_states(&mut states);
        let r = states[0].com - anchor;
        // The angle off the hanging direction, signed towards −X.
        let off = (-r.x).atan2(-r.y).to_degrees();
        println!("{name}: rod {off:.2}° off the vertical towards −X");
        assert!(
            (off - 30.0).abs() < 3.0,
            "{name}: the rod rests {off:.2}° off the vertical towards −X, expected 30°"
        );
    }
}
