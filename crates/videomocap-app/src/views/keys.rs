//! Keyboard shortcuts (listed in the F1 window) turned into intents; nothing while a text field
//! has the keyboard.

use crate::intent::Intent;
use crate::state::State;

/// Space's state between frames: a tap plays or pauses; held while dragging, it pans instead.
#[derive(Debug, Default)]
pub(crate) struct SpaceKey {
    dragged: bool,
}

/// Reads this frame's keys; what they ask for goes to `out`.
pub(crate) fn read(
    ctx: &egui::Context,
    state: &State,
    space: &mut SpaceKey,
    out: &mut Vec<Intent>,
) {
    if ctx.egui_wants_keyboard_input() {
        return;
    }
    let cmd = egui::Modifiers::COMMAND;
    let (undo, redo, save, quit) = ctx.input_mut(|i| {
        let redo = i.consume_key(cmd | egui::Modifiers::SHIFT, egui::Key::Z);
        let undo = i.consume_key(cmd, egui::Key::Z);
        let save = i.consume_key(cmd, egui::Key::S);
        let quit = i.consume_key(cmd, egui::Key::Q);
        (undo, redo, save, quit)
    });
    if redo {
        out.push(Intent::Redo);
    } else if undo {
        out.push(Intent::Undo);
    }
    if save {
        out.push(Intent::Save);
    }
    if quit {
        out.push(Intent::Quit);
    }
    let (left, right, home, end, shift, f1, esc, m, t, space_up) = ctx.input(|i| {
        (
            i.key_pressed(egui::Key::ArrowLeft),
            i.key_pressed(egui::Key::ArrowRight),
            i.key_pressed(egui::Key::Home),
            i.key_pressed(egui::Key::End),
            i.modifiers.shift,
            i.key_pressed(egui::Key::F1),
            i.key_pressed(egui::Key::Escape),
            i.key_pressed(egui::Key::M),
            i.key_pressed(egui::Key::T),
            i.key_released(egui::Key::Space),
        )
    });
    let step = if shift { 10 } else { 1 };
    if left {
        out.push(Intent::Step(-step));
    }
    if right {
        out.push(Intent::Step(step));
    }
    if home {
        out.push(Intent::GoTo(0));
    }
    if end {
        out.push(Intent::GoTo(state.frame_count().saturating_sub(1)));
    }
    if f1 {
        out.push(Intent::Help(!state.show_help()));
    }
    if esc {
        out.push(Intent::Escape);
    }
    if m {
        out.push(Intent::StartMarking);
    }
    if t && !state.busy() {
        out.push(Intent::Track);
    }
    if ctx.input(|i| i.key_down(egui::Key::Space) && i.pointer.is_decidedly_dragging()) {
        space.dragged = true;
    }
    if space_up {
        if !space.dragged {
            out.push(Intent::TogglePlay);
        }
        space.dragged = false;
    }
}
