//! Constraint blocks: the six Doom 3 types, their limits, and our limit extensions.

use super::ctx::{Ctx, Defaults, R, unknown_key};
use super::parser::{Block, Entry, Value};
use crate::scene::lexer::Pos;
use crate::scene::{
    AngleRange, BodyId, BodyRef, ConstraintDesc, JointKind, LimitStyle, SwingLimit, TwistLimit,
};
use glam::Vec3;
use std::collections::HashMap;

/// The keys of a constraint block as read, before they are checked against its type.
struct Keys {
    body1: Option<BodyRef>,
    body2: Option<BodyRef>,
    anchor: Option<Vec3>,
    anchor1: Option<Vec3>,
    anchor2: Option<Vec3>,
    axis: Option<Vec3>,
    shafts: Option<(Vec3, Vec3)>,
    axes: Option<(Vec3, Vec3)>,
    /// The swing limit and where it was written (a universal joint's needs `shafts`).
    swing: Option<(SwingLimit, Pos)>,
    twist: Option<TwistLimit>,
    range: Option<AngleRange>,
    ranges: Option<[AngleRange; 2]>,
    soft: LimitStyle,
    friction: f32,
    /// stretch, compress, damping, restLength, minLength, maxLength.
    spring: [f32; 6],
}

/// A constraint block of type `kind` (one of Doom 3's six) named `name`, its bodies
/// looked up in `ids`: every key read and checked against the type, then the joint
/// built from them.
pub(super) fn read_constraint(
    ctx: &mut Ctx,
    b: &Block,
    kind: &str,
    name: &str,
    ids: &HashMap<&str, BodyId>,
    d: &Defaults,
) -> R<ConstraintDesc> {
    let mut keys = Keys {
        body1: None,
        body2: None,
        anchor: None,
        anchor1: None,
        anchor2: None,
        axis: None,
        shafts: None,
        axes: None,
        swing: None,
        twist: None,
        range: None,
        ranges: None,
        soft: LimitStyle::Hard,
        friction: d.constraint_friction,
        spring: [0.0; 6],
    };
    for e in &b.entries {
        let key = e.key.to_ascii_lowercase();
        match key_applies(kind, &key) {
            None => {
                return Err(unknown_key(
                    ctx,
                    e,
                    &format!("{kind} \"{name}\""),
                    "body1, body2, anchor, anchor1, anchor2, axis, shafts, limit, conelimit, pyramidlimit, friction, stretch, compress, damping, restLength, minLength, maxLength; ours: range, ranges, axes, twistLimit, softLimit",
                ));
            }
            Some(false) => {
                return Err(ctx.err(e.pos, format!("`{}` does not apply to a {kind}", e.key)));
            }
            Some(true) => read_key(ctx, &mut keys, e, &key, kind, ids)?,
        }
    }
    let missing = |what: &str| ctx.err(b.pos, format!("{kind} \"{name}\" is missing `{what}`"));
    let body1 = keys
        .body1
        .ok_or_else(|| missing("body1"))?
        .body()
        .expect("body1 is never the world");
    let body2 = keys.body2.ok_or_else(|| ctx.err(b.pos, format!("{kind} \"{name}\" is missing `body2` (write body2 \"world\" to attach it to the world)")))?;
    if body2 == BodyRef::Body(body1) {
        return Err(ctx.err(
            b.pos,
            format!(
                "{kind} \"{name}\" connects body \"{}\" to itself",
                ids.iter()
                    .find(|(_, id)| **id == body1)
                    .map_or("", |(n, _)| *n)
            ),
        ));
    }
    let friction = keys.friction;
    Ok(ConstraintDesc {
        name: name.to_string(),
        body1,
        body2,
        kind: joint_kind(ctx, kind, keys, &missing)?,
        friction,
    })
}

/// Whether the lower-cased `key` applies to a constraint of type `kind`; `None` for a
/// key no constraint has.
fn key_applies(kind: &str, key: &str) -> Option<bool> {
    let is = |k: &str| kind == k;
    Some(match key {
        "body1" | "body2" | "friction" => true,
        "anchor" => !is("spring") && !is("slider") && !is("fixed"),
        "anchor1" | "anchor2" | "stretch" | "compress" | "damping" | "restlength" | "minlength"
        | "maxlength" => is("spring"),
        "axis" => is("hinge") || is("slider"),
        "limit" | "range" => is("hinge"),
        "shafts" | "axes" | "ranges" => is("universalJoint"),
        "conelimit" | "pyramidlimit" => is("ballAndSocketJoint") || is("universalJoint"),
        "twistlimit" | "softlimit" => is("ballAndSocketJoint"),
        _ => return None,
    })
}

/// Reads entry `e` (its lower-cased key `key`, which applies to `kind`) into `keys`.
fn read_key(
    ctx: &mut Ctx,
    keys: &mut Keys,
    e: &Entry,
    key: &str,
    kind: &str,
    ids: &HashMap<&str, BodyId>,
) -> R<()> {
    let scale = ctx.conv.scale;
    let ball = kind == "ballAndSocketJoint";
    match key {
        "body1" => keys.body1 = Some(body_ref(ctx, e, ids, false)?),
        "body2" => keys.body2 = Some(body_ref(ctx, e, ids, true)?),
        "friction" => keys.friction = ctx.nonneg(e)?,
        "anchor" | "anchor1" | "anchor2" => {
            ctx.arity(e, 1..=1, "a vector")?;
            let p = ctx.point(&e.values[0])?;
            match key {
                "anchor" => keys.anchor = Some(p),
                "anchor1" => keys.anchor1 = Some(p),
                _ => keys.anchor2 = Some(p),
            }
        }
        "stretch" => keys.spring[0] = ctx.nonneg(e)?,
        "compress" => keys.spring[1] = ctx.nonneg(e)?,
        "damping" => keys.spring[2] = ctx.nonneg(e)?,
        "restlength" => keys.spring[3] = ctx.nonneg(e)? * scale,
        "minlength" => keys.spring[4] = ctx.nonneg(e)? * scale,
        "maxlength" => keys.spring[5] = ctx.nonneg(e)? * scale,
        "axis" => {
            ctx.arity(e, 1..=1, "a vector")?;
            keys.axis = Some(ctx.dir(&e.values[0])?);
        }
        "shafts" | "axes" => {
            ctx.arity(e, 2..=2, "two vectors")?;
            let pair = (ctx.dir(&e.values[0])?, ctx.dir(&e.values[1])?);
            if key == "shafts" {
                keys.shafts = Some(pair)
            } else {
                keys.axes = Some(pair)
            }
        }
        "limit" => {
            ctx.arity(e, 3..=3, "centre, width and shaft angles in degrees")?;
            let (c, w, s) = (ctx.arg(e, 0)?, ctx.arg(e, 1)?, ctx.arg(e, 2)?);
            if w < 0.0 {
                return Err(ctx.err(
                    e.values[1].pos(),
                    format!("the limit's width must not be negative; found {w}"),
                ));
            }
            keys.range = Some(hinge_limit_range(c, w, s));
        }
        "range" => {
            ctx.arity(e, 2..=2, "min and max angles in degrees")?;
            keys.range = Some(angle_range(ctx, &e.values[0], &e.values[1])?);
        }
        "ranges" => {
            ctx.arity(e, 4..=4, "min1, max1, min2, max2 in degrees")?;
            keys.ranges = Some([
                angle_range(ctx, &e.values[0], &e.values[1])?,
                angle_range(ctx, &e.values[2], &e.values[3])?,
            ]);
        }
        "conelimit" => keys.swing = Some((cone_limit(ctx, e, ball)?, e.pos)),
        "pyramidlimit" => keys.swing = Some((pyramid_limit(ctx, e, ball)?, e.pos)),
        "twistlimit" => {
            ctx.arity(e, 3..=3, "( axis ), min, max in degrees")?;
            let ax = ctx.dir(&e.values[0])?;
            let r = angle_range(ctx, &e.values[1], &e.values[2])?;
            keys.twist = Some(TwistLimit {
                axis: ax,
                min: r.min,
                max: r.max,
            });
        }
        "softlimit" => {
            keys.soft = LimitStyle::Soft {
                torque: ctx.nonneg(e)?,
            }
        }
        _ => unreachable!("filtered by `key_applies`"),
    }
    Ok(())
}

/// The body a `body1` / `body2` entry names, looked up in `ids`; `world` only where
/// `allow_world` (body2).
fn body_ref(ctx: &Ctx, e: &Entry, ids: &HashMap<&str, BodyId>, allow_world: bool) -> R<BodyRef> {
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
}

/// `coneLimit ( axis ), angle[, ( shaft )]` (the shaft on a ball joint only; a
/// universal joint's is its first shaft, filled in by [`universal`]).
fn cone_limit(ctx: &mut Ctx, e: &Entry, ball: bool) -> R<SwingLimit> {
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
    Ok(SwingLimit::Cone {
        axis: ax,
        half_angle: angle * 0.5,
        shaft,
    })
}

/// `pyramidLimit ( axis ), angle1, angle2, angle3[, ( shaft )]`, as [`cone_limit`].
fn pyramid_limit(ctx: &mut Ctx, e: &Entry, ball: bool) -> R<SwingLimit> {
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
    Ok(SwingLimit::Pyramid {
        axis: ax,
        half_angle1: a1 * 0.5,
        half_angle2: a2 * 0.5,
        roll,
        shaft,
    })
}

/// The joint of type `kind` from its keys; `missing` is the error for a required key
/// not given.
fn joint_kind(
    ctx: &Ctx,
    kind: &str,
    keys: Keys,
    missing: &dyn Fn(&str) -> super::AfError,
) -> R<JointKind> {
    Ok(match kind {
        "ballAndSocketJoint" => JointKind::BallAndSocket {
            anchor: keys.anchor.ok_or_else(|| missing("anchor"))?,
            swing: keys.swing.map(|s| s.0),
            twist: keys.twist,
            limit_style: keys.soft,
        },
        "universalJoint" => universal(ctx, keys, missing)?,
        "hinge" => JointKind::Hinge {
            anchor: keys.anchor.ok_or_else(|| missing("anchor"))?,
            axis: keys.axis.ok_or_else(|| missing("axis"))?,
            limit: keys.range,
        },
        "slider" => JointKind::Slider {
            axis: keys.axis.ok_or_else(|| missing("axis"))?,
        },
        "fixed" => JointKind::Fixed,
        _ => JointKind::Spring {
            anchor1: keys.anchor1.ok_or_else(|| missing("anchor1"))?,
            anchor2: keys.anchor2.ok_or_else(|| missing("anchor2"))?,
            stretch: keys.spring[0],
            compress: keys.spring[1],
            damping: keys.spring[2],
            rest_length: keys.spring[3],
            min_length: keys.spring[4],
            max_length: keys.spring[5],
        },
    })
}

/// A universal joint. Doom 3's shafts run along the bones; the joint removes twist
/// about them. We store the cross's two rotation axes, each perpendicular to its shaft
/// and to each other (docs/af-format.md); `axes` gives them directly. A cone or
/// pyramid limit bounds the first shaft.
fn universal(ctx: &Ctx, keys: Keys, missing: &dyn Fn(&str) -> super::AfError) -> R<JointKind> {
    let shafts = keys.shafts;
    let (a1, a2) = match (keys.axes, shafts) {
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
    let swing = match keys.swing {
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
    Ok(JointKind::Universal {
        anchor: keys.anchor.ok_or_else(|| missing("anchor"))?,
        shaft1: a1,
        shaft2: a2,
        swing,
        axis_ranges: keys.ranges,
    })
}

/// The range of our hinge angle for Doom 3's `limit c, w, s` (degrees in, radians out).
///
/// The engine (`idAF::LoadConstraint`, `idAFConstraint_Hinge::SetLimit`,
/// `idAFConstraint_ConeLimit`) builds, at the `af_pose` where the figure is set up,
/// `(left, up) = OrthogonalBasis(axis)`, a cone axis `left * idRotation(axis, c)`
/// fixed in body2 and a shaft `left * idRotation(axis, s)` fixed in body1, and keeps
/// the shaft within the cone's half apex angle `w/2` of the cone axis. `v * idRotation(n, θ)`
/// is `Mᵀ v` with `M` the right-handed rotation matrix of θ about n, so it turns `v` by
/// `−θ`: cone axis `= R(n, −c) left`, shaft `= R(n, −s) left`. Our hinge angle `φ` is
/// body1's rotation relative to body2 about the axis, right-handed, zero at the file's
/// pose (the same `af_pose`); the axis conversion is a proper rotation and keeps its
/// sign. Seen from body2 the shaft is then `R(n, φ − s) left`, at the signed angle
/// `φ − s + c` from the cone axis, and the cone allows `|φ − s + c| ≤ w/2`:
///
/// ```text
/// s − c − w/2 ≤ φ ≤ s − c + w/2
/// ```
///
/// The cone is a direction test, so the centre `s − c` counts modulo 360°; it is taken
/// in (−180°, 180°], where our angle is measured.
pub(super) fn hinge_limit_range(c: f32, w: f32, s: f32) -> AngleRange {
    let centre = 180.0 - (180.0 - (s - c)).rem_euclid(360.0);
    AngleRange {
        min: (centre - w * 0.5).to_radians(),
        max: (centre + w * 0.5).to_radians(),
    }
}

pub(super) fn shaft1(ctx: &Ctx, shafts: Option<(Vec3, Vec3)>, pos: Pos) -> R<Vec3> {
    shafts.map(|s| s.0).ok_or_else(|| ctx.err(pos, "a universal joint's cone or pyramid limit applies to its first shaft; give `shafts` too"))
}

pub(super) fn cone_angle(ctx: &Ctx, v: &Value) -> R<f32> {
    let a = ctx.num(v, "the angle")?;
    if !(0.0..=360.0).contains(&a) {
        return Err(ctx.err(
            v.pos(),
            format!("a limit angle must be within 0 to 360 degrees; found {a}"),
        ));
    }
    Ok(a.to_radians())
}

pub(super) fn angle_range(ctx: &Ctx, lo: &Value, hi: &Value) -> R<AngleRange> {
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

#[cfg(test)]
mod tests {
    use super::super::{AfOptions, parse};
    use crate::scene::{AngleRange, JointKind};
    use glam::Vec3;
    use std::path::Path;

    /// The range and axis (ours) the reader gives a hinge of a Doom 3-unit file with
    /// `axis ( 0, 1, 0 )` and the given `limit`.
    fn hinge(limit: &str) -> (AngleRange, Vec3) {
        let text = format!(
            "body \"shin\" {{ model box( ( -2, -2, -20 ), ( 2, 2, 0 ) ) origin ( 0, 0, 40 ) }}\n\
             hinge \"knee\" {{ body1 \"shin\" body2 \"world\" anchor ( 0, 0, 40 ) axis ( 0, 1, 0 ) limit {limit} }}\n"
        );
        let scene = parse(&text, Path::new("t.af"), &AfOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        match &scene.desc.constraints[0].kind {
            JointKind::Hinge {
                axis,
                limit: Some(r),
                ..
            } => (*r, *axis),
            k => panic!("expected a limited hinge, got {k:?}"),
        }
    }

    fn degrees(r: AngleRange) -> (f32, f32) {
        (r.min.to_degrees(), r.max.to_degrees())
    }

    /// `limit 90, 60, 0` about Doom's `( 0, 1, 0 )` (Z up). The engine's
    /// `OrthogonalBasis(( 0, 1, 0 ))` gives left `= ( −1, 0, 0 )`; `v * idRotation(n, θ)`
    /// turns v by −θ right-handed, so the cone axis is left turned −90° about +Y:
    /// `( 0, 0, −1 )`, straight down, and the shaft is left itself, `( −1, 0, 0 )`. The
    /// shaft (body1's) may stray 30° from the cone axis (body2's). A right-handed turn φ
    /// of body1 about +Y takes `( −1, 0, 0 )` to `( −cos φ, 0, sin φ )`, which points
    /// down at φ = −90°: body1 may turn between −120° and −60°, never to positive angles.
    /// Our Y-up axis is `( 0, 0, −1 )` (Z-up `( x, y, z )` is ours `( x, z, −y )`, a
    /// proper rotation), about which right-handed angles are the same turns.
    #[test]
    fn a_hinge_limit_allows_the_side_doom_3_allows() {
        let (range, axis) = hinge("90, 60, 0");
        assert!((axis - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6, "{axis}");
        let (lo, hi) = degrees(range);
        assert!(
            (lo + 120.0).abs() < 1e-3 && (hi + 60.0).abs() < 1e-3,
            "[{lo}, {hi}]"
        );
    }

    /// The cone tests directions, so a centre past a half turn wraps: with `limit −170,
    /// 20, 30` the shaft is where the cone axis is after a turn of 200°, the same
    /// direction as −160°.
    #[test]
    fn a_hinge_limit_centre_wraps_into_a_half_turn() {
        let (lo, hi) = degrees(hinge("-170, 20, 30").0);
        assert!(
            (lo + 170.0).abs() < 1e-3 && (hi + 150.0).abs() < 1e-3,
            "[{lo}, {hi}]"
        );
    }
}
