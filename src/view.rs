//! The window (`ragdoll-lab` / `ragdoll-lab view`): winit 0.30's `ApplicationHandler`
//! around the same compositor capture uses. Keys and mouse go through
//! [`crate::input::InputMapper`] into [`crate::app_state::AppState`]; egui sees every
//! event first and keeps the ones over its panel and menu.

use crate::AppError;
use crate::app_state::{Action, AppState, Rebuild, SCENES, SettingsOverride};
use crate::cli::{SceneArgs, ViewArgs};
use crate::compose::Compositor;
use crate::input::InputMapper;
use crate::picking;
use crate::render::camera::OrbitCamera;
use crate::render::gpu::{self, Gpu};
use crate::scenes::{self, LoadedScene};
use crate::session::Session;
use glam::Vec2;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// Opens the window and runs until the user quits.
pub fn run(args: ViewArgs) -> Result<(), AppError> {
    // Load before opening a window, so a bad scene is reported without one.
    let loaded = scenes::load(&args.scene)?;
    let scene = args
        .scene
        .scene
        .as_deref()
        .and_then(scenes::find_builtin)
        .map(|b| b.number as usize - 1)
        .or(if args.scene.af.is_some() || args.scene.entity.is_some() {
            None
        } else {
            Some(7)
        });
    let mut state = AppState::new(
        scene,
        loaded.desc.variant,
        OrbitCamera::from_desc(&loaded.desc.settings.camera),
    );
    state.particle_solver = args.particle_solver;
    state.running = !args.paused;
    state.overrides = SettingsOverride {
        timestep: args.timestep,
        iterations: args.iterations,
        substeps: args.substeps,
    };
    let mut session = Session::configured(loaded, args.particle_solver, &state.overrides)?;
    session.refresh();
    state.camera = fitted_camera(&session, INITIAL_HALF_ASPECT);
    let event_loop =
        EventLoop::new().map_err(|e| AppError::Gpu(format!("cannot open a window: {e}")))?;
    let mut app = App {
        args,
        state,
        session,
        input: InputMapper::new(),
        window: None,
        error: None,
        last: Instant::now(),
        grab_viewport: None,
        hidden: false,
        idle: false,
        watched: None,
        shots_taken: 0,
        record_dir: None,
        recorded: 0,
        offscreen: None,
        polled: Instant::now(),
    };
    app.watched = app.session.loaded.path.as_deref().and_then(modified);
    event_loop
        .run_app(&mut app)
        .map_err(|e| AppError::Gpu(format!("event loop: {e}")))?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Everything that exists only while the window does.
struct WindowState {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    compositor: Compositor,
    egui: egui_winit::State,
}

struct App {
    args: ViewArgs,
    state: AppState,
    session: Session,
    input: InputMapper,
    window: Option<WindowState>,
    error: Option<AppError>,
    last: Instant,
    /// The half a grab started in: the cursor's ray is taken through it while dragging.
    grab_viewport: Option<crate::render::Viewport>,
    /// The window cannot be seen (occluded, or minimised to no pixels): no frame is
    /// drawn or simulated, and the event loop sleeps until something happens, instead
    /// of a hidden demo keeping a core busy.
    hidden: bool,
    /// The last frame asked for no next one: nothing moved and nothing was pending. The
    /// clock restarts on the next frame, so the idle time is not caught up.
    idle: bool,
    /// The scene file's modification time when it was loaded, polled to reload on change.
    watched: Option<std::time::SystemTime>,
    /// Screenshots written so far (numbers the files).
    shots_taken: u32,
    /// The directory a recording writes into, while recording.
    record_dir: Option<std::path::PathBuf>,
    /// Frames written into it.
    recorded: u32,
    /// Where screenshots are rendered when the surface cannot be read back.
    offscreen: Option<crate::capture::Offscreen>,
    /// When the scene file's modification time was last read.
    polled: Instant,
}

/// Width / height of one half at the window's first size (1280×720 with the panel), for
/// fitting the first camera before the window exists.
const INITIAL_HALF_ASPECT: f32 = 490.0 / 720.0;

/// How often the scene file's modification time is read (s).
const WATCH_SECONDS: f64 = 0.5;

/// The file's modification time, if it can be read.
fn modified(path: &std::path::Path) -> Option<std::time::SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// The scene's own camera, pulled back if the bodies at rest do not all fit in a view of
/// `aspect` clear of the labels (see [`picking::fits`]).
fn fitted_camera(session: &Session, aspect: f32) -> OrbitCamera {
    let desc = &session.loaded.desc.settings.camera;
    picking::scene_camera(OrbitCamera::from_desc(desc), &session.snapshots, aspect)
}

impl App {
    fn open_window(&self, event_loop: &ActiveEventLoop) -> Result<WindowState, AppError> {
        let attrs = Window::default_attributes()
            .with_title("ragdoll-lab — particle (left) vs multibody (right)")
            .with_inner_size(PhysicalSize::new(1280, 720));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| AppError::Gpu(format!("cannot open a window: {e}")))?,
        );
        let backends = gpu::backends();
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(
                event_loop.owned_display_handle(),
            ))
        });
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| AppError::Gpu(format!("cannot draw into the window: {e}")))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            apply_limit_buckets: false,
        }))
        .map_err(|e| AppError::Gpu(format!("no adapter can draw into the window: {e}")))?;
        let gpu = gpu::open(instance, adapter)?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or(caps.formats.first().copied())
            .ok_or_else(|| AppError::Gpu("the window offers no surface format".into()))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| AppError::Gpu("the adapter cannot draw into the window".into()))?;
        config.format = format;
        config.present_mode = wgpu::PresentMode::AutoVsync;
        // Screenshots and recordings read the frame back, where the platform allows it.
        if caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            config.usage |= wgpu::TextureUsages::COPY_SRC;
        }
        // egui wants the non-sRGB view of an sRGB surface, where the platform allows one.
        let view_formats_ok = gpu
            .adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::SURFACE_VIEW_FORMATS);
        let ui_format = if view_formats_ok && format.is_srgb() {
            config.view_formats = vec![format.remove_srgb_suffix()];
            format.remove_srgb_suffix()
        } else {
            format
        };
        surface.configure(&gpu.device, &config);
        let compositor = Compositor::new(
            &gpu.device,
            format,
            ui_format,
            gpu::msaa_samples(&gpu.adapter, format),
        );
        let egui = egui_winit::State::new(
            compositor.ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        log::info!("window on {}", gpu.adapter.get_info().name);
        Ok(WindowState {
            window,
            surface,
            config,
            gpu,
            compositor,
            egui,
        })
    }

    /// Applies an action; grabs need the methods and the viewports, the rest is state.
    fn act(&mut self, action: Action) {
        let viewports = match &self.window {
            Some(w) => w.compositor.viewports,
            None => return,
        };
        match action {
            Action::GrabStart(p) => {
                self.state.apply(action);
                // A grab takes the figure from the animation first: it pulls the ragdoll.
                self.take_over();
                for (side, vp) in viewports.iter().enumerate() {
                    if vp.contains(p) {
                        let (o, d) = self.state.camera.ray(vp.ndc(p), vp.aspect());
                        if self.session.grab_start(side, o, d) {
                            self.grab_viewport = Some(*vp);
                        }
                    }
                }
            }
            Action::GrabMove(p) => {
                if let Some(vp) = self.grab_viewport {
                    let (o, d) = self.state.camera.ray(vp.ndc(p), vp.aspect());
                    self.session.grab_move(o, d);
                }
            }
            Action::GrabEnd => {
                self.grab_viewport = None;
                self.session.grab_end();
            }
            Action::Pick(p) | Action::Hover(p) => {
                let click = matches!(action, Action::Pick(_));
                self.state.apply(action);
                let hit = picking::cursor_ray(&self.state.camera, &viewports, p).and_then(|r| {
                    self.session.methods[r.side]
                        .raycast(r.origin, r.dir)
                        .map(|h| h.body)
                });
                if click {
                    self.state.selected = hit;
                } else if self.state.hovered == hit {
                    return; // nothing to draw anew
                } else {
                    self.state.hovered = hit;
                }
            }
            other => {
                self.state.viewport_height = viewports[0].height.max(viewports[1].height);
                self.state.apply(other);
            }
        }
        self.wake();
    }

    /// The ragdoll takes over from the animation playing, if one is: returns whether one
    /// was. A failure is reported and the animation keeps playing.
    fn take_over(&mut self) -> bool {
        match self.session.take_over() {
            Ok(taken) => {
                if taken {
                    self.state.notice = None;
                }
                taken
            }
            Err(e) => {
                self.report(e);
                false
            }
        }
    }

    /// Something changed: draw a frame (the loop otherwise waits for input).
    fn wake(&self) {
        if let Some(w) = &self.window {
            w.window.request_redraw();
        }
    }

    /// Whether the next frame must come without input: the simulation moves, steps or a
    /// rebuild are pending, a notice is counting down, something is being recorded or
    /// dragged, or egui animates.
    fn busy(&self, egui_soon: bool) -> bool {
        let s = &self.state;
        let moving = s.running
            && (self.session.playing.is_some()
                || !self.session.samples.iter().all(|x| x.all_asleep));
        let notice = s.notice.as_ref().is_some_and(|(_, at)| {
            at.elapsed().as_secs_f32() < crate::app_state::NOTICE_SECONDS + 0.1
        });
        moving
            || s.pending_steps > 0
            || s.rebuild.is_some()
            || s.pending_settings
            || s.pending_camera_reset
            || !s.pending_shots.is_empty()
            || s.pending_screenshot
            || s.pending_takeover
            || s.recording
            || s.follow && moving
            || notice
            || self.session.grabbing()
            || egui_soon
    }

    /// A failed action keeps the scene that runs: the state goes back to its variant,
    /// and the error is logged and shown in the window, where the user looks.
    fn report(&mut self, e: AppError) {
        log::error!("{e}");
        self.state.variant = self.session.loaded.desc.variant;
        self.state.notice = Some((e.to_string(), std::time::Instant::now()));
    }

    /// Reloads or rebuilds the scene the state asks for; on failure keeps the old one.
    fn rebuild(&mut self, kind: Rebuild) {
        let result = match kind {
            Rebuild::Restart => {
                let mut loaded = self.session.loaded.clone();
                let (wanted, have) = (self.state.variant, loaded.desc.variants.len() as u32);
                if wanted > have.max(1) {
                    // Keys 2 and 3 on a scene without that variant: say so in the
                    // scene's terms, not as a file error, and keep running.
                    let name = &loaded.desc.name;
                    let what = match have {
                        0 => format!("{name} has no variants (1 resets it)"),
                        n => format!("{name} has variants 1 to {n} only"),
                    };
                    self.state.variant = loaded.desc.variant;
                    self.state.notice = Some((what, std::time::Instant::now()));
                    return;
                }
                // A variant change needs the file's variant overrides: load it again.
                if loaded.desc.variant != self.state.variant {
                    match self.load(false) {
                        Ok(l) => loaded = l,
                        Err(e) => return self.report(e),
                    }
                }
                // What the new variant sets itself (hinge-chain's iterations) shows.
                self.state.overrides = self
                    .state
                    .overrides
                    .without_changed(&self.session.loaded.desc.settings, &loaded.desc.settings);
                Session::configured(loaded, self.state.particle_solver, &self.state.overrides)
            }
            Rebuild::Load => {
                if let Some(path) = self.state.pending_open.take() {
                    self.args.scene.af = Some(path);
                    self.args.scene.scene = None;
                    // A dropped file is that file alone: not the entity, nor its anim.
                    self.args.scene.entity = None;
                    self.args.scene.anim = None;
                    self.args.scene.at = None;
                }
                self.load(true).and_then(|l| {
                    Session::configured(l, self.state.particle_solver, &self.state.overrides)
                })
            }
        };
        match result {
            Ok(mut session) => {
                let scene_changed = session.loaded.desc.name != self.session.loaded.desc.name
                    || session.loaded.path != self.session.loaded.path;
                session.refresh();
                if scene_changed {
                    let aspect = self.half_aspect();
                    self.state.camera = fitted_camera(&session, aspect);
                }
                self.state.variant = session.loaded.desc.variant;
                self.state.notice = None;
                self.watched = session.loaded.path.as_deref().and_then(modified);
                self.session = session;
                self.grab_viewport = None;
            }
            Err(e) => self.report(e),
        }
    }

    /// Width / height of the widest half now.
    fn half_aspect(&self) -> f32 {
        self.window.as_ref().map_or(INITIAL_HALF_ASPECT, |w| {
            let v = w.compositor.viewports;
            if v[0].width >= v[1].width {
                v[0].aspect()
            } else {
                v[1].aspect()
            }
        })
    }

    /// Loads the state's scene and variant; `from_disk` prefers the file on disk (R).
    fn load(&self, from_disk: bool) -> Result<LoadedScene, AppError> {
        let mut args = SceneArgs {
            variant: Some(self.state.variant),
            ..self.args.scene.clone()
        };
        // Without a built-in scene this is the --af file, read from disk again.
        if let Some(i) = self.state.scene {
            args.af = None;
            args.scene = Some(SCENES[i].to_string());
            // A built-in scene is neither the Doom 3 entity nor its animation.
            args.entity = None;
            args.anim = None;
            args.at = None;
            let on_disk = scenes::find_builtin(SCENES[i]).map(|b| b.asset_path());
            if from_disk && let Some(path) = on_disk.filter(|p| p.exists()) {
                args.scene = None;
                args.af = Some(path);
            }
        }
        scenes::load(&args)
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(kind) = self.state.rebuild.take() {
            self.rebuild(kind);
        }
        if std::mem::take(&mut self.state.pending_settings) {
            let settings = self
                .state
                .overrides
                .apply(&self.session.loaded.desc.settings);
            self.session.set_settings(&settings);
        }
        if std::mem::take(&mut self.state.pending_takeover) && !self.take_over() {
            self.state.notice = Some((
                "K: no animation is playing; open a figure with --anim NAME".into(),
                Instant::now(),
            ));
        }
        if std::mem::take(&mut self.state.pending_camera_reset) {
            self.state.follow = false;
            self.state.camera = fitted_camera(&self.session, self.half_aspect());
        }
        let now = Instant::now();
        // After an idle wait the clock starts afresh: nothing moved meanwhile.
        let dt = if std::mem::take(&mut self.idle) {
            0.0
        } else {
            (now - self.last).as_secs_f64()
        };
        self.last = now;
        let timestep = self.session.settings().timestep as f64;
        // Shots hit the mesh while it is drawn (see `impacts`).
        self.session.mesh_shots = self.state.show.mesh
            && (self.session.loaded.skin.as_ref())
                .is_some_and(|s| s.rig.joints.len() <= crate::render::skin::MAX_JOINTS);
        for _ in 0..self.state.steps_due(dt, timestep) {
            self.session.step();
        }
        let viewports = self.window.as_ref().map_or(
            [crate::render::Viewport {
                x: 0.0,
                y: 0.0,
                width: 1.0,
                height: 1.0,
            }; 2],
            |w| w.compositor.viewports,
        );
        // A box shot at the playing animation meets the ragdoll, as a Doom 3 death does.
        if !self.state.pending_shots.is_empty() {
            self.take_over();
        }
        for at in std::mem::take(&mut self.state.pending_shots) {
            let camera = &self.state.camera;
            let ray = at
                .and_then(|p| picking::cursor_ray(camera, &viewports, p))
                .unwrap_or_else(|| picking::centre_ray(camera, &viewports));
            self.session.shoot(ray.origin, ray.dir, &self.state.shot);
        }
        self.session.refresh();
        if self.state.follow {
            let figure = picking::figure(&self.session.loaded.desc, self.state.selected);
            if let Some((centre, radius)) =
                picking::bounding_sphere(&self.session.snapshots, figure)
            {
                picking::follow(&mut self.state.camera, centre, radius, dt as f32);
            }
        }
        self.session
            .highlight(self.state.selected, self.state.show.limits);

        let Some(w) = self.window.as_mut() else {
            return;
        };
        let size = w.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return; // minimised
        }
        let frame = match w.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) => f,
            wgpu::CurrentSurfaceTexture::Suboptimal(f) => {
                // Draw this one; reconfigure before the next.
                w.config.width = size.width;
                w.config.height = size.height;
                f
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                w.config.width = size.width;
                w.config.height = size.height;
                w.surface.configure(&w.gpu.device, &w.config);
                return;
            }
            other => {
                log::warn!("skipping a frame: {other:?}");
                return;
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let ui_view = frame.texture.create_view(&wgpu::TextureViewDescriptor {
            format: w.config.view_formats.first().copied(),
            ..Default::default()
        });
        let raw = w.egui.take_egui_input(&w.window);
        let ppp = egui_winit::pixels_per_point(&w.compositor.ctx, &w.window);
        let out = w.compositor.frame(
            &w.gpu.device,
            &w.gpu.queue,
            &view,
            &ui_view,
            (frame.texture.width(), frame.texture.height()),
            ppp,
            raw,
            &self.state,
            &self.session,
        );
        w.egui.handle_platform_output(&w.window, out.platform);
        let want_image = self.state.pending_screenshot || self.state.recording;
        let image = want_image
            .then(|| crate::readback::read_texture(&w.gpu.device, &w.gpu.queue, &frame.texture));
        w.window.pre_present_notify();
        w.gpu.queue.present(frame);
        if (w.config.width, w.config.height) != (size.width, size.height) {
            w.surface.configure(&w.gpu.device, &w.config);
        }
        if let Some(image) = image {
            // A surface that cannot be read back (GL on X11, for one): the same frame,
            // rendered offscreen as `capture` does.
            let image = image.or_else(|e| {
                log::info!("{e}; rendering the screenshot offscreen");
                let (width, height) = (size.width, size.height);
                if self
                    .offscreen
                    .as_ref()
                    .is_none_or(|o| o.size() != (width, height))
                {
                    self.offscreen = Some(crate::capture::Offscreen::new(width, height)?);
                }
                match self.offscreen.as_mut() {
                    Some(o) => o.render(&self.state, &self.session),
                    None => Err(AppError::Gpu("no offscreen target".into())),
                }
            });
            self.save(image);
        }
        let egui_soon = out.repaint_after < std::time::Duration::from_millis(100);
        for a in out.actions {
            self.act(a);
        }
        if self.state.quit {
            event_loop.exit();
        }
        self.idle = !self.busy(egui_soon);
        if !self.idle && !self.hidden {
            self.wake();
        }
    }

    /// Writes a frame read back from the window: one numbered screenshot (P), or the next
    /// frame of a recording (Shift+P), as `capture --every` numbers them.
    fn save(&mut self, image: Result<crate::capture::Image, AppError>) {
        let result = image.and_then(|image| {
            if std::mem::take(&mut self.state.pending_screenshot) {
                let path = loop {
                    self.shots_taken += 1;
                    let p = std::path::PathBuf::from(format!(
                        "ragdoll-lab-{:04}.png",
                        self.shots_taken
                    ));
                    if !p.exists() {
                        break p;
                    }
                };
                image.write_png(&path)?;
                self.state.notice =
                    Some((format!("screenshot: {}", path.display()), Instant::now()));
            }
            if self.state.recording {
                let dir = match &self.record_dir {
                    Some(d) => d.clone(),
                    None => {
                        let mut n = 1;
                        let dir = loop {
                            let d = std::path::PathBuf::from(format!("ragdoll-lab-rec-{n:03}"));
                            if !d.exists() {
                                break d;
                            }
                            n += 1;
                        };
                        std::fs::create_dir_all(&dir).map_err(|source| AppError::Io {
                            path: dir.display().to_string(),
                            source,
                        })?;
                        self.recorded = 0;
                        self.record_dir = Some(dir.clone());
                        dir
                    }
                };
                image.write_png(&dir.join(format!("frame_{:05}.png", self.recorded)))?;
                self.recorded += 1;
            }
            Ok(())
        });
        if let Err(e) = result {
            self.state.recording = false;
            self.state.pending_screenshot = false;
            self.report(e);
        }
    }

    /// A recording that stopped says where its frames went.
    fn finish_recording(&mut self) {
        if !self.state.recording
            && let Some(dir) = self.record_dir.take()
        {
            self.state.notice = Some((
                format!("recorded {} frames into {}", self.recorded, dir.display()),
                Instant::now(),
            ));
        }
    }

    /// Reloads the scene when its file changed on disk since it was loaded.
    fn poll_file(&mut self) {
        let Some(path) = self.session.loaded.path.clone() else {
            return;
        };
        let now = modified(&path);
        if now.is_some() && now != self.watched {
            self.watched = now;
            log::info!("{} changed on disk: reloading", path.display());
            self.state.apply(Action::Reload);
            self.wake();
        }
    }
}

impl App {
    /// Stops drawing and stepping while the window cannot be seen. The simulation pauses
    /// with it and resumes where it was: the clock restarts on showing, so the hidden
    /// time is not caught up.
    fn set_hidden(&mut self, hidden: bool) {
        if hidden == self.hidden {
            return;
        }
        self.hidden = hidden;
        if !hidden {
            self.last = Instant::now();
            if let Some(w) = &self.window {
                w.window.request_redraw();
            }
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        match self.open_window(event_loop) {
            Ok(w) => {
                w.window.request_redraw();
                self.window = Some(w);
                self.last = Instant::now();
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(w) = self.window.as_mut() else {
            return;
        };
        // Keys belong to the app (egui would move its focus on Tab and press focused
        // buttons on Space) except while a slider's number field is being edited.
        let editing = w.compositor.ctx.text_edit_focused();
        let is_key = matches!(event, WindowEvent::KeyboardInput { .. });
        // egui is not told of redraws: it answers every event with "repaint", and a
        // redraw asked for on each redraw never lets the loop wait.
        if matches!(event, WindowEvent::RedrawRequested) {
            self.redraw(event_loop);
            return;
        }
        let response = (!is_key || editing).then(|| w.egui.on_window_event(&w.window, &event));
        let consumed = response.as_ref().is_some_and(|r| r.consumed);
        if response.is_some_and(|r| r.repaint) {
            w.window.request_redraw();
        }
        let action = match &event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                None
            }
            WindowEvent::Resized(size) => {
                if size.width > 0 && size.height > 0 {
                    w.config.width = size.width;
                    w.config.height = size.height;
                    w.surface.configure(&w.gpu.device, &w.config);
                    w.window.request_redraw();
                }
                self.set_hidden(size.width == 0 || size.height == 0);
                None
            }
            WindowEvent::Occluded(occluded) => {
                self.set_hidden(*occluded);
                None
            }
            WindowEvent::DroppedFile(path) => Some(Action::OpenFile(path.clone())),
            WindowEvent::ModifiersChanged(m) => {
                self.input.set_modifiers(m.state());
                None
            }
            WindowEvent::Focused(false) | WindowEvent::CursorLeft { .. } => {
                self.input.release_all()
            }
            WindowEvent::CursorMoved { position, .. } => {
                let a = self
                    .input
                    .cursor_moved(Vec2::new(position.x as f32, position.y as f32));
                // A drag that started in the 3D view continues over the panel.
                a.filter(|_| !consumed || self.grab_viewport.is_some())
            }
            WindowEvent::KeyboardInput { event, .. } if !editing => self
                .input
                .key(&event.logical_key, event.state == ElementState::Pressed),
            // Releases always reach the mapper, or a drag ending over the panel would stick.
            WindowEvent::MouseInput { state, button, .. }
                if !consumed || *state == ElementState::Released =>
            {
                self.input.button(*button, *state == ElementState::Pressed)
            }
            _ if consumed => None,
            WindowEvent::MouseWheel { delta, .. } => self.input.wheel(match delta {
                MouseScrollDelta::LineDelta(_, y) => *y,
                MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
            }),
            _ => None,
        };
        if let Some(a) = action {
            self.act(a);
            self.finish_recording();
        }
        if self.state.quit {
            event_loop.exit();
        }
    }

    /// Waits for input; wakes every [`WATCH_SECONDS`] to see whether the scene file
    /// changed. Frames are asked for only while something changes ([`App::busy`]), so a
    /// paused or sleeping scene costs next to no CPU.
    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if !self.hidden && self.polled.elapsed().as_secs_f64() >= WATCH_SECONDS {
            self.polled = Instant::now();
            self.poll_file();
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(
            Instant::now() + std::time::Duration::from_secs_f64(WATCH_SECONDS),
        ));
    }
}
