//! The joints section of an `.md5mesh` (version 10): the bind pose that `joint("name")`,
//! `bonecenter(...)` and `bonedir(...)` in an `.af` file resolve against.
//!
//! ```text
//! MD5Version 10
//! numJoints 2
//! joints {
//!     "origin"  -1 ( 0 0 0 ) ( -0.5 -0.5 -0.5 )   // name parent ( position ) ( orientation x y z )
//!     "Hips"     0 ( 0 0 40 ) ( 0 0 0 )
//! }
//! ```
//!
//! Positions are object space in the file's own units and axes (Doom 3: inches, Z up);
//! the `.af` reader converts them together with the rest of the figure. Only the joints
//! are read; meshes, weights and everything after the joints block are skipped.

use super::af::AfError;
use super::af::lexer::{Cursor, Pos, Tok, tokenize};
use glam::{Quat, Vec3};
use std::path::Path;

/// One joint of the bind pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Md5Joint {
    /// Joint name.
    pub name: String,
    /// Index of the parent joint, `None` for a root (`-1`).
    pub parent: Option<usize>,
    /// Object-space position (file units and axes).
    pub position: Vec3,
    /// Object-space orientation; md5 stores x, y, z and w = -sqrt(1 - x² - y² - z²).
    pub orientation: Quat,
}

/// The bind-pose skeleton of an `.md5mesh`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Md5Skeleton {
    /// Joints in file order (parents come before children).
    pub joints: Vec<Md5Joint>,
}

impl Md5Skeleton {
    /// The joint with this name (Doom 3 compares joint names exactly).
    pub fn joint(&self, name: &str) -> Option<&Md5Joint> {
        self.joints.iter().find(|j| j.name == name)
    }
}

/// Reads the joints of an `.md5mesh` file.
pub fn load(path: &Path) -> Result<Md5Skeleton, AfError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| AfError {
        file: file.clone(),
        line: 1,
        col: 1,
        message: format!("cannot read the mesh: {e}"),
    })?;
    parse(&text, &file)
}

/// Parses the joints of md5mesh text; `file` names it in errors.
pub fn parse(text: &str, file: &str) -> Result<Md5Skeleton, AfError> {
    let tokens = tokenize(text, file)?;
    let mut r = Reader {
        c: Cursor::new(&tokens, file),
    };
    let version_pos = r.c.peek().pos;
    r.ident("MD5Version")?;
    let version = r.number("the md5 version")?;
    if version != 10.0 {
        return Err(AfError::at(
            file,
            version_pos,
            format!("MD5Version {version} is not supported; expected 10"),
        ));
    }
    let mut declared = None;
    // Skip header keys until the joints block.
    loop {
        let t = r.c.next();
        match &t.tok {
            Tok::Ident(k) if k == "numJoints" => declared = Some((r.number("numJoints")?, t.pos)),
            Tok::Ident(k) if k == "joints" => break,
            Tok::Eof => {
                return Err(AfError::at(
                    file,
                    t.pos,
                    "the mesh has no `joints {` block".into(),
                ));
            }
            _ => {}
        }
    }
    r.expect(&Tok::LBrace, "`{` after `joints`")?;
    let mut joints: Vec<Md5Joint> = Vec::new();
    loop {
        let t = r.c.next();
        let name = match &t.tok {
            Tok::RBrace => break,
            Tok::Str(s) => s.clone(),
            _ => return Err(r.c.unexpected(t, "a quoted joint name or `}`")),
        };
        let parent_pos = r.c.peek().pos;
        let parent = r.number("the parent index")?;
        let parent = if parent == -1.0 {
            None
        } else if parent >= 0.0 && parent.fract() == 0.0 && (parent as usize) < joints.len() {
            Some(parent as usize)
        } else {
            return Err(AfError::at(
                file,
                parent_pos,
                format!("parent index {parent} of joint \"{name}\" does not name an earlier joint"),
            ));
        };
        let p = r.vec3()?;
        let q = r.vec3()?;
        // md5 stores a unit quaternion's x, y, z; w is the non-positive root.
        let w = -(1.0 - q.length_squared()).max(0.0).sqrt();
        joints.push(Md5Joint {
            name,
            parent,
            position: p,
            orientation: Quat::from_xyzw(q.x, q.y, q.z, w).normalize(),
        });
    }
    if let Some((n, pos)) = declared
        && n != joints.len() as f64
    {
        return Err(AfError::at(
            file,
            pos,
            format!(
                "numJoints says {n} but the joints block lists {}",
                joints.len()
            ),
        ));
    }
    Ok(Md5Skeleton { joints })
}

struct Reader<'a> {
    c: Cursor<'a>,
}

impl<'a> Reader<'a> {
    fn expect(&mut self, tok: &Tok, what: &str) -> Result<Pos, AfError> {
        let t = self.c.next();
        if &t.tok == tok {
            Ok(t.pos)
        } else {
            Err(self.c.unexpected(t, what))
        }
    }

    fn ident(&mut self, word: &str) -> Result<(), AfError> {
        let t = self.c.next();
        match &t.tok {
            Tok::Ident(s) if s == word => Ok(()),
            _ => Err(self.c.unexpected(t, &format!("`{word}`"))),
        }
    }

    fn number(&mut self, what: &str) -> Result<f64, AfError> {
        let t = self.c.next();
        match t.tok {
            Tok::Num(n) if n.is_finite() => Ok(n),
            _ => Err(self.c.unexpected(t, &format!("a number ({what})"))),
        }
    }

    fn vec3(&mut self) -> Result<Vec3, AfError> {
        self.expect(&Tok::LParen, "`(`")?;
        let x = self.number("x")?;
        let y = self.number("y")?;
        let z = self.number("z")?;
        self.expect(&Tok::RParen, "`)`")?;
        Ok(Vec3::new(x as f32, y as f32, z as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MESH: &str = "MD5Version 10\ncommandline \"\"\nnumJoints 2\nnumMeshes 0\njoints {\n\t\"origin\" -1 ( 0 0 0 ) ( 0 0 0 )\n\t\"Hips\" 0 ( 1 2 40 ) ( 0 0 0.7071068 ) // hips\n}\n";

    #[test]
    fn reads_names_parents_positions() {
        let s = parse(MESH, "m").unwrap();
        assert_eq!(s.joints.len(), 2);
        let h = s.joint("Hips").unwrap();
        assert_eq!(h.parent, Some(0));
        assert_eq!(h.position, Vec3::new(1.0, 2.0, 40.0));
        assert!((h.orientation.length() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn wrong_parent_and_count_are_errors() {
        let bad = MESH.replace("\"Hips\" 0", "\"Hips\" 5");
        assert!(
            parse(&bad, "m")
                .unwrap_err()
                .message
                .contains("parent index")
        );
        let bad = MESH.replace("numJoints 2", "numJoints 3");
        assert!(parse(&bad, "m").unwrap_err().message.contains("numJoints"));
        assert!(parse("MD5Version 11", "m").is_err());
    }
}
