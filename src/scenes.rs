//! The built-in scenes (the README's scene table) and loading any scene the CLI names.
//!
//! Every scene is an `.af` file under `assets/scenes/`; the files are also embedded in
//! the binary so `ragdoll-lab` works from any directory. `R` in the viewer re-reads the
//! file from disk when it is there.

use crate::AppError;
use crate::cli::SceneArgs;
use crate::render::skin::SkinModel;
use ragdoll_sim::SceneDesc;
use ragdoll_sim::scene::af::{self, AfOptions, AfScene, FigureSource};
use ragdoll_sim::scene::decl::{Doom3Base, Doom3Character};
use ragdoll_sim::scene::takeover::Takeover;
use ragdoll_sim::scene::{md5anim, md5mesh};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A scene loaded for a run.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The description with the variant applied.
    pub desc: SceneDesc,
    /// Where it came from (a file path, or the built-in scene's asset path).
    pub path: Option<PathBuf>,
    /// Keys the reader read but ignored, for `check` and the log.
    pub ignored: Vec<String>,
    /// The figure's skinned mesh and how its bodies drive it, when it has one.
    pub skin: Option<Arc<SkinModel>>,
    /// The animation the figure starts from (`--anim`), when one was asked for.
    pub animation: Option<SceneAnimation>,
}

/// An animation the figure plays before the ragdoll takes over (`--anim`, `--at`).
#[derive(Clone, Debug)]
pub struct SceneAnimation {
    /// The figure on the animation.
    pub takeover: Arc<Takeover>,
    /// When in the animation to start (s): the `--at` frame's time.
    pub start: f32,
}

impl LoadedScene {
    /// The scene as the ragdoll takes over from its animation at `time` (s): every body
    /// where the animation puts it, with the animation's velocities
    /// ([`Takeover::scene_at`]); the scene itself when it has no animation. Variant and
    /// settings stay the loaded ones.
    pub fn taken_over_at(&self, time: f32) -> LoadedScene {
        let mut out = self.clone();
        if let Some(a) = out.animation.take() {
            let settings = out.desc.settings.clone();
            out.desc = a.takeover.scene_at(time);
            out.desc.settings = settings;
        }
        out
    }

    /// [`LoadedScene::taken_over_at`] the `--at` frame: what `stats` and `capture` run.
    pub fn taken_over(&self) -> LoadedScene {
        match &self.animation {
            Some(a) => self.taken_over_at(a.start),
            None => self.clone(),
        }
    }
}

/// One scene of the built-in table, shipped as a file and embedded in the binary.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// Its number in the table (1-10), the `--scene` number.
    pub number: u32,
    /// Its name, the `--scene` name.
    pub name: &'static str,
    /// File name under `assets/scenes/`.
    pub file: &'static str,
    /// The file's text as built into the binary.
    pub text: &'static str,
}

impl BuiltinScene {
    /// The file on disk in this source tree (it may not exist where the binary runs).
    pub fn asset_path(&self) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes")
            .join(self.file)
    }
}

macro_rules! builtin {
    ($number:expr, $name:expr) => {
        BuiltinScene {
            number: $number,
            name: $name,
            file: concat!($name, ".af"),
            text: include_str!(concat!("../assets/scenes/", $name, ".af")),
        }
    };
}

static BUILTIN: [BuiltinScene; 10] = [
    builtin!(1, "collision"),
    builtin!(2, "ball-chain"),
    builtin!(3, "hinge-chain"),
    builtin!(4, "box-masses"),
    builtin!(5, "ball-limits"),
    builtin!(6, "hinge-limits"),
    builtin!(7, "spider"),
    builtin!(8, "human"),
    builtin!(9, "capsule-human"),
    builtin!(10, "pile"),
];

/// The built-in scenes, in order.
pub fn builtin_scenes() -> &'static [BuiltinScene] {
    &BUILTIN
}

/// The built-in scene with this number or name (case-insensitive).
pub fn find_builtin(key: &str) -> Option<&'static BuiltinScene> {
    let key = key.trim();
    match key.parse::<u32>() {
        Ok(n) => BUILTIN.iter().find(|s| s.number == n),
        Err(_) => BUILTIN.iter().find(|s| s.name.eq_ignore_ascii_case(key)),
    }
}

/// Loads the scene the arguments name (default: scene 8, the human).
pub fn load(args: &SceneArgs) -> Result<LoadedScene, AppError> {
    let opts = AfOptions {
        variant: args.variant.unwrap_or(1),
        mesh: args.mesh.clone(),
        count: args.count,
    };
    if let (Some(base), Some(entity)) = (&args.doom3, &args.entity) {
        let (scene, c) = load_entity(base, entity, &opts)?;
        let mesh = opts.mesh.clone().or(c.mesh.clone());
        let out = with_skin(
            loaded(scene.clone(), Some(c.af_file.clone())),
            &scene,
            mesh.as_deref(),
        )?;
        let anim = match &args.anim {
            Some(name) => Some((entity_anim(&c, entity, name)?, name.clone())),
            None => None,
        };
        return with_animation(out, &scene, mesh.as_deref(), anim, args.at);
    }
    if let Some(path) = &args.af {
        let source = FigureSource {
            base: args.doom3.clone(),
            ..FigureSource::default()
        };
        let scene =
            af::load_figure(path, &opts, &source).map_err(|e| AppError::Scene(e.to_string()))?;
        let out = with_skin(
            loaded(scene.clone(), Some(path.clone())),
            &scene,
            opts.mesh.as_deref(),
        )?;
        let anim = args
            .anim
            .as_ref()
            .map(|file| (PathBuf::from(file), file.clone()));
        if anim.is_some() && opts.mesh.is_none() {
            return Err(AppError::Usage(
                "--anim with --af needs the figure's skeleton: pass --mesh FILE.md5mesh".into(),
            ));
        }
        return with_animation(out, &scene, opts.mesh.as_deref(), anim, args.at);
    }
    if args.anim.is_some() {
        return Err(AppError::Usage(
            "--anim needs a Doom 3 figure: --doom3 BASE --entity NAME, or --af FILE --mesh FILE.md5mesh"
                .into(),
        ));
    }
    let key = args.scene.as_deref().unwrap_or("8");
    let builtin = find_builtin(key).ok_or_else(|| {
        let names: Vec<String> = BUILTIN
            .iter()
            .map(|s| format!("{} {}", s.number, s.name))
            .collect();
        AppError::Usage(format!(
            "unknown scene \"{key}\"; expected one of: {}",
            names.join(", ")
        ))
    })?;
    load_builtin(builtin, &opts)
}

/// Reads the figure of Doom 3 entity `entity` from the mod folder `base`: the entity's
/// `ragdoll` (or `articulatedFigure`) figure on its model's mesh, posed by the model's
/// `af_pose` when it has one, else in the bind pose. `opts.mesh` overrides the mesh.
pub fn load_entity(
    base: &Path,
    entity: &str,
    opts: &AfOptions,
) -> Result<(AfScene, Doom3Character), AppError> {
    let scene_err = |e: af::AfError| AppError::Scene(e.to_string());
    let decls = Doom3Base::open(base).map_err(scene_err)?;
    for w in &decls.warnings {
        eprintln!("warning: {w}");
    }
    let c = decls.character(entity).map_err(scene_err)?;
    let scene = af::load_character(&c, base, opts).map_err(scene_err)?;
    Ok((scene, c))
}

/// The file of anim `name` of the entity's model (Doom 3 compares anim names exactly).
fn entity_anim(c: &Doom3Character, entity: &str, name: &str) -> Result<PathBuf, AppError> {
    let found = c
        .anims
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, p)| p.clone())
        .or_else(|| c.af_pose.clone().filter(|_| name == "af_pose"));
    found.ok_or_else(|| {
        let mut names: Vec<&str> = c.af_pose.iter().map(|_| "af_pose").collect();
        names.extend(c.anims.iter().map(|(n, _)| n.as_str()));
        let have = if names.is_empty() {
            "it has none".to_string()
        } else {
            format!("it has {}", names.join(", "))
        };
        AppError::Usage(format!(
            "entity \"{entity}\" has no anim \"{name}\" (anim names compare exactly); {have}"
        ))
    })
}

/// Adds the animation `anim` (its file, and how the user named it) to a figure built on
/// the mesh `mesh`, starting at frame `at`.
fn with_animation(
    mut out: LoadedScene,
    scene: &AfScene,
    mesh: Option<&Path>,
    anim: Option<(PathBuf, String)>,
    at: Option<u32>,
) -> Result<LoadedScene, AppError> {
    let Some((file, name)) = anim else {
        return Ok(out);
    };
    let err = |e: String| AppError::Scene(e);
    let mesh = match mesh {
        Some(m) => md5mesh::load(m).map_err(|e| err(e.to_string()))?,
        None => {
            return Err(AppError::Usage(format!(
                "--anim {name}: the figure has no mesh to animate"
            )));
        }
    };
    let anim = md5anim::load(&file).map_err(|e| err(e.to_string()))?;
    let takeover = Takeover::new(&scene.desc, scene.rig.as_ref(), &mesh.skeleton, anim, &name)
        .map_err(|e| AppError::Usage(e.to_string()))?;
    let start = takeover
        .frame_time(at.unwrap_or(0))
        .map_err(|e| AppError::Usage(e.to_string()))?;
    out.animation = Some(SceneAnimation {
        takeover: Arc::new(takeover),
        start,
    });
    Ok(out)
}

/// Reads a built-in scene from its embedded text (messages name its asset path).
pub fn load_builtin(scene: &BuiltinScene, opts: &AfOptions) -> Result<LoadedScene, AppError> {
    let shown = Path::new("assets/scenes").join(scene.file);
    let parsed = af::parse(scene.text, &shown, opts).map_err(|e| AppError::Scene(e.to_string()))?;
    Ok(loaded(parsed, Some(scene.asset_path())))
}

/// Adds the skinned mesh to a figure read with a rig from the mesh file `mesh`.
fn with_skin(
    mut out: LoadedScene,
    scene: &AfScene,
    mesh: Option<&Path>,
) -> Result<LoadedScene, AppError> {
    if let (Some(rig), Some(path)) = (&scene.rig, mesh) {
        let mesh = md5mesh::load(path).map_err(|e| AppError::Scene(e.to_string()))?;
        out.skin = Some(Arc::new(SkinModel::new(
            rig.clone(),
            mesh,
            &scene.desc.bodies,
        )));
    }
    Ok(out)
}

fn loaded(scene: AfScene, path: Option<PathBuf>) -> LoadedScene {
    let ignored = scene
        .ignored
        .iter()
        .map(|i| format!("{}:{}: `{}`: {}", i.line, i.col, i.key, i.reason))
        .collect();
    LoadedScene {
        desc: scene.desc,
        path,
        ignored,
        skin: None,
        animation: None,
    }
}
