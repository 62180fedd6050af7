//! The app's state machine, independent of any window: running or paused, single steps,
//! scene and variant, the right-click menu, slow motion, overlay toggles, and the fixed
//! timestep accumulator. [`crate::input`] turns keys and mouse into [`Action`]s; the
//! window and the egui panel apply them here, so tests can drive it without a window.

use crate::cli::ParticleSolverArg;
use crate::render::ShowOptions;
use crate::render::camera::OrbitCamera;
use glam::Vec2;
use ragdoll_sim::scene::Settings;

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
    /// B: shoot a small box from the camera.
    ShootBox,
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
    /// New timestep, iterations or substeps for both methods.
    Settings(Settings),
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
    /// Boxes to shoot, asked for and not yet shot.
    pub pending_shots: u32,
    /// Settings to apply to both methods.
    pub pending_settings: Option<Settings>,
    /// The scene must be rebuilt or reloaded.
    pub rebuild: Option<Rebuild>,
    /// The user asked to quit.
    pub quit: bool,
    /// The shared camera.
    pub camera: OrbitCamera,
    /// Viewport height in pixels, for panning at the right speed.
    pub viewport_height: f32,
    /// The last error a user action ran into (a missing variant, a broken file on R),
    /// and when: the window shows it for [`NOTICE_SECONDS`] over the scene it kept.
    pub notice: Option<(String, std::time::Instant)>,
    accumulator: f64,
}

/// How long an error notice stays on screen (s).
pub const NOTICE_SECONDS: f32 = 6.0;

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
            pending_shots: 0,
            pending_settings: None,
            rebuild: None,
            quit: false,
            camera,
            viewport_height: 720.0,
            notice: None,
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
                self.restart(Rebuild::Load);
            }
            Action::SelectScene(i) => {
                self.scene = Some(i.min(SCENES.len() - 1));
                self.variant = 1;
                self.restart(Rebuild::Load);
            }
            Action::Reload => self.restart(Rebuild::Load),
            Action::Slower => self.time_scale = self.time_scale.saturating_sub(1),
            Action::Faster => self.time_scale = (self.time_scale + 1).min(TIME_SCALES.len() - 1),
            Action::ShootBox => self.pending_shots += 1,
            Action::OpenMenu(at) => self.menu = Some(at),
            Action::CloseMenu => self.menu = None,
            Action::TogglePanel => self.panel = !self.panel,
            Action::ParticleSolver(s) => {
                self.particle_solver = s;
                self.restart(Rebuild::Restart);
            }
            Action::Show(show) => self.show = show,
            Action::Settings(s) => self.pending_settings = Some(s),
            Action::Orbit(d) => self.camera.orbit(d),
            Action::Pan(d) => self.camera.pan(d, self.viewport_height),
            Action::Zoom(steps) => self.camera.zoom(steps),
            Action::GrabStart(_) | Action::GrabMove(_) | Action::GrabEnd => self.menu = None,
        }
    }

    fn restart(&mut self, kind: Rebuild) {
        self.accumulator = 0.0;
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
        } else {
            self.accumulator = 0.0;
        }
        steps
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
}
