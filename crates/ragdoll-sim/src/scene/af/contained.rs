//! `containedJoints`: which skeleton joints' parts of the visual mesh belong to which
//! body, so that a projectile hitting the mesh near a joint pushes the body containing
//! it (MrElusive's articulated-figure document: "a joint can only be contained by one
//! body").
//!
//! A body's list is read left to right as dhewm3's `idDeclModelDef::GetJointList` reads
//! it: names separated by white space, each optionally prefixed `-` (remove rather than
//! add) and then `*` (the joint and the joints after it in file order, up to the first
//! whose parent index is below the named joint's: its descendants when the file lists
//! them right after it). Names compare without regard to case. A body without the key
//! contains `*origin`, Doom 3's default. Bodies are taken in file order and a later
//! body's claim on a joint replaces an earlier one's (Doom 3 warns and does the same).
//!
//! The result is each body's [`crate::scene::BodyDesc::contained_joints`]: sorted joint
//! indices of the skeleton the figure was built on, every joint in at most one body.
//! Without a skeleton (a figure of plain numbers) the key is listed as ignored.

use super::Ignored;
use super::build::canonical;
use super::ctx::{Ctx, R};
use super::parser::{Block, Value};
use crate::scene::SceneDesc;
use crate::scene::lexer::Pos;
use crate::scene::md5mesh::Md5Skeleton;

/// Doom 3's `containedJoints` when a body does not say.
const DEFAULT_CONTAINED: &str = "*origin";

/// One name of a list: where it is written, whether it removes, whether it takes the
/// joints that follow.
struct Term<'a> {
    name: &'a str,
    subtract: bool,
    children: bool,
    pos: Pos,
}

/// Splits a list into terms; `at` is where the quoted value starts (its `"`), so a
/// term's column is `at.col + 1` plus the characters before it.
fn terms(list: &str, at: Pos) -> Vec<Term<'_>> {
    let mut out = Vec::new();
    let mut rest = list;
    let mut col = at.col + 1;
    loop {
        let skipped = rest.len() - rest.trim_start().len();
        col += rest[..skipped].chars().count() as u32;
        rest = &rest[skipped..];
        if rest.is_empty() {
            return out;
        }
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let word = &rest[..end];
        let (subtract, word_rest) = match word.strip_prefix('-') {
            Some(w) => (true, w),
            None => (false, word),
        };
        let (children, name) = match word_rest.strip_prefix('*') {
            Some(w) => (true, w),
            None => (false, word_rest),
        };
        // Errors point at the name itself, after its modifiers.
        let prefix = (word.len() - name.len()) as u32;
        let pos = Pos {
            line: at.line,
            col: col + prefix,
        };
        out.push(Term {
            name,
            subtract,
            children,
            pos,
        });
        col += word.chars().count() as u32;
        rest = &rest[end..];
    }
}

/// The joints one list names, in the order Doom 3 builds them (no duplicates).
/// An unknown joint is an error at the name.
fn joint_list(ctx: &Ctx, skel: &Md5Skeleton, list: &str, at: Pos) -> R<Vec<usize>> {
    let mut out: Vec<usize> = Vec::new();
    for t in terms(list, at) {
        let Some(j) = skel.index(t.name) else {
            let what = if t.name.is_empty() {
                "a joint name after `-` or `*`".to_string()
            } else {
                format!("no joint \"{}\"", t.name)
            };
            return Err(ctx.err(
                t.pos,
                format!(
                    "containedJoints: the mesh has {what} (it has {})",
                    skel.some_joint_names()
                ),
            ));
        };
        // The joint, then (for `*`) those after it down to the first one whose parent
        // comes before it: the joints file are ordered parents first.
        let mut take = vec![j];
        if t.children {
            take.extend(
                (j + 1..skel.joints.len())
                    .take_while(|&c| skel.joints[c].parent.is_some_and(|p| p >= j)),
            );
        }
        for k in take {
            if t.subtract {
                out.retain(|&x| x != k);
            } else if !out.contains(&k) {
                out.push(k);
            }
        }
    }
    Ok(out)
}

/// Fills every body's `contained_joints` from the body blocks of `merged` (in the order
/// `desc.bodies` was read from them).
pub(super) fn resolve(ctx: &mut Ctx, merged: &[Block], desc: &mut SceneDesc) -> R<()> {
    let bodies: Vec<&Block> = merged
        .iter()
        .filter(|b| canonical(&b.kind) == Some("body"))
        .collect();
    let keys: Vec<Option<(&str, Pos, Pos)>> = bodies
        .iter()
        .map(|b| {
            b.entries
                .iter()
                .rev()
                .find(|e| e.key.eq_ignore_ascii_case("containedJoints"))
                .map(|e| match e.values.first() {
                    Some(Value::Str(s, p)) => Ok((s.as_str(), e.pos, *p)),
                    Some(v) => Err(ctx.err(
                        v.pos(),
                        format!(
                            "containedJoints takes a quoted list of joint names, found {}",
                            v.describe()
                        ),
                    )),
                    None => {
                        Err(ctx.err(e.pos, "containedJoints takes a quoted list of joint names"))
                    }
                })
                .transpose()
        })
        .collect::<R<_>>()?;
    let Some(skel) = ctx.mesh.as_ref() else {
        for (_, key_pos, _) in keys.iter().flatten() {
            ctx.ignored.push(Ignored {
                line: key_pos.line,
                col: key_pos.col,
                key: "containedJoints".into(),
                reason: "names the mesh parts each body contains, for hits on the skinned mesh; this figure is built without a mesh".into(),
            });
        }
        return Ok(());
    };
    let mut owner: Vec<Option<usize>> = vec![None; skel.joints.len()];
    let mut notes = Vec::new();
    for (i, key) in keys.iter().enumerate() {
        let list = match key {
            Some((list, _, at)) => joint_list(ctx, skel, list, *at)?,
            // The default names a joint a mesh may lack; then the body contains none.
            None => match skel.index("origin") {
                Some(_) => joint_list(ctx, skel, DEFAULT_CONTAINED, Pos { line: 1, col: 1 })?,
                None => Vec::new(),
            },
        };
        for j in list {
            if let Some(prev) = owner[j]
                && prev != i
            {
                let at = key.map_or(bodies[i].pos, |k| k.1);
                notes.push(Ignored {
                    line: at.line,
                    col: at.col,
                    key: "containedJoints".into(),
                    reason: format!(
                        "joint \"{}\" was contained by body \"{}\"; body \"{}\", later in the file, takes it (as in Doom 3)",
                        skel.joints[j].name, desc.bodies[prev].name, desc.bodies[i].name
                    ),
                });
            }
            owner[j] = Some(i);
        }
    }
    let free: Vec<&str> = owner
        .iter()
        .zip(&skel.joints)
        .filter(|(o, _)| o.is_none())
        .map(|(_, j)| j.name.as_str())
        .collect();
    if !free.is_empty() && keys.iter().any(Option::is_some) {
        let at = keys
            .iter()
            .flatten()
            .next()
            .map_or(Pos { line: 1, col: 1 }, |k| k.1);
        notes.push(Ignored {
            line: at.line,
            col: at.col,
            key: "containedJoints".into(),
            reason: format!(
                "no body contains joint(s) {}: a hit on the mesh nearest to them pushes nothing",
                free.join(", ")
            ),
        });
    }
    for (b, body) in desc.bodies.iter_mut().enumerate() {
        body.contained_joints = (0..owner.len())
            .filter(|&j| owner[j] == Some(b))
            .map(|j| j as u32)
            .collect();
    }
    ctx.ignored.extend(notes);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_carry_their_modifiers_and_columns() {
        let t = terms("origin  -*Lupleg *Waist", Pos { line: 3, col: 18 });
        let got: Vec<(&str, bool, bool, u32)> = t
            .iter()
            .map(|t| (t.name, t.subtract, t.children, t.pos.col))
            .collect();
        // The quote is at column 18: "origin" starts at 19, "-*Lupleg" at 27 (its name
        // at 29), "*Waist" at 36 (its name at 37).
        assert_eq!(
            got,
            [
                ("origin", false, false, 19),
                ("Lupleg", true, true, 29),
                ("Waist", false, true, 37)
            ]
        );
    }
}
