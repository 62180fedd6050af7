//! The command line (`docs/cli.md`). Tests and checks call it; keep it stable.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Particle (Verlet) and impulse-based multibody ragdolls, side by side.
#[derive(Parser, Debug)]
#[command(name = "ragdoll-lab", version, about)]
pub struct Cli {
    /// What to do; the window (`view`) when omitted.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Options of `view`, usable without the subcommand name.
    #[command(flatten)]
    pub view: ViewArgs,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the split-screen window (the default).
    View(ViewArgs),
    /// Render offscreen to PNG, no window.
    Capture(CaptureArgs),
    /// Run a scene headless and print its metrics as JSON.
    Stats(StatsArgs),
    /// Read an .af file and print a summary, or the first error with its position.
    Check(CheckArgs),
    /// Performance tables (the paper's tests 9-12, scale).
    Bench(BenchArgs),
}

/// Which scene to load: a built-in one by number or name, or any .af file.
#[derive(Args, Debug, Clone, Default)]
pub struct SceneArgs {
    /// Scene number (1-10) or name (collision, ball-chain, ..., pile).
    #[arg(long, short = 's')]
    pub scene: Option<String>,
    /// Variant (the paper's keys 1/2/3).
    #[arg(long, short = 'v')]
    pub variant: Option<u32>,
    /// Load this .af file instead of a built-in scene.
    #[arg(long, conflicts_with = "scene")]
    pub af: Option<PathBuf>,
    /// The .md5mesh bind pose for joint("name") references (overrides the file's `mesh`).
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Number of humans for the pile scene.
    #[arg(long)]
    pub count: Option<u32>,
    /// A Doom 3 mod's base folder (holding def/, af/, models/): `--entity` is looked up
    /// in it, and an --af file's `settings { model }` resolves through its declarations.
    #[arg(long, value_name = "BASE")]
    pub doom3: Option<PathBuf>,
    /// An entityDef of the --doom3 folder: its figure (`ragdoll` or
    /// `articulatedFigure`), built on its model's mesh in the `af_pose` frame.
    #[arg(long, requires = "doom3", conflicts_with_all = ["scene", "af"])]
    pub entity: Option<String>,
    /// Start from an animation: one of the --entity model's anims by name (`walk`), or
    /// with --af and --mesh an .md5anim file. The figure is placed on its frame --at
    /// with the animation's velocities (`stats`, `capture`); `view` plays it on the
    /// skinned model until K hands over to the ragdoll.
    #[arg(long, value_name = "NAME|FILE")]
    pub anim: Option<String>,
    /// The --anim frame (0-based) the ragdoll takes over at, or `view` starts playing
    /// from. Default 0.
    #[arg(long, value_name = "FRAME", requires = "anim")]
    pub at: Option<u32>,
}

/// The particle method's solver.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ParticleSolverArg {
    /// Section 3 of the paper, as written.
    Paper,
    /// Position-based rigid bones (rigid frames with evaluated corner particles),
    /// particulated mass properties, substeps, friction, sleeping.
    #[default]
    RigidFrames,
    /// XPBD on particles with small steps: every particle keeps its own position and
    /// velocity; bones are particulated tetrahedra of sticks; joints, limits and
    /// contacts are constraints on the particles.
    Xpbd,
}

/// `view` options.
#[derive(Args, Debug, Clone, Default)]
pub struct ViewArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The particle method's solver.
    #[arg(long, value_enum, default_value_t)]
    pub particle_solver: ParticleSolverArg,
    /// Override the scene's timestep (s); kept across resets, as the panel's slider.
    #[arg(long)]
    pub timestep: Option<f32>,
    /// Override the scene's iterations (both methods).
    #[arg(long)]
    pub iterations: Option<u32>,
    /// Override the scene's substeps (both methods).
    #[arg(long)]
    pub substeps: Option<u32>,
    /// Open stopped at t = 0 (Space or S starts).
    #[arg(long)]
    pub paused: bool,
}

/// `capture` options.
#[derive(Args, Debug, Clone)]
pub struct CaptureArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The particle method's solver.
    #[arg(long, value_enum, default_value_t)]
    pub particle_solver: ParticleSolverArg,
    /// Frames to simulate before the (last) capture.
    #[arg(long, default_value_t = 0)]
    pub frames: u32,
    /// Image size, WxH.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Output PNG (single capture).
    #[arg(long, required_unless_present = "out_dir")]
    pub out: Option<PathBuf>,
    /// Capture every K frames into --out-dir.
    #[arg(long, requires = "out_dir")]
    pub every: Option<u32>,
    /// Directory for a frame sequence.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Draw the egui overlay too.
    #[arg(long)]
    pub ui: bool,
}

/// Which methods `stats` runs.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MethodArg {
    /// The particle method only.
    Particle,
    /// The multibody method only.
    Multibody,
    /// Both.
    #[default]
    Both,
}

/// `stats` options.
#[derive(Args, Debug, Clone)]
pub struct StatsArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Simulated seconds.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Which method(s).
    #[arg(long, value_enum, default_value_t)]
    pub method: MethodArg,
    /// The particle method's solver.
    #[arg(long, value_enum, default_value_t)]
    pub particle_solver: ParticleSolverArg,
    /// Override the scene's timestep (s).
    #[arg(long)]
    pub timestep: Option<f32>,
    /// Override the scene's iterations (both methods).
    #[arg(long)]
    pub iterations: Option<u32>,
    /// Override the scene's substeps.
    #[arg(long)]
    pub substeps: Option<u32>,
    /// Write a JSON-lines trace of every frame here.
    #[arg(long)]
    pub trace: Option<PathBuf>,
}

/// `check` options.
#[derive(Args, Debug, Clone)]
pub struct CheckArgs {
    /// The .af file.
    #[arg(required_unless_present = "entity")]
    pub file: Option<PathBuf>,
    /// The .md5mesh bind pose for joint("name") references.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// A Doom 3 mod's base folder (see `view --doom3`).
    #[arg(long, value_name = "BASE")]
    pub doom3: Option<PathBuf>,
    /// An entityDef of the --doom3 folder to check instead of a file.
    #[arg(long, requires = "doom3", conflicts_with = "file")]
    pub entity: Option<String>,
}

/// Which benchmark.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum BenchKind {
    /// Test 9: bytes per simulation as bones grow.
    Memory,
    /// Test 10: t_real/t_sim against the timestep.
    Timestep,
    /// Test 11: t_real/t_sim against the number of bones.
    Bones,
    /// Test 12: t_real/t_sim against the iterations.
    Iterations,
    /// The pile of humans: ms per frame, 1 and all threads.
    Scale,
    /// Humans dropped in groups at a steady rate: µs per moving body per step.
    Rain,
}

/// `bench` options.
#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// Which table.
    #[arg(value_enum)]
    pub kind: BenchKind,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Smoke test: tiny sizes and a few frames, seconds in all (for CI; the figures
    /// mean nothing).
    #[arg(long)]
    pub quick: bool,
    /// Run only the rows whose first column is one of these (bones, timestep, iterations
    /// or humans), e.g. `--only 1920` to profile one size.
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<f64>,
    /// Sleeping off in both methods: every body stays awake, so the figures compare
    /// solvers, not sleep policies (scale and rain; the paper's tests never sleep).
    #[arg(long)]
    pub no_sleep: bool,
    /// The particle solver the scale and rain tables time beside the multibody.
    #[arg(long, value_enum, default_value_t)]
    pub particle_solver: ParticleSolverArg,
}
