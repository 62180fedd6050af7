//! Keys and mouse to [`Action`]s, the paper's section 5.1.1 plus ours. Plain data in, plain
//! data out: the window feeds it winit's key and button values, tests feed it the same
//! values without a window.

use crate::app_state::Action;
use glam::Vec2;
use winit::event::MouseButton;
use winit::keyboard::{Key, ModifiersState, NamedKey};

/// Mouse-drag bookkeeping between events.
#[derive(Clone, Debug, Default)]
pub struct InputMapper {
    modifiers: ModifiersState,
    cursor: Vec2,
    orbiting: bool,
    panning: bool,
    grabbing: bool,
    /// Where the left button went down, while it has not moved more than a click's
    /// tolerance: a release then is a click (select), not the end of an orbit.
    press: Option<Vec2>,
}

/// A left press and release within this many pixels is a click, not a drag.
const CLICK_TOLERANCE: f32 = 4.0;

impl InputMapper {
    /// A mapper with no buttons held.
    pub fn new() -> InputMapper {
        InputMapper::default()
    }

    /// The last cursor position (physical pixels).
    pub fn cursor(&self) -> Vec2 {
        self.cursor
    }

    /// Records Shift/Ctrl/Alt.
    pub fn set_modifiers(&mut self, modifiers: ModifiersState) {
        self.modifiers = modifiers;
    }

    /// A key press (`pressed`) or release. Only presses act; repeats act again (holding T
    /// steps repeatedly, as in the paper's program).
    pub fn key(&mut self, key: &Key, pressed: bool) -> Option<Action> {
        if !pressed {
            return None;
        }
        match key {
            Key::Named(NamedKey::Space) => Some(Action::Start),
            Key::Named(NamedKey::Escape) => Some(Action::Quit),
            Key::Named(NamedKey::Tab) => Some(if self.modifiers.shift_key() {
                Action::PrevScene
            } else {
                Action::NextScene
            }),
            Key::Named(NamedKey::F1) => Some(Action::TogglePanel),
            Key::Named(NamedKey::Home) => Some(Action::ResetCamera),
            Key::Character(c) => match c.to_lowercase().as_str() {
                "t" if self.modifiers.shift_key() => Some(Action::StepFrames(10)),
                "t" => Some(Action::StepOnce),
                "s" => Some(Action::ToggleRun),
                "q" => Some(Action::Quit),
                "1" => Some(Action::Variant(1)),
                "2" => Some(Action::Variant(2)),
                "3" => Some(Action::Variant(3)),
                "b" => Some(Action::ShootBox(Some(self.cursor))),
                "f" => Some(Action::Follow),
                "k" => Some(Action::TakeOver),
                "p" if self.modifiers.shift_key() => Some(Action::Record),
                "p" => Some(Action::Screenshot),
                "m" => Some(Action::CycleLayout),
                "r" => Some(Action::Reload),
                "[" => Some(Action::Slower),
                "]" => Some(Action::Faster),
                "h" => Some(Action::TogglePanel),
                _ => None,
            },
            _ => None,
        }
    }

    /// A button press or release at the current cursor.
    pub fn button(&mut self, button: MouseButton, pressed: bool) -> Option<Action> {
        match (button, pressed) {
            (MouseButton::Left, true) if self.modifiers.control_key() => {
                self.grabbing = true;
                Some(Action::GrabStart(self.cursor))
            }
            (MouseButton::Left, true) => {
                self.orbiting = true;
                self.press = Some(self.cursor);
                Some(Action::CloseMenu)
            }
            (MouseButton::Left, false) => {
                self.orbiting = false;
                if std::mem::take(&mut self.grabbing) {
                    self.press = None;
                    Some(Action::GrabEnd)
                } else {
                    self.press.take().map(|_| Action::Pick(self.cursor))
                }
            }
            (MouseButton::Middle, pressed) => {
                self.panning = pressed;
                None
            }
            (MouseButton::Right, true) => Some(Action::OpenMenu(self.cursor)),
            _ => None,
        }
    }

    /// The cursor moved to `to` (physical pixels).
    pub fn cursor_moved(&mut self, to: Vec2) -> Option<Action> {
        let delta = to - self.cursor;
        self.cursor = to;
        if self.press.is_some_and(|p| p.distance(to) > CLICK_TOLERANCE) {
            self.press = None;
        }
        if self.grabbing {
            Some(Action::GrabMove(to))
        } else if self.orbiting {
            Some(Action::Orbit(delta))
        } else if self.panning {
            Some(Action::Pan(delta))
        } else {
            Some(Action::Hover(to))
        }
    }

    /// The wheel turned by `notches` (positive: away from the user, zoom in).
    pub fn wheel(&mut self, notches: f32) -> Option<Action> {
        (notches != 0.0).then_some(Action::Zoom(notches))
    }

    /// The window lost focus or the cursor left it: drop any drag.
    pub fn release_all(&mut self) -> Option<Action> {
        self.orbiting = false;
        self.panning = false;
        self.press = None;
        std::mem::take(&mut self.grabbing).then_some(Action::GrabEnd)
    }
}
