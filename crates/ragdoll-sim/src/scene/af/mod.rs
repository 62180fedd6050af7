//! The Doom 3 articulated-figure (`.af`) reader, with our extensions.
//!
//! Every scene of ragdoll-lab is an `.af` file. The reader takes Doom 3's syntax as
//! MrElusive's document describes it (settings, bodies, the six constraint types, the
//! four vector forms, every collision model, `totalMass`) plus the keys real id files
//! use, and adds what a Doom 3 file cannot say: units and up axis, ground, camera,
//! timestep and iterations, variants, twist limits, fixed bodies, initial velocities,
//! explicit particles, a figure transform and a grid of copies. `docs/af-format.md` is
//! the user's reference; this module is the implementation:
//!
//! - `parser`: tokens to blocks of `key value, ...` entries, all positions kept.
//! - `ctx`: units and axes, the four vector forms against the `.md5mesh`, typed values
//!   with positioned errors, the ignored-key list.
//! - `build`: the pipeline — variants, settings and our scene blocks, validation, masses.
//! - `body`, `models`: a body block; Doom 3 collision models as our shapes.
//! - `constraint`: the six constraint types and their limits.
//! - `contained`: `containedJoints`, the mesh parts each body contains.
//! - `place`: the `transform` block and the `replicate` grid.
//!
//! Axis mapping: a Z-up file (Doom 3's default) maps `(x, y, z)` to `(x, z, -y)`, a
//! proper rotation, so handedness and the sign of every angle are kept; a Y-up file is
//! taken as is. Lengths are multiplied by the unit (`inch` = 0.0254 m by default).

mod body;
mod build;
mod constraint;
mod contained;
mod ctx;
pub(crate) mod models;
mod parser;
mod place;

pub use crate::scene::AfError;
use crate::scene::SceneDesc;
use crate::scene::decl::Doom3Character;
use crate::scene::file_error::read_text;
use crate::scene::lexer;
use std::path::{Path, PathBuf};

/// What to build from a file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AfOptions {
    /// Variant to apply, 1-based (the paper's keys 1/2/3). Default 1.
    pub variant: u32,
    /// The `.md5mesh` for `joint("name")` references; overrides the file's `mesh` key.
    pub mesh: Option<PathBuf>,
    /// Number of copies of the figure (overrides a `replicate` block's `count`).
    pub count: Option<u32>,
}

impl Default for AfOptions {
    fn default() -> Self {
        AfOptions {
            variant: 1,
            mesh: None,
            count: None,
        }
    }
}

/// Where a Doom 3 figure's skeleton comes from beyond [`AfOptions::mesh`]: which figure
/// of the file, which animation poses it, and the mod's base folder through which
/// `settings { model "..." }` resolves. [`super::decl::Doom3Base::character`] fills it
/// for an entity.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FigureSource {
    /// The `articulatedFigure` to build when the file declares several (by name,
    /// without regard to case); `None`: all of the file's blocks.
    pub figure: Option<String>,
    /// The `.md5anim` whose first frame poses the mesh (Doom 3's `anim af_pose`); `None`:
    /// the mesh's bind pose.
    pub pose_anim: Option<PathBuf>,
    /// A Doom 3 base folder: a settings `model` then names a model declaration (its
    /// mesh and `af_pose`) or a path relative to this folder, as the engine reads it.
    pub base: Option<PathBuf>,
}

/// A key the reader understood but does not use, with why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ignored {
    /// 1-based line of the key.
    pub line: u32,
    /// 1-based column of the key.
    pub col: u32,
    /// The key as written.
    pub key: String,
    /// Why it has no effect here.
    pub reason: String,
}

/// A file read into a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct AfScene {
    /// The validated description, masses resolved to kilograms.
    pub desc: SceneDesc,
    /// Keys that were read but have no effect.
    pub ignored: Vec<Ignored>,
    /// How the bodies drive the mesh's skeleton (joints in our units and axes, body
    /// poses as the description's shape frames), when the figure was built on a mesh
    /// and placed as one copy where the file put it.
    pub rig: Option<crate::scene::rig::Rig>,
}

/// Reads `.af` text. `file` names it in messages and anchors a relative `mesh` path.
pub fn parse(text: &str, file: &Path, opts: &AfOptions) -> Result<AfScene, AfError> {
    parse_figure(text, file, opts, &FigureSource::default())
}

/// Reads `.af` text with the skeleton from `source`.
pub fn parse_figure(
    text: &str,
    file: &Path,
    opts: &AfOptions,
    source: &FigureSource,
) -> Result<AfScene, AfError> {
    let name = file.display().to_string();
    let tokens = lexer::tokenize(text, &name)?;
    let blocks = parser::parse(&tokens, &name)?;
    build::build(blocks, file, opts, source)
}

/// Reads an `.af` file from disk with the skeleton from `source`.
pub fn load_figure(
    path: &Path,
    opts: &AfOptions,
    source: &FigureSource,
) -> Result<AfScene, AfError> {
    let text = read_text(path, "file")?;
    parse_figure(&text, path, opts, source)
}

/// Builds an entity's figure as the engine does: the `articulatedFigure` its declarations
/// name, on its mesh (unless `opts` names another), posed by its model's `af_pose`, with
/// `base` (the Doom 3 base folder the declarations came from) resolving the file's
/// `settings { model }`.
pub fn load_character(
    c: &Doom3Character,
    base: &Path,
    opts: &AfOptions,
) -> Result<AfScene, AfError> {
    let opts = AfOptions {
        mesh: opts.mesh.clone().or_else(|| c.mesh.clone()),
        ..opts.clone()
    };
    let source = FigureSource {
        figure: Some(c.figure.clone()),
        pose_anim: c.af_pose.clone(),
        base: Some(base.to_path_buf()),
    };
    load_figure(&c.af_file, &opts, &source)
}

/// Reads an `.af` file from disk.
pub fn load(path: &Path, opts: &AfOptions) -> Result<AfScene, AfError> {
    load_figure(path, opts, &FigureSource::default())
}
