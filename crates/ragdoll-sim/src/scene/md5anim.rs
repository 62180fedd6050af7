//! The `.md5anim` (version 10) reader and the joint poses of its frames.
//!
//! ```text
//! MD5Version 10
//! commandline "..."
//! numFrames F   numJoints N   frameRate R   numAnimatedComponents C
//! hierarchy { "name" parent flags startIndex   × N }   // parent < index; -1: root
//! bounds    { ( min ) ( max )                  × F }   // model space
//! baseframe { ( tx ty tz ) ( qx qy qz )        × N }   // relative to the parent
//! frame k { C numbers }                        × F     // k = 0 … F−1 in order
//! ```
//!
//! A joint's pose in frame k starts from its baseframe entry; the flags say which of
//! Tx=1, Ty=2, Tz=4, Qx=8, Qy=16, Qz=32 the frame replaces, read in that order from
//! `startIndex`. A replaced quaternion component recomputes w (see
//! [`super::md5mesh::file_quat`] for the sign). Poses compose from the root:
//! R_w = R_p R_l, t_w = R_p t_l + t_p.

use super::Pose;
use super::file_error::{AfError, read_text};
use super::lexer::{Cursor, Tok, tokenize};
use super::md5mesh::{MAX_COUNT, Md5Skeleton, Reader, file_quat};
use glam::Vec3;
use std::path::Path;

/// One joint of the hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimJoint {
    /// Joint name (must equal the mesh's, case and all, as Doom 3 checks).
    pub name: String,
    /// Parent index, `None` for the root.
    pub parent: Option<usize>,
    /// Which components the frames animate: Tx=1, Ty=2, Tz=4, Qx=8, Qy=16, Qz=32.
    pub flags: u8,
    /// Where this joint's animated components start in a frame.
    pub start_index: usize,
}

/// A joint's baseframe entry: translation and quaternion x, y, z, parent-relative.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseJoint {
    /// Translation relative to the parent (file units).
    pub position: Vec3,
    /// The file's quaternion x, y, z.
    pub orientation: Vec3,
}

/// A whole `.md5anim`.
#[derive(Clone, Debug, PartialEq)]
pub struct Md5Anim {
    /// The hierarchy.
    pub joints: Vec<AnimJoint>,
    /// Frames per second (a whole number, at least 1).
    pub frame_rate: u32,
    /// Numbers per frame.
    pub num_animated_components: usize,
    /// Model-space bounds (min, max) per frame.
    pub bounds: Vec<[Vec3; 2]>,
    /// The baseframe.
    pub base: Vec<BaseJoint>,
    /// The frames' numbers, `num_animated_components` each.
    pub frames: Vec<Vec<f32>>,
}

impl Md5Anim {
    /// Number of frames (at least 1).
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// Every joint's parent-relative (translation, quaternion x y z) in `frame`.
    fn raw_locals(&self, frame: usize) -> Vec<BaseJoint> {
        let f = &self.frames[frame.min(self.frames.len() - 1)];
        self.joints
            .iter()
            .zip(&self.base)
            .map(|(j, b)| {
                let mut c = [
                    b.position.x,
                    b.position.y,
                    b.position.z,
                    b.orientation.x,
                    b.orientation.y,
                    b.orientation.z,
                ];
                let mut k = j.start_index;
                for (bit, v) in c.iter_mut().enumerate() {
                    if j.flags & (1 << bit) != 0 {
                        *v = f[k];
                        k += 1;
                    }
                }
                BaseJoint {
                    position: Vec3::new(c[0], c[1], c[2]),
                    orientation: Vec3::new(c[3], c[4], c[5]),
                }
            })
            .collect()
    }

    /// Every joint's parent-relative pose in `frame` (clamped to the last frame).
    pub fn local_poses(&self, frame: usize) -> Vec<Pose> {
        self.raw_locals(frame)
            .into_iter()
            .map(|b| Pose {
                position: b.position,
                rotation: file_quat(b.orientation),
            })
            .collect()
    }

    /// Parent-relative poses at `time` seconds, as Doom 3 samples a cycling animation:
    /// frame ⌊tR⌋ taken modulo F−1 (the last frame equals the first), translations
    /// lerped and rotations slerped toward the next frame.
    pub fn local_poses_at(&self, time: f32) -> Vec<Pose> {
        let n = self.frames.len();
        if n < 2 {
            return self.local_poses(0);
        }
        let ft = (time.max(0.0) * self.frame_rate as f32) as f64;
        let f1 = (ft.floor() as usize) % (n - 1);
        let t = (ft - ft.floor()) as f32;
        self.blend(f1, t)
    }

    /// Parent-relative poses a fraction `t` of the way from frame `f` to frame `f + 1`:
    /// translations lerped, rotations slerped.
    fn blend(&self, f: usize, t: f32) -> Vec<Pose> {
        let (a, b) = (self.local_poses(f), self.local_poses(f + 1));
        a.iter()
            .zip(&b)
            .map(|(a, b)| Pose {
                position: a.position.lerp(b.position, t),
                rotation: a.rotation.slerp(b.rotation, t),
            })
            .collect()
    }

    /// The animation's length (s): frames 0 … F−1 at `frameRate`, the last frame at
    /// (F−1)/R.
    pub fn duration(&self) -> f32 {
        (self.frames.len().saturating_sub(1)) as f32 / self.frame_rate as f32
    }

    /// Parent-relative poses at `time` seconds within one pass of the animation, without
    /// cycling: `time` is clamped to [0, (F−1)/R], translations are lerped and rotations
    /// slerped between the two frames around it. Unlike [`Md5Anim::local_poses_at`], the
    /// last frame is reached (with its root motion) rather than wrapped to the first.
    pub fn local_poses_within(&self, time: f32) -> Vec<Pose> {
        let n = self.frames.len();
        if n < 2 {
            return self.local_poses(0);
        }
        let ft = (time.max(0.0) * self.frame_rate as f32).min((n - 1) as f32);
        let f1 = (ft.floor() as usize).min(n - 2);
        let t = ft - f1 as f32;
        self.blend(f1, t)
    }

    /// Composes parent-relative poses into model space (parents come first).
    pub fn compose(&self, locals: &[Pose]) -> Vec<Pose> {
        let mut out: Vec<Pose> = Vec::with_capacity(locals.len());
        for (j, l) in self.joints.iter().zip(locals) {
            let w = match j.parent {
                None => *l,
                Some(p) => {
                    let p = out[p];
                    Pose {
                        position: p.position + p.rotation * l.position,
                        rotation: (p.rotation * l.rotation).normalize(),
                    }
                }
            };
            out.push(w);
        }
        out
    }

    /// Model-space joint poses of `frame`.
    pub fn frame_poses(&self, frame: usize) -> Vec<Pose> {
        self.compose(&self.local_poses(frame))
    }

    /// The skeleton `mesh` takes in this animation at `time` seconds, with the root joint
    /// at the model origin as idActor places it (root motion moves the entity, not the
    /// joint). Names and parents come from the mesh.
    pub fn pose_skeleton(&self, mesh: &Md5Skeleton, time: f32) -> Md5Skeleton {
        let mut locals = self.local_poses_at(time);
        locals[0].position = Vec3::ZERO;
        let poses = self.compose(&locals);
        let mut s = mesh.clone();
        for (j, p) in s.joints.iter_mut().zip(poses) {
            j.position = p.position;
            j.orientation = p.rotation;
        }
        s
    }

    /// Doom 3's `CheckModelHierarchy`: the same joint count, names (compared exactly)
    /// and parents as the mesh, else the animation cannot play on it.
    pub fn check_hierarchy(&self, mesh: &Md5Skeleton) -> Result<(), String> {
        if self.joints.len() != mesh.joints.len() {
            return Err(format!(
                "the animation has {} joints but the mesh has {}",
                self.joints.len(),
                mesh.joints.len()
            ));
        }
        for (a, m) in self.joints.iter().zip(&mesh.joints) {
            if a.name != m.name || a.parent != m.parent {
                return Err(format!(
                    "animation joint \"{}\" (parent {:?}) differs from mesh joint \"{}\" (parent {:?})",
                    a.name, a.parent, m.name, m.parent
                ));
            }
        }
        Ok(())
    }
}

/// Reads an `.md5anim` file.
pub fn load(path: &Path) -> Result<Md5Anim, AfError> {
    let text = read_text(path, "animation")?;
    parse(&text, &path.display().to_string())
}

/// Parses md5anim text; `file` names it in errors.
pub fn parse(text: &str, file: &str) -> Result<Md5Anim, AfError> {
    let tokens = tokenize(text, file)?;
    let mut r = Reader::new(Cursor::new(&tokens, file));
    r.version()?;
    r.optional_commandline()?;
    let (num_frames, frames_pos) = r.count_key("numFrames")?;
    if num_frames == 0 {
        return Err(r.err(frames_pos, "an animation needs at least one frame".into()));
    }
    let (num_joints, joints_pos) = r.count_key("numJoints")?;
    if num_joints == 0 {
        return Err(r.err(joints_pos, "an animation needs at least one joint".into()));
    }
    let (frame_rate, rate_pos) = r.count_key("frameRate")?;
    if frame_rate == 0 {
        return Err(r.err(rate_pos, "frameRate must be at least 1".into()));
    }
    let (components, comp_pos) = r.count_key("numAnimatedComponents")?;
    if components > 6 * num_joints {
        return Err(r.err(
            comp_pos,
            format!("numAnimatedComponents {components} exceeds 6 per joint ({num_joints} joints)"),
        ));
    }

    r.ident("hierarchy")?;
    r.expect(&Tok::LBrace, "`{` after `hierarchy`")?;
    let mut joints: Vec<AnimJoint> = Vec::new();
    for i in 0..num_joints {
        let name = r.string("a joint name")?;
        let parent_pos = r.c.peek().pos;
        let parent = r.parent(&name, joints.len())?;
        if parent.is_none() && i > 0 {
            return Err(r.err(
                parent_pos,
                format!("only the first joint may be a root; \"{name}\" has parent -1"),
            ));
        }
        let flags = r.whole("the flags", 63)? as u8;
        let start_pos = r.c.peek().pos;
        let start_index = r.whole("the start index", MAX_COUNT)?;
        let used = flags.count_ones() as usize;
        if start_index + used > components {
            return Err(r.err(
                start_pos,
                format!("joint \"{name}\" reads components {start_index}..{} but a frame has {components}", start_index + used),
            ));
        }
        joints.push(AnimJoint {
            name,
            parent,
            flags,
            start_index,
        });
    }
    r.expect(&Tok::RBrace, "`}` closing the hierarchy (numJoints joints)")?;

    r.ident("bounds")?;
    r.expect(&Tok::LBrace, "`{` after `bounds`")?;
    let mut bounds = Vec::new();
    for _ in 0..num_frames {
        bounds.push([r.vec3()?, r.vec3()?]);
    }
    r.expect(&Tok::RBrace, "`}` closing the bounds (numFrames entries)")?;

    r.ident("baseframe")?;
    r.expect(&Tok::LBrace, "`{` after `baseframe`")?;
    let mut base = Vec::new();
    for _ in 0..num_joints {
        base.push(BaseJoint {
            position: r.vec3()?,
            orientation: r.vec3()?,
        });
    }
    r.expect(
        &Tok::RBrace,
        "`}` closing the baseframe (numJoints entries)",
    )?;

    let mut frames = Vec::new();
    for k in 0..num_frames {
        r.ident("frame")?;
        let pos = r.c.peek().pos;
        let n = r.whole("the frame number", MAX_COUNT)?;
        if n != k {
            return Err(r.err(pos, format!("expected frame {k} here, found frame {n}")));
        }
        r.expect(&Tok::LBrace, "`{` after the frame number")?;
        let mut f = Vec::new();
        for _ in 0..components {
            f.push(r.number("an animated component")? as f32);
        }
        r.expect(
            &Tok::RBrace,
            "`}` closing the frame (numAnimatedComponents numbers)",
        )?;
        frames.push(f);
    }
    let t = r.c.next();
    if t.tok != Tok::Eof {
        return Err(r.c.unexpected(
            t,
            &format!("the end of the file (numFrames says {num_frames})"),
        ));
    }
    Ok(Md5Anim {
        joints,
        frame_rate: frame_rate as u32,
        num_animated_components: components,
        bounds,
        base,
        frames,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const ANIM: &str = "MD5Version 10\ncommandline \"\"\nnumFrames 2\nnumJoints 2\nframeRate 24\nnumAnimatedComponents 3\nhierarchy {\n\t\"origin\" -1 0 0\n\t\"Hips\" 0 36 0 // Tz and Qz\n}\nbounds {\n\t( -1 -1 0 ) ( 1 1 2 )\n\t( -1 -1 0 ) ( 1 1 2 )\n}\nbaseframe {\n\t( 0 0 0 ) ( 0 0 0 )\n\t( 0 0 40 ) ( 0 0 0 )\n}\nframe 0 {\n\t0 0 0\n}\nframe 1 {\n\t0 0 0\n}\n";

    #[test]
    fn flags_pick_components_in_order() {
        // Hips animates Tz (4) and Qz (32): two numbers from index 0; the third is spare.
        let text = ANIM
            .replace("numAnimatedComponents 3", "numAnimatedComponents 2")
            .replace("frame 1 {\n\t0 0 0", "frame 1 {\n\t50 0.7071068")
            .replace("frame 0 {\n\t0 0 0", "frame 0 {\n\t40 0");
        let a = parse(&text, "a").unwrap();
        let p = a.frame_poses(1);
        assert!((p[1].position - Vec3::new(0.0, 0.0, 50.0)).length() < 1e-5);
        // Qz = sin 45°: Doom's rotation turns X to −Y (the conjugate of the file's).
        assert!((p[1].rotation * Vec3::X - Vec3::NEG_Y).length() < 1e-4);
        let p0 = a.frame_poses(0);
        assert!((p0[1].position.z - 40.0).abs() < 1e-5);
        // Half-way between frames 0 and 1 at 24 fps.
        let mid = a.compose(&a.local_poses_at(0.5 / 24.0));
        assert!((mid[1].position.z - 45.0).abs() < 1e-3);
    }

    #[test]
    fn bad_input_is_a_located_error() {
        let at = |from: &str, to: &str| {
            assert!(ANIM.contains(from), "{from}");
            parse(&ANIM.replacen(from, to, 1), "a").unwrap_err()
        };
        assert!(at("36 0 //", "64 0 //").message.contains("flags"));
        assert!(at("36 0 //", "36 2 //").message.contains("components"));
        assert!(at("\"Hips\" 0", "\"Hips\" -1").message.contains("root"));
        assert!(
            at("frame 1 {", "frame 2 {")
                .message
                .contains("expected frame 1")
        );
        assert!(
            at("numAnimatedComponents 3", "numAnimatedComponents 13")
                .message
                .contains("exceeds")
        );
        let e = at("frameRate 24", "frameRate 0");
        assert_eq!((e.line, e.col), (5, 11));
    }
}
