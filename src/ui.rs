//! The egui layer: per-half labels and the divider (always), the side panel (scene list,
//! variant, play/pause/step, solver, sliders, overlay toggles, live numbers, the energy
//! plot) and the right-click menu. It only reads the state and emits [`Action`]s.

use crate::app_state::{Action, AppState, SCENES, TIME_SCALES};
use crate::cli::ParticleSolverArg;
use crate::render::{self, Viewport};
use crate::session::Session;
use egui::{Align2, Color32, FontId, Id, LayerId, Order, Pos2, Rect, Stroke, Vec2};
use egui_plot::{Legend, Line, Plot};

/// Side colours of the labels and the plot.
const BLUE: Color32 = Color32::from_rgb(70, 130, 235);
const RED: Color32 = Color32::from_rgb(230, 70, 55);

/// What one UI pass reads and where it writes.
pub struct UiModel<'a> {
    /// App state.
    pub state: &'a AppState,
    /// The running scene.
    pub session: &'a Session,
    /// Physical pixels per egui point.
    pub pixels_per_point: f32,
    /// Actions the user took in this pass.
    pub actions: &'a mut Vec<Action>,
}

/// Builds the UI of one frame; returns the area left for the 3D view (points).
pub fn build(ui: &mut egui::Ui, model: &mut UiModel) -> Rect {
    if model.state.panel {
        // At most 40 % of a small window, so the two views keep room to be seen.
        let widest = (ui.available_width() * 0.4).max(150.0);
        egui::Panel::left("panel")
            .default_size(290.0_f32.min(widest))
            .max_size(widest)
            .resizable(true)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| panel(ui, model));
            });
    }
    let area = ui.available_rect_before_wrap();
    labels(ui.ctx(), area, model);
    if let Some(at) = model.state.menu {
        menu(
            ui.ctx(),
            Pos2::new(at.x, at.y) / model.pixels_per_point,
            model,
        );
    }
    area
}

/// The two viewports of `area` (points), in physical pixels.
pub fn viewports(area: Rect, pixels_per_point: f32) -> [Viewport; 2] {
    render::split(Viewport {
        x: area.min.x * pixels_per_point,
        y: area.min.y * pixels_per_point,
        width: area.width() * pixels_per_point,
        height: area.height() * pixels_per_point,
    })
}

fn side_title(session: &Session, i: usize) -> String {
    let m = &session.methods[i];
    let name = if i == 0 { "particle" } else { "multibody" };
    format!("{name} · {}", m.solver_label())
}

/// Per-half label with the step time, the divider, the clock and body names.
fn labels(ctx: &egui::Context, area: Rect, model: &UiModel) {
    let painter = ctx.layer_painter(LayerId::new(Order::Background, Id::unique("labels")));
    let (state, session) = (model.state, model.session);
    let mid = (area.min.x + (area.width() * 0.5).floor()).round();
    // 14 px in a 720 px tall view, smaller in small captures (never below 8 px).
    let font = (area.height() / 50.0).clamp(8.0, 14.0);
    for i in 0..2 {
        let (x, half) = if i == 0 {
            (area.min.x, mid - area.min.x)
        } else {
            (mid, area.max.x - mid)
        };
        let text = format!(
            "{}\nstep {:.2} ms",
            side_title(session, i),
            session.step_ms[i]
        );
        // Wrapped to its half, or a narrow window runs it into the other one.
        let wrap = (half - 28.0).max(40.0);
        let galley = painter.layout(text, FontId::proportional(font), Color32::WHITE, wrap);
        let pos = Pos2::new(x + 10.0, area.min.y + 10.0);
        let bg = Rect::from_min_size(pos, galley.size()).expand(6.0);
        painter.rect_filled(bg, 4.0, Color32::from_black_alpha(150));
        painter.rect_filled(
            Rect::from_min_size(bg.min, Vec2::new(4.0, bg.height())),
            0.0,
            if i == 0 { BLUE } else { RED },
        );
        painter.galley(pos + Vec2::new(2.0, 0.0), galley, Color32::WHITE);
    }
    painter.line_segment(
        [Pos2::new(mid, area.min.y), Pos2::new(mid, area.max.y)],
        Stroke::new(2.0, Color32::from_gray(40)),
    );
    let clock = format!(
        "{}  ·  t {:.2} s  ·  {}  ·  ×{}",
        session.loaded.desc.name,
        session.time(),
        if state.running { "running" } else { "stopped" },
        state.time_scale()
    );
    let galley = painter.layout_no_wrap(clock, FontId::proportional(font), Color32::WHITE);
    let pos = Pos2::new(area.min.x + 10.0, area.max.y - 10.0 - galley.size().y);
    painter.rect_filled(
        Rect::from_min_size(pos, galley.size()).expand(5.0),
        4.0,
        Color32::from_black_alpha(150),
    );
    painter.galley(pos, galley, Color32::WHITE);
    if let Some((text, at)) = &state.notice
        && at.elapsed().as_secs_f32() < crate::app_state::NOTICE_SECONDS
    {
        let wrap = (area.width() - 20.0).max(50.0);
        let galley = painter.layout(
            text.clone(),
            FontId::proportional(font),
            Color32::WHITE,
            wrap,
        );
        let above = pos.y - 14.0 - galley.size().y;
        let at = Pos2::new(area.min.x + 10.0, above);
        painter.rect_filled(
            Rect::from_min_size(at, galley.size()).expand(5.0),
            4.0,
            Color32::from_rgba_unmultiplied(150, 20, 20, 220),
        );
        painter.galley(at, galley, Color32::WHITE);
    }
    if state.show.names {
        let ppp = model.pixels_per_point;
        for (vp, snap) in viewports(area, ppp).iter().zip(&session.snapshots) {
            for b in &snap.bodies {
                let name = session
                    .loaded
                    .desc
                    .bodies
                    .get(b.body.index())
                    .map_or("projectile", |d| d.name.as_str());
                if let Some(p) = vp.project(&state.camera, b.pose.position) {
                    let p = Pos2::new(p.x / ppp, p.y / ppp);
                    if area.contains(p) {
                        // White on a dark plate: readable over light and dark bodies,
                        // and over the sky, where black text vanished on dark limbs.
                        let galley = painter.layout_no_wrap(
                            name.to_string(),
                            FontId::proportional(11.0),
                            Color32::WHITE,
                        );
                        let at = Align2::CENTER_CENTER.anchor_size(p, galley.size()).min;
                        painter.rect_filled(
                            Rect::from_min_size(at, galley.size()).expand(2.0),
                            3.0,
                            Color32::from_black_alpha(170),
                        );
                        painter.galley(at, galley, Color32::WHITE);
                    }
                }
            }
        }
    }
}

/// The side panel.
fn panel(ui: &mut egui::Ui, model: &mut UiModel) {
    let (state, session) = (model.state, model.session);
    let actions = &mut *model.actions;
    ui.heading("ragdoll-lab");
    ui.label("left: particles (blue) · right: multibody (red)");
    ui.separator();

    ui.strong("Scene");
    let current = state.scene.map_or_else(
        || session.loaded.desc.name.clone(),
        |i| format!("{} {}", i + 1, SCENES[i]),
    );
    egui::ComboBox::new("scene", "")
        .selected_text(current)
        .width(200.0)
        .show_ui(ui, |ui| {
            for (i, name) in SCENES.iter().enumerate() {
                if ui
                    .selectable_label(state.scene == Some(i), format!("{} {name}", i + 1))
                    .clicked()
                {
                    actions.push(Action::SelectScene(i));
                }
            }
        });
    let desc = &session.loaded.desc;
    if !desc.variants.is_empty() {
        ui.strong("Variant");
        for v in &desc.variants {
            if ui
                .radio(desc.variant == v.number, format!("{} {}", v.number, v.name))
                .clicked()
            {
                actions.push(Action::Variant(v.number));
            }
        }
    }
    ui.separator();

    ui.horizontal(|ui| {
        let (label, action) = if state.running {
            ("Stop", Action::ToggleRun)
        } else {
            ("Start", Action::Start)
        };
        if ui.button(label).clicked() {
            actions.push(action);
        }
        if ui.button("Step").clicked() {
            actions.push(Action::StepOnce);
        }
        if ui.button("Reset").clicked() {
            actions.push(Action::Reset);
        }
    });
    ui.horizontal(|ui| {
        if ui.button("[").clicked() {
            actions.push(Action::Slower);
        }
        ui.label(format!("time ×{}", state.time_scale()));
        if ui.button("]").clicked() {
            actions.push(Action::Faster);
        }
        if ui.button("Shoot box").clicked() {
            actions.push(Action::ShootBox);
        }
    });
    ui.separator();

    ui.strong("Particle solver");
    ui.horizontal(|ui| {
        for (solver, name) in [
            (ParticleSolverArg::Paper, "paper"),
            (ParticleSolverArg::RigidFrames, "rigid frames"),
        ] {
            if ui.radio(state.particle_solver == solver, name).clicked() {
                actions.push(Action::ParticleSolver(solver));
            }
        }
    });
    let mut settings = session.settings();
    let mut timestep_ms = settings.timestep * 1e3;
    let mut changed = ui
        .add(egui::Slider::new(&mut timestep_ms, 2.0..=50.0).text("timestep (ms)"))
        .changed();
    changed |= ui
        .add(egui::Slider::new(&mut settings.iterations, 1..=50).text("iterations"))
        .changed();
    // The slider sets both methods' substeps; a scene's own multibody count
    // (`multibodySubsteps`, shown in the solver labels) gives way to it once moved.
    if ui
        .add(egui::Slider::new(&mut settings.substeps, 1..=32).text("substeps"))
        .changed()
    {
        settings.multibody_substeps = None;
        changed = true;
    }
    if changed {
        settings.timestep = timestep_ms * 1e-3;
        actions.push(Action::Settings(settings));
    }
    ui.separator();

    ui.strong("Show");
    let mut show = state.show;
    let mut toggled = false;
    ui.horizontal_wrapped(|ui| {
        toggled |= ui.checkbox(&mut show.particles, "particles").changed();
        toggled |= ui.checkbox(&mut show.sticks, "sticks").changed();
        toggled |= ui.checkbox(&mut show.contacts, "contacts").changed();
        toggled |= ui.checkbox(&mut show.limits, "limits").changed();
        toggled |= ui.checkbox(&mut show.names, "names").changed();
        toggled |= ui.checkbox(&mut show.bodies, "bodies").changed();
        toggled |= ui.checkbox(&mut show.mesh, "mesh").changed();
    });
    if toggled {
        actions.push(Action::Show(show));
    }
    ui.separator();

    egui::Grid::new("numbers").striped(true).show(ui, |ui| {
        ui.label("");
        ui.colored_label(BLUE, "particle");
        ui.colored_label(RED, "multibody");
        ui.end_row();
        let row = |ui: &mut egui::Ui, name: &str, f: &dyn Fn(usize) -> String| {
            ui.label(name);
            ui.label(f(0));
            ui.label(f(1));
            ui.end_row();
        };
        row(ui, "step (ms)", &|i| format!("{:.3}", session.step_ms[i]));
        row(ui, "energy (J)", &|i| {
            format!("{:.2}", session.samples[i].energy)
        });
        row(ui, "kinetic (J)", &|i| {
            format!("{:.2}", session.samples[i].kinetic)
        });
        row(ui, "bodies", &|i| {
            session.methods[i].body_count().to_string()
        });
        row(ui, "particles", &|i| {
            session.methods[i].particle_count().to_string()
        });
        row(ui, "asleep", &|i| {
            if session.samples[i].all_asleep {
                "yes"
            } else {
                "no"
            }
            .to_string()
        });
    });

    let lines = [
        ("particle", BLUE, session.energy[0].clone()),
        ("multibody", RED, session.energy[1].clone()),
    ];
    Plot::new("energy")
        .height(150.0)
        .legend(Legend::default())
        .x_axis_label("t (s)")
        .y_axis_label("E (J)")
        .allow_scroll(false)
        .show(ui, move |plot| {
            for (name, color, points) in lines {
                plot.line(Line::new(name, points).color(color));
            }
        });

    egui::CollapsingHeader::new("Keys").show(ui, |ui| {
        ui.label(KEYS);
    });
}

/// Every key, as the README lists them.
pub const KEYS: &str = "Space start · T one step · S stop/start · Esc/Q quit\n\
1 reset (variant 1) · 2/3 variants · Tab/Shift+Tab next/previous scene\n\
left drag orbit · middle drag pan · wheel zoom · right click menu\n\
Ctrl+left drag grab a body · B shoot a box · R reload file\n\
[ / ] slower / faster · F1 or H panel";

/// The right-click menu: every option.
fn menu(ctx: &egui::Context, at: Pos2, model: &mut UiModel) {
    let (state, session) = (model.state, model.session);
    let mut chosen: Vec<Action> = Vec::new();
    egui::Area::new(Id::unique("menu"))
        .fixed_pos(at)
        .order(Order::Foreground)
        .show(ctx, |ui| {
            egui::Frame::menu(ui.style()).show(ui, |ui| {
                ui.set_min_width(180.0);
                let mut item = |ui: &mut egui::Ui, text: &str, action: Action| {
                    if ui.button(text).clicked() {
                        chosen.push(action);
                    }
                };
                if state.running {
                    item(ui, "Stop (S)", Action::ToggleRun);
                } else {
                    item(ui, "Start (Space)", Action::Start);
                }
                item(ui, "One step (T)", Action::StepOnce);
                item(ui, "Reset (1)", Action::Reset);
                let desc = &session.loaded.desc;
                for v in &desc.variants {
                    item(
                        ui,
                        &format!("Variant {} ({})", v.number, v.name),
                        Action::Variant(v.number),
                    );
                }
                ui.separator();
                item(ui, "Next scene (Tab)", Action::NextScene);
                item(ui, "Previous scene (Shift+Tab)", Action::PrevScene);
                ui.menu_button("Scene", |ui| {
                    for (i, name) in SCENES.iter().enumerate() {
                        item(ui, &format!("{} {name}", i + 1), Action::SelectScene(i));
                    }
                });
                item(ui, "Reload file (R)", Action::Reload);
                ui.separator();
                let other = match state.particle_solver {
                    ParticleSolverArg::Paper => ParticleSolverArg::RigidFrames,
                    ParticleSolverArg::RigidFrames => ParticleSolverArg::Paper,
                };
                item(
                    ui,
                    &format!("Particle solver: {other:?}"),
                    Action::ParticleSolver(other),
                );
                let s = state.show;
                let toggles = [
                    ("particles", ShowFlag::Particles, s.particles),
                    ("sticks", ShowFlag::Sticks, s.sticks),
                    ("contacts", ShowFlag::Contacts, s.contacts),
                    ("limits", ShowFlag::Limits, s.limits),
                    ("names", ShowFlag::Names, s.names),
                ];
                for (name, flag, on) in toggles {
                    let text = format!("{} {name}", if on { "Hide" } else { "Show" });
                    item(ui, &text, Action::Show(flag.toggle(s)));
                }
                ui.separator();
                item(ui, "Shoot a box (B)", Action::ShootBox);
                item(
                    ui,
                    &format!("Slower ([) — now ×{}", state.time_scale()),
                    Action::Slower,
                );
                item(
                    ui,
                    &format!("Faster (]) — max ×{}", TIME_SCALES[TIME_SCALES.len() - 1]),
                    Action::Faster,
                );
                item(ui, "Toggle panel (F1)", Action::TogglePanel);
                item(ui, "Quit (Esc)", Action::Quit);
            });
        });
    if !chosen.is_empty() {
        model.actions.extend(chosen);
        model.actions.push(Action::CloseMenu);
    }
}

#[derive(Clone, Copy)]
enum ShowFlag {
    Particles,
    Sticks,
    Contacts,
    Limits,
    Names,
}

impl ShowFlag {
    fn toggle(self, mut s: render::ShowOptions) -> render::ShowOptions {
        let f = match self {
            ShowFlag::Particles => &mut s.particles,
            ShowFlag::Sticks => &mut s.sticks,
            ShowFlag::Contacts => &mut s.contacts,
            ShowFlag::Limits => &mut s.limits,
            ShowFlag::Names => &mut s.names,
        };
        *f = !*f;
        s
    }
}
