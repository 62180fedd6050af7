//! From parsed blocks to a validated [`SceneDesc`]: variants, units and axes, vector
//! forms, bodies, constraints, masses, the figure transform and the grid of copies.

use super::lexer::Pos;
use super::models;
use super::parser::{Block, Entry, Value};
use super::{AfError, AfOptions, AfScene, Ignored};
use crate::scene::md5mesh::{self, Md5Skeleton};
use crate::scene::{
    AngleRange, BodyDesc, BodyId, BodyRef, CameraDesc, ConstraintDesc, Friction, JointKind,
    LimitStyle, MassSpec, Motion, Pose, SceneDesc, SceneError, Settings, Shape, SwingLimit,
    TwistLimit, VariantInfo, validate,
};
use glam::{Mat3, Quat, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

type R<T> = Result<T, AfError>;

/// The file's units and axes: how a file vector becomes ours.
#[derive(Clone, Copy, Debug)]
struct Conv {
    /// Metres per file unit.
    scale: f32,
    /// Z up (Doom 3) rather than Y up.
    z_up: bool,
}

impl Conv {
    /// The axis mapping alone: Z-up `(x, y, z)` → `(x, z, -y)`, a proper rotation.
    fn axes(&self, v: Vec3) -> Vec3 {
        if self.z_up {
            Vec3::new(v.x, v.z, -v.y)
        } else {
            v
        }
    }
    fn point(&self, v: Vec3) -> Vec3 {
        self.axes(v) * self.scale
    }
    /// The axis mapping as a matrix (columns are the images of the file's axes).
    fn matrix(&self) -> Mat3 {
        Mat3::from_cols(self.axes(Vec3::X), self.axes(Vec3::Y), self.axes(Vec3::Z))
    }
}

/// Doom 3 angles `( pitch, yaw, roll )` in degrees as a rotation of our world.
///
/// Doom 3's `idAngles::ToMat3` is `Rz(yaw)·Ry(pitch)·Rx(roll)` in its Z-up frame. Mapped
/// through the axis conversion that is yaw about our +Y, pitch about our −Z and roll
/// about our +X; we use this one meaning for Y-up files too.
fn angles_to_quat(a: Vec3) -> Quat {
    let (p, y, r) = (a.x.to_radians(), a.y.to_radians(), a.z.to_radians());
    Quat::from_axis_angle(Vec3::Y, y)
        * Quat::from_axis_angle(Vec3::NEG_Z, p)
        * Quat::from_axis_angle(Vec3::X, r)
}

/// Reading context: the file, its conversion, the lazily loaded mesh, ignored keys.
struct Ctx<'a> {
    file: String,
    dir: PathBuf,
    conv: Conv,
    opts: &'a AfOptions,
    /// The `mesh`/`model` path from settings and where it was written.
    mesh_key: Option<(String, Pos)>,
    mesh: Option<Md5Skeleton>,
    ignored: Vec<Ignored>,
}

impl Ctx<'_> {
    fn err(&self, pos: Pos, message: impl Into<String>) -> AfError {
        AfError::at(&self.file, pos, message.into())
    }

    fn ignore(&mut self, e: &Entry, reason: &str) {
        self.ignored.push(Ignored {
            line: e.pos.line,
            col: e.pos.col,
            key: e.key.clone(),
            reason: reason.into(),
        });
    }

    fn arity(&self, e: &Entry, n: std::ops::RangeInclusive<usize>, form: &str) -> R<()> {
        if n.contains(&e.values.len()) {
            Ok(())
        } else {
            let at = e.values.get(*n.end()).map_or(e.pos, Value::pos);
            Err(self.err(
                at,
                format!(
                    "`{}` takes {form}; found {} value(s)",
                    e.key,
                    e.values.len()
                ),
            ))
        }
    }

    fn num(&self, v: &Value, what: &str) -> R<f32> {
        match v {
            Value::Num(n, p) => {
                let f = *n as f32;
                if f.is_finite() {
                    Ok(f)
                } else {
                    Err(self.err(
                        *p,
                        format!("{what} must be a finite number; {n} is too large"),
                    ))
                }
            }
            other => Err(self.err(
                other.pos(),
                format!("expected a number for {what}, found {}", other.describe()),
            )),
        }
    }

    fn arg(&self, e: &Entry, i: usize) -> R<f32> {
        self.num(&e.values[i], &format!("`{}`", e.key))
    }

    fn one(&self, e: &Entry) -> R<f32> {
        self.arity(e, 1..=1, "one number")?;
        self.arg(e, 0)
    }

    fn nonneg(&self, e: &Entry) -> R<f32> {
        let v = self.one(e)?;
        if v < 0.0 {
            return Err(self.err(
                e.values[0].pos(),
                format!("`{}` must not be negative; found {v}", e.key),
            ));
        }
        Ok(v)
    }

    fn flag(&self, e: &Entry) -> R<bool> {
        let v = self.one(e)?;
        match v {
            0.0 => Ok(false),
            1.0 => Ok(true),
            _ => Err(self.err(
                e.values[0].pos(),
                format!("`{}` takes 0 or 1; found {v}", e.key),
            )),
        }
    }

    fn string<'v>(&self, v: &'v Value, what: &str) -> R<&'v str> {
        match v {
            Value::Str(s, _) => Ok(s),
            other => Err(self.err(
                other.pos(),
                format!(
                    "expected a quoted string for {what}, found {}",
                    other.describe()
                ),
            )),
        }
    }

    fn mesh(&mut self, at: Pos, what: &str) -> R<&Md5Skeleton> {
        if self.mesh.is_none() {
            let (path, pos) = match (&self.opts.mesh, &self.mesh_key) {
                (Some(p), _) => (p.clone(), at),
                (None, Some((p, pos))) => (self.dir.join(p), *pos),
                (None, None) => {
                    return Err(self.err(
                        at,
                        format!(
                            "{what} cannot be resolved without the figure's mesh: add `mesh \"FILE.md5mesh\"` to settings (relative to this file) or pass --mesh FILE.md5mesh"
                        ),
                    ));
                }
            };
            let skel = md5mesh::load(&path).map_err(|e| {
                if e.message.starts_with("cannot read") {
                    self.err(pos, format!("{what} needs the mesh {}, which {}; pass --mesh FILE.md5mesh to use another", path.display(), e.message.trim_start_matches("cannot read the mesh: ")))
                } else {
                    e
                }
            })?;
            self.mesh = Some(skel);
        }
        Ok(self.mesh.as_ref().expect("loaded above"))
    }

    fn joint_pos(&mut self, name_v: &Value, form: &str) -> R<Vec3> {
        let name = self.string(name_v, "a joint name")?.to_string();
        let at = name_v.pos();
        let skel = self.mesh(at, &format!("{form}(\"{name}\")"))?;
        match skel.joint(&name) {
            Some(j) => Ok(j.position),
            None => {
                let known: Vec<&str> = skel
                    .joints
                    .iter()
                    .take(12)
                    .map(|j| j.name.as_str())
                    .collect();
                let more = if skel.joints.len() > 12 { ", ..." } else { "" };
                let message = format!(
                    "the mesh has no joint \"{name}\" (it has {}{more})",
                    known.join(", ")
                );
                Err(AfError::at(&self.file, at, message))
            }
        }
    }

    /// Any of the four vector forms, in file units and axes (not converted).
    fn vector(&mut self, v: &Value) -> R<Vec3> {
        match v {
            Value::Group(items, p) => {
                if items.len() != 3 {
                    return Err(self.err(*p, format!("expected a vector ( x, y, z ) of 3 numbers, found {} values", items.len())));
                }
                Ok(Vec3::new(self.num(&items[0], "x")?, self.num(&items[1], "y")?, self.num(&items[2], "z")?))
            }
            Value::Call(f, args, p) => {
                let f_l = f.to_ascii_lowercase();
                match (f_l.as_str(), args.len()) {
                    ("joint", 1) => self.joint_pos(&args[0], "joint"),
                    ("bonecenter", 2) => {
                        let a = self.joint_pos(&args[0], "bonecenter")?;
                        let b = self.joint_pos(&args[1], "bonecenter")?;
                        Ok((a + b) * 0.5)
                    }
                    ("bonedir", 2) => {
                        let a = self.joint_pos(&args[0], "bonedir")?;
                        let b = self.joint_pos(&args[1], "bonedir")?;
                        (b - a).try_normalize().ok_or_else(|| self.err(*p, "bonedir between two joints at the same place has no direction"))
                    }
                    ("joint" | "bonecenter" | "bonedir", n) => Err(self.err(*p, format!("`{f}` takes {} joint name(s), found {n}", if f_l == "joint" { 1 } else { 2 }))),
                    _ => Err(self.err(*p, format!("expected a vector: ( x, y, z ), joint(\"name\"), bonecenter(\"a\", \"b\") or bonedir(\"a\", \"b\"); found `{f}( ... )`"))),
                }
            }
            other => Err(self.err(other.pos(), format!("expected a vector ( x, y, z ), joint(...), bonecenter(...) or bonedir(...), found {}", other.describe()))),
        }
    }

    fn point(&mut self, v: &Value) -> R<Vec3> {
        let p = self.vector(v)?;
        Ok(self.conv.point(p))
    }

    fn dir(&mut self, v: &Value) -> R<Vec3> {
        let d = self.vector(v)?;
        self.conv
            .axes(d)
            .try_normalize()
            .ok_or_else(|| self.err(v.pos(), "this direction has zero length"))
    }

    fn deg(&self, v: &Value, what: &str) -> R<f32> {
        Ok(self.num(v, what)?.to_radians())
    }
}

/// Body and constraint kinds by their Doom 3 keyword.
const CONSTRAINTS: [&str; 6] = [
    "ballAndSocketJoint",
    "universalJoint",
    "hinge",
    "spring",
    "slider",
    "fixed",
];
const SINGLETONS: [&str; 5] = ["settings", "ground", "camera", "transform", "replicate"];

fn canonical(kind: &str) -> Option<&'static str> {
    CONSTRAINTS
        .iter()
        .chain(SINGLETONS.iter())
        .chain(["body", "variant", "articulatedFigure"].iter())
        .find(|k| k.eq_ignore_ascii_case(kind))
        .copied()
}

/// Builds the scene. See the module docs of [`super`] for the pipeline.
pub(super) fn build(blocks: Vec<Block>, file: &Path, opts: &AfOptions) -> R<AfScene> {
    let fname = file.display().to_string();
    let err = |pos: Pos, m: String| AfError::at(&fname, pos, m);

    // 1. Unwrap `articulatedFigure name { ... }` and check every kind.
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

    // 2. Variants: base blocks plus the chosen variant's overrides.
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
    let merged = merge(base, chosen, &fname)?;

    // 3. Settings first: units and axes decide how everything else is read.
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
    let mut ctx = Ctx {
        file: fname.clone(),
        dir: file.parent().map(Path::to_path_buf).unwrap_or_default(),
        conv,
        opts,
        mesh_key,
        mesh: None,
        ignored: Vec::new(),
    };

    let mut settings = Settings::default();
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

    // 4. Bodies, then constraints (which may name bodies declared after them).
    let mut desc = SceneDesc {
        name,
        settings,
        variant: wanted,
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
    if desc.bodies.is_empty() {
        return Err(err(
            Pos { line: 1, col: 1 },
            "the file defines no bodies; expected at least one `body \"name\" { ... }`".into(),
        ));
    }

    // 5. Validate, resolve masses (with totalMass), place the figure.
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
        for body in &mut desc.bodies {
            place_body(body, &transform);
        }
        for c in &mut desc.constraints {
            place_joint(&mut c.kind, &transform);
        }
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
    if count > 1 || replicate.is_some() {
        let grid = replicate.unwrap_or_default();
        replicate_figure(&mut desc, &grid, count);
    }
    let mut ignored = ctx.ignored;
    ignored.sort_by_key(|i| (i.line, i.col));
    Ok(AfScene { desc, ignored })
}

/// Most copies `replicate` or `--count` may ask for (160 000 bodies of the human).
const MAX_COPIES: u32 = 10_000;

fn unknown_block(kind: &str) -> String {
    format!(
        "unknown block `{kind}`; expected settings, body, ballAndSocketJoint, universalJoint, hinge, spring, slider, fixed, or our ground, camera, transform, replicate, variant"
    )
}

/// Applies a variant's blocks over the base: a block with the kind and name of a base
/// block adds its entries after the base's (later keys win); any other block is new.
fn merge(mut base: Vec<Block>, overrides: Vec<Block>, file: &str) -> R<Vec<Block>> {
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

/// Figure-wide defaults from `settings`.
struct Defaults {
    friction: Friction,
    self_collision: bool,
    constraint_friction: f32,
}

fn read_settings(
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
            "contacthertz" => s.contact_hertz = ctx.nonneg(e)?,
            "jointhertz" => s.joint_hertz = ctx.nonneg(e)?,
            "dampingratio" => s.damping_ratio = ctx.nonneg(e)?,
            "maxpushoutspeed" => s.max_push_out_speed = ctx.nonneg(e)? * scale,
            "restitutionthreshold" => s.restitution_threshold = ctx.nonneg(e)? * scale,
            _ => return Err(unknown_key(ctx, e, "settings", "mesh, model, anim, skin, friction, selfCollision, suspendSpeed, totalMass, noMoveTime, noMoveTranslation, noMoveRotation, minMoveTime, maxMoveTime, contents, clipMask; ours: name, units, up, gravity, timestep, iterations, substeps, contactHertz, jointHertz, dampingRatio, maxPushOutSpeed, restitutionThreshold")),
        }
    }
    Ok(())
}

fn count(ctx: &Ctx, e: &Entry) -> R<u32> {
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

fn unknown_key(ctx: &Ctx, e: &Entry, block: &str, known: &str) -> AfError {
    ctx.err(
        e.pos,
        format!(
            "unknown key `{}` in {block}; expected one of: {known}",
            e.key
        ),
    )
}

fn read_ground(ctx: &mut Ctx, b: &Block, s: &mut Settings) -> R<()> {
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

fn read_camera(ctx: &mut Ctx, b: &Block, c: &mut CameraDesc) -> R<()> {
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

fn read_transform(ctx: &mut Ctx, b: &Block) -> R<Pose> {
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
struct Grid {
    count: u32,
    columns: u32,
    rows: u32,
    layers: u32,
    /// Steps along world X (columns), Z (rows), Y (layers), metres; `None`: from the
    /// figure's size.
    spacing: Option<Vec3>,
    layer_yaw: f32,
    /// Where the block starts, for errors about the count.
    pos: Pos,
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

fn read_replicate(ctx: &mut Ctx, b: &Block) -> R<Grid> {
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

fn read_body(ctx: &mut Ctx, b: &Block, name: &str, d: &Defaults) -> R<BodyDesc> {
    let mut model: Option<&Value> = None;
    let mut origin = Vec3::ZERO;
    let mut rotation = Quat::IDENTITY;
    let mut body = BodyDesc::new(
        name,
        Shape::Box {
            half_extents: Vec3::ONE,
        },
        Pose::IDENTITY,
        MassSpec::Density(1000.0),
    );
    body.friction = d.friction;
    body.self_collision = d.self_collision;
    let mut mass_given = None;
    let mut particles = None;
    let s3 = ctx.conv.scale.powi(3);
    for e in &b.entries {
        match e.key.to_ascii_lowercase().as_str() {
            "joint" => body.skeleton_joint = Some(ctx.string(&e.values[0], "`joint`")?.to_string()),
            "mod" => ctx.ignore(e, "`mod` says how the body drives its skeleton joint; there is no skinned mesh to drive"),
            "model" => {
                ctx.arity(e, 1..=1, "one collision model")?;
                model = Some(&e.values[0]);
            }
            "origin" => {
                ctx.arity(e, 1..=1, "a vector")?;
                origin = ctx.point(&e.values[0])?;
            }
            "angles" => {
                ctx.arity(e, 1..=1, "( pitch, yaw, roll )")?;
                rotation = angles_to_quat(ctx.vector(&e.values[0])?);
            }
            "density" => {
                let v = ctx.one(e)?;
                if v <= 0.0 {
                    return Err(ctx.err(e.values[0].pos(), format!("density must be positive; found {v}")));
                }
                body.mass = MassSpec::Density(v / s3);
            }
            "mass" => {
                let v = ctx.one(e)?;
                if v <= 0.0 {
                    return Err(ctx.err(e.values[0].pos(), format!("mass must be positive; found {v}")));
                }
                mass_given = Some(v);
            }
            "inertiascale" => body.inertia_scale = Some(inertia_scale(ctx, e)?),
            "friction" => {
                ctx.arity(e, 3..=3, "linear, angular, contact friction")?;
                body.friction = Friction { linear: ctx.arg(e, 0)?, angular: ctx.arg(e, 1)?, contact: ctx.arg(e, 2)? };
            }
            "selfcollision" => body.self_collision = ctx.flag(e)?,
            "contents" | "clipmask" => ctx.ignore(e, "Doom 3's collision groups: every body collides with the ground and other figures, and with its own figure per selfCollision"),
            "containedjoints" => ctx.ignore(e, "maps projectile hits on the skinned mesh to bodies; there is no skinned mesh"),
            "frictiondirection" => ctx.ignore(e, "anisotropic contact friction is not simulated; friction is isotropic"),
            "contactmotordirection" => ctx.ignore(e, "contact motors (conveyor-like contacts) are not simulated"),
            "fixed" => body.motion = if ctx.flag(e)? { Motion::Fixed } else { Motion::Dynamic },
            "restitution" => body.restitution = ctx.one(e)?,
            "linearvelocity" => {
                ctx.arity(e, 1..=1, "a vector")?;
                body.linear_velocity = ctx.point(&e.values[0])?;
            }
            "angularvelocity" => {
                ctx.arity(e, 1..=1, "a vector in degrees per second")?;
                let w = ctx.vector(&e.values[0])?;
                body.angular_velocity = ctx.conv.axes(w) * 1f32.to_radians();
            }
            "particles" => {
                ctx.arity(e, 4..=4, "four vectors")?;
                let mut p = [Vec3::ZERO; 4];
                for (i, v) in e.values.iter().enumerate() {
                    p[i] = ctx.point(v)?;
                }
                particles = Some((p, e.pos));
            }
            _ => {
                return Err(unknown_key(ctx, e, &format!("body \"{name}\""), "joint, mod, model, origin, angles, density, inertiaScale, friction, selfCollision, contents, clipMask, containedJoints, frictionDirection, contactMotorDirection; ours: mass, fixed, restitution, linearVelocity, angularVelocity, particles"));
            }
        }
    }
    let Some(model) = model else {
        return Err(ctx.err(b.pos, format!("body \"{name}\" has no collision model; add e.g. `model box( ( -1, -1, -1 ), ( 1, 1, 1 ) )`")));
    };
    let (shape, pose) = read_model(ctx, model, origin, rotation)?;
    body.shape = shape;
    body.pose = pose;
    if let Some(m) = mass_given {
        body.mass = MassSpec::Mass(m);
    }
    if let Some((p, _)) = particles {
        // Written relative to the body's origin in the file's axes at the body's
        // orientation; stored in the shape frame.
        let off = pose.rotation.inverse() * (origin - pose.position);
        body.particles = Some(p.map(|q| q + off));
    }
    Ok(body)
}

fn inertia_scale(ctx: &mut Ctx, e: &Entry) -> R<[[f32; 3]; 3]> {
    // Forms: one number (uniform); nine numbers; three row vectors; one group of three
    // row groups (Doom 3's `( ( a b c ) ( d e f ) ( g h i ) )`).
    let mut nums = Vec::new();
    fn flatten(v: &Value, out: &mut Vec<Value>) {
        match v {
            Value::Group(items, _) => items.iter().for_each(|i| flatten(i, out)),
            other => out.push(other.clone()),
        }
    }
    e.values.iter().for_each(|v| flatten(v, &mut nums));
    let vals: Vec<f32> = nums
        .iter()
        .map(|v| ctx.num(v, "`inertiaScale`"))
        .collect::<R<_>>()?;
    let m = match vals.len() {
        1 => Mat3::from_diagonal(Vec3::splat(vals[0])),
        9 => Mat3::from_cols_array(&[
            vals[0], vals[3], vals[6], vals[1], vals[4], vals[7], vals[2], vals[5], vals[8],
        ]),
        n => {
            return Err(ctx.err(
                e.pos,
                format!("`inertiaScale` takes 1 or 9 numbers (a 3×3 matrix); found {n}"),
            ));
        }
    };
    if m.to_cols_array().iter().any(|v| !v.is_finite()) || m.diagonal_min() <= 0.0 {
        return Err(ctx.err(e.pos, "`inertiaScale` needs a positive diagonal"));
    }
    // The scale acts in the body frame; our body frame is the file's mapped by the axes.
    let c = ctx.conv.matrix();
    let m = c * m * c.transpose();
    Ok([
        m.row(0).to_array(),
        m.row(1).to_array(),
        m.row(2).to_array(),
    ])
}

trait DiagMin {
    fn diagonal_min(&self) -> f32;
}
impl DiagMin for Mat3 {
    fn diagonal_min(&self) -> f32 {
        self.x_axis.x.min(self.y_axis.y).min(self.z_axis.z)
    }
}

/// A collision model value → shape and the world pose of its shape frame.
fn read_model(ctx: &mut Ctx, v: &Value, origin: Vec3, rotation: Quat) -> R<(Shape, Pose)> {
    let Value::Call(f, args, p) = v else {
        return Err(ctx.err(
            v.pos(),
            format!(
                "expected a collision model such as box( ( x, y, z ), ( x, y, z ) ), found {}",
                v.describe()
            ),
        ));
    };
    let f_l = f.to_ascii_lowercase();
    let need = |ctx: &Ctx, n: usize, form: &str| -> R<()> {
        if args.len() == n {
            Ok(())
        } else {
            Err(ctx.err(
                *p,
                format!("`{f}` takes {form}; found {} argument(s)", args.len()),
            ))
        }
    };
    // Box-bounded models: centre and half extents in our axes, metres.
    let bounds = |ctx: &mut Ctx| -> R<(Vec3, Vec3)> {
        let a = ctx.vector(&args[0])?;
        let b = ctx.vector(&args[1])?;
        let d = b - a;
        if d.min_element() <= 0.0 {
            return Err(ctx.err(
                args[1].pos(),
                format!(
                    "`{f}`'s max ( {}, {}, {} ) must exceed its min ( {}, {}, {} ) on every axis",
                    b.x, b.y, b.z, a.x, a.y, a.z
                ),
            ));
        }
        let half = ctx.conv.axes(d * 0.5).abs() * ctx.conv.scale;
        let centre = ctx.conv.point((a + b) * 0.5);
        Ok((centre, half))
    };
    let sides = |ctx: &Ctx| -> R<u32> {
        let n = ctx.num(&args[2], "numSides")?;
        if n == 0.0 || (n >= 3.0 && n.fract() == 0.0 && n <= 1024.0) {
            Ok(n as u32)
        } else {
            Err(ctx.err(
                args[2].pos(),
                format!("numSides must be a whole number ≥ 3 (or 0 for smooth); found {n}"),
            ))
        }
    };
    let placed = |centre: Vec3| Pose {
        position: origin + rotation * centre,
        rotation,
    };
    match f_l.as_str() {
        "box" | "octahedron" | "dodecahedron" => {
            need(ctx, 2, "( min ), ( max )")?;
            let (c, h) = bounds(ctx)?;
            let shape = match f_l.as_str() {
                "box" => models::boxed(h),
                "octahedron" => models::octahedron(h),
                _ => models::dodecahedron(h),
            };
            Ok((shape, placed(c)))
        }
        "cylinder" | "cone" => {
            need(ctx, 3, "( min ), ( max ), numSides")?;
            let (c, h) = bounds(ctx)?;
            let n = sides(ctx)?;
            let shape = if f_l == "cylinder" { models::cylinder(h, n) } else { models::cone(h, n) };
            Ok((shape, placed(c)))
        }
        "bone" | "capsule" => {
            need(ctx, 3, if f_l == "bone" { "( start ), ( end ), width" } else { "( start ), ( end ), radius" })?;
            let a = ctx.point(&args[0])?;
            let b = ctx.point(&args[1])?;
            let w = ctx.num(&args[2], if f_l == "bone" { "width" } else { "radius" })? * ctx.conv.scale;
            if w <= 0.0 {
                return Err(ctx.err(args[2].pos(), format!("`{f}`'s {} must be positive", if f_l == "bone" { "width" } else { "radius" })));
            }
            let d = b - a;
            let half = d.length() * 0.5;
            let rot = d.try_normalize().map_or(Quat::IDENTITY, models::rotation_from_y);
            if f_l == "bone" && half <= 0.0 {
                return Err(ctx.err(args[1].pos(), "a bone's start and end must differ"));
            }
            let shape = if f_l == "bone" { models::bone(half, w) } else { Shape::Capsule { half_height: half, radius: w } };
            // The ends place these models; `origin` and `angles` do not apply.
            Ok((shape, Pose { position: (a + b) * 0.5, rotation: rot }))
        }
        "custom" => {
            need(ctx, 1, "a quoted model name")?;
            let n = ctx.string(&args[0], "the custom model's name")?.to_string();
            ctx.ignored.push(Ignored {
                line: p.line,
                col: p.col,
                key: format!("custom(\"{n}\")"),
                reason: "custom collision models live in Doom 3's model files; the body is a 10 cm cube at its origin instead".into(),
            });
            Ok((models::boxed(Vec3::splat(0.05)), placed(Vec3::ZERO)))
        }
        _ => Err(ctx.err(*p, format!("unknown collision model `{f}`; expected box, octahedron, dodecahedron, cone, cylinder, bone, custom, or our capsule"))),
    }
}

fn read_constraint(
    ctx: &mut Ctx,
    b: &Block,
    kind: &str,
    name: &str,
    ids: &HashMap<&str, BodyId>,
    d: &Defaults,
) -> R<ConstraintDesc> {
    let mut body1 = None;
    let mut body2 = None;
    let mut anchor = None;
    let mut anchor1 = None;
    let mut anchor2 = None;
    let mut axis = None;
    let mut shafts: Option<(Vec3, Vec3)> = None;
    let mut axes: Option<(Vec3, Vec3)> = None;
    let mut swing = None;
    let mut twist = None;
    let mut range = None;
    let mut ranges = None;
    let mut soft = LimitStyle::Hard;
    let mut friction = d.constraint_friction;
    let mut spring = [0.0f32; 6]; // stretch, compress, damping, restLength, minLength, maxLength
    let scale = ctx.conv.scale;
    let is = |k: &str| kind == k;
    let body_ref = |ctx: &Ctx, e: &Entry, allow_world: bool| -> R<BodyRef> {
        ctx.arity(e, 1..=1, "a quoted body name")?;
        let n = ctx.string(&e.values[0], &format!("`{}`", e.key))?;
        if n.eq_ignore_ascii_case("world") {
            return if allow_world {
                Ok(BodyRef::World)
            } else {
                Err(ctx.err(
                    e.values[0].pos(),
                    "body1 cannot be the world; swap body1 and body2",
                ))
            };
        }
        ids.get(n).map(|id| BodyRef::Body(*id)).ok_or_else(|| {
            ctx.err(
                e.values[0].pos(),
                format!(
                    "unknown body \"{n}\" in `{}`; no `body \"{n}\" {{ ... }}` is defined",
                    e.key
                ),
            )
        })
    };
    for e in &b.entries {
        let key = e.key.to_ascii_lowercase();
        let applies = match key.as_str() {
            "body1" | "body2" | "friction" => true,
            "anchor" => !is("spring") && !is("slider") && !is("fixed"),
            "anchor1" | "anchor2" | "stretch" | "compress" | "damping" | "restlength"
            | "minlength" | "maxlength" => is("spring"),
            "axis" => is("hinge") || is("slider"),
            "limit" | "range" => is("hinge"),
            "shafts" | "axes" | "ranges" => is("universalJoint"),
            "conelimit" | "pyramidlimit" => is("ballAndSocketJoint") || is("universalJoint"),
            "twistlimit" | "softlimit" => is("ballAndSocketJoint"),
            _ => {
                return Err(unknown_key(
                    ctx,
                    e,
                    &format!("{kind} \"{name}\""),
                    "body1, body2, anchor, anchor1, anchor2, axis, shafts, limit, conelimit, pyramidlimit, friction, stretch, compress, damping, restLength, minLength, maxLength; ours: range, ranges, axes, twistLimit, softLimit",
                ));
            }
        };
        if !applies {
            return Err(ctx.err(e.pos, format!("`{}` does not apply to a {kind}", e.key)));
        }
        match key.as_str() {
            "body1" => body1 = Some(body_ref(ctx, e, false)?),
            "body2" => body2 = Some(body_ref(ctx, e, true)?),
            "friction" => friction = ctx.nonneg(e)?,
            "anchor" | "anchor1" | "anchor2" => {
                ctx.arity(e, 1..=1, "a vector")?;
                let p = ctx.point(&e.values[0])?;
                match key.as_str() {
                    "anchor" => anchor = Some(p),
                    "anchor1" => anchor1 = Some(p),
                    _ => anchor2 = Some(p),
                }
            }
            "stretch" => spring[0] = ctx.nonneg(e)?,
            "compress" => spring[1] = ctx.nonneg(e)?,
            "damping" => spring[2] = ctx.nonneg(e)?,
            "restlength" => spring[3] = ctx.nonneg(e)? * scale,
            "minlength" => spring[4] = ctx.nonneg(e)? * scale,
            "maxlength" => spring[5] = ctx.nonneg(e)? * scale,
            "axis" => {
                ctx.arity(e, 1..=1, "a vector")?;
                axis = Some(ctx.dir(&e.values[0])?);
            }
            "shafts" | "axes" => {
                ctx.arity(e, 2..=2, "two vectors")?;
                let pair = (ctx.dir(&e.values[0])?, ctx.dir(&e.values[1])?);
                if key == "shafts" {
                    shafts = Some(pair)
                } else {
                    axes = Some(pair)
                }
            }
            "limit" => {
                // Doom 3: centre of the V, its full width, the shaft's angle (degrees).
                ctx.arity(e, 3..=3, "centre, width and shaft angles in degrees")?;
                let (c, w, s) = (ctx.arg(e, 0)?, ctx.arg(e, 1)?, ctx.arg(e, 2)?);
                if w < 0.0 {
                    return Err(ctx.err(
                        e.values[1].pos(),
                        format!("the limit's width must not be negative; found {w}"),
                    ));
                }
                range = Some(AngleRange {
                    min: (c - s - w * 0.5).to_radians(),
                    max: (c - s + w * 0.5).to_radians(),
                });
            }
            "range" => {
                ctx.arity(e, 2..=2, "min and max angles in degrees")?;
                range = Some(angle_range(ctx, &e.values[0], &e.values[1])?);
            }
            "ranges" => {
                ctx.arity(e, 4..=4, "min1, max1, min2, max2 in degrees")?;
                ranges = Some([
                    angle_range(ctx, &e.values[0], &e.values[1])?,
                    angle_range(ctx, &e.values[2], &e.values[3])?,
                ]);
            }
            "conelimit" => {
                let ball = is("ballAndSocketJoint");
                ctx.arity(
                    e,
                    if ball { 3..=3 } else { 2..=2 },
                    if ball {
                        "( axis ), angle, ( shaft )"
                    } else {
                        "( axis ), angle"
                    },
                )?;
                let ax = ctx.dir(&e.values[0])?;
                let angle = cone_angle(ctx, &e.values[1])?;
                let shaft = if ball {
                    ctx.dir(&e.values[2])?
                } else {
                    Vec3::ZERO
                };
                swing = Some((
                    SwingLimit::Cone {
                        axis: ax,
                        half_angle: angle * 0.5,
                        shaft,
                    },
                    e.pos,
                ));
            }
            "pyramidlimit" => {
                let ball = is("ballAndSocketJoint");
                ctx.arity(
                    e,
                    if ball { 5..=5 } else { 4..=4 },
                    if ball {
                        "( axis ), angle1, angle2, angle3, ( shaft )"
                    } else {
                        "( axis ), angle1, angle2, angle3"
                    },
                )?;
                let ax = ctx.dir(&e.values[0])?;
                let a1 = cone_angle(ctx, &e.values[1])?;
                let a2 = cone_angle(ctx, &e.values[2])?;
                let roll = ctx.deg(&e.values[3], "the pyramid's rotation")?;
                let shaft = if ball {
                    ctx.dir(&e.values[4])?
                } else {
                    Vec3::ZERO
                };
                swing = Some((
                    SwingLimit::Pyramid {
                        axis: ax,
                        half_angle1: a1 * 0.5,
                        half_angle2: a2 * 0.5,
                        roll,
                        shaft,
                    },
                    e.pos,
                ));
            }
            "twistlimit" => {
                ctx.arity(e, 3..=3, "( axis ), min, max in degrees")?;
                let ax = ctx.dir(&e.values[0])?;
                let r = angle_range(ctx, &e.values[1], &e.values[2])?;
                twist = Some(TwistLimit {
                    axis: ax,
                    min: r.min,
                    max: r.max,
                });
            }
            "softlimit" => {
                soft = LimitStyle::Soft {
                    torque: ctx.nonneg(e)?,
                }
            }
            _ => unreachable!("filtered by `applies`"),
        }
    }
    let missing = |what: &str| ctx.err(b.pos, format!("{kind} \"{name}\" is missing `{what}`"));
    let body1 = body1
        .ok_or_else(|| missing("body1"))?
        .body()
        .expect("body1 is never the world");
    let body2 = body2.ok_or_else(|| ctx.err(b.pos, format!("{kind} \"{name}\" is missing `body2` (write body2 \"world\" to attach it to the world)")))?;
    if body2 == BodyRef::Body(body1) {
        return Err(ctx.err(
            b.pos,
            format!(
                "{kind} \"{name}\" connects body \"{}\" to itself",
                b.entries
                    .iter()
                    .find(|e| e.key.eq_ignore_ascii_case("body1"))
                    .and_then(|e| e.values[0].clone().into_str())
                    .unwrap_or_default()
            ),
        ));
    }
    let kind = match kind {
        "ballAndSocketJoint" => JointKind::BallAndSocket {
            anchor: anchor.ok_or_else(|| missing("anchor"))?,
            swing: swing.map(|s| s.0),
            twist,
            limit_style: soft,
        },
        "universalJoint" => {
            // Doom 3's shafts run along the bones; the joint removes twist about them.
            // We store the cross's two rotation axes, each perpendicular to its shaft
            // and to each other (docs/af-format.md); `axes` gives them directly.
            let (a1, a2) = match (axes, shafts) {
                (Some(a), _) => a,
                (None, Some((s1, s2))) => {
                    let a2 = s2.any_orthonormal_vector();
                    let a1 = s1
                        .cross(a2)
                        .try_normalize()
                        .unwrap_or_else(|| s1.any_orthonormal_vector());
                    (a1, a2)
                }
                (None, None) => return Err(missing("shafts")),
            };
            let swing = match swing {
                Some((
                    SwingLimit::Cone {
                        axis, half_angle, ..
                    },
                    pos,
                )) => Some(SwingLimit::Cone {
                    axis,
                    half_angle,
                    shaft: shaft1(ctx, shafts, pos)?,
                }),
                Some((
                    SwingLimit::Pyramid {
                        axis,
                        half_angle1,
                        half_angle2,
                        roll,
                        ..
                    },
                    pos,
                )) => Some(SwingLimit::Pyramid {
                    axis,
                    half_angle1,
                    half_angle2,
                    roll,
                    shaft: shaft1(ctx, shafts, pos)?,
                }),
                None => None,
            };
            JointKind::Universal {
                anchor: anchor.ok_or_else(|| missing("anchor"))?,
                shaft1: a1,
                shaft2: a2,
                swing,
                axis_ranges: ranges,
            }
        }
        "hinge" => JointKind::Hinge {
            anchor: anchor.ok_or_else(|| missing("anchor"))?,
            axis: axis.ok_or_else(|| missing("axis"))?,
            limit: range,
        },
        "slider" => JointKind::Slider {
            axis: axis.ok_or_else(|| missing("axis"))?,
        },
        "fixed" => JointKind::Fixed,
        _ => JointKind::Spring {
            anchor1: anchor1.ok_or_else(|| missing("anchor1"))?,
            anchor2: anchor2.ok_or_else(|| missing("anchor2"))?,
            stretch: spring[0],
            compress: spring[1],
            damping: spring[2],
            rest_length: spring[3],
            min_length: spring[4],
            max_length: spring[5],
        },
    };
    Ok(ConstraintDesc {
        name: name.to_string(),
        body1,
        body2,
        kind,
        friction,
    })
}

fn shaft1(ctx: &Ctx, shafts: Option<(Vec3, Vec3)>, pos: Pos) -> R<Vec3> {
    shafts.map(|s| s.0).ok_or_else(|| ctx.err(pos, "a universal joint's cone or pyramid limit applies to its first shaft; give `shafts` too"))
}

fn cone_angle(ctx: &Ctx, v: &Value) -> R<f32> {
    let a = ctx.num(v, "the angle")?;
    if !(0.0..=360.0).contains(&a) {
        return Err(ctx.err(
            v.pos(),
            format!("a limit angle must be within 0 to 360 degrees; found {a}"),
        ));
    }
    Ok(a.to_radians())
}

fn angle_range(ctx: &Ctx, lo: &Value, hi: &Value) -> R<AngleRange> {
    let (a, b) = (
        ctx.num(lo, "the minimum angle")?,
        ctx.num(hi, "the maximum angle")?,
    );
    if a > b {
        return Err(ctx.err(
            hi.pos(),
            format!("the maximum angle {b} is below the minimum {a}"),
        ));
    }
    Ok(AngleRange {
        min: a.to_radians(),
        max: b.to_radians(),
    })
}

trait IntoStr {
    fn into_str(self) -> Option<String>;
}
impl IntoStr for Value {
    fn into_str(self) -> Option<String> {
        match self {
            Value::Str(s, _) => Some(s),
            _ => None,
        }
    }
}

/// Moves a body by a rigid transform of the world.
fn place_body(b: &mut BodyDesc, t: &Pose) {
    b.pose = t.mul_pose(&b.pose);
    b.linear_velocity = t.rotation * b.linear_velocity;
    b.angular_velocity = t.rotation * b.angular_velocity;
}

/// Moves a joint's world-space anchors and axes by a rigid transform.
fn place_joint(k: &mut JointKind, t: &Pose) {
    let r = t.rotation;
    let swing = |s: &mut SwingLimit| match s {
        SwingLimit::Cone { axis, shaft, .. } | SwingLimit::Pyramid { axis, shaft, .. } => {
            *axis = r * *axis;
            *shaft = r * *shaft;
        }
    };
    match k {
        JointKind::BallAndSocket {
            anchor,
            swing: s,
            twist,
            ..
        } => {
            *anchor = t.transform_point(*anchor);
            if let Some(s) = s {
                swing(s);
            }
            if let Some(tw) = twist {
                tw.axis = r * tw.axis;
            }
        }
        JointKind::Universal {
            anchor,
            shaft1,
            shaft2,
            swing: s,
            ..
        } => {
            *anchor = t.transform_point(*anchor);
            *shaft1 = r * *shaft1;
            *shaft2 = r * *shaft2;
            if let Some(s) = s {
                swing(s);
            }
        }
        JointKind::Hinge { anchor, axis, .. } => {
            *anchor = t.transform_point(*anchor);
            *axis = r * *axis;
        }
        JointKind::Slider { axis } => *axis = r * *axis,
        JointKind::Fixed => {}
        JointKind::Spring {
            anchor1, anchor2, ..
        } => {
            *anchor1 = t.transform_point(*anchor1);
            *anchor2 = t.transform_point(*anchor2);
        }
    }
}

/// Replaces the figure by `count` copies in a grid: columns along X, rows along Z,
/// layers up Y, centred on the figure's place in X and Z; copy `i` names its bodies and
/// constraints `name.i` (copy 0 keeps the original names). Layer `k` is turned by
/// `k · layerYaw` about the vertical through the figure's centre.
fn replicate_figure(desc: &mut SceneDesc, g: &Grid, count: u32) {
    let n = desc.bodies.len();
    let centre = desc.bodies.iter().map(|b| b.pose.position).sum::<Vec3>() / n.max(1) as f32;
    let reach = desc
        .bodies
        .iter()
        .map(|b| {
            ((b.pose.position - centre) * Vec3::new(1.0, 0.0, 1.0)).length()
                + b.shape.local_half_extents().length()
        })
        .fold(0.0f32, f32::max);
    let height = desc
        .bodies
        .iter()
        .map(|b| b.shape.local_half_extents().length() * 2.0)
        .fold(0.0f32, f32::max);
    let spacing = g.spacing.unwrap_or(Vec3::new(
        2.0 * reach + 0.3,
        height + 0.2,
        2.0 * reach + 0.3,
    ));
    let layers = g.layers.max(1);
    let (mut cols, mut rows) = (g.columns, g.rows);
    if cols == 0
        || rows == 0
        || u64::from(count) > u64::from(cols) * u64::from(rows) * u64::from(layers)
    {
        // Grow the floor grid, keeping it square, until the copies fit in `layers`.
        let per_layer = count.div_ceil(layers);
        let side = (per_layer as f64).sqrt().ceil() as u32;
        cols = cols.max(side);
        rows = rows.max(per_layer.div_ceil(cols));
    }
    let bodies = std::mem::take(&mut desc.bodies);
    let constraints = std::mem::take(&mut desc.constraints);
    desc.bodies.reserve(n * count as usize);
    desc.constraints.reserve(constraints.len() * count as usize);
    for i in 0..count {
        let (c, r, l) = (i % cols, (i / cols) % rows, i / cols / rows);
        let offset = Vec3::new(
            (c as f32 - (cols - 1) as f32 * 0.5) * spacing.x,
            l as f32 * spacing.y,
            (r as f32 - (rows - 1) as f32 * 0.5) * spacing.z,
        );
        // Turn about the figure's centre, then move: p' = R (p - c) + c + offset.
        let rot = Quat::from_rotation_y(l as f32 * g.layer_yaw);
        let t = Pose {
            position: centre + offset - rot * centre,
            rotation: rot,
        };
        let suffix = |s: &str| {
            if i == 0 {
                s.to_string()
            } else {
                format!("{s}.{i}")
            }
        };
        let base = BodyId(i * n as u32);
        for b in &bodies {
            let mut b = b.clone();
            b.name = suffix(&b.name);
            place_body(&mut b, &t);
            desc.bodies.push(b);
        }
        for c in &constraints {
            let mut c = c.clone();
            c.name = suffix(&c.name);
            c.body1 = BodyId(base.0 + c.body1.0);
            if let BodyRef::Body(b2) = c.body2 {
                c.body2 = BodyRef::Body(BodyId(base.0 + b2.0));
            }
            place_joint(&mut c.kind, &t);
            desc.constraints.push(c);
        }
    }
}
