//! From parsed blocks to a validated [`SceneDesc`]: variants, settings and our scene
//! blocks, then bodies ([`super::body`]) and constraints ([`super::constraint`]), masses,
//! and the figure's placement ([`super::place`]).

use super::body::read_body;
use super::constraint::read_constraint;
use super::ctx::{Conv, Ctx, Defaults, R, angles_to_quat, unknown_key};
use super::parser::{Block, Entry, Value};
use super::place::replicate_figure;
use super::{AfError, AfOptions, AfScene, FigureSource};
use crate::scene::lexer::Pos;
use crate::scene::md5mesh::Md5Skeleton;
use crate::scene::rig::{JointMod, Rig};
use crate::scene::{
    BodyId, CameraDesc, Friction, Pose, SceneDesc, SceneError, Settings, VariantInfo, validate,
};
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// Body and constraint kinds by their Doom 3 keyword.
pub(super) const CONSTRAINTS: [&str; 6] = [
    "ballAndSocketJoint",
    "universalJoint",
    "hinge",
    "spring",
    "slider",
    "fixed",
];
pub(super) const SINGLETONS: [&str; 5] = ["settings", "ground", "camera", "transform", "replicate"];

pub(super) fn canonical(kind: &str) -> Option<&'static str> {
    CONSTRAINTS
        .iter()
        .chain(SINGLETONS.iter())
        .chain(["body", "variant", "articulatedFigure"].iter())
        .find(|k| k.eq_ignore_ascii_case(kind))
        .copied()
}

/// Builds the scene. See the module docs of [`super`] for the pipeline.
pub(super) fn build(
    blocks: Vec<Block>,
    file: &Path,
    opts: &AfOptions,
    source: &FigureSource,
) -> R<AfScene> {
    let fname = file.display().to_string();
    let err = |pos: Pos, m: String| AfError::at(&fname, pos, m);

    let blocks = select_figure(blocks, source, &fname)?;
    let (figure_name, merged, variant_info) = select_variant(blocks, opts, &fname)?;
    let (conv, mesh_key) = read_units(&merged, &fname)?;
    let mut ctx = Ctx {
        file: fname.clone(),
        dir: file.parent().map(Path::to_path_buf).unwrap_or_default(),
        conv,
        opts,
        source,
        mesh_key,
        mesh: None,
        ignored: Vec::new(),
    };

    if opts.mesh.is_some() || source.pose_anim.is_some() {
        // A mesh or pose named on the command line must be readable even when no
        // vector of the figure refers to a joint.
        ctx.mesh(Pos { line: 1, col: 1 }, "the figure")?;
    }

    let mut settings = Settings::default();
    let doom3_syntax = !merged.iter().any(|b| {
        canonical(&b.kind) == Some("settings")
            && b.entries
                .iter()
                .any(|e| e.key.eq_ignore_ascii_case("units"))
    });
    if doom3_syntax {
        // A file in Doom 3's own units was written for Doom 3's solver and says nothing
        // about ours: it starts from the multibody stiffness our own articulated
        // figures need (see FIGURE_MULTIBODY), which its settings may still override.
        let (substeps, iterations, hertz) = FIGURE_MULTIBODY;
        settings.multibody_substeps = Some(substeps);
        settings.multibody_iterations = Some(iterations);
        settings.contact_hertz = hertz;
        settings.joint_hertz = hertz;
    }
    let mut defaults = Defaults {
        friction: Friction::default(),
        self_collision: true,
        constraint_friction: 0.0,
    };
    let mut name = figure_name.unwrap_or_else(|| {
        file.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    let mut transform = Pose::IDENTITY;
    let mut replicate = None;
    let mut settings_pos = Pos { line: 1, col: 1 };
    for b in &merged {
        match canonical(&b.kind).unwrap_or("") {
            "settings" => {
                settings_pos = b.pos;
                read_settings(&mut ctx, b, &mut settings, &mut defaults, &mut name)?
            }
            "ground" => read_ground(&mut ctx, b, &mut settings)?,
            "camera" => read_camera(&mut ctx, b, &mut settings.camera)?,
            "transform" => transform = read_transform(&mut ctx, b)?,
            "replicate" => replicate = Some(read_replicate(&mut ctx, b)?),
            _ => {}
        }
    }

    // Bodies, then constraints (which may name bodies declared after them).
    let mut desc = SceneDesc {
        name,
        settings,
        variant: opts.variant.max(1),
        variants: variant_info,
        ..Default::default()
    };
    let mut body_pos: HashMap<String, Pos> = HashMap::new();
    for b in merged.iter().filter(|b| canonical(&b.kind) == Some("body")) {
        let (bname, npos) = b
            .name()
            .ok_or_else(|| err(b.pos, "expected `body \"name\" {`".into()))?;
        if bname.eq_ignore_ascii_case("world") {
            return Err(err(
                npos,
                "a body may not be named \"world\": that name means the static world in body2"
                    .into(),
            ));
        }
        if bname.eq_ignore_ascii_case("origin") {
            // Doom 3 refuses it too: "origin" names the skeleton's root joint.
            return Err(err(
                npos,
                "a body may not be named \"origin\": Doom 3 reserves it for the skeleton's root"
                    .into(),
            ));
        }
        if let Some(prev) = body_pos.get(bname) {
            return Err(err(
                npos,
                format!(
                    "a body named \"{bname}\" is already defined at line {}",
                    prev.line
                ),
            ));
        }
        body_pos.insert(bname.to_string(), npos);
        let body = read_body(&mut ctx, b, bname, &defaults)?;
        desc.bodies.push(body);
    }
    let ids: HashMap<&str, BodyId> = desc
        .bodies
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.as_str(), BodyId(i as u32)))
        .collect();
    let mut constraint_pos: HashMap<String, Pos> = HashMap::new();
    let mut constraints = Vec::new();
    for b in merged
        .iter()
        .filter(|b| CONSTRAINTS.contains(&canonical(&b.kind).unwrap_or("")))
    {
        let kind = canonical(&b.kind).expect("filtered");
        let (cname, npos) = b
            .name()
            .ok_or_else(|| err(b.pos, format!("expected `{kind} \"name\" {{`")))?;
        if let Some(prev) = constraint_pos.get(cname) {
            return Err(err(
                npos,
                format!(
                    "a constraint named \"{cname}\" is already defined at line {}",
                    prev.line
                ),
            ));
        }
        constraint_pos.insert(cname.to_string(), npos);
        constraints.push(read_constraint(&mut ctx, b, kind, cname, &ids, &defaults)?);
    }
    desc.constraints = constraints;
    super::contained::resolve(&mut ctx, &merged, &mut desc)?;
    if desc.bodies.is_empty() {
        return Err(err(
            Pos { line: 1, col: 1 },
            "the file defines no bodies; expected at least one `body \"name\" { ... }`".into(),
        ));
    }

    // Validate, resolve masses (with totalMass), place the figure.
    let locate = |e: SceneError| -> AfError {
        let pos = match &e {
            SceneError::Degenerate { body, .. } => body_pos.get(body).copied(),
            SceneError::BadConstraint { constraint, .. } => constraint_pos.get(constraint).copied(),
            SceneError::BadSetting { .. } => Some(settings_pos),
        };
        err(pos.unwrap_or(Pos { line: 1, col: 1 }), e.to_string())
    };
    validate(&desc).map_err(locate)?;
    desc.resolve_masses().map_err(locate)?;
    if transform != Pose::IDENTITY {
        desc.transform(&transform);
    }
    let count = opts
        .count
        .or(replicate.as_ref().map(|r| r.count))
        .unwrap_or(1);
    if count == 0 || count > MAX_COPIES {
        let pos = replicate
            .as_ref()
            .map_or(Pos { line: 1, col: 1 }, |r| r.pos);
        return Err(err(
            pos,
            format!("the number of copies must be from 1 to {MAX_COPIES}; found {count}"),
        ));
    }
    let one_copy_in_place = count == 1 && replicate.is_none() && transform == Pose::IDENTITY;
    if count > 1 || replicate.is_some() {
        let grid = replicate.unwrap_or_default();
        replicate_figure(&mut desc, &grid, count);
    }
    // The skeleton the bodies drive, for one figure where the file put it.
    let rig = match &ctx.mesh {
        Some(skel) if one_copy_in_place => Some(figure_rig(&ctx, skel, &merged, &desc)?),
        _ => None,
    };
    let mut ignored = ctx.ignored;
    ignored.sort_by_key(|i| (i.line, i.col));
    Ok(AfScene { desc, ignored, rig })
}

/// The rig of a figure built on `skel` (file units and axes): joints converted to ours,
/// each body's `joint` and `mod` (Doom 3's defaults: joint "origin", orientation), the
/// origin body driving the first child of joint 0 by orientation, as idAF does.
fn figure_rig(ctx: &Ctx, skel: &Md5Skeleton, merged: &[Block], desc: &SceneDesc) -> R<Rig> {
    let axes = glam::Quat::from_mat3(&ctx.conv.matrix());
    let joints: Vec<(String, Option<usize>, Pose)> = skel
        .joints
        .iter()
        .map(|j| {
            let pose = Pose {
                position: ctx.conv.point(j.position),
                rotation: (axes * j.orientation * axes.inverse()).normalize(),
            };
            (j.name.clone(), j.parent, pose)
        })
        .collect();
    let first_child = skel.joints.iter().position(|j| j.parent == Some(0));
    let mut drivers = Vec::new();
    let mut origin_body = None;
    let bodies = merged.iter().filter(|b| canonical(&b.kind) == Some("body"));
    for (i, b) in bodies.enumerate() {
        let mut joint = ("origin".to_string(), b.pos);
        let mut mode = JointMod::Orientation;
        for e in &b.entries {
            match (e.key.to_ascii_lowercase().as_str(), e.values.first()) {
                ("joint", Some(Value::Str(s, p))) => joint = (s.clone(), *p),
                ("mod", Some(Value::Ident(m, p) | Value::Str(m, p))) => {
                    mode = match m.to_ascii_lowercase().as_str() {
                        "orientation" => JointMod::Orientation,
                        "position" => JointMod::Position,
                        "both" => JointMod::Both,
                        _ => {
                            return Err(ctx.err(
                                *p,
                                format!(
                                    "unknown `mod` {m}; expected orientation, position or both"
                                ),
                            ));
                        }
                    }
                }
                _ => {}
            }
        }
        // Doom 3 tests the origin body's joint name exactly.
        if joint.0 == "origin" {
            if origin_body.is_none()
                && let Some(child) = first_child
            {
                origin_body = Some(i);
                drivers.push((i, child, JointMod::Orientation));
            }
            continue;
        }
        let j = skel.index(&joint.0).ok_or_else(|| {
            ctx.err(
                joint.1,
                format!(
                    "the mesh has no joint \"{}\" for body \"{}\" to drive",
                    joint.0, desc.bodies[i].name
                ),
            )
        })?;
        drivers.push((i, j, mode));
    }
    let rest: Vec<Pose> = desc.bodies.iter().map(|b| b.pose).collect();
    let mut rig = Rig::new(&joints, &drivers, &rest, origin_body);
    rig.file_axes = axes;
    rig.file_scale = ctx.conv.scale;
    Ok(rig)
}

/// Keeps only the `articulatedFigure` that `source` names, when it names one.
fn select_figure(blocks: Vec<Block>, source: &FigureSource, fname: &str) -> R<Vec<Block>> {
    let Some(want) = &source.figure else {
        return Ok(blocks);
    };
    let is_it = |b: &Block| {
        canonical(&b.kind) == Some("articulatedFigure")
            && b.name().is_some_and(|(n, _)| n.eq_ignore_ascii_case(want))
    };
    if blocks.iter().any(is_it) {
        Ok(blocks.into_iter().filter(is_it).take(1).collect())
    } else {
        Err(AfError::at(
            fname,
            Pos { line: 1, col: 1 },
            format!("the file declares no `articulatedFigure {want}`"),
        ))
    }
}

/// Unwraps `articulatedFigure name { ... }`, then applies the chosen variant's blocks
/// over the base ones. Returns the figure's name, the merged blocks and the variant list.
fn select_variant(
    blocks: Vec<Block>,
    opts: &AfOptions,
    fname: &str,
) -> R<(Option<String>, Vec<Block>, Vec<VariantInfo>)> {
    let err = |pos: Pos, m: String| AfError::at(fname, pos, m);
    let mut figure_name = None;
    let mut items = Vec::new();
    for b in blocks {
        match canonical(&b.kind) {
            Some("articulatedFigure") => {
                figure_name = b.name().map(|(n, _)| n.to_string());
                items.extend(b.children);
            }
            Some(_) => items.push(b),
            None => return Err(err(b.pos, unknown_block(&b.kind))),
        }
    }

    let mut variants: Vec<(u32, String, Pos, Vec<Block>)> = Vec::new();
    let mut base = Vec::new();
    for b in items {
        let kind = canonical(&b.kind).ok_or_else(|| err(b.pos, unknown_block(&b.kind)))?;
        if kind == "articulatedFigure" {
            return Err(err(b.pos, "`articulatedFigure` blocks do not nest".into()));
        }
        if kind != "variant" {
            base.push(b);
            continue;
        }
        let n = match b.header.first() {
            Some(Value::Num(n, _)) if *n >= 1.0 && n.fract() == 0.0 && *n <= 9.0 => *n as u32,
            _ => {
                return Err(err(
                    b.pos,
                    "expected `variant N \"name\" {` with N a whole number from 1 to 9".into(),
                ));
            }
        };
        if variants.iter().any(|v| v.0 == n) {
            return Err(err(b.pos, format!("variant {n} is defined twice")));
        }
        let name = b
            .name()
            .map(|(s, _)| s.to_string())
            .unwrap_or_else(|| format!("variant {n}"));
        for c in &b.children {
            if canonical(&c.kind) == Some("variant") {
                return Err(err(c.pos, "variants do not nest".into()));
            }
            if canonical(&c.kind).is_none() {
                return Err(err(c.pos, unknown_block(&c.kind)));
            }
        }
        variants.push((n, name, b.pos, b.children));
    }
    variants.sort_by_key(|v| v.0);
    let wanted = opts.variant.max(1);
    let mut chosen = Vec::new();
    if wanted > 1 || variants.iter().any(|v| v.0 == 1) {
        match variants.iter_mut().find(|v| v.0 == wanted) {
            Some(v) => chosen = std::mem::take(&mut v.3),
            None => {
                let have: Vec<String> = std::iter::once(1)
                    .chain(variants.iter().map(|v| v.0).filter(|n| *n != 1))
                    .map(|n| n.to_string())
                    .collect();
                let pos = variants.last().map_or(Pos { line: 1, col: 1 }, |v| v.2);
                return Err(err(
                    pos,
                    format!(
                        "variant {wanted} does not exist; this scene has variant(s) {}",
                        have.join(", ")
                    ),
                ));
            }
        }
    }
    let variant_info: Vec<VariantInfo> = if variants.is_empty() {
        Vec::new()
    } else {
        let mut v: Vec<VariantInfo> = variants
            .iter()
            .map(|v| VariantInfo {
                number: v.0,
                name: v.1.clone(),
            })
            .collect();
        if !v.iter().any(|x| x.number == 1) {
            v.insert(
                0,
                VariantInfo {
                    number: 1,
                    name: "default".into(),
                },
            );
        }
        v
    };
    let merged = merge(base, chosen, fname)?;
    Ok((figure_name, merged, variant_info))
}

/// Reads `units`, `up` and the mesh path from the settings first: they decide how every
/// other value is read.
fn read_units(merged: &[Block], fname: &str) -> R<(Conv, Option<(String, Pos)>)> {
    let err = |pos: Pos, m: String| AfError::at(fname, pos, m);
    let mut conv = Conv {
        scale: 0.0254,
        z_up: true,
    };
    let mut mesh_key = None;
    for b in merged
        .iter()
        .filter(|b| canonical(&b.kind) == Some("settings"))
    {
        for e in &b.entries {
            let k = e.key.to_ascii_lowercase();
            match k.as_str() {
                "units" => {
                    let u = match e.values.as_slice() {
                        [Value::Str(s, _)] => s.clone(),
                        _ => {
                            return Err(err(
                                e.pos,
                                "`units` takes one of \"inch\", \"cm\", \"mm\", \"m\"".into(),
                            ));
                        }
                    };
                    conv.scale = match u.as_str() {
                        "inch" | "in" => 0.0254,
                        "cm" => 0.01,
                        "mm" => 0.001,
                        "m" => 1.0,
                        _ => {
                            return Err(err(
                                e.values[0].pos(),
                                format!(
                                    "unknown unit \"{u}\"; expected \"inch\", \"cm\", \"mm\" or \"m\""
                                ),
                            ));
                        }
                    };
                }
                "up" => {
                    conv.z_up = match e.values.as_slice() {
                        [Value::Str(s, _)] if s.eq_ignore_ascii_case("z") => true,
                        [Value::Str(s, _)] if s.eq_ignore_ascii_case("y") => false,
                        _ => return Err(err(e.pos, "`up` takes \"y\" or \"z\"".into())),
                    };
                }
                "mesh" | "model" => match e.values.as_slice() {
                    [Value::Str(s, p)] => mesh_key = Some((s.clone(), *p)),
                    _ => {
                        return Err(err(
                            e.pos,
                            format!("`{}` takes the quoted path of an .md5mesh", e.key),
                        ));
                    }
                },
                _ => {}
            }
        }
    }
    Ok((conv, mesh_key))
}

/// The multibody solver's substeps, velocity iterations and contact and joint stiffness
/// (Hz) for a figure read in Doom 3's units: those of the shipped human. A figure
/// landing on one limb needs stiff joints and contacts to keep its joint gaps under 2 mm
/// and its penetrations under 1 cm, and the soft step honours a stiffness only up to a
/// quarter of its substep rate (60 Hz × 16 / 4 = 240 Hz); at the defaults (4 substeps,
/// 60 Hz) id's zombies open 6–7 mm joint gaps and overshoot their limits by 3–5° when
/// they land. Five iterations: at three the mod's humanoid falls asleep in 70 of 72
/// nearby starts instead of all, and gains up to 2.9 % of its energy scale.
pub(super) const FIGURE_MULTIBODY: (u32, u32, f32) = (16, 5, 240.0);

/// Most copies `replicate` or `--count` may ask for (160 000 bodies of the human).
pub(super) const MAX_COPIES: u32 = 10_000;

pub(super) fn unknown_block(kind: &str) -> String {
    format!(
        "unknown block `{kind}`; expected settings, body, ballAndSocketJoint, universalJoint, hinge, spring, slider, fixed, or our ground, camera, transform, replicate, variant"
    )
}

/// Applies a variant's blocks over the base: a block with the kind and name of a base
/// block adds its entries after the base's (later keys win); any other block is new.
pub(super) fn merge(mut base: Vec<Block>, overrides: Vec<Block>, file: &str) -> R<Vec<Block>> {
    for o in overrides {
        let okind = canonical(&o.kind).unwrap_or("");
        let target = base.iter_mut().find(|b| {
            let bkind = canonical(&b.kind).unwrap_or("");
            if SINGLETONS.contains(&okind) {
                bkind == okind
            } else {
                b.name().map(|n| n.0) == o.name().map(|n| n.0)
                    && (bkind == "body") == (okind == "body")
            }
        });
        match target {
            Some(t) => {
                if canonical(&t.kind) != Some(okind) {
                    return Err(AfError::at(
                        file,
                        o.pos,
                        format!(
                            "this variant changes \"{}\" from `{}` to `{}`; a variant may only override keys",
                            o.name().map_or("", |n| n.0),
                            t.kind,
                            o.kind
                        ),
                    ));
                }
                t.entries.extend(o.entries)
            }
            None => base.push(o),
        }
    }
    Ok(base)
}

pub(super) fn read_settings(
    ctx: &mut Ctx,
    b: &Block,
    s: &mut Settings,
    d: &mut Defaults,
    name: &mut String,
) -> R<()> {
    let scale = ctx.conv.scale;
    for e in &b.entries {
        match e.key.to_ascii_lowercase().as_str() {
            "units" | "up" | "mesh" | "model" => {}
            "anim" => ctx.ignore(e, "the initial animation only poses Doom 3's skeleton; the figure starts in the pose the file gives"),
            "skin" => ctx.ignore(e, "skins are not drawn; bodies are drawn as their collision shapes"),
            "contents" | "clipmask" => ctx.ignore(e, "Doom 3's collision groups: every body collides with the ground and other figures, and with its own figure per selfCollision"),
            "name" => *name = ctx.string(&e.values[0], "`name`")?.to_string(),
            "friction" => {
                ctx.arity(e, 3..=4, "linear, angular, contact[, constraint] friction")?;
                d.friction = Friction { linear: ctx.arg(e, 0)?, angular: ctx.arg(e, 1)?, contact: ctx.arg(e, 2)? };
                if e.values.len() == 4 {
                    d.constraint_friction = ctx.arg(e, 3)?;
                }
            }
            "selfcollision" => d.self_collision = ctx.flag(e)?,
            // The one-value forms of the friction keys.
            "linearfriction" => d.friction.linear = ctx.nonneg(e)?,
            "angularfriction" => d.friction.angular = ctx.nonneg(e)?,
            "contactfriction" => d.friction.contact = ctx.nonneg(e)?,
            "constraintfriction" => d.constraint_friction = ctx.nonneg(e)?,
            "totalmass" => {
                let m = ctx.one(e)?;
                s.total_mass = (m > 0.0).then_some(m);
            }
            "suspendspeed" => {
                ctx.arity(e, 4..=4, "linear velocity, angular velocity, linear acceleration, angular acceleration")?;
                s.sleep.linear_velocity = ctx.arg(e, 0)? * scale;
                s.sleep.angular_velocity = ctx.arg(e, 1)?.to_radians();
                s.sleep.linear_acceleration = ctx.arg(e, 2)? * scale;
                s.sleep.angular_acceleration = ctx.arg(e, 3)?.to_radians();
            }
            "nomovetime" => s.sleep.time = ctx.one(e)?.max(0.0),
            "nomovetranslation" => s.sleep.translation = ctx.one(e)?.max(0.0) * scale,
            "nomoverotation" => s.sleep.rotation = ctx.one(e)?.max(0.0).to_radians(),
            // Doom 3 writes -1 for "no limit".
            "minmovetime" => s.sleep.min_move_time = ctx.one(e)?.max(0.0),
            "maxmovetime" => s.sleep.max_move_time = ctx.one(e)?.max(0.0),
            "gravity" => {
                ctx.arity(e, 1..=1, "a vector")?;
                s.gravity = ctx.point(&e.values[0])?;
            }
            "timestep" => s.timestep = ctx.one(e)?,
            "iterations" => s.iterations = count(ctx, e)?,
            "substeps" => s.substeps = count(ctx, e)?,
            "multibodysubsteps" => s.multibody_substeps = Some(count(ctx, e)?),
            "multibodyiterations" => s.multibody_iterations = Some(count(ctx, e)?),
            "relaxpasses" => s.relax_passes = count(ctx, e)?,
            "xpbdsubsteps" => s.xpbd_substeps = Some(count(ctx, e)?),
            "xpbdpasses" => s.xpbd_passes = count(ctx, e)?,
            "contacthertz" => s.contact_hertz = ctx.nonneg(e)?,
            "jointhertz" => s.joint_hertz = ctx.nonneg(e)?,
            "dampingratio" => s.damping_ratio = ctx.nonneg(e)?,
            "maxpushoutspeed" => s.max_push_out_speed = ctx.nonneg(e)? * scale,
            "restitutionthreshold" => s.restitution_threshold = ctx.nonneg(e)? * scale,
            _ => return Err(unknown_key(ctx, e, "settings", "mesh, model, anim, skin, friction, linearFriction, angularFriction, contactFriction, constraintFriction, selfCollision, suspendSpeed, totalMass, noMoveTime, noMoveTranslation, noMoveRotation, minMoveTime, maxMoveTime, contents, clipMask; ours: name, units, up, gravity, timestep, iterations, substeps, multibodySubsteps, multibodyIterations, relaxPasses, xpbdSubsteps, xpbdPasses, contactHertz, jointHertz, dampingRatio, maxPushOutSpeed, restitutionThreshold")),
        }
    }
    Ok(())
}

pub(super) fn count(ctx: &Ctx, e: &Entry) -> R<u32> {
    let v = ctx.one(e)?;
    if v >= 1.0 && v.fract() == 0.0 && v <= 1000.0 {
        Ok(v as u32)
    } else {
        Err(ctx.err(
            e.values[0].pos(),
            format!("`{}` takes a whole number from 1 to 1000; found {v}", e.key),
        ))
    }
}

pub(super) fn read_ground(ctx: &mut Ctx, b: &Block, s: &mut Settings) -> R<()> {
    let mut g = s.ground.unwrap_or_default();
    let mut enabled = true;
    for e in &b.entries {
        match e.key.to_ascii_lowercase().as_str() {
            "enabled" => enabled = ctx.flag(e)?,
            "height" => g.height = ctx.one(e)? * ctx.conv.scale,
            "thickness" => g.thickness = ctx.nonneg(e)? * ctx.conv.scale,
            "friction" => g.friction = ctx.nonneg(e)?,
            "restitution" => g.restitution = ctx.nonneg(e)?,
            "tilt" => g.tilt = ctx.one(e)?.to_radians(),
            _ => {
                return Err(unknown_key(
                    ctx,
                    e,
                    "ground",
                    "enabled, height, thickness, friction, restitution, tilt",
                ));
            }
        }
    }
    s.ground = enabled.then_some(g);
    Ok(())
}

pub(super) fn read_camera(ctx: &mut Ctx, b: &Block, c: &mut CameraDesc) -> R<()> {
    for e in &b.entries {
        ctx.arity(e, 1..=1, "a vector")?;
        match e.key.to_ascii_lowercase().as_str() {
            "eye" => c.eye = ctx.point(&e.values[0])?,
            "target" => c.target = ctx.point(&e.values[0])?,
            _ => return Err(unknown_key(ctx, e, "camera", "eye, target")),
        }
    }
    Ok(())
}

pub(super) fn read_transform(ctx: &mut Ctx, b: &Block) -> R<Pose> {
    let mut pose = Pose::IDENTITY;
    for e in &b.entries {
        ctx.arity(e, 1..=1, "a vector")?;
        match e.key.to_ascii_lowercase().as_str() {
            "origin" => pose.position = ctx.point(&e.values[0])?,
            "angles" => pose.rotation = angles_to_quat(ctx.vector(&e.values[0])?),
            _ => return Err(unknown_key(ctx, e, "transform", "origin, angles")),
        }
    }
    Ok(pose)
}

/// The `replicate` block: copies of the figure in a grid.
#[derive(Clone, Debug)]
pub(super) struct Grid {
    pub(super) count: u32,
    pub(super) columns: u32,
    pub(super) rows: u32,
    pub(super) layers: u32,
    /// Steps along world X (columns), Z (rows), Y (layers), metres; `None`: from the
    /// figure's size.
    pub(super) spacing: Option<Vec3>,
    pub(super) layer_yaw: f32,
    /// Where the block starts, for errors about the count.
    pub(super) pos: Pos,
}

impl Default for Grid {
    fn default() -> Self {
        Grid {
            count: 1,
            columns: 0,
            rows: 0,
            layers: 1,
            spacing: None,
            layer_yaw: 0.0,
            pos: Pos { line: 1, col: 1 },
        }
    }
}

pub(super) fn read_replicate(ctx: &mut Ctx, b: &Block) -> R<Grid> {
    let mut g = Grid {
        pos: b.pos,
        ..Grid::default()
    };
    let whole = |ctx: &Ctx, e: &Entry| -> R<u32> {
        let v = ctx.one(e)?;
        if v >= 1.0 && v.fract() == 0.0 && v <= MAX_COPIES as f32 {
            Ok(v as u32)
        } else {
            Err(ctx.err(
                e.values[0].pos(),
                format!(
                    "`{}` takes a whole number from 1 to {MAX_COPIES}; found {v}",
                    e.key
                ),
            ))
        }
    };
    for e in &b.entries {
        match e.key.to_ascii_lowercase().as_str() {
            "count" => g.count = whole(ctx, e)?,
            "columns" => g.columns = whole(ctx, e)?,
            "rows" => g.rows = whole(ctx, e)?,
            "layers" => g.layers = whole(ctx, e)?,
            "spacing" => {
                ctx.arity(e, 3..=3, "column, row and layer steps")?;
                let s = Vec3::new(ctx.arg(e, 0)?, ctx.arg(e, 1)?, ctx.arg(e, 2)?) * ctx.conv.scale;
                if s.min_element() < 0.0 {
                    return Err(ctx.err(e.pos, "spacing must not be negative"));
                }
                // Columns along X, rows along Z, layers along Y (up).
                g.spacing = Some(Vec3::new(s.x, s.z, s.y));
            }
            "layeryaw" => g.layer_yaw = ctx.one(e)?.to_radians(),
            _ => {
                return Err(unknown_key(
                    ctx,
                    e,
                    "replicate",
                    "count, columns, rows, layers, spacing, layerYaw",
                ));
            }
        }
    }
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::super::{AfOptions, parse};
    use super::FIGURE_MULTIBODY;
    use std::path::Path;

    fn settings(text: &str) -> crate::scene::Settings {
        parse(text, Path::new("t.af"), &AfOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
            .desc
            .settings
    }

    #[test]
    fn a_file_in_doom_3_units_starts_from_the_figure_stiffness() {
        let body = "body \"b\" { model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, 10 ) }\n";
        let (n, it, hz) = FIGURE_MULTIBODY;
        let s = settings(body);
        assert_eq!(
            (s.multibody_substeps, s.contact_hertz, s.joint_hertz),
            (Some(n), hz, hz)
        );
        assert_eq!(s.multibody_iterations, Some(it));
        // The file's own keys win.
        let s = settings(&format!(
            "settings {{ multibodySubsteps 4 jointHertz 60 }}\n{body}"
        ));
        assert_eq!(
            (s.multibody_substeps, s.contact_hertz, s.joint_hertz),
            (Some(4), hz, 60.0)
        );
        // A file that names its units is ours: the solver's defaults.
        let s = settings(&format!("settings {{ units \"inch\" }}\n{body}"));
        let d = crate::scene::Settings::default();
        assert_eq!(
            (s.multibody_substeps, s.contact_hertz, s.joint_hertz),
            (d.multibody_substeps, d.contact_hertz, d.joint_hertz)
        );
    }

    #[test]
    fn the_xpbd_schedule_is_read_from_the_settings() {
        let body = "body \"b\" { model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, 10 ) }\n";
        let d = crate::scene::Settings::default();
        let s = settings(body);
        assert_eq!((s.xpbd_substeps, s.xpbd_passes), (None, d.xpbd_passes));
        let s = settings(&format!(
            "settings {{ xpbdSubsteps 60 xpbdPasses 1 }}\n{body}"
        ));
        assert_eq!((s.xpbd_substeps, s.xpbd_passes), (Some(60), 1));
        // No pass at all is no schedule.
        let text = format!("settings {{ xpbdPasses 0 }}\n{body}");
        let err = parse(&text, Path::new("t.af"), &AfOptions::default()).err();
        assert!(err.is_some_and(|e| e.to_string().contains("xpbdPasses")));
    }
}
