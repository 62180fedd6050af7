//! A `body` block: collision model, placement, mass, friction and our extensions.

use super::Ignored;
use super::ctx::{Ctx, Defaults, R, angles_to_quat, unknown_key};
use super::models;
use super::parser::{Block, Entry, Value};
use crate::scene::{BodyDesc, Friction, MassSpec, Motion, Pose, Shape};
use glam::{Mat3, Quat, Vec3};

pub(super) fn read_body(ctx: &mut Ctx, b: &Block, name: &str, d: &Defaults) -> R<BodyDesc> {
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
            "mod" => ctx.ignore(e, "no effect on the simulation: it only sets how the body moves its joint of the skinned mesh, drawn when the figure comes with its mesh's triangles (--doom3 with --entity, or --mesh)"),
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
            "linearfriction" => body.friction.linear = ctx.nonneg(e)?,
            "angularfriction" => body.friction.angular = ctx.nonneg(e)?,
            "contactfriction" => body.friction.contact = ctx.nonneg(e)?,
            "contents" | "clipmask" => ctx.ignore(e, "Doom 3's collision groups: every body collides with the ground and other figures, and with its own figure per selfCollision"),
            // Resolved against the skeleton once every body is read (`contained`).
            "containedjoints" => {}
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
                return Err(unknown_key(ctx, e, &format!("body \"{name}\""), "joint, mod, model, origin, angles, density, inertiaScale, friction, linearFriction, angularFriction, contactFriction, selfCollision, contents, clipMask, containedJoints, frictionDirection, contactMotorDirection; ours: mass, fixed, restitution, linearVelocity, angularVelocity, particles"));
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

pub(super) fn inertia_scale(ctx: &mut Ctx, e: &Entry) -> R<[[f32; 3]; 3]> {
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
    let diagonal = [m.x_axis.x, m.y_axis.y, m.z_axis.z];
    if m.to_cols_array().iter().any(|v| !v.is_finite()) || diagonal.iter().any(|d| *d <= 0.0) {
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

/// A collision model value → shape and the world pose of its shape frame.
pub(super) fn read_model(
    ctx: &mut Ctx,
    v: &Value,
    origin: Vec3,
    rotation: Quat,
) -> R<(Shape, Pose)> {
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
            if f_l == "bone" && half <= 0.0 {
                return Err(ctx.err(args[1].pos(), "a bone's start and end must differ"));
            }
            let rot = if f_l == "bone" {
                // Doom 3's bone axes, worked out in the file's axes and mapped to ours.
                let m = models::bone_frame(ctx.conv.file_axes(d));
                let m = ctx.conv.matrix() * m;
                Quat::from_mat3(&m).normalize()
            } else {
                d.try_normalize().map_or(Quat::IDENTITY, models::rotation_from_y)
            };
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
