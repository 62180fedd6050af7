//! The paper's keys (section 5.1.1) and ours, fed through the input mapping into the app
//! state without a window.

use glam::Vec2;
use ragdoll_lab::app_state::{Action, AppState, Rebuild, SCENES};
use ragdoll_lab::input::InputMapper;
use ragdoll_lab::render::camera::OrbitCamera;
use ragdoll_sim::scene::CameraDesc;
use winit::event::MouseButton;
use winit::keyboard::{Key, ModifiersState, NamedKey};

fn setup() -> (InputMapper, AppState) {
    let camera = OrbitCamera::from_desc(&CameraDesc::default());
    (InputMapper::new(), AppState::new(Some(1), 1, camera))
}

fn press(input: &mut InputMapper, state: &mut AppState, key: Key) {
    if let Some(action) = input.key(&key, true) {
        state.apply(action);
    }
    assert_eq!(input.key(&key, false), None, "releases do nothing");
}

fn ch(c: &str) -> Key {
    Key::Character(c.into())
}

#[test]
fn the_papers_keys_drive_the_state() {
    let (mut input, mut state) = setup();
    assert!(state.running, "started by default");

    press(&mut input, &mut state, ch("s"));
    assert!(!state.running, "S stops");
    assert_eq!(state.steps_due(1.0, 1.0 / 60.0), 0, "stopped: no steps");

    press(&mut input, &mut state, Key::Named(NamedKey::Space));
    assert!(state.running, "Space starts");

    press(&mut input, &mut state, ch("t"));
    assert!(!state.running, "T pauses");
    assert_eq!(state.steps_due(1.0, 1.0 / 60.0), 1, "T: exactly one step");
    assert_eq!(state.steps_due(1.0, 1.0 / 60.0), 0, "and only one");

    press(&mut input, &mut state, ch("S"));
    assert!(state.running, "S starts again (shifted too)");

    press(&mut input, &mut state, ch("2"));
    assert_eq!(state.variant, 2, "2 selects variant 2");
    assert_eq!(state.rebuild.take(), Some(Rebuild::Restart));

    press(&mut input, &mut state, ch("1"));
    assert_eq!(state.variant, 1, "1 resets to the first variant");
    assert_eq!(state.rebuild.take(), Some(Rebuild::Restart));

    press(&mut input, &mut state, Key::Named(NamedKey::Tab));
    assert_eq!(state.scene, Some(2), "Tab: next scene");
    assert_eq!(state.scene_name(), Some(SCENES[2]));
    assert_eq!(state.rebuild.take(), Some(Rebuild::Load));

    input.set_modifiers(ModifiersState::SHIFT);
    press(&mut input, &mut state, Key::Named(NamedKey::Tab));
    press(&mut input, &mut state, Key::Named(NamedKey::Tab));
    assert_eq!(state.scene, Some(0), "Shift+Tab: previous scene");
    press(&mut input, &mut state, Key::Named(NamedKey::Tab));
    assert_eq!(state.scene, Some(SCENES.len() - 1), "wraps around");
    input.set_modifiers(ModifiersState::empty());

    press(&mut input, &mut state, ch("]"));
    assert_eq!(state.time_scale(), 2.0, "] speeds up");
    press(&mut input, &mut state, ch("["));
    press(&mut input, &mut state, ch("["));
    assert_eq!(state.time_scale(), 0.5, "[ slows down");

    press(&mut input, &mut state, ch("b"));
    assert_eq!(state.pending_shots.len(), 1, "B shoots a box");
    press(&mut input, &mut state, ch("r"));
    assert_eq!(state.rebuild.take(), Some(Rebuild::Load), "R reloads");

    assert!(!state.quit);
    press(&mut input, &mut state, ch("q"));
    assert!(state.quit, "Q quits");
    let (mut input, mut state) = setup();
    press(&mut input, &mut state, Key::Named(NamedKey::Escape));
    assert!(state.quit, "Esc quits");
}

#[test]
fn the_mouse_opens_the_menu_orbits_pans_zooms_and_grabs() {
    let (mut input, mut state) = setup();
    let apply = |state: &mut AppState, a: Option<Action>| {
        if let Some(a) = a {
            state.apply(a);
        }
    };

    let a = input.cursor_moved(Vec2::new(100.0, 80.0));
    assert_eq!(
        a,
        Some(Action::Hover(Vec2::new(100.0, 80.0))),
        "moving with no button only hovers"
    );
    apply(&mut state, input.button(MouseButton::Right, true));
    assert_eq!(
        state.menu,
        Some(Vec2::new(100.0, 80.0)),
        "right click opens the menu"
    );

    let before = state.camera;
    apply(&mut state, input.button(MouseButton::Left, true));
    assert_eq!(state.menu, None, "a left click elsewhere closes it");
    apply(&mut state, input.cursor_moved(Vec2::new(140.0, 80.0)));
    apply(&mut state, input.button(MouseButton::Left, false));
    assert!(state.camera.yaw != before.yaw, "left drag orbits");
    assert_eq!(state.camera.target, before.target);

    apply(&mut state, input.button(MouseButton::Middle, true));
    apply(&mut state, input.cursor_moved(Vec2::new(160.0, 100.0)));
    apply(&mut state, input.button(MouseButton::Middle, false));
    assert!(state.camera.target != before.target, "middle drag pans");

    let d = state.camera.distance;
    apply(&mut state, input.wheel(2.0));
    assert!(state.camera.distance < d, "wheel forward zooms in");

    input.set_modifiers(ModifiersState::CONTROL);
    assert_eq!(
        input.button(MouseButton::Left, true),
        Some(Action::GrabStart(Vec2::new(160.0, 100.0))),
        "Ctrl + left press grabs"
    );
    let yaw = state.camera.yaw;
    let a = input.cursor_moved(Vec2::new(170.0, 90.0));
    assert_eq!(a, Some(Action::GrabMove(Vec2::new(170.0, 90.0))));
    apply(&mut state, a);
    assert_eq!(state.camera.yaw, yaw, "a grab drag does not orbit");
    assert_eq!(
        input.button(MouseButton::Left, false),
        Some(Action::GrabEnd)
    );
}

#[test]
fn tab_walks_the_built_in_scenes_in_table_order() {
    let names: Vec<&str> = ragdoll_lab::scenes::builtin_scenes()
        .iter()
        .map(|s| s.name)
        .collect();
    assert_eq!(names, SCENES.to_vec());
}

#[test]
fn our_new_keys_and_a_click_that_is_not_a_drag() {
    let (mut input, mut state) = setup();
    let key = |input: &mut InputMapper, k: Key| input.key(&k, true);
    assert_eq!(key(&mut input, ch("f")), Some(Action::Follow));
    assert_eq!(key(&mut input, ch("p")), Some(Action::Screenshot));
    assert_eq!(key(&mut input, ch("m")), Some(Action::CycleLayout));
    assert_eq!(
        key(&mut input, Key::Named(NamedKey::Home)),
        Some(Action::ResetCamera)
    );
    input.set_modifiers(ModifiersState::SHIFT);
    assert_eq!(key(&mut input, ch("P")), Some(Action::Record));
    assert_eq!(key(&mut input, ch("T")), Some(Action::StepFrames(10)));
    input.set_modifiers(ModifiersState::empty());

    // B aims through the cursor.
    input.cursor_moved(Vec2::new(420.0, 310.0));
    assert_eq!(
        key(&mut input, ch("b")),
        Some(Action::ShootBox(Some(Vec2::new(420.0, 310.0))))
    );

    // Press and release in place: a pick there. Press, move away, release: an orbit.
    input.button(MouseButton::Left, true);
    input.cursor_moved(Vec2::new(422.0, 311.0));
    assert_eq!(
        input.button(MouseButton::Left, false),
        Some(Action::Pick(Vec2::new(422.0, 311.0)))
    );
    input.button(MouseButton::Left, true);
    let orbit = input.cursor_moved(Vec2::new(460.0, 311.0));
    assert!(matches!(orbit, Some(Action::Orbit(_))));
    assert_eq!(
        input.button(MouseButton::Left, false),
        None,
        "a drag picks nothing"
    );

    for a in [Action::Follow, Action::CycleLayout, Action::Record] {
        state.apply(a);
    }
    assert!(state.follow && state.recording);
    assert_eq!(state.layout, ragdoll_lab::app_state::ViewLayout::Particle);
    state.apply(Action::NextScene);
    assert!(!state.follow, "another scene: nothing to follow");
    assert_eq!(state.selected, None);
}

#[test]
fn k_hands_the_playing_animation_to_the_ragdoll() {
    use ragdoll_lab::cli::{ParticleSolverArg, SceneArgs};
    use ragdoll_lab::session::Session;

    let (mut input, mut state) = setup();
    press(&mut input, &mut state, ch("s"));
    assert!(!state.running);
    assert_eq!(input.key(&ch("K"), true), Some(Action::TakeOver));
    press(&mut input, &mut state, ch("k"));
    assert!(state.pending_takeover, "K asks for the take-over");
    assert!(state.running, "and the ragdoll runs");

    // The window's part: the figure walks until K, then falls on both sides.
    let base = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/doom3");
    let loaded = ragdoll_lab::scenes::load(&SceneArgs {
        doom3: Some(base),
        entity: Some("monster_lab_human".into()),
        anim: Some("walk".into()),
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let mut session = Session::new(loaded, ParticleSolverArg::default()).unwrap();
    assert!(session.playing.is_some(), "--anim plays the animation");
    let rest: Vec<_> = session.snapshots[0].bodies.iter().map(|b| b.pose).collect();
    // Half a second of the one-second walk cycle: the animation moved the bodies (the
    // methods did not step) and the skinned mesh follows the animated skeleton.
    for _ in 0..30 {
        session.step();
    }
    session.refresh();
    let time = session.playing.as_ref().map(|p| p.1).unwrap();
    assert!((time - 0.5).abs() < 1e-3, "{time}");
    assert_eq!(session.methods[0].time(), 0.0, "no physics while it plays");
    let moved = session.snapshots[1].bodies[0].pose.position - rest[0].position;
    assert!(
        moved.x > 0.5,
        "the walk carries the figure forward: {moved}"
    );
    assert_eq!(session.joint_poses[0].len(), 20, "the mesh's skeleton");
    // The mesh plays the animation on both sides: its hips walked with the bodies.
    let rest_hips = session.loaded.skin.as_ref().unwrap().rig.rest[1].position;
    for side in &session.joint_poses {
        let hips = side[1].position - rest_hips;
        assert!(
            (hips.x - moved.x).abs() < 0.05,
            "hips {hips} vs body {moved}"
        );
    }
    // Another half second loops back to the start of the cycle.
    for _ in 0..36 {
        session.step();
    }
    let time = session.playing.as_ref().map(|p| p.1).unwrap();
    assert!((time - 0.1).abs() < 1e-3, "{time}");

    assert!(session.take_over().unwrap(), "K while playing takes over");
    assert!(session.playing.is_none());
    assert!(
        !session.take_over().unwrap(),
        "a second K has nothing to take"
    );
    for m in &session.methods {
        let mut states = Vec::new();
        m.body_states(&mut states);
        let vx = states.iter().map(|s| s.linear_velocity.x).sum::<f32>() / states.len() as f32;
        assert!(
            vx > 1.0,
            "{}: the walk's velocity {vx} m/s",
            m.kind().name()
        );
    }
    session.step();
    assert!(session.methods[0].time() > 0.0, "the ragdoll runs");
}
