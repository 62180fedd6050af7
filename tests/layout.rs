//! The window's layout at the sizes people use, rendered offscreen with the panel (as
//! `ragdoll-lab capture --ui --size WxH` does), checked through the rectangles the UI
//! reports: the panel keeps one width whatever the scene and solver, its contents stay
//! inside it, the plot and its axes are visible without scrolling from 800×600 up, every label of the view stays inside its half in legible text within
//! its rows, and the view starts where the panel ends.

use ragdoll_lab::app_state::AppState;
use ragdoll_lab::capture::{Offscreen, half_aspect};
use ragdoll_lab::cli::{ParticleSolverArg, SceneArgs};
use ragdoll_lab::picking;
use ragdoll_lab::render::camera::OrbitCamera;
use ragdoll_lab::scenes;
use ragdoll_lab::session::Session;
use ragdoll_lab::ui::UiLayout;

/// Smallest text the overlay may use (points): legible on any screen.
const MIN_FONT: f32 = 11.0;

fn render(
    target: &mut Offscreen,
    (w, h): (u32, u32),
    scene: &str,
    solver: ParticleSolverArg,
    notice: Option<&str>,
) -> UiLayout {
    let loaded = scenes::load(&SceneArgs {
        scene: Some(scene.into()),
        ..Default::default()
    })
    .unwrap();
    let mut state = AppState::new(
        None,
        1,
        OrbitCamera::from_desc(&loaded.desc.settings.camera),
    );
    state.particle_solver = solver;
    state.notice = notice.map(|n| (n.to_string(), std::time::Instant::now()));
    let mut session = Session::new(loaded, solver).unwrap();
    for _ in 0..10 {
        session.step();
    }
    session.refresh();
    state.camera = picking::scene_camera(state.camera, &session.snapshots, half_aspect(w, h, true));
    target.render(&state, &session).unwrap();
    target.last_layout().unwrap().clone()
}

fn check(size: (u32, u32), scene: &str, solver: ParticleSolverArg, l: &UiLayout) {
    let what = format!("{}x{} {scene} {solver:?}", size.0, size.1);
    let panel = l.panel.unwrap_or_else(|| panic!("{what}: no panel"));
    let content = l.panel_content.unwrap();
    assert!(
        content.max.x <= panel.max.x + 0.5,
        "{what}: panel contents run {} points past its edge",
        content.max.x - panel.max.x
    );
    assert!(
        (l.view.min.x - panel.max.x).abs() <= 1.0 && l.view.max.x <= l.screen.max.x + 0.5,
        "{what}: view {:?} beside panel {:?}",
        l.view,
        panel
    );
    let plot = l.plot.unwrap();
    assert!(
        plot.min.x >= panel.min.x - 0.5 && plot.max.x <= panel.max.x + 0.5,
        "{what}: plot {plot:?} wider than the panel {panel:?}"
    );
    // Shorter or narrower windows scroll the panel (a narrow one puts slider names above
    // the sliders).
    if size.0 >= 640 && size.1 >= 600 {
        assert!(
            plot.max.y <= panel.max.y,
            "{what}: the plot's time axis at {} is below the panel's bottom {}",
            plot.max.y,
            panel.max.y
        );
    }
    let labels = l
        .texts
        .iter()
        .filter(|t| t.what.starts_with("label"))
        .count();
    assert_eq!(labels, 2, "{what}: a label per method");
    assert!(l.texts.iter().any(|t| t.what == "clock"), "{what}: clock");
    for t in &l.texts {
        assert!(
            t.bounds.contains_rect(t.rect),
            "{what}: {} {:?} leaves its area {:?}",
            t.what,
            t.rect,
            t.bounds
        );
        assert!(
            l.view.contains_rect(t.bounds),
            "{what}: {}'s area leaves the view",
            t.what
        );
        assert!(t.font >= MIN_FONT, "{what}: {} at {} pt", t.what, t.font);
        assert!(
            t.rows.0 <= t.rows.1,
            "{what}: {} in {} rows, at most {}",
            t.what,
            t.rows.0,
            t.rows.1
        );
    }
}

#[test]
fn panel_and_labels_stay_inside_their_areas_at_common_sizes() {
    for size in [(640, 400), (800, 600), (1280, 720), (360, 640)] {
        let mut target = Offscreen::new(size.0, size.1).unwrap();
        let mut widths = Vec::new();
        for scene in ["ball-chain", "hinge-chain", "human"] {
            for solver in [ParticleSolverArg::Paper, ParticleSolverArg::RigidFrames] {
                let l = render(&mut target, size, scene, solver, None);
                check(size, scene, solver, &l);
                widths.push(l.panel.unwrap().width());
            }
        }
        assert!(
            widths.iter().all(|w| (w - widths[0]).abs() < 0.5),
            "{size:?}: the panel's width changes with scene or solver: {widths:?}"
        );
    }
}

#[test]
fn a_long_error_notice_stays_inside_the_left_view() {
    let size = (800, 600);
    let mut target = Offscreen::new(size.0, size.1).unwrap();
    let path =
        "/a/rather/long/path/without/any/spaces/to/break/at/scenes/some-figure-of-many-bodies.af";
    let message = format!("{path}:12:3: error: expected a number after `origin (`, found `)`");
    let l = render(
        &mut target,
        size,
        "human",
        ParticleSolverArg::RigidFrames,
        Some(&message),
    );
    check(size, "human", ParticleSolverArg::RigidFrames, &l);
    let notice = l.texts.iter().find(|t| t.what == "notice").unwrap();
    let left = l.texts.iter().find(|t| t.what == "label 0").unwrap().bounds;
    assert_eq!(notice.bounds, left, "the notice keeps to the left view");
}
