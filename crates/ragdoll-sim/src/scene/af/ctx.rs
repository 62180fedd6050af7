//! Reading context: the file's units and axes, the lazily loaded mesh, the four vector
//! forms, typed value access with positioned errors, and the list of ignored keys.

use super::parser::{Entry, Value};
use super::{AfError, AfOptions, FigureSource, Ignored};
use crate::scene::Friction;
use crate::scene::decl::Doom3Base;
use crate::scene::lexer::Pos;
use crate::scene::md5anim;
use crate::scene::md5mesh::{self, Md5Skeleton};
use glam::{Mat3, Quat, Vec3};
use std::path::PathBuf;

pub(super) type R<T> = Result<T, AfError>;

/// The file's units and axes: how a file vector becomes ours.
#[derive(Clone, Copy, Debug)]
pub(super) struct Conv {
    /// Metres per file unit.
    pub(super) scale: f32,
    /// Z up (Doom 3) rather than Y up.
    pub(super) z_up: bool,
}

impl Conv {
    /// The axis mapping alone: Z-up `(x, y, z)` → `(x, z, -y)`, a proper rotation.
    pub(super) fn axes(&self, v: Vec3) -> Vec3 {
        if self.z_up {
            Vec3::new(v.x, v.z, -v.y)
        } else {
            v
        }
    }
    /// The inverse of [`Conv::axes`]: our `(x, y, z)` → Z-up `(x, -z, y)`.
    pub(super) fn file_axes(&self, v: Vec3) -> Vec3 {
        if self.z_up {
            Vec3::new(v.x, -v.z, v.y)
        } else {
            v
        }
    }
    pub(super) fn point(&self, v: Vec3) -> Vec3 {
        self.axes(v) * self.scale
    }
    /// The axis mapping as a matrix (columns are the images of the file's axes).
    pub(super) fn matrix(&self) -> Mat3 {
        Mat3::from_cols(self.axes(Vec3::X), self.axes(Vec3::Y), self.axes(Vec3::Z))
    }
}

/// Doom 3 angles `( pitch, yaw, roll )` in degrees as a rotation of our world.
///
/// Doom 3's `idAngles::ToMat3` is `Rz(yaw)·Ry(pitch)·Rx(roll)` in its Z-up frame. Mapped
/// through the axis conversion that is yaw about our +Y, pitch about our −Z and roll
/// about our +X; we use this one meaning for Y-up files too.
pub(super) fn angles_to_quat(a: Vec3) -> Quat {
    let (p, y, r) = (a.x.to_radians(), a.y.to_radians(), a.z.to_radians());
    Quat::from_axis_angle(Vec3::Y, y)
        * Quat::from_axis_angle(Vec3::NEG_Z, p)
        * Quat::from_axis_angle(Vec3::X, r)
}

/// Reading context: the file, its conversion, the lazily loaded mesh, ignored keys.
pub(super) struct Ctx<'a> {
    pub(super) file: String,
    pub(super) dir: PathBuf,
    pub(super) conv: Conv,
    pub(super) opts: &'a AfOptions,
    pub(super) source: &'a FigureSource,
    /// The `mesh`/`model` path from settings and where it was written.
    pub(super) mesh_key: Option<(String, Pos)>,
    pub(super) mesh: Option<Md5Skeleton>,
    pub(super) ignored: Vec<Ignored>,
}

impl Ctx<'_> {
    pub(super) fn err(&self, pos: Pos, message: impl Into<String>) -> AfError {
        AfError::at(&self.file, pos, message.into())
    }

    pub(super) fn ignore(&mut self, e: &Entry, reason: &str) {
        self.ignored.push(Ignored {
            line: e.pos.line,
            col: e.pos.col,
            key: e.key.clone(),
            reason: reason.into(),
        });
    }

    pub(super) fn arity(&self, e: &Entry, n: std::ops::RangeInclusive<usize>, form: &str) -> R<()> {
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

    pub(super) fn num(&self, v: &Value, what: &str) -> R<f32> {
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

    pub(super) fn arg(&self, e: &Entry, i: usize) -> R<f32> {
        self.num(&e.values[i], &format!("`{}`", e.key))
    }

    pub(super) fn one(&self, e: &Entry) -> R<f32> {
        self.arity(e, 1..=1, "one number")?;
        self.arg(e, 0)
    }

    pub(super) fn nonneg(&self, e: &Entry) -> R<f32> {
        let v = self.one(e)?;
        if v < 0.0 {
            return Err(self.err(
                e.values[0].pos(),
                format!("`{}` must not be negative; found {v}", e.key),
            ));
        }
        Ok(v)
    }

    pub(super) fn flag(&self, e: &Entry) -> R<bool> {
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

    pub(super) fn string<'v>(&self, v: &'v Value, what: &str) -> R<&'v str> {
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

    pub(super) fn mesh(&mut self, at: Pos, what: &str) -> R<&Md5Skeleton> {
        if self.mesh.is_none() {
            let skel = self.load_skeleton(at, what)?;
            self.mesh = Some(skel);
        }
        Ok(self.mesh.as_ref().expect("loaded above"))
    }

    /// The mesh's skeleton in the pose the figure is built from: the `af_pose`
    /// animation's first instant when there is one (Doom 3 samples it at 1 ms), else the
    /// bind pose.
    fn load_skeleton(&self, at: Pos, what: &str) -> R<Md5Skeleton> {
        let mut pose_anim = self.source.pose_anim.clone();
        let (path, pos) = match (&self.opts.mesh, &self.mesh_key, &self.source.base) {
            (Some(p), _, _) => (p.clone(), at),
            (None, Some((key, pos)), Some(root)) => {
                // Through the mod's declarations, as Doom 3 reads a model key.
                let base = Doom3Base::open(root)?;
                let files = base
                    .model_files(key)
                    .map_err(|e| self.err(*pos, e.message))?;
                let (mesh, pose) = (files.mesh, files.af_pose);
                if pose_anim.is_none() {
                    pose_anim = pose;
                }
                match mesh {
                    Some(m) => (m, *pos),
                    None => {
                        return Err(self.err(*pos, format!("model \"{key}\" has no mesh")));
                    }
                }
            }
            (None, Some((p, pos)), None) => (self.dir.join(p), *pos),
            (None, None, _) => {
                return Err(self.err(
                    at,
                    format!(
                        "{what} cannot be resolved without the figure's mesh: add `mesh \"FILE.md5mesh\"` to settings (relative to this file) or pass --mesh FILE.md5mesh"
                    ),
                ));
            }
        };
        let skel = md5mesh::load(&path).map(|m| m.skeleton).map_err(|e| {
            let why = e.message.trim_start_matches("cannot read the mesh: ");
            if e.message.starts_with("cannot read") && self.opts.mesh.is_some() {
                self.err(pos, format!("the mesh {} given with --mesh cannot be read: {why}", path.display()))
            } else if e.message.starts_with("cannot read") {
                self.err(pos, format!("{what} needs the mesh {}, which cannot be read ({why}); pass --mesh FILE.md5mesh to use another", path.display()))
            } else {
                e
            }
        })?;
        match pose_anim {
            None => Ok(skel),
            Some(a) => {
                let anim = md5anim::load(&a)?;
                anim.check_hierarchy(&skel).map_err(|m| {
                    self.err(
                        pos,
                        format!(
                            "the pose animation {} does not fit the mesh {}: {m}",
                            a.display(),
                            path.display()
                        ),
                    )
                })?;
                Ok(anim.pose_skeleton(&skel, AF_POSE_TIME))
            }
        }
    }

    pub(super) fn joint_pos(&mut self, name_v: &Value, form: &str) -> R<Vec3> {
        let name = self.string(name_v, "a joint name")?.to_string();
        let at = name_v.pos();
        let skel = self.mesh(at, &format!("{form}(\"{name}\")"))?;
        match skel.joint(&name) {
            Some(j) => Ok(j.position),
            None => {
                let message = format!(
                    "the mesh has no joint \"{name}\" (it has {})",
                    skel.some_joint_names()
                );
                Err(AfError::at(&self.file, at, message))
            }
        }
    }

    /// Any of the four vector forms, in file units and axes (not converted).
    pub(super) fn vector(&mut self, v: &Value) -> R<Vec3> {
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

    pub(super) fn point(&mut self, v: &Value) -> R<Vec3> {
        let p = self.vector(v)?;
        Ok(self.conv.point(p))
    }

    pub(super) fn dir(&mut self, v: &Value) -> R<Vec3> {
        let d = self.vector(v)?;
        self.conv
            .axes(d)
            .try_normalize()
            .ok_or_else(|| self.err(v.pos(), "this direction has zero length"))
    }

    pub(super) fn deg(&self, v: &Value, what: &str) -> R<f32> {
        Ok(self.num(v, what)?.to_radians())
    }
}

/// When Doom 3 samples `af_pose` (idAF::Load: 1 ms, frame 0 a little toward frame 1).
pub(super) const AF_POSE_TIME: f32 = 0.001;

/// Figure-wide defaults from `settings`.
pub(super) struct Defaults {
    pub(super) friction: Friction,
    pub(super) self_collision: bool,
    pub(super) constraint_friction: f32,
}

/// The error for a key a block does not know, listing the ones it does.
pub(super) fn unknown_key(ctx: &Ctx, e: &Entry, block: &str, known: &str) -> AfError {
    ctx.err(
        e.pos,
        format!(
            "unknown key `{}` in {block}; expected one of: {known}",
            e.key
        ),
    )
}
