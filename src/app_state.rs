//! The app's state machine, independent of any window: running or paused, single steps,
//! scene and variant, the right-click menu, slow motion, overlay toggles, and the fixed
//! timestep accumulator. [`crate::input`] turns keys and mouse into [`Action`]s; the
//! window and the egui panel apply them here, so tests can drive it without a window.

use crate::cli::ParticleSolverArg;
use crate::render::ShowOptions;
use crate::render::camera::OrbitCamera;
use crate::session::ShotSettings;
use glam::Vec2;
use ragdoll_sim::scene::{BodyId, Settings};

/// The built-in scenes in order (the README's scene table); Tab walks this list.
pub const SCENES: [&str; 10] = [
    "collision",
    "ball-chain",
    "hinge-chain",
    "box-masses",
    "ball-limits",
    "hinge-limits",
    "spider",
    "human",
    "capsule-human",
    "pile",
];

/// Time scales `[` and `]` step through.
pub const TIME_SCALES: [f32; 7] = [0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0];

/// At most this many steps per frame: after a stall (a breakpoint, a dragged window) the
/// simulation slows down instead of spiralling into ever longer frames.
pub const MAX_STEPS_PER_FRAME: u32 = 8;

/// Something the user asked for.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Space: start the animation.
    Start,
    /// T: run exactly one timestep (and pause).
    StepOnce,
    /// S: stop if running, start if stopped.
    ToggleRun,
    /// Esc / Q: quit.
    Quit,
    /// Restart the current scene and variant.
    Reset,
    /// Keys 1/2/3: select that variant and restart (1 is the paper's reset).
    Variant(u32),
    /// Tab.
    NextScene,
    /// Shift+Tab.
    PrevScene,
    /// Pick a built-in scene by index into [`SCENES`].
    SelectScene(usize),
    /// R: re-read the scene file from disk and restart.
    Reload,
    /// `[`: slower.
    Slower,
    /// `]`: faster.
    Faster,
    /// B: shoot a box from the camera through this cursor pixel (`None`: through the
    /// view's centre, as the panel's button does).
    ShootBox(Option<Vec2>),
    /// New size and speed for the boxes B shoots.
    Shot(ShotSettings),
    /// Right button: open the menu at this pixel.
    OpenMenu(Vec2),
    /// Close the menu.
    CloseMenu,
    /// Show or hide the side panel.
    TogglePanel,
    /// The particle solver.
    ParticleSolver(ParticleSolverArg),
    /// Overlay toggles.
    Show(ShowOptions),
    /// New timestep, iterations or substeps for both methods: the fields given replace
    /// the user's earlier choices and outlive a reset.
    Settings(SettingsOverride),
    /// Drop the user's timestep, iterations and substeps: back to the scene's own.
    SceneSettings,
    /// Run this many timesteps (and pause).
    StepFrames(u32),
    /// Home: the scene's own camera again.
    ResetCamera,
    /// A left click (press and release in place) at this pixel: select the body under
    /// it, or clear the selection over empty space.
    Pick(Vec2),
    /// The cursor rests over this pixel with no button held (names the body under it).
    Hover(Vec2),
    /// F: follow the selected figure (or every body) with the camera, or stop following.
    Follow,
    /// P: write the window's next frame to a numbered PNG.
    Screenshot,
    /// Shift+P: start or stop writing every frame to numbered PNGs.
    Record,
    /// M: both methods side by side, or one of them over the whole view.
    CycleLayout,
    /// An `.af` file dropped on the window: open it.
    OpenFile(std::path::PathBuf),
    /// Left drag: rotate the view by this many pixels.
    Orbit(Vec2),
    /// Middle drag: move the view by this many pixels.
    Pan(Vec2),
    /// Wheel: zoom by this many notches (positive: closer).
    Zoom(f32),
    /// Ctrl + left press: grab the body under this pixel.
    GrabStart(Vec2),
    /// The grabbing cursor moved here.
    GrabMove(Vec2),
    /// Left button released while grabbing.
    GrabEnd,
    /// K: the ragdoll takes over from the animation playing (`--anim`), on both sides,
    /// with the animation's velocities, and runs.
    TakeOver,
}

/// Which methods the view shows: both side by side (the comparison), or one over the
/// whole view, for small windows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ViewLayout {
    /// Particle left, multibody right.
    #[default]
    Both,
    /// The particle method alone.
    Particle,
    /// The multibody method alone.
    Multibody,
}

impl ViewLayout {
    /// The next layout M gives.
    pub fn next(self) -> ViewLayout {
        match self {
            ViewLayout::Both => ViewLayout::Particle,
            ViewLayout::Particle => ViewLayout::Multibody,
            ViewLayout::Multibody => ViewLayout::Both,
        }
    }

    /// Whether side `i` (0 particle, 1 multibody) is shown.
    pub fn shows(self, i: usize) -> bool {
        match self {
            ViewLayout::Both => true,
            ViewLayout::Particle => i == 0,
            ViewLayout::Multibody => i == 1,
        }
    }
}

/// What the scene needs after an action.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rebuild {
    /// Rebuild both methods from the loaded description (reset, variant, solver).
    Restart,
    /// Load the scene again (another scene, or the file changed on disk) and restart.
    Load,
}

/// The app's state apart from the simulation itself.
#[derive(Clone, Debug)]
pub struct AppState {
    /// The animation runs.
    pub running: bool,
    /// Single steps asked for with T and not yet taken.
    pub pending_steps: u32,
    /// Index into [`SCENES`], or `None` for a file given with `--af`.
    pub scene: Option<usize>,
    /// Selected variant (1-based).
    pub variant: u32,
    /// The particle solver.
    pub particle_solver: ParticleSolverArg,
    /// Right-click menu position, when open.
    pub menu: Option<Vec2>,
    /// The side panel is shown.
    pub panel: bool,
    /// Index into [`TIME_SCALES`].
    pub time_scale: usize,
    /// Overlays.
    pub show: ShowOptions,
    /// Boxes to shoot, asked for and not yet shot: the cursor pixel each flies through
    /// (`None`: the centre of the left view).
    pub pending_shots: Vec<Option<Vec2>>,
    /// Size and speed of the boxes B shoots.
    pub shot: ShotSettings,
    /// The user's timestep, iterations and substeps (panel, menu, command line): applied
    /// over every scene build until another scene is picked.
    pub overrides: SettingsOverride,
    /// The overrides changed: apply them to both methods live.
    pub pending_settings: bool,
    /// Home was pressed: the window puts the scene's camera back.
    pub pending_camera_reset: bool,
    /// The scene must be rebuilt or reloaded.
    pub rebuild: Option<Rebuild>,
    /// The user asked to quit.
    pub quit: bool,
    /// The body clicked (the same body in both methods).
    pub selected: Option<BodyId>,
    /// The body under the resting cursor.
    pub hovered: Option<BodyId>,
    /// The camera follows the selected figure, or every body.
    pub follow: bool,
    /// Write the next frame to a PNG.
    pub pending_screenshot: bool,
    /// K was pressed: the ragdoll takes over from the animation.
    pub pending_takeover: bool,
    /// Every frame goes to a PNG.
    pub recording: bool,
    /// Which methods the view shows.
    pub layout: ViewLayout,
    /// A file to open, dropped on the window.
    pub pending_open: Option<std::path::PathBuf>,
    /// The shared camera.
    pub camera: OrbitCamera,
    /// Viewport height in pixels, for panning at the right speed.
    pub viewport_height: f32,
    /// The last error a user action ran into (a missing variant, a broken file on R),
    /// and when: the window shows it for [`NOTICE_SECONDS`] over the scene it kept.
    pub notice: Option<(String, std::time::Instant)>,
    /// Frame time and the time scale reached.
    pub rate: FrameRate,
    accumulator: f64,
}

/// Wall-clock frame time and the time scale the simulation reached, each an exponential
/// average over about a second of frames (weight `real_dt / 1 s` per frame), so a label
/// can say when the window falls short of the scale asked for (at most
/// [`MAX_STEPS_PER_FRAME`] steps a frame, or steps slower than real time).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameRate {
    /// Wall-clock time between frames (ms).
    pub frame_ms: f64,
    /// Simulated seconds per wall-clock second while running.
    pub reached_scale: f64,
}

impl FrameRate {
    /// Frames per second.
    pub fn fps(&self) -> f64 {
        if self.frame_ms > 0.0 {
            1e3 / self.frame_ms
        } else {
            0.0
        }
    }

    fn record(&mut self, real_dt: f64, simulated: Option<f64>) {
        if real_dt <= 0.0 {
            return;
        }
        let w = real_dt.min(1.0);
        let first = self.frame_ms == 0.0;
        let blend = |old: f64, new: f64| if first { new } else { old + (new - old) * w };
        self.frame_ms = blend(self.frame_ms, real_dt * 1e3);
        if let Some(sim) = simulated {
            self.reached_scale = blend(self.reached_scale, sim / real_dt);
        }
    }
}

/// How long an error notice stays on screen (s).
pub const NOTICE_SECONDS: f32 = 6.0;

/// The timestep, iterations and substeps the user chose over the scene's own. They are
/// applied to every build of the scene (reset, variant, solver, reload), so the paper's
/// experiment — rerun a scene from its start with other iterations — keeps them; a
/// variant drops those it sets itself (see [`SettingsOverride::without_changed`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SettingsOverride {
    /// Timestep (s).
    pub timestep: Option<f32>,
    /// Constraint iterations, for both methods (a scene's `multibodyIterations` gives
    /// way to it).
    pub iterations: Option<u32>,
    /// Substeps, for both methods (a scene's `multibodySubsteps` gives way to it).
    pub substeps: Option<u32>,
}

impl SettingsOverride {
    /// Nothing overridden.
    pub fn is_empty(&self) -> bool {
        *self == SettingsOverride::default()
    }

    /// `self` with the fields `newer` gives replaced.
    pub fn merged(self, newer: SettingsOverride) -> SettingsOverride {
        SettingsOverride {
            timestep: newer.timestep.or(self.timestep),
            iterations: newer.iterations.or(self.iterations),
            substeps: newer.substeps.or(self.substeps),
        }
    }

    /// `scene`'s settings with the overrides applied.
    pub fn apply(&self, scene: &Settings) -> Settings {
        let mut s = scene.clone();
        if let Some(dt) = self.timestep {
            s.timestep = dt;
        }
        if let Some(n) = self.iterations {
            s.iterations = n;
            s.multibody_iterations = None;
        }
        if let Some(n) = self.substeps {
            s.substeps = n;
            s.multibody_substeps = None;
        }
        s
    }

    /// The overrides minus the fields in which `before` and `after` differ: when a
    /// variant sets its own iterations (hinge-chain's 2 and 20), picking it shows them.
    pub fn without_changed(self, before: &Settings, after: &Settings) -> SettingsOverride {
        SettingsOverride {
            timestep: self.timestep.filter(|_| before.timestep == after.timestep),
            iterations: self.iterations.filter(|_| {
                before.iterations == after.iterations
                    && before.multibody_iterations == after.multibody_iterations
            }),
            substeps: self.substeps.filter(|_| {
                before.substeps == after.substeps
                    && before.multibody_substeps == after.multibody_substeps
            }),
        }
    }
}

impl AppState {
    /// The state at start-up: running (the paper's "started by default").
    pub fn new(scene: Option<usize>, variant: u32, camera: OrbitCamera) -> AppState {
        AppState {
            running: true,
            pending_steps: 0,
            scene,
            variant: variant.max(1),
            particle_solver: ParticleSolverArg::default(),
            menu: None,
            panel: true,
            time_scale: TIME_SCALES.iter().position(|&s| s == 1.0).unwrap_or(0),
            show: ShowOptions::default(),
            pending_shots: Vec::new(),
            shot: ShotSettings::default(),
            overrides: SettingsOverride::default(),
            pending_settings: false,
            pending_camera_reset: false,
            rebuild: None,
            quit: false,
            selected: None,
            hovered: None,
            follow: false,
            pending_screenshot: false,
            pending_takeover: false,
            recording: false,
            layout: ViewLayout::Both,
            pending_open: None,
            camera,
            viewport_height: 720.0,
            notice: None,
            rate: FrameRate::default(),
            accumulator: 0.0,
        }
    }

    /// Simulated seconds per real second.
    pub fn time_scale(&self) -> f32 {
        TIME_SCALES[self.time_scale]
    }

    /// The scene argument for [`crate::scenes::load`]: the built-in scene's name.
    pub fn scene_name(&self) -> Option<&'static str> {
        self.scene.map(|i| SCENES[i])
    }

    /// Applies one action. Grabbing is the window's business (it needs the methods); here
    /// it only closes the menu.
    pub fn apply(&mut self, action: Action) {
        match action {
            Action::Start => self.running = true,
            Action::StepOnce => {
                self.running = false;
                self.pending_steps += 1;
            }
            Action::StepFrames(n) => {
                self.running = false;
                self.pending_steps = self.pending_steps.saturating_add(n);
            }
            Action::ToggleRun => self.running = !self.running,
            // Esc first closes an open menu, as menus do; with none open it quits.
            Action::Quit if self.menu.is_some() => self.menu = None,
            Action::Quit => self.quit = true,
            Action::Reset => self.restart(Rebuild::Restart),
            Action::Variant(v) => {
                self.variant = v.max(1);
                self.restart(Rebuild::Restart);
            }
            Action::NextScene | Action::PrevScene => {
                let n = SCENES.len();
                let delta = if action == Action::NextScene {
                    1
                } else {
                    n - 1
                };
                // From an --af file, Tab enters the built-in list at its start.
                self.scene = Some(self.scene.map_or(0, |i| (i + delta) % n));
                self.variant = 1;
                // Another scene has its own timestep and counts.
                self.overrides = SettingsOverride::default();
                self.restart(Rebuild::Load);
            }
            Action::SelectScene(i) => {
                self.scene = Some(i.min(SCENES.len() - 1));
                self.variant = 1;
                self.overrides = SettingsOverride::default();
                self.restart(Rebuild::Load);
            }
            Action::Reload => self.restart(Rebuild::Load),
            Action::Slower => self.time_scale = self.time_scale.saturating_sub(1),
            Action::Faster => self.time_scale = (self.time_scale + 1).min(TIME_SCALES.len() - 1),
            Action::ShootBox(at) => self.pending_shots.push(at),
            Action::Shot(shot) => self.shot = shot,
            Action::OpenMenu(at) => self.menu = Some(at),
            Action::CloseMenu => self.menu = None,
            Action::TogglePanel => self.panel = !self.panel,
            Action::ParticleSolver(s) => {
                self.particle_solver = s;
                self.restart(Rebuild::Restart);
            }
            Action::Show(show) => self.show = show,
            Action::Settings(s) => {
                self.overrides = self.overrides.merged(s);
                self.pending_settings = true;
            }
            Action::SceneSettings => {
                self.overrides = SettingsOverride::default();
                self.pending_settings = true;
            }
            Action::ResetCamera => self.pending_camera_reset = true,
            Action::Orbit(d) => self.camera.orbit(d),
            Action::Pan(d) => self.camera.pan(d, self.viewport_height),
            Action::Zoom(steps) => self.camera.zoom(steps),
            Action::GrabStart(_) | Action::GrabMove(_) | Action::GrabEnd => self.menu = None,
            // Picking casts into the methods: the window's business.
            Action::Pick(_) => self.menu = None,
            Action::Hover(_) => {}
            Action::Follow => self.follow = !self.follow,
            Action::Screenshot => self.pending_screenshot = true,
            Action::TakeOver => {
                self.pending_takeover = true;
                self.running = true;
            }
            Action::Record => self.recording = !self.recording,
            Action::CycleLayout => self.layout = self.layout.next(),
            Action::OpenFile(path) => {
                self.pending_open = Some(path);
                self.scene = None;
                self.variant = 1;
                self.overrides = SettingsOverride::default();
                self.restart(Rebuild::Load);
            }
        }
    }

    fn restart(&mut self, kind: Rebuild) {
        self.accumulator = 0.0;
        if kind == Rebuild::Load {
            // Another scene's bodies: the old selection means nothing there.
            self.selected = None;
            self.hovered = None;
            self.follow = false;
        }
        self.pending_steps = 0;
        // A reload outranks a restart when both are pending.
        self.rebuild = match (self.rebuild, kind) {
            (Some(Rebuild::Load), _) | (_, Rebuild::Load) => Some(Rebuild::Load),
            _ => Some(Rebuild::Restart),
        };
    }

    /// How many fixed steps of `timestep` seconds to take after `real_dt` seconds of wall
    /// time: the accumulator collects scaled real time and pays it out in whole steps, so
    /// the simulation speed does not depend on the frame rate. Single steps asked for with
    /// T are added while paused.
    pub fn steps_due(&mut self, real_dt: f64, timestep: f64) -> u32 {
        let mut steps = std::mem::take(&mut self.pending_steps);
        if self.running && timestep > 0.0 {
            self.accumulator += real_dt.max(0.0) * self.time_scale() as f64;
            let due = (self.accumulator / timestep).floor();
            let taken = due.min(MAX_STEPS_PER_FRAME as f64);
            self.accumulator -= due * timestep; // drop what we cannot catch up on
            steps += taken as u32;
            self.rate.record(real_dt, Some(taken * timestep));
        } else {
            self.accumulator = 0.0;
            self.rate.record(real_dt, None);
        }
        steps
    }

    /// Whether the time scale reached falls visibly (5 %) short of the one asked for.
    pub fn falls_short(&self) -> bool {
        self.running
            && self.rate.reached_scale > 0.0
            && self.rate.reached_scale < 0.95 * self.time_scale() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ragdoll_sim::scene::CameraDesc;

    fn state() -> AppState {
        AppState::new(Some(0), 1, OrbitCamera::from_desc(&CameraDesc::default()))
    }

    #[test]
    fn accumulator_pays_out_whole_steps_independent_of_frame_rate() {
        let dt = 1.0 / 60.0;
        for fps in [30.0, 60.0, 144.0] {
            let mut s = state();
            let frames = (fps * 2.0) as usize;
            let steps: u32 = (0..frames).map(|_| s.steps_due(1.0 / fps, dt)).sum();
            // Two seconds of wall time are 120 steps, give or take the one still accumulating.
            assert!((119..=120).contains(&steps), "{fps} fps: {steps} steps");
        }
    }

    #[test]
    fn slow_motion_scales_time_and_pause_stops_it() {
        let mut s = state();
        s.apply(Action::Slower); // 0.5×
        let steps: u32 = (0..120).map(|_| s.steps_due(1.0 / 60.0, 1.0 / 60.0)).sum();
        assert!((59..=60).contains(&steps), "{steps}");
        s.apply(Action::ToggleRun);
        assert_eq!(s.steps_due(1.0, 1.0 / 60.0), 0);
    }

    #[test]
    fn a_stall_is_capped() {
        let mut s = state();
        assert_eq!(s.steps_due(5.0, 1.0 / 60.0), MAX_STEPS_PER_FRAME);
        assert_eq!(s.steps_due(0.0, 1.0 / 60.0), 0, "the backlog is dropped");
    }

    #[test]
    fn the_time_scale_reached_is_measured_and_a_shortfall_said() {
        let dt = 1.0 / 60.0;
        let mut s = state();
        for _ in 0..120 {
            s.steps_due(1.0 / 60.0, dt);
        }
        assert!((s.rate.reached_scale - 1.0).abs() < 0.05, "{:?}", s.rate);
        assert!((s.rate.fps() - 60.0).abs() < 0.5, "{:?}", s.rate);
        assert!(!s.falls_short());
        // ×4 at 5 fps needs 48 steps a frame; the cap allows 8: ×(8/60)/(1/5) = ×0.67.
        for _ in 0..3 {
            s.apply(Action::Faster);
        }
        for _ in 0..30 {
            s.steps_due(0.2, dt);
        }
        let expected = MAX_STEPS_PER_FRAME as f64 * dt / 0.2;
        assert!(
            (s.rate.reached_scale - expected).abs() < 0.02,
            "{:?} vs {expected}",
            s.rate
        );
        assert!(s.falls_short());
    }

    #[test]
    fn overrides_outlive_a_reset_and_a_variant_drops_what_it_sets() {
        let mut s = state();
        s.apply(Action::Settings(SettingsOverride {
            iterations: Some(12),
            ..Default::default()
        }));
        s.apply(Action::Settings(SettingsOverride {
            timestep: Some(0.01),
            ..Default::default()
        }));
        assert!(s.pending_settings);
        s.apply(Action::Reset);
        assert_eq!(s.overrides.iterations, Some(12), "kept across reset");
        assert_eq!(s.overrides.timestep, Some(0.01), "merged, not replaced");
        let scene = Settings::default();
        let applied = s.overrides.apply(&scene);
        assert_eq!((applied.iterations, applied.timestep), (12, 0.01));
        let mut variant = scene.clone();
        variant.iterations = 2;
        let kept = s.overrides.without_changed(&scene, &variant);
        assert_eq!(kept.iterations, None, "the variant's own iterations show");
        assert_eq!(kept.timestep, Some(0.01));
        s.apply(Action::NextScene);
        assert!(s.overrides.is_empty(), "another scene, its own settings");
    }

    #[test]
    fn step_frames_pauses_and_queues_exactly_n() {
        let mut s = state();
        s.apply(Action::StepFrames(10));
        assert!(!s.running);
        assert_eq!(s.steps_due(1.0, 1.0 / 60.0), 10);
        assert_eq!(s.steps_due(1.0, 1.0 / 60.0), 0);
    }
}
