//! The egui layer: per-half labels and the divider (always), the side panel (scene list,
//! variant, play/pause/step, solver, sliders, overlay toggles and their legend, live
//! quality numbers per method with a plot, the inspected body) and the right-click menu.
//! It only reads the state and emits [`Action`]s, and reports where it put things
//! ([`UiLayout`]) so tests can check that nothing leaves its area.

use crate::app_state::{Action, AppState, SCENES, SettingsOverride, TIME_SCALES, ViewLayout};
use crate::cli::ParticleSolverArg;
use crate::inspect;
use crate::render::{self, Viewport};
use crate::session::{HistoryPoint, Session};
use egui::text::{LayoutJob, TextWrapping};
use egui::{
    Align2, Color32, FontId, Galley, Id, LayerId, Order, Painter, Pos2, Rect, Stroke, Vec2,
};
use egui_plot::{Legend, Line, Plot};
use std::sync::Arc;

/// Side colours of the labels and the plot.
const BLUE: Color32 = Color32::from_rgb(70, 130, 235);
const RED: Color32 = Color32::from_rgb(230, 70, 55);
/// Amber, for a time scale the window does not reach.
const AMBER: Color32 = Color32::from_rgb(250, 190, 60);

/// The panel's width (points): 300, or 40 % of a narrower window but never under 190,
/// the narrowest its rows are laid out for. Fixed for a given window width, so switching
/// solvers or scenes never moves the views.
pub fn panel_width(screen_width: f32) -> f32 {
    (screen_width * 0.4).clamp(190.0, 300.0)
}

/// Text height of the view labels (points): 13 in a 650 pt tall view, never under 11
/// (legible) nor over 14.
fn label_font(view_height: f32) -> f32 {
    (view_height / 50.0).clamp(11.0, 14.0)
}

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
    /// Where the parts went.
    pub layout: &'a mut UiLayout,
}

/// A text the view's overlay placed, and the area it must stay in (points).
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedText {
    /// Which text ("label 0", "clock", "notice", "name").
    pub what: String,
    /// Its plate.
    pub rect: Rect,
    /// The area it belongs to.
    pub bounds: Rect,
    /// Text height (points).
    pub font: f32,
    /// Rows it was laid out in, and the most it may take.
    pub rows: (usize, usize),
}

/// Where one UI pass put its parts (points).
#[derive(Clone, Debug, PartialEq)]
pub struct UiLayout {
    /// The whole window.
    pub screen: Rect,
    /// The area of the 3D views.
    pub view: Rect,
    /// The side panel, when shown.
    pub panel: Option<Rect>,
    /// The panel's laid-out contents (taller than the panel when it scrolls).
    pub panel_content: Option<Rect>,
    /// The plot, axes included.
    pub plot: Option<Rect>,
    /// The view's texts.
    pub texts: Vec<PlacedText>,
}

impl Default for UiLayout {
    fn default() -> Self {
        UiLayout {
            screen: Rect::NOTHING,
            view: Rect::NOTHING,
            panel: None,
            panel_content: None,
            plot: None,
            texts: Vec::new(),
        }
    }
}

/// Builds the UI of one frame into `model.layout` (the 3D area is `layout.view`).
pub fn build(ui: &mut egui::Ui, model: &mut UiModel) {
    model.layout.screen = ui.max_rect();
    if model.state.panel {
        let width = panel_width(ui.max_rect().width());
        let shown = egui::Panel::left("panel")
            .exact_size(width)
            .resizable(false)
            .show(ui, |ui| {
                egui::ScrollArea::vertical()
                    .show(ui, |ui| {
                        panel(ui, model);
                        ui.min_rect()
                    })
                    .inner
            });
        model.layout.panel = Some(shown.response.rect);
        model.layout.panel_content = Some(shown.inner);
    }
    let area = ui.available_rect_before_wrap();
    model.layout.view = area;
    labels(ui.ctx(), area, model);
    if let Some(at) = model.state.menu {
        menu(
            ui.ctx(),
            Pos2::new(at.x, at.y) / model.pixels_per_point,
            model,
        );
    }
}

/// The two viewports of `area` (points), in physical pixels; a side the layout hides
/// gets no pixels.
pub fn viewports(area: Rect, pixels_per_point: f32, layout: ViewLayout) -> [Viewport; 2] {
    let full = Viewport {
        x: area.min.x * pixels_per_point,
        y: area.min.y * pixels_per_point,
        width: area.width() * pixels_per_point,
        height: area.height() * pixels_per_point,
    };
    let none = Viewport { width: 0.0, ..full };
    match layout {
        ViewLayout::Both => render::split(full),
        ViewLayout::Particle => [full, none],
        ViewLayout::Multibody => [none, full],
    }
}

/// Whether to say the time scale falls short: not while everything sleeps, when no
/// frames are drawn and the last measurement is stale.
fn falls_short(state: &AppState, session: &Session) -> bool {
    state.falls_short() && !session.samples.iter().all(|s| s.all_asleep)
}

/// A galley of at most `max_rows` rows of `max_width`, cut with "…" beyond; one-row texts
/// may break anywhere (to elide), longer ones only between words.
fn text(painter: &Painter, s: String, font: f32, max_width: f32, max_rows: usize) -> Arc<Galley> {
    let mut job = LayoutJob::simple(s, FontId::proportional(font), Color32::WHITE, max_width);
    job.wrap = TextWrapping {
        max_width,
        max_rows,
        break_anywhere: max_rows == 1,
        overflow_character: Some('…'),
    };
    painter.layout_job(job)
}

/// Draws `galley` on a dark plate at `pos` and records it.
/// `what` names it, `bounds` is the area it must stay in, `max_rows` the rows it may take.
fn plate(
    painter: &Painter,
    layout: &mut UiLayout,
    (what, bounds, max_rows): (&str, Rect, usize),
    pos: Pos2,
    galley: Arc<Galley>,
    (font, fill): (f32, Color32),
) -> Rect {
    let rect = Rect::from_min_size(pos, galley.size()).expand(5.0);
    painter.rect_filled(rect, 4.0, fill);
    layout.texts.push(PlacedText {
        what: what.to_string(),
        rect,
        bounds,
        font,
        rows: (galley.rows.len(), max_rows),
    });
    painter.galley(pos, galley, Color32::WHITE);
    rect
}

/// The method's own label, with "×" spelled so that "1 × 5" cannot read as "15".
fn side_title(session: &Session, i: usize) -> String {
    let m = &session.methods[i];
    let name = if i == 0 { "particle" } else { "multibody" };
    format!("{name} · {}", m.solver_label().replace(" × ", " x "))
}

/// Per-half labels with the step time, the divider, the clock, the notice and names.
fn labels(ctx: &egui::Context, area: Rect, model: &mut UiModel) {
    let painter = ctx.layer_painter(LayerId::new(Order::Background, Id::unique("labels")));
    let (state, session) = (model.state, model.session);
    let ppp = model.pixels_per_point;
    let font = label_font(area.height());
    let plate_fill = Color32::from_black_alpha(160);
    let vps = viewports(area, ppp, state.layout);
    let halves = vps.map(|vp| {
        Rect::from_min_size(
            Pos2::new(vp.x, vp.y) / ppp,
            Vec2::new(vp.width, vp.height) / ppp,
        )
    });
    for (i, half) in halves.iter().enumerate() {
        if half.width() < 1.0 {
            continue;
        }
        let inner = half.width() - 30.0;
        // A word longer than a row would be broken inside: in a narrow half the title is
        // only the method's name, cut with "…" if even that does not fit.
        let title = if inner >= 150.0 {
            text(&painter, side_title(session, i), font, inner, 2)
        } else {
            let name = if i == 0 { "particle" } else { "multibody" };
            text(&painter, name.to_string(), font, inner, 1)
        };
        let step = text(
            &painter,
            format!("step {:.2} ms", session.step_ms[i]),
            font,
            inner,
            1,
        );
        let pos = half.min + Vec2::new(10.0, 10.0);
        let title_h = title.size().y;
        let size = Vec2::new(title.size().x.max(step.size().x), title_h + step.size().y);
        let rect = Rect::from_min_size(pos, size).expand(5.0);
        painter.rect_filled(rect, 4.0, plate_fill);
        painter.rect_filled(
            Rect::from_min_size(rect.min, Vec2::new(4.0, rect.height())),
            0.0,
            if i == 0 { BLUE } else { RED },
        );
        model.layout.texts.push(PlacedText {
            what: format!("label {i}"),
            rect,
            bounds: *half,
            font,
            rows: (title.rows.len() + step.rows.len(), 3),
        });
        painter.galley(pos + Vec2::new(3.0, 0.0), title, Color32::WHITE);
        painter.galley(pos + Vec2::new(3.0, title_h), step, Color32::WHITE);
    }
    if state.layout == ViewLayout::Both {
        let mid = halves[1].min.x;
        painter.line_segment(
            [Pos2::new(mid, area.min.y), Pos2::new(mid, area.max.y)],
            Stroke::new(2.0, Color32::from_gray(40)),
        );
    }

    // The clock: what runs, how fast it was asked to and how fast it goes.
    let rate = &state.rate;
    let mut clock = format!(
        "{} · t {:.2} s · {} · ×{}",
        session.loaded.desc.name,
        session.time(),
        if state.running { "running" } else { "stopped" },
        state.time_scale()
    );
    let asleep = session.samples.iter().all(|s| s.all_asleep);
    if state.running && rate.reached_scale > 0.0 && !asleep {
        clock += &format!(" (reached ×{:.2})", rate.reached_scale);
    }
    if rate.frame_ms > 0.0 {
        clock += &format!(" · {:.0} fps, {:.1} ms", rate.fps(), rate.frame_ms);
    }
    if asleep {
        clock += " · all asleep";
    }
    if state.follow {
        clock += " · following (F)";
    }
    if state.recording {
        clock += " · ● recording (Shift+P)";
    }
    if let Some((a, t)) = &session.playing {
        let rate = a.takeover.anim().frame_rate as f32;
        clock += &format!(" · animation frame {:.1} (K: ragdoll takes over)", t * rate);
    }
    let wide = area.width() - 30.0;
    let galley = text(&painter, clock, font, wide, 2);
    let pos = Pos2::new(area.min.x + 10.0, area.max.y - 10.0 - galley.size().y);
    let fill = if falls_short(state, session) {
        Color32::from_rgba_unmultiplied(120, 80, 0, 220)
    } else {
        plate_fill
    };
    let clock_rect = plate(
        &painter,
        model.layout,
        ("clock", area, 2),
        pos,
        galley,
        (font, fill),
    );
    if falls_short(state, session) {
        let why = text(
            &painter,
            format!(
                "slower than asked: ×{:.2} of ×{} (at most {} steps a frame)",
                rate.reached_scale,
                state.time_scale(),
                crate::app_state::MAX_STEPS_PER_FRAME
            ),
            font,
            wide,
            2,
        );
        let at = Pos2::new(
            clock_rect.min.x + 5.0,
            clock_rect.min.y - 10.0 - why.size().y,
        );
        painter.rect_filled(
            Rect::from_min_size(at, why.size()).expand(5.0),
            4.0,
            Color32::from_black_alpha(160),
        );
        painter.galley(at, why, AMBER);
    }

    // The error notice stays inside the left view, above the clock, wrapped anywhere (a
    // long path has no spaces to break at).
    if let Some((message, at)) = &state.notice
        && at.elapsed().as_secs_f32() < crate::app_state::NOTICE_SECONDS
    {
        let bounds = if halves[0].width() >= 1.0 {
            halves[0]
        } else {
            halves[1]
        };
        let mut job = LayoutJob::simple(
            message.clone(),
            FontId::proportional(font),
            Color32::WHITE,
            bounds.width() - 30.0,
        );
        job.wrap.break_anywhere = true;
        job.wrap.max_rows = 6;
        job.wrap.overflow_character = Some('…');
        let galley = painter.layout_job(job);
        let pos = Pos2::new(
            bounds.min.x + 10.0,
            clock_rect.min.y - 40.0 - galley.size().y,
        );
        plate(
            &painter,
            model.layout,
            ("notice", bounds, 6),
            pos,
            galley,
            (font, Color32::from_rgba_unmultiplied(150, 20, 20, 230)),
        );
    }
    lost_bodies(&painter, &vps, model);
    names(&painter, &vps, model);
}

/// A half whose dynamic bodies all left its view (the paper solver's human sliding
/// away) says how to find them again.
fn lost_bodies(painter: &Painter, vps: &[Viewport; 2], model: &mut UiModel) {
    let (state, session) = (model.state, model.session);
    let ppp = model.pixels_per_point;
    for (side, (vp, snap)) in vps.iter().zip(&session.snapshots).enumerate() {
        let moving = snap
            .bodies
            .iter()
            .filter(|b| b.role != ragdoll_sim::snapshot::BodyRole::Fixed);
        let mut any = false;
        let mut seen = false;
        for b in moving {
            any = true;
            seen |= vp
                .project(&state.camera, b.pose.position)
                .is_some_and(|p| vp.contains(p));
        }
        if vp.width < 1.0 || !any || seen {
            continue;
        }
        let bounds = Rect::from_min_size(
            Pos2::new(vp.x, vp.y) / ppp,
            Vec2::new(vp.width, vp.height) / ppp,
        );
        let font = label_font(bounds.height());
        let galley = text(
            painter,
            "the bodies left this view: F follows them (F again stops)".into(),
            font,
            bounds.width() - 30.0,
            3,
        );
        let pos = Pos2::new(
            bounds.min.x + 10.0,
            bounds.center().y - galley.size().y * 0.5,
        );
        plate(
            painter,
            model.layout,
            (&format!("lost {side}"), bounds, 3),
            pos,
            galley,
            (font, Color32::from_black_alpha(180)),
        );
    }
}

/// Body names: with "names" on, every body's that does not overlap one already placed
/// (bodies nearer the camera first); always the hovered and the selected body's.
fn names(painter: &Painter, vps: &[Viewport; 2], model: &mut UiModel) {
    let (state, session) = (model.state, model.session);
    let ppp = model.pixels_per_point;
    let wanted = |id: ragdoll_sim::scene::BodyId| {
        state.show.names || state.selected == Some(id) || state.hovered == Some(id)
    };
    let eye = state.camera.eye();
    for (side, (vp, snap)) in vps.iter().zip(&session.snapshots).enumerate() {
        if vp.width < 1.0 {
            continue;
        }
        let bounds = Rect::from_min_size(
            Pos2::new(vp.x, vp.y) / ppp,
            Vec2::new(vp.width, vp.height) / ppp,
        );
        let mut order: Vec<_> = snap.bodies.iter().filter(|b| wanted(b.body)).collect();
        // Selected and hovered first, then nearest first.
        order.sort_by(|a, b| {
            let key = |x: &&ragdoll_sim::snapshot::BodyInstance| {
                let pinned = state.selected == Some(x.body) || state.hovered == Some(x.body);
                (!pinned, x.pose.position.distance_squared(eye))
            };
            key(a)
                .partial_cmp(&key(b))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let mut placed: Vec<Rect> = Vec::new();
        for b in order {
            let name = session
                .loaded
                .desc
                .bodies
                .get(b.body.index())
                .map_or("projectile", |d| d.name.as_str());
            let Some(p) = vp.project(&state.camera, b.pose.position) else {
                continue;
            };
            let p = Pos2::new(p.x / ppp, p.y / ppp);
            let galley = text(painter, name.to_string(), 11.0, bounds.width() - 20.0, 1);
            let at = Align2::CENTER_CENTER.anchor_size(p, galley.size()).min;
            let rect = Rect::from_min_size(at, galley.size()).expand(2.0);
            let pinned = state.selected == Some(b.body) || state.hovered == Some(b.body);
            if !bounds.contains_rect(rect) || (!pinned && placed.iter().any(|r| r.intersects(rect)))
            {
                continue;
            }
            placed.push(rect);
            let fill = if state.selected == Some(b.body) {
                Color32::from_rgba_unmultiplied(40, 40, 10, 220)
            } else {
                Color32::from_black_alpha(170)
            };
            painter.rect_filled(rect, 3.0, fill);
            model.layout.texts.push(PlacedText {
                what: format!("name {side}"),
                rect,
                bounds,
                font: 11.0,
                rows: (galley.rows.len(), 1),
            });
            painter.galley(at, galley, Color32::WHITE);
        }
    }
}

/// The side panel: the scene and its running first, then the solver and its settings,
/// the live numbers and their plot (all visible without scrolling at 720 points), then
/// the inspected body, and what is looked up less often in collapsed sections.
fn panel(ui: &mut egui::Ui, model: &mut UiModel) {
    let (state, session) = (model.state, model.session);
    let actions = &mut *model.actions;
    let width = ui.available_width();
    ui.horizontal_wrapped(|ui| {
        ui.strong("ragdoll-lab");
        ui.colored_label(BLUE, "left: particles");
        ui.colored_label(RED, "right: multibody");
    });

    let current = state.scene.map_or_else(
        || session.loaded.desc.name.clone(),
        |i| format!("{} {}", i + 1, SCENES[i]),
    );
    egui::ComboBox::new("scene", "")
        .selected_text(current)
        .width(width - 8.0)
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
        let now = desc
            .variants
            .iter()
            .find(|v| v.number == desc.variant)
            .map_or_else(
                || format!("variant {}", desc.variant),
                |v| format!("variant {} {}", v.number, v.name),
            );
        egui::ComboBox::new("variant", "")
            .selected_text(now)
            .width(width - 8.0)
            .truncate()
            .show_ui(ui, |ui| {
                for v in &desc.variants {
                    let text = format!("{} {}", v.number, v.name);
                    if ui
                        .selectable_label(desc.variant == v.number, text)
                        .clicked()
                    {
                        actions.push(Action::Variant(v.number));
                    }
                }
            });
    }
    ui.horizontal_wrapped(|ui| {
        let (label, action) = if state.running {
            ("Stop", Action::ToggleRun)
        } else {
            ("Start", Action::Start)
        };
        if ui.button(label).clicked() {
            actions.push(action);
        }
        if ui
            .button("Step")
            .on_hover_text("one timestep (T)")
            .clicked()
        {
            actions.push(Action::StepOnce);
        }
        if ui
            .button("Step 10")
            .on_hover_text("ten timesteps, then stop (Shift+T)")
            .clicked()
        {
            actions.push(Action::StepFrames(10));
        }
        if ui
            .button("Reset")
            .on_hover_text("from the start, your settings kept (1)")
            .clicked()
        {
            actions.push(Action::Reset);
        }
    });
    ui.horizontal_wrapped(|ui| {
        if ui.button("[").on_hover_text("slower").clicked() {
            actions.push(Action::Slower);
        }
        let asked = format!("time ×{}", state.time_scale());
        if falls_short(state, session) {
            ui.colored_label(
                AMBER,
                format!("{asked}, reached ×{:.2}", state.rate.reached_scale),
            );
        } else {
            ui.label(asked);
        }
        if ui.button("]").on_hover_text("faster").clicked() {
            actions.push(Action::Faster);
        }
    });
    ui.separator();

    ui.horizontal_wrapped(|ui| {
        ui.strong("Particle solver");
        for (solver, name) in [
            (ParticleSolverArg::Paper, "paper"),
            (ParticleSolverArg::RigidFrames, "rigid frames"),
            (ParticleSolverArg::Xpbd, "xpbd particles"),
        ] {
            if ui.radio(state.particle_solver == solver, name).clicked() {
                actions.push(Action::ParticleSolver(solver));
            }
        }
    });
    if state.particle_solver != ParticleSolverArg::Paper
        && desc.variants.iter().any(|v| v.name.contains("particles"))
    {
        ui.small("Variants alike here: only the paper solver uses their particles.")
            .on_hover_text(
                "These variants move only the particles the paper's solver places in each \
                 box; rigid frames and the multibody method do not use them, so both variants \
                 run the same. Pick \"paper\" to see them differ.",
            );
    }
    settings_sliders(ui, state, session, actions);
    ui.separator();

    numbers(ui, session);
    step_phases(ui, session);
    let plot = plot(ui, session);
    model.layout.plot = Some(plot);
    if let Some(body) = state.selected {
        ui.separator();
        inspector(ui, session, body);
    }
    ui.separator();

    egui::CollapsingHeader::new("Show")
        .default_open(true)
        .show(ui, |ui| {
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
            ui.horizontal_wrapped(|ui| {
                ui.label("view (M)");
                for (layout, name) in [
                    (ViewLayout::Both, "both"),
                    (ViewLayout::Particle, "particle"),
                    (ViewLayout::Multibody, "multibody"),
                ] {
                    if ui.selectable_label(state.layout == layout, name).clicked() {
                        // M cycles; step until the wanted layout.
                        let mut l = state.layout;
                        while l != layout {
                            actions.push(Action::CycleLayout);
                            l = l.next();
                        }
                    }
                }
            });
            ui.small(LEGEND);
        });
    egui::CollapsingHeader::new("Shoot (B)").show(ui, |ui| {
        let mut shot = state.shot;
        let mut edge_cm = shot.edge * 100.0;
        let mut moved = slider(ui, egui::Slider::new(&mut edge_cm, 4.0..=60.0), "edge (cm)");
        moved |= slider(
            ui,
            egui::Slider::new(&mut shot.speed, 1.0..=40.0),
            "speed (m/s)",
        );
        if moved {
            shot.edge = edge_cm / 100.0;
            actions.push(Action::Shot(shot));
        }
        ui.small("B shoots through the cursor; this button through the left view's centre.");
        ui.horizontal_wrapped(|ui| {
            if ui.button("Shoot box").clicked() {
                actions.push(Action::ShootBox(None));
            }
            ui.small(format!("{:.2} kg", shot.mass()));
        });
    });
    egui::CollapsingHeader::new("Keys").show(ui, |ui| {
        ui.small(KEYS);
    });
}

/// A slider with its name beside it where the panel is wide enough, above it where not,
/// so neither the name nor the number is cut at the panel's edge. Returns whether it moved.
fn slider(ui: &mut egui::Ui, slider: egui::Slider, name: &str) -> bool {
    let width = ui.available_width();
    // The number box and spacing take about 70 points, a name beside it about 95.
    if width >= 250.0 {
        ui.spacing_mut().slider_width = width - 170.0;
        ui.add(slider.text(name)).changed()
    } else {
        ui.small(name);
        ui.spacing_mut().slider_width = (width - 75.0).max(40.0);
        ui.add(slider).changed()
    }
}

/// What the colours mean.
pub const LEGEND: &str = "Blue: particle method; red: multibody. \
Darker: the body sleeps (it rests, the solver skips it until something touches it). \
Lighter: grabbed or selected. Particles: green where two bones share one (paper solver), \
red inside a bone, grey on a fixed bone. White lines: sticks.";

/// A number that is very small or very large in a short form.
fn short(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(0.01..10000.0).contains(&a) {
        format!("{v:.1e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}

/// The live numbers per method: now, and the worst since the start. Text is 12.5
/// points in a wide panel and 10 in a narrow one, so the three columns always fit.
fn numbers(ui: &mut egui::Ui, session: &Session) {
    let wide = ui.available_width() >= 250.0;
    let size = if wide { 12.5 } else { 10.0 };
    let t = |s: String| egui::RichText::new(s).size(size);
    egui::Grid::new("numbers")
        .striped(true)
        .num_columns(3)
        .spacing([6.0, 1.0])
        .show(ui, |ui| {
            ui.label(t("now (worst)".into()));
            ui.label(t("particle".into()).color(BLUE));
            let multibody = if wide { "multibody" } else { "multib." };
            ui.label(t(multibody.into()).color(RED));
            ui.end_row();
            let mut row = |name: &str, hover: &str, f: &dyn Fn(usize) -> String| {
                ui.label(t(name.into())).on_hover_text(hover);
                ui.label(t(f(0)));
                ui.label(t(f(1)));
                ui.end_row();
            };
            let (s, w) = (&session.samples, &session.worst);
            row("energy J", "kinetic + potential now", &|i| {
                short(s[i].energy)
            });
            row(
                "gained J",
                "largest rise above the start's energy so far",
                &|i| short(w[i].energy_rise),
            );
            row(
                "lost J",
                "largest fall below the start's energy so far",
                &|i| short(w[i].energy_loss),
            );
            row("penetr. mm", "deepest overlap now (worst so far)", &|i| {
                format!(
                    "{:.1} ({:.1})",
                    s[i].max_penetration * 1e3,
                    w[i].penetration * 1e3
                )
            });
            row("gap mm", "widest joint gap now (worst so far)", &|i| {
                format!(
                    "{:.1} ({:.1})",
                    s[i].max_joint_gap * 1e3,
                    w[i].joint_gap * 1e3
                )
            });
            row(
                "limit °",
                "largest excess beyond a joint limit now (worst so far)",
                &|i| {
                    format!(
                        "{:.1} ({:.1})",
                        s[i].max_limit_violation_deg, w[i].limit_excess_deg
                    )
                },
            );
            row(
                "stretch %",
                "largest stick-length error of a bone now (worst so far)",
                &|i| match s[i].max_bone_stretch {
                    Some(v) => format!("{:.2} ({:.2})", v * 100.0, w[i].stretch * 100.0),
                    None => "—".into(),
                },
            );
            row("asleep", "every body sleeps (drawn darker)", &|i| {
                if s[i].all_asleep { "yes" } else { "no" }.to_string()
            });
        });
}

/// The last step's wall time per phase of each method, collapsed by default. Each
/// solver names the phases it really runs; where joints, contacts and integration
/// interleave within a substep they are one phase ("substeps").
fn step_phases(ui: &mut egui::Ui, session: &Session) {
    egui::CollapsingHeader::new("Step phases (ms)")
        .default_open(false)
        .show(ui, |ui| {
            let size = if ui.available_width() >= 250.0 {
                12.5
            } else {
                10.0
            };
            let t = |s: String| egui::RichText::new(s).size(size);
            for (i, (name, color)) in [("particle", BLUE), ("multibody", RED)]
                .into_iter()
                .enumerate()
            {
                let times = session.methods[i].phase_times();
                egui::Grid::new(("step phases", i))
                    .striped(true)
                    .num_columns(2)
                    .spacing([6.0, 1.0])
                    .show(ui, |ui| {
                        ui.label(t(name.into()).color(color));
                        ui.label(t(format!("{:.3}", times.total * 1e3)))
                            .on_hover_text("the whole step's wall time");
                        ui.end_row();
                        for (phase, seconds) in times.phases() {
                            ui.label(t(format!("  {phase}")));
                            ui.label(t(format!("{:.3}", seconds * 1e3)));
                            ui.end_row();
                        }
                        if times.phases().next().is_none() {
                            ui.label(t("  (not split)".into()));
                            ui.end_row();
                        }
                    });
            }
        });
}

/// Which quantity the plot shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
enum PlotQuantity {
    #[default]
    Energy,
    Kinetic,
    Penetration,
    JointGap,
    LimitExcess,
    Stretch,
}

impl PlotQuantity {
    const ALL: [PlotQuantity; 6] = [
        PlotQuantity::Energy,
        PlotQuantity::Kinetic,
        PlotQuantity::Penetration,
        PlotQuantity::JointGap,
        PlotQuantity::LimitExcess,
        PlotQuantity::Stretch,
    ];

    fn name(self) -> &'static str {
        match self {
            PlotQuantity::Energy => "energy (J)",
            PlotQuantity::Kinetic => "kinetic (J)",
            PlotQuantity::Penetration => "penetration (mm)",
            PlotQuantity::JointGap => "joint gap (mm)",
            PlotQuantity::LimitExcess => "limit excess (°)",
            PlotQuantity::Stretch => "stretch (%)",
        }
    }

    fn value(self, p: &HistoryPoint) -> f64 {
        let s = &p.sample;
        match self {
            PlotQuantity::Energy => s.energy,
            PlotQuantity::Kinetic => s.kinetic,
            PlotQuantity::Penetration => s.max_penetration as f64 * 1e3,
            PlotQuantity::JointGap => s.max_joint_gap as f64 * 1e3,
            PlotQuantity::LimitExcess => s.max_limit_violation_deg as f64,
            PlotQuantity::Stretch => s.max_bone_stretch.unwrap_or(0.0) as f64 * 100.0,
        }
    }
}

/// Both methods' history of one quantity; returns the plot's rect (axes included).
fn plot(ui: &mut egui::Ui, session: &Session) -> Rect {
    let id = Id::unique("plot quantity");
    let mut quantity: PlotQuantity = ui.data_mut(|d| *d.get_temp_mut_or_default(id));
    egui::ComboBox::new("plot", "plot")
        .selected_text(quantity.name())
        .show_ui(ui, |ui| {
            for q in PlotQuantity::ALL {
                ui.selectable_value(&mut quantity, q, q.name());
            }
        });
    ui.data_mut(|d| d.insert_temp(id, quantity));
    let lines: Vec<(&str, Color32, Vec<[f64; 2]>)> = [("particle", BLUE), ("multibody", RED)]
        .iter()
        .zip(&session.history)
        .map(|(&(name, color), h)| {
            (
                name,
                color,
                h.iter().map(|p| [p.t, quantity.value(p)]).collect(),
            )
        })
        .collect();
    let shown = Plot::new("history")
        .height(120.0)
        .width(ui.available_width())
        .legend(Legend::default())
        .x_axis_label("t (s)")
        .allow_scroll(false)
        .show(ui, move |plot| {
            for (name, color, points) in lines {
                plot.line(Line::new(name, points).color(color));
            }
        });
    shown.response.rect
}

/// The selected body in both methods: mass, motion, its joints against their limits.
fn inspector(ui: &mut egui::Ui, session: &Session, body: ragdoll_sim::scene::BodyId) {
    let desc = &session.loaded.desc;
    let name = desc.bodies.get(body.index()).map_or_else(
        || format!("projectile {}", body.index()),
        |b| b.name.clone(),
    );
    ui.strong(format!("Selected: {name}"));
    let mass = desc.bodies.get(body.index()).map(|b| match b.mass {
        ragdoll_sim::scene::MassSpec::Mass(m) | ragdoll_sim::scene::MassSpec::Density(m) => m,
    });
    if let Some(m) = mass {
        ui.small(format!("mass {m:.2} kg"));
    }
    let mut states = [Vec::new(), Vec::new()];
    for (m, out) in session.methods.iter().zip(&mut states) {
        m.body_states(out);
    }
    egui::Grid::new("inspector")
        .num_columns(3)
        .spacing([6.0, 2.0])
        .show(ui, |ui| {
            ui.small("");
            ui.colored_label(BLUE, "particle");
            ui.colored_label(RED, "multib.");
            ui.end_row();
            let mut row = |label: &str, f: &dyn Fn(&ragdoll_sim::BodyState) -> String| {
                ui.small(label);
                for s in &states {
                    ui.small(s.get(body.index()).map_or("—".into(), f));
                }
                ui.end_row();
            };
            row("speed m/s", &|s| format!("{:.2}", inspect::speeds(s).0));
            row("spin rad/s", &|s| format!("{:.2}", inspect::speeds(s).1));
            row("height m", &|s| format!("{:.2}", inspect::height(desc, s)));
        });
    let readings = [0, 1].map(|i| inspect::joint_readings(desc, &states[i], body));
    if !readings[0].is_empty() {
        ui.small("joints: angle (limit), particle / multibody");
        for (a, b) in readings[0].iter().zip(&readings[1]) {
            let limit = a
                .limit_deg
                .map_or(String::new(), |(lo, hi)| format!(" [{lo:.0}°, {hi:.0}°]"));
            let text = format!(
                "{} {}: {:.1}° / {:.1}°{limit}",
                a.kind, a.name, a.angle_deg, b.angle_deg
            );
            if a.excess_deg() > 0.5 || b.excess_deg() > 0.5 {
                ui.colored_label(AMBER, text);
            } else {
                ui.small(text);
            }
        }
    }
    let near = |i: usize| {
        let Some(s) = states[i].get(body.index()) else {
            return 0;
        };
        let r = desc
            .bodies
            .get(body.index())
            .map_or(0.2, |b| b.shape.local_half_extents().length());
        session.snapshots[i]
            .contacts
            .iter()
            .filter(|c| c.point.distance(s.com) <= r * 1.05)
            .count()
    };
    ui.small(format!("contact points on it: {} / {}", near(0), near(1)));
}

/// Timestep, iterations and substeps: what the user moves becomes an override that
/// outlives resets (until another scene is picked); a button drops them.
fn settings_sliders(
    ui: &mut egui::Ui,
    state: &AppState,
    session: &Session,
    actions: &mut Vec<Action>,
) {
    let settings = session.settings();
    let mut timestep_ms = settings.timestep * 1e3;
    let mut iterations = settings.iterations;
    let mut substeps = settings.substeps;
    let mut chosen = SettingsOverride::default();
    if slider(
        ui,
        egui::Slider::new(&mut timestep_ms, 2.0..=50.0),
        "timestep (ms)",
    ) {
        chosen.timestep = Some(timestep_ms * 1e-3);
    }
    // The slider sets both methods' iterations; the multibody's own count
    // (`multibodyIterations`, shown in the solver labels) gives way to it once moved.
    if slider(ui, egui::Slider::new(&mut iterations, 1..=50), "iterations") {
        chosen.iterations = Some(iterations);
    }
    // The slider sets both methods' substeps; a scene's own multibody count
    // (`multibodySubsteps`, shown in the solver labels) gives way to it once moved.
    if slider(ui, egui::Slider::new(&mut substeps, 1..=32), "substeps") {
        chosen.substeps = Some(substeps);
    }
    if !chosen.is_empty() {
        actions.push(Action::Settings(chosen));
    }
    if !state.overrides.is_empty() {
        ui.horizontal_wrapped(|ui| {
            ui.small("yours, kept on reset");
            if ui.small_button("scene's own").clicked() {
                actions.push(Action::SceneSettings);
            }
        });
    }
}

/// Every key, as the README lists them.
pub const KEYS: &str = "Space start · T one step · Shift+T ten steps · S stop/start · Esc/Q quit\n\
1 reset (variant 1, your settings kept) · 2/3 variants · Tab/Shift+Tab next/previous scene\n\
left drag orbit · middle drag pan · wheel zoom · right click menu\n\
click a body: inspect it · Ctrl+left drag grab a body · B shoot a box through the cursor\n\
K the ragdoll takes over from the animation playing (--anim)\n\
Home camera back · F follow the selected figure (or all) · M both / one method\n\
P screenshot · Shift+P record frames · R reload file (also when it changes on disk)\n\
drop an .af file on the window to open it · [ / ] slower / faster · F1 or H panel";

fn menu(ctx: &egui::Context, at: Pos2, model: &mut UiModel) {
    let (state, session) = (model.state, model.session);
    let chosen: std::cell::RefCell<Vec<Action>> = Default::default();
    let menu_at = state.menu.unwrap_or_default();
    egui::Area::new(Id::unique("menu"))
        .fixed_pos(at)
        .order(Order::Foreground)
        .show(ctx, |ui| {
            egui::Frame::menu(ui.style()).show(ui, |ui| {
                ui.set_min_width(180.0);
                // The sliders would take every point offered: keep the menu a menu.
                ui.set_max_width(300.0);
                let item = |ui: &mut egui::Ui, text: &str, action: Action| {
                    if ui.button(text).clicked() {
                        chosen.borrow_mut().push(action);
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
                // Timestep, iterations and substeps, as in the panel.
                settings_sliders(ui, state, session, &mut chosen.borrow_mut());
                ui.separator();
                let other = match state.particle_solver {
                    ParticleSolverArg::Paper => ParticleSolverArg::RigidFrames,
                    ParticleSolverArg::RigidFrames => ParticleSolverArg::Xpbd,
                    ParticleSolverArg::Xpbd => ParticleSolverArg::Paper,
                };
                let other_name = match other {
                    ParticleSolverArg::Paper => "paper",
                    ParticleSolverArg::RigidFrames => "rigid frames",
                    ParticleSolverArg::Xpbd => "xpbd",
                };
                item(
                    ui,
                    &format!("Particle solver: {other_name}"),
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
                item(ui, "Shoot a box here (B)", Action::ShootBox(Some(menu_at)));
                item(ui, "Camera back (Home)", Action::ResetCamera);
                item(
                    ui,
                    if state.follow {
                        "Stop following (F)"
                    } else {
                        "Follow (F)"
                    },
                    Action::Follow,
                );
                item(ui, "Both / one method (M)", Action::CycleLayout);
                item(ui, "Screenshot (P)", Action::Screenshot);
                item(
                    ui,
                    if state.recording {
                        "Stop recording (Shift+P)"
                    } else {
                        "Record frames (Shift+P)"
                    },
                    Action::Record,
                );
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
    // A slider keeps the menu open; a button closes it.
    let chosen = chosen.into_inner();
    let close = chosen
        .iter()
        .any(|a| !matches!(a, Action::Settings(_) | Action::SceneSettings));
    model.actions.extend(chosen);
    if close {
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
