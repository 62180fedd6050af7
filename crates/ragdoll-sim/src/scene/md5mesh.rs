//! The `.md5mesh` (version 10) reader: the bind-pose skeleton that `joint("name")`,
//! `bonecenter(...)` and `bonedir(...)` in an `.af` file resolve against, and the
//! skinned meshes (shader, vertices with texture coordinates and weight ranges,
//! triangles, weights).
//!
//! ```text
//! MD5Version 10
//! commandline "..."                 // ignored
//! numJoints 2
//! numMeshes 1
//! joints {
//!     "origin"  -1 ( 0 0 0 ) ( 0 0 0 )     // name parent ( position ) ( orientation x y z )
//!     "Hips"     0 ( 0 0 40 ) ( 0 0 0 )
//! }
//! mesh {
//!     shader "models/test/skin"
//!     numverts 3
//!     vert 0 ( 0.5 0.5 ) 0 1            // texture s t, first weight, weight count
//!     ...
//!     numtris 1
//!     tri 0 0 1 2
//!     numweights 3
//!     weight 0 1 1.0 ( 0 0 5 )          // joint, bias, offset in the joint's frame
//!     ...
//! }
//! ```
//!
//! Joint positions and orientations are model space in the file's units and axes (Doom 3:
//! inches, Z up); the `.af` reader converts them with the rest of the figure. The number
//! after `vert`, `tri` and `weight` is discarded, as Doom 3 does: file order is the index.
//!
//! Quaternions: the file stores x, y, z of a unit quaternion; Doom 3 takes
//! w = +sqrt(|1 − x² − y² − z²|) but applies the Hamilton matrix to row vectors (v·M), so
//! the rotation it uses is the conjugate. As a column-vector (glam) rotation that is
//! `(x, y, z, −w)`, which is what [`file_quat`] returns.

use super::Pose;
use super::file_error::{AfError, read_text};
use super::lexer::{Cursor, Pos, Tok, tokenize};
use glam::{Quat, Vec2, Vec3};
use std::path::Path;

/// One joint of the bind pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Md5Joint {
    /// Joint name as written (lookups ignore case, as Doom 3's `Icmp` does).
    pub name: String,
    /// Index of the parent joint, `None` for a root (`-1`).
    pub parent: Option<usize>,
    /// Model-space position (file units and axes).
    pub position: Vec3,
    /// Model-space orientation, from the file's x, y, z by [`file_quat`].
    pub orientation: Quat,
}

impl Md5Joint {
    /// The joint's model-space pose.
    pub fn pose(&self) -> Pose {
        Pose {
            position: self.position,
            rotation: self.orientation,
        }
    }
}

/// A skeleton: the bind pose of an `.md5mesh`, or an animation frame's pose of it.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Md5Skeleton {
    /// Joints in file order (parents come before children).
    pub joints: Vec<Md5Joint>,
}

impl Md5Skeleton {
    /// The first dozen joint names, comma-separated, with ", ..." when there are more:
    /// what an error about an unknown joint lists.
    pub fn some_joint_names(&self) -> String {
        let names: Vec<&str> = self
            .joints
            .iter()
            .take(12)
            .map(|j| j.name.as_str())
            .collect();
        let more = if self.joints.len() > 12 { ", ..." } else { "" };
        format!("{}{more}", names.join(", "))
    }

    /// The index of the joint with this name, compared without regard to ASCII case
    /// (Doom 3's `idRenderModelMD5::GetJointHandle` and `idDeclModelDef::FindJoint`).
    pub fn index(&self, name: &str) -> Option<usize> {
        self.joints
            .iter()
            .position(|j| j.name.eq_ignore_ascii_case(name))
    }

    /// The joint with this name, compared without regard to ASCII case.
    pub fn joint(&self, name: &str) -> Option<&Md5Joint> {
        self.index(name).map(|i| &self.joints[i])
    }

    /// Every joint's model-space pose, in joint order.
    pub fn poses(&self) -> Vec<Pose> {
        self.joints.iter().map(Md5Joint::pose).collect()
    }
}

/// One weight: a joint, how much it counts, and where the vertex sits in its frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Md5Weight {
    /// Joint index.
    pub joint: u32,
    /// Bias (Doom 3 does not renormalise a vertex's biases).
    pub bias: f32,
    /// Position in the joint's frame (file units).
    pub offset: Vec3,
}

/// One vertex: texture coordinates and a range of the mesh's weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Md5Vertex {
    /// Texture coordinates (s, t).
    pub uv: Vec2,
    /// First weight index.
    pub first_weight: u32,
    /// Number of weights (at least one).
    pub weight_count: u32,
}

/// One `mesh { ... }` block.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Md5SubMesh {
    /// The optional `name`.
    pub name: Option<String>,
    /// The material (`shader`).
    pub shader: String,
    /// Vertices in file order.
    pub vertices: Vec<Md5Vertex>,
    /// Triangles as vertex indices, in the file's winding (Doom 3's front faces are
    /// clockwise as seen).
    pub triangles: Vec<[u32; 3]>,
    /// Weights in file order.
    pub weights: Vec<Md5Weight>,
}

impl Md5SubMesh {
    /// Vertex positions for model-space joint poses `joints` (one per skeleton joint):
    /// p = Σₖ biasₖ (tₖ + Rₖ oₖ). The offsets are in each joint's frame, so no inverse
    /// bind matrices are needed.
    pub fn skin(&self, joints: &[Pose]) -> Vec<Vec3> {
        self.vertices
            .iter()
            .map(|v| {
                let first = v.first_weight as usize;
                self.weights[first..first + v.weight_count as usize]
                    .iter()
                    .map(|w| {
                        let j = &joints[w.joint as usize];
                        (j.position + j.rotation * w.offset) * w.bias
                    })
                    .sum()
            })
            .collect()
    }
}

/// A whole `.md5mesh`: skeleton and meshes.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Md5Mesh {
    /// The bind pose.
    pub skeleton: Md5Skeleton,
    /// The meshes in file order.
    pub meshes: Vec<Md5SubMesh>,
}

/// The rotation Doom 3 applies for a file's quaternion x, y, z (see the module docs).
pub fn file_quat(xyz: Vec3) -> Quat {
    let w = (1.0 - xyz.length_squared()).abs().sqrt();
    Quat::from_xyzw(xyz.x, xyz.y, xyz.z, -w).normalize()
}

/// Reads an `.md5mesh` file; a file that cannot be read is an error at 1:1.
pub fn load(path: &Path) -> Result<Md5Mesh, AfError> {
    let file = path.display().to_string();
    let text = read_text(path, "mesh")?;
    parse(&text, &file)
}

/// Parses md5mesh text; `file` names it in errors.
pub fn parse(text: &str, file: &str) -> Result<Md5Mesh, AfError> {
    let tokens = tokenize(text, file)?;
    let mut r = Reader::new(Cursor::new(&tokens, file));
    r.version()?;
    r.optional_commandline()?;
    let (num_joints, joints_pos) = r.count_key("numJoints")?;
    let (num_meshes, _) = r.count_key("numMeshes")?;
    r.ident("joints")?;
    r.expect(&Tok::LBrace, "`{` after `joints`")?;
    let mut joints: Vec<Md5Joint> = Vec::new();
    loop {
        let t = r.c.next();
        let name = match &t.tok {
            Tok::RBrace => break,
            Tok::Str(s) => s.clone(),
            _ => return Err(r.c.unexpected(t, "a quoted joint name or `}`")),
        };
        let parent = r.parent(&name, joints.len())?;
        let position = r.vec3()?;
        let orientation = file_quat(r.vec3()?);
        joints.push(Md5Joint {
            name,
            parent,
            position,
            orientation,
        });
    }
    if num_joints != joints.len() {
        return Err(r.err(
            joints_pos,
            format!(
                "numJoints says {num_joints} but the joints block lists {}",
                joints.len()
            ),
        ));
    }
    let mut meshes = Vec::new();
    for _ in 0..num_meshes {
        meshes.push(r.mesh(joints.len())?);
    }
    let t = r.c.next();
    if t.tok != Tok::Eof {
        return Err(r.c.unexpected(
            t,
            &format!("the end of the file (numMeshes says {num_meshes})"),
        ));
    }
    Ok(Md5Mesh {
        skeleton: Md5Skeleton { joints },
        meshes,
    })
}

/// Token reading shared by the md5mesh and md5anim readers.
pub(crate) struct Reader<'a> {
    pub(crate) c: Cursor<'a>,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(c: Cursor<'a>) -> Reader<'a> {
        Reader { c }
    }

    pub(crate) fn err(&self, pos: Pos, message: String) -> AfError {
        AfError::at(self.c.file(), pos, message)
    }

    pub(crate) fn expect(&mut self, tok: &Tok, what: &str) -> Result<Pos, AfError> {
        let t = self.c.next();
        if &t.tok == tok {
            Ok(t.pos)
        } else {
            Err(self.c.unexpected(t, what))
        }
    }

    /// The keyword `word` (md5 keywords compare exactly, as Doom 3's do).
    pub(crate) fn ident(&mut self, word: &str) -> Result<Pos, AfError> {
        let t = self.c.next();
        match &t.tok {
            Tok::Ident(s) if s == word => Ok(t.pos),
            _ => Err(self.c.unexpected(t, &format!("`{word}`"))),
        }
    }

    pub(crate) fn number(&mut self, what: &str) -> Result<f64, AfError> {
        let t = self.c.next();
        match t.tok {
            Tok::Num(n) if n.is_finite() && (n as f32).is_finite() => Ok(n),
            _ => Err(self.c.unexpected(t, &format!("a number ({what})"))),
        }
    }

    /// A whole number from 0 to `max`.
    pub(crate) fn whole(&mut self, what: &str, max: usize) -> Result<usize, AfError> {
        let pos = self.c.peek().pos;
        let n = self.number(what)?;
        if n >= 0.0 && n.fract() == 0.0 && n <= max as f64 {
            Ok(n as usize)
        } else {
            Err(self.err(
                pos,
                format!("{what} must be a whole number from 0 to {max}; found {n}"),
            ))
        }
    }

    /// `key N` with N a count (at most [`MAX_COUNT`]), and where N was written.
    pub(crate) fn count_key(&mut self, key: &str) -> Result<(usize, Pos), AfError> {
        self.ident(key)?;
        let pos = self.c.peek().pos;
        Ok((self.whole(key, MAX_COUNT)?, pos))
    }

    pub(crate) fn version(&mut self) -> Result<(), AfError> {
        self.ident("MD5Version")?;
        let pos = self.c.peek().pos;
        let version = self.number("the md5 version")?;
        if version != 10.0 {
            return Err(self.err(
                pos,
                format!("MD5Version {version} is not supported; expected 10"),
            ));
        }
        Ok(())
    }

    pub(crate) fn optional_commandline(&mut self) -> Result<(), AfError> {
        if matches!(&self.c.peek().tok, Tok::Ident(k) if k == "commandline") {
            self.c.next();
            let t = self.c.next();
            if !matches!(t.tok, Tok::Str(_)) {
                return Err(self.c.unexpected(t, "a quoted command line"));
            }
        }
        Ok(())
    }

    /// A joint's parent index: -1 for a root, else an earlier joint (`count` so far).
    pub(crate) fn parent(&mut self, name: &str, count: usize) -> Result<Option<usize>, AfError> {
        let pos = self.c.peek().pos;
        let parent = self.number("the parent index")?;
        if parent == -1.0 {
            Ok(None)
        } else if parent >= 0.0 && parent.fract() == 0.0 && (parent as usize) < count {
            Ok(Some(parent as usize))
        } else {
            Err(self.err(
                pos,
                format!("parent index {parent} of joint \"{name}\" does not name an earlier joint"),
            ))
        }
    }

    pub(crate) fn vec3(&mut self) -> Result<Vec3, AfError> {
        self.expect(&Tok::LParen, "`(`")?;
        let x = self.number("x")?;
        let y = self.number("y")?;
        let z = self.number("z")?;
        self.expect(&Tok::RParen, "`)`")?;
        Ok(Vec3::new(x as f32, y as f32, z as f32))
    }

    fn mesh(&mut self, num_joints: usize) -> Result<Md5SubMesh, AfError> {
        self.ident("mesh")?;
        self.expect(&Tok::LBrace, "`{` after `mesh`")?;
        let mut m = Md5SubMesh::default();
        if matches!(&self.c.peek().tok, Tok::Ident(k) if k == "name") {
            self.c.next();
            m.name = Some(self.string("the mesh's name")?);
        }
        self.ident("shader")?;
        m.shader = self.string("the shader name")?;

        let (numverts, _) = self.count_key("numverts")?;
        let mut ranges = Vec::new();
        for _ in 0..numverts {
            self.ident("vert")?;
            self.number("the vertex index")?;
            self.expect(&Tok::LParen, "`(`")?;
            let s = self.number("s")? as f32;
            let t = self.number("t")? as f32;
            self.expect(&Tok::RParen, "`)`")?;
            let first_pos = self.c.peek().pos;
            let first = self.whole("the first weight", MAX_COUNT)?;
            let count_pos = self.c.peek().pos;
            let count = self.whole("the weight count", MAX_COUNT)?;
            if count == 0 {
                return Err(self.err(
                    count_pos,
                    format!("vertex {} has no weights", m.vertices.len()),
                ));
            }
            ranges.push((first_pos, first + count));
            m.vertices.push(Md5Vertex {
                uv: Vec2::new(s, t),
                first_weight: first as u32,
                weight_count: count as u32,
            });
        }
        let (numtris, _) = self.count_key("numtris")?;
        for _ in 0..numtris {
            self.ident("tri")?;
            self.number("the triangle index")?;
            let mut tri = [0u32; 3];
            for corner in &mut tri {
                let pos = self.c.peek().pos;
                let v = self.whole("a vertex index", MAX_COUNT)?;
                if v >= numverts {
                    return Err(self.err(
                        pos,
                        format!(
                            "vertex index {v} is out of range; the mesh has {numverts} vertices"
                        ),
                    ));
                }
                *corner = v as u32;
            }
            m.triangles.push(tri);
        }
        let (numweights, _) = self.count_key("numweights")?;
        for _ in 0..numweights {
            self.ident("weight")?;
            self.number("the weight index")?;
            let pos = self.c.peek().pos;
            let joint = self.whole("the weight's joint", MAX_COUNT)?;
            if joint >= num_joints {
                return Err(self.err(
                    pos,
                    format!(
                        "weight joint {joint} is out of range; the mesh has {num_joints} joints"
                    ),
                ));
            }
            let bias = self.number("the bias")? as f32;
            let offset = self.vec3()?;
            m.weights.push(Md5Weight {
                joint: joint as u32,
                bias,
                offset,
            });
        }
        self.expect(&Tok::RBrace, "`}` closing the mesh")?;
        // Doom 3 only warns here and reads past the weights; we refuse it, since
        // skinning would read weights that are not there.
        for (i, (pos, end)) in ranges.into_iter().enumerate() {
            if end > numweights {
                return Err(self.err(
                    pos,
                    format!(
                        "vertex {i} uses weights up to {} but the mesh has {numweights}",
                        end - 1
                    ),
                ));
            }
        }
        Ok(m)
    }

    pub(crate) fn string(&mut self, what: &str) -> Result<String, AfError> {
        let t = self.c.next();
        match &t.tok {
            Tok::Str(s) => Ok(s.clone()),
            _ => Err(self.c.unexpected(t, &format!("a quoted string ({what})"))),
        }
    }
}

/// The largest count or index the md5 readers accept (far above any real model; keeps
/// a mistyped count from asking for absurd memory).
pub(crate) const MAX_COUNT: usize = 1 << 24;

#[cfg(test)]
mod tests {
    use super::*;

    const MESH: &str = "MD5Version 10\ncommandline \"\"\nnumJoints 2\nnumMeshes 1\njoints {\n\t\"origin\" -1 ( 0 0 0 ) ( 0 0 0 )\n\t\"Hips\" 0 ( 1 2 40 ) ( 0 0 0.7071068 ) // hips\n}\nmesh {\n\tshader \"skin\"\n\tnumverts 2\n\tvert 0 ( 0 1 ) 0 1\n\tvert 1 ( 1 0 ) 1 2\n\tnumtris 1\n\ttri 0 0 1 1\n\tnumweights 3\n\tweight 0 1 1 ( 0 0 5 )\n\tweight 1 0 0.5 ( 1 0 0 )\n\tweight 2 1 0.5 ( 1 0 0 )\n}\n";

    #[test]
    fn reads_names_parents_positions_and_meshes() {
        let m = parse(MESH, "m").unwrap();
        let s = &m.skeleton;
        assert_eq!(s.joints.len(), 2);
        let h = s.joint("hips").unwrap();
        assert_eq!(h.parent, Some(0));
        assert_eq!(h.position, Vec3::new(1.0, 2.0, 40.0));
        assert!((h.orientation.length() - 1.0).abs() < 1e-5);
        let sm = &m.meshes[0];
        assert_eq!(sm.shader, "skin");
        assert_eq!(sm.vertices[1].uv, Vec2::new(1.0, 0.0));
        assert_eq!(
            (sm.vertices[1].first_weight, sm.vertices[1].weight_count),
            (1, 2)
        );
        assert_eq!(sm.triangles, vec![[0, 1, 1]]);
        assert_eq!(sm.weights[2].joint, 1);
    }

    #[test]
    fn doom_applies_the_conjugate_of_the_file_quaternion() {
        // x, y, z = (0, 0, sin 45°): Doom's w is +cos 45°, and v·M with that quaternion
        // turns X to −Y, i.e. −90° about Z as a column-vector rotation.
        let q = file_quat(Vec3::new(0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2));
        assert!((q * Vec3::X - Vec3::NEG_Y).length() < 1e-5);
    }

    #[test]
    fn skinning_sums_biased_joint_space_offsets() {
        let m = parse(MESH, "m").unwrap();
        let poses = m.skeleton.poses();
        let p = m.meshes[0].skin(&poses);
        // Vertex 0: one weight on Hips at ( 0 0 5 ): the Hips position plus R·(0, 0, 5).
        let hips = poses[1];
        assert!(
            (p[0] - (hips.position + hips.rotation * Vec3::new(0.0, 0.0, 5.0))).length() < 1e-5
        );
        // Vertex 1: half origin's ( 1 0 0 ), half Hips' ( 1 0 0 ).
        let expect = 0.5 * Vec3::X + 0.5 * (hips.position + hips.rotation * Vec3::X);
        assert!((p[1] - expect).length() < 1e-5);
    }

    #[test]
    fn bad_input_is_a_located_error() {
        let at = |from: &str, to: &str| {
            assert!(MESH.contains(from), "{from}");
            parse(&MESH.replacen(from, to, 1), "m").unwrap_err()
        };
        let e = at("\"Hips\" 0", "\"Hips\" 5");
        assert!(e.message.contains("parent index"), "{e}");
        assert_eq!((e.line, e.col), (7, 9));
        assert!(
            at("numJoints 2", "numJoints 3")
                .message
                .contains("numJoints")
        );
        assert!(
            at("vert 1 ( 1 0 ) 1 2", "vert 1 ( 1 0 ) 1 0")
                .message
                .contains("no weights")
        );
        assert!(
            at("vert 1 ( 1 0 ) 1 2", "vert 1 ( 1 0 ) 2 2")
                .message
                .contains("weights up to 3")
        );
        assert!(
            at("tri 0 0 1 1", "tri 0 0 1 2")
                .message
                .contains("out of range")
        );
        assert!(
            at("weight 2 1", "weight 2 2")
                .message
                .contains("out of range")
        );
        assert!(at("numMeshes 1", "numMeshes 2").message.contains("`mesh`"));
        assert!(parse("MD5Version 11", "m").is_err());
        // A byte-order mark and a comment before the version are accepted.
        assert!(parse(&format!("\u{feff}// x\n{MESH}"), "m").is_ok());
    }
}
