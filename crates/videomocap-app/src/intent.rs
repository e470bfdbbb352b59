//! What the user asked for: the views return these, and the state carries them out
//! ([`crate::state::State::apply`]), so no view changes the state itself.

use crate::state::{Choose, ExportKind, SaveAnswer, volume::Layers};
use nalgebra::Point2;
use std::path::PathBuf;
use videomocap_core::project::Settings;
use videomocap_core::skeleton::{Bone, Joint};

/// One thing the user asked for.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Intent {
    /// Open a video, image folder, project or point-volume folder (asks to save first when
    /// there are unsaved changes).
    Open(PathBuf),
    /// Ask the user for a file or folder (a dialog, or the app's own path field).
    Choose(Choose),
    /// Save the project to its file (asking where when it has none).
    Save,
    /// Save the project to a new file.
    SaveAs,
    /// Write one export, asking where.
    Export(ExportKind),
    /// Quit (asks to save first when there are unsaved changes).
    Quit,
    /// The answer to "save changes?".
    AnswerSave(SaveAnswer),
    /// The answer to "recover unsaved work?".
    AnswerRecovery(bool),
    /// "Not now" to the saved project offered for a video.
    DismissProjectBeside,
    /// The subject is seen from behind (the marking guide mirrors its diagram) or not.
    SeenFromBehind(bool),
    /// The text of the app's path field changed.
    PathEdited(String),
    /// The path field was confirmed (`Some`) or cancelled (`None`).
    PathChosen(Option<PathBuf>),
    /// "Create the folder" in the path field: make the folder it names, then write.
    CreateFolder,
    /// Undo the last edit.
    Undo,
    /// Redo an undone edit.
    Redo,
    /// Start the marking guide on the current frame.
    StartMarking,
    /// Skip the joint the marking guide asks for.
    SkipJoint,
    /// End the marking guide.
    StopMarking,
    /// Whether dragging a joint moves the limb below it.
    MoveLimb(bool),
    /// A click on the frame (places the joint the marking guide asks for).
    Click(Point2<f64>),
    /// A joint dragged to a new place on the current frame (a correction).
    Moved(Joint, Point2<f64>),
    /// Track the whole video from the key frames, then lift.
    Track,
    /// Lift the tracks to 3D again.
    Lift,
    /// Cancel the running job.
    Cancel,
    /// Flip a bone's depth choice on the current frame.
    Flip(Bone),
    /// Go to a frame.
    GoTo(usize),
    /// Step some frames forwards (positive) or backwards.
    Step(isize),
    /// Play or pause.
    TogglePlay,
    /// New project settings from the side panel; `dragging` while a slider is held (one undo
    /// step for the whole drag).
    Settings {
        /// The settings as the panel shows them now (boxed: the other intents are small).
        settings: Box<Settings>,
        /// A slider is being dragged.
        dragging: bool,
    },
    /// A settings drag ended.
    SettingsReleased,
    /// Which layers volume mode draws.
    VolumeLayers(Layers),
    /// Show or hide the shortcuts window.
    Help(bool),
    /// Show or hide the user guide.
    Guide(bool),
    /// Esc: stop marking, close the help windows.
    Escape,
}
