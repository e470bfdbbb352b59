//! The state's edits of the project, each one named undo step autosaved at once: marking the 16
//! joints, correcting a joint by dragging it (which re-tracks from there), settings from the
//! side panel (a slider drag is one step), flipping a bone's depth on a frame.

use super::State;
use nalgebra::Point2;
use videomocap_core::formats::FrameIndex;
use videomocap_core::project::{History, Project, Settings};
use videomocap_core::skeleton::{Bone, Joint, MarkingView, PerJoint};

/// Undo or redo: the project to bring back and the name of the edit.
type HistoryStep = fn(&mut History<Project>, Project) -> Option<(Project, String)>;

/// A frame's pose before the user flipped a bone's depth on it: the 3D view draws it grey
/// under the new pose, so the flip shows (a forearm's flip moved it a few pixels).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FlipGhost {
    /// The frame flipped on.
    pub frame: usize,
    /// The bone flipped.
    pub bone: Bone,
    /// The joints before the flip, world metres.
    pub joints: PerJoint<nalgebra::Point3<f64>>,
}

/// What the marking guide asks and shows.
impl State {
    /// Whether the subject is seen from behind on the current frame (their own left on the
    /// image's left): from the shoulders placed there, else the hips, else as the user said.
    pub(crate) fn seen_from_behind(&self) -> bool {
        let Some(keys) = self
            .project
            .as_ref()
            .and_then(|p| p.keys.frames.get(&FrameIndex(self.current)))
        else {
            return self.from_behind;
        };
        [
            (Joint::LeftShoulder, Joint::RightShoulder),
            (Joint::LeftHip, Joint::RightHip),
        ]
        .into_iter()
        .find_map(|(l, r)| Some(keys[l]?.x < keys[r]?.x))
        .unwrap_or(self.from_behind)
    }

    /// The joint the marking guide asks for, if marking, and its place in the order.
    pub(crate) fn asking(&self) -> Option<(usize, Joint)> {
        self.marking
            .and_then(|k| Joint::MARKING_ORDER.get(k).map(|&j| (k, j)))
    }

    /// Where the joint asked for lies by its definition, when the joints placed already say:
    /// the pelvis halfway between the two hips placed on the current frame.
    pub(crate) fn marking_hint(&self) -> Option<Point2<f64>> {
        let (_, Joint::Pelvis) = self.asking()? else {
            return None;
        };
        let keys = self
            .project
            .as_ref()?
            .keys
            .frames
            .get(&FrameIndex(self.current))?;
        Some(nalgebra::center(
            &keys[Joint::LeftHip]?,
            &keys[Joint::RightHip]?,
        ))
    }

    /// The words the marking guide uses for what the camera sees.
    pub(crate) fn marking_view(&self) -> MarkingView {
        if self.seen_from_behind() {
            MarkingView::Behind
        } else {
            MarkingView::Front
        }
    }

    /// The pose before the last edit, when that edit was a flip of a bone's depth.
    pub(crate) fn flip_ghost(&self) -> Option<&FlipGhost> {
        self.flip_ghost.as_ref()
    }
}

impl State {
    /// Applies an edit named `what` to the project, with undo and autosave.
    pub(super) fn edit(&mut self, what: &str, f: impl FnOnce(&mut Project)) {
        let Some(p) = &mut self.project else { return };
        self.flip_ghost = None;
        self.history.record(p.clone(), what);
        f(p);
        self.dirty = true;
        self.autosave();
        self.results_changed();
    }

    /// A settings change from the side panel: a slider drag is one undo step, not one per
    /// repaint.
    pub(super) fn edit_settings(&mut self, settings: Settings, dragging: bool) {
        if dragging && self.settings_drag_recorded {
            if let Some(p) = &mut self.project {
                p.settings = settings;
                self.dirty = true;
                self.autosave();
            }
        } else {
            let what = self.project.as_ref().map_or("change settings", |p| {
                settings_changed(&p.settings, &settings)
            });
            self.edit(what, |p| p.settings = settings);
        }
        self.settings_drag_recorded = dragging;
        self.say_outdated();
    }

    pub(super) fn autosave(&self) {
        if let (Some(a), Some(p)) = (&self.autosaver, &self.project) {
            a.save(p);
        }
    }

    /// Undoes the last edit.
    pub(super) fn undo(&mut self) {
        self.step_history(History::undo, "Undid");
    }

    /// Redoes an undone edit.
    pub(super) fn redo(&mut self) {
        self.step_history(History::redo, "Redid");
    }

    /// Swaps the project for the one `step` brings back from the history, if any.
    fn step_history(&mut self, step: HistoryStep, done: &str) {
        let Some(p) = self.project.take() else { return };
        self.flip_ghost = None;
        self.project = Some(match step(&mut self.history, p.clone()) {
            Some((other, what)) => {
                self.status = format!("{done}: {what}");
                other
            }
            None => {
                self.status = format!("Nothing to {}", done.to_lowercase());
                p
            }
        });
        self.dirty = true;
        self.autosave();
        self.results_changed();
    }

    /// Starts the marking guide on the current frame (asks for each joint in turn).
    pub(super) fn start_marking(&mut self) {
        if self.project.is_some() {
            self.marking = Some(0);
            self.status = "Marking: click each joint in turn (Esc to stop)".to_owned();
        }
    }

    pub(super) fn skip_joint(&mut self) {
        self.marking = self
            .marking
            .filter(|&k| k + 1 < Joint::MARKING_ORDER.len())
            .map(|k| k + 1);
    }

    /// Places (or moves) a joint on the current frame by hand; with "move the limb below" on,
    /// the joints below it on its limb move by the same amount.
    fn place(&mut self, what: &str, joint: Joint, pos: Point2<f64>) {
        let frame = self.current;
        let shown = self.points(frame);
        let move_limb = self.move_limb;
        // Hand-placed joints stay on the image (marks and key frames must be on it to be saved
        // and read back); a click beside the image lands on its edge.
        let size = self.video_info().map(|i| (i.width, i.height));
        let onto_image = move |q: Point2<f64>| match size {
            Some((w, h)) => Point2::new(
                q.x.clamp(-0.5, f64::from(w) - 0.5),
                q.y.clamp(-0.5, f64::from(h) - 0.5),
            ),
            None => q,
        };
        self.edit(what, |p| {
            let old = shown[joint].map(|(q, _)| q);
            p.keys.set(FrameIndex(frame), joint, onto_image(pos));
            if move_limb && let Some(old) = old {
                let delta = pos - old;
                for j in descendants(joint) {
                    if let Some((q, _)) = shown[j] {
                        p.keys.set(FrameIndex(frame), j, onto_image(q + delta));
                    }
                }
            }
        });
    }

    /// A click on the frame: places the joint the marking guide asks for.
    pub(super) fn click(&mut self, pos: Point2<f64>) {
        let Some((k, joint)) = self.asking() else {
            return;
        };
        self.place(&format!("mark the {}", words(joint)), joint, pos);
        if k + 1 < Joint::MARKING_ORDER.len() {
            self.marking = Some(k + 1);
        } else {
            self.marking = None;
            self.status =
                "All 16 joints marked: Track (T) follows them through the video".to_owned();
        }
    }

    /// A joint dragged on the current frame: a key there, and a re-track from it.
    pub(super) fn moved(&mut self, joint: Joint, pos: Point2<f64>) {
        let what = format!("move the {} on frame {}", words(joint), self.current);
        self.place(&what, joint, pos);
        let has_tracks = self.project.as_ref().is_some_and(|p| p.tracks.is_some());
        if has_tracks && self.marking.is_none() {
            self.status = format!(
                "{} corrected on frame {}: re-tracking from there",
                joint.name(),
                self.current
            );
            self.start_tracking(Some(self.current));
        } else {
            self.status = format!("Moved {} on frame {}", joint.name(), self.current);
        }
    }

    /// Flips the depth choice of `bone` on the current frame and lifts again; says why not
    /// when the bone has one depth only there.
    pub(super) fn flip(&mut self, bone: Bone) {
        let frame = self.current;
        let Some(k) = self
            .project
            .as_ref()
            .and_then(|p| p.tracks.as_ref())
            .and_then(|t| {
                t.frames
                    .binary_search_by_key(&FrameIndex(frame), |f| f.index)
                    .ok()
            })
        else {
            self.status = format!("Frame {frame} is not tracked: nothing to flip");
            return;
        };
        let skeleton = self.project.as_ref().and_then(|p| p.skeleton.clone());
        let known = skeleton.and_then(|s| {
            self.choices
                .iter()
                .find(|c| std::sync::Arc::ptr_eq(&c.skeleton, &s))
        });
        let Some(choices) = known else {
            self.status = "This 3D result's depth choices are not known (it was loaded from a \
                           file): lift again (Track > Lift to 3D again), then flip"
                .to_owned();
            return;
        };
        if choices
            .bones
            .get(k)
            .is_some_and(|s| s[bone.index()].single_root)
        {
            self.status = format!(
                "{} cannot flip on frame {frame}: its 2D image is longer than the bone, so both \
                 depths are one point. Correct its joints on the frame, or the subject height",
                bone.key()
            );
            return;
        }
        let Some(current) = choices.bones.get(k).map(|c| c[bone.index()].root) else {
            return;
        };
        let before = self.shown_world().and_then(|(w, _)| {
            w.indices
                .binary_search(&FrameIndex(frame))
                .ok()
                .map(|k| w.frames[k])
        });
        self.edit(&format!("flip {} on frame {frame}", bone.key()), |p| {
            p.overrides
                .insert((FrameIndex(frame), bone), current.flipped());
        });
        self.flip_ghost = before.map(|joints| FlipGhost {
            frame,
            bone,
            joints,
        });
        self.status = format!(
            "The {} flipped on frame {frame}: lifting again (grey in the 3D view: before)",
            bone.plain_name()
        );
        self.start_lift();
    }
}

/// A name for a settings change (the undo step's name).
fn settings_changed(before: &Settings, after: &Settings) -> &'static str {
    if before.height_m != after.height_m {
        "change the subject height"
    } else if before.focal_px != after.focal_px {
        "change the focal length"
    } else if before.lengths != after.lengths {
        "change the known lengths"
    } else if before.tracker != after.tracker {
        "change the tracker settings"
    } else if before.lift != after.lift {
        "change the lift settings"
    } else {
        "change settings"
    }
}

/// A joint's name in words ("left wrist").
fn words(joint: Joint) -> String {
    joint.name().replace('_', " ")
}

/// Joints below `joint` on its limb (the bone tree's descendants).
fn descendants(joint: Joint) -> Vec<Joint> {
    let mut out = Vec::new();
    let mut frontier = vec![joint];
    while let Some(j) = frontier.pop() {
        for b in Bone::ALL {
            if b.parent == j {
                out.push(b.child);
                frontier.push(b.child);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intent::Intent;
    use crate::state::file_dialogs::PreparedDialogs;
    use crate::state::{Config, LiftChoices};
    use std::sync::Arc;
    use videomocap_core::camera::PinholeCamera;
    use videomocap_core::formats::Tracks2d;
    use videomocap_core::formats::{
        FrameTracks, PointSource, Skeleton3d, SourceInfo, TrackedPoint,
    };
    use videomocap_core::lift::{BoneDepth, Root};
    use videomocap_core::skeleton::{BONE_COUNT, PerJoint};

    /// A state without a window, dialogs or autosave, on a project of `frames` tracked frames.
    fn state_with_tracks(frames: usize) -> State {
        let config = Config {
            dialogs: Box::new(PreparedDialogs::default()),
            autosave_dir: None,
            proxy_dir: None,
        };
        let mut s = State::new(&egui::Context::default(), config);
        let mut p = Project::new("clip.mp4".into());
        p.tracks = Some(Arc::new(Tracks2d {
            source: SourceInfo {
                path: "clip.mp4".into(),
                width: 64,
                height: 48,
                fps: 30.0,
                frame_count: frames,
            },
            frames: (0..frames)
                .map(|index| FrameTracks {
                    index: FrameIndex(index),
                    body3d: None,
                    points: PerJoint::from_fn(|_| TrackedPoint {
                        pos: Point2::new(10.0, 10.0),
                        confidence: 0.9,
                        source: PointSource::Tracked,
                    }),
                })
                .collect(),
        }));
        s.set_project(p);
        s
    }

    /// A lift's result with its choices: bone 4 has one root on frame 0.
    fn lifted(s: &mut State, frames: usize) {
        let skeleton = Arc::new(Skeleton3d {
            camera: PinholeCamera::centred(60.0, 64, 48),
            fps: Some(30.0),
            bone_lengths_m: Default::default(),
            frames: Vec::new(),
        });
        let near = BoneDepth {
            root: Root::Near,
            single_root: false,
            margin: 2.0 * videomocap_core::lift::UNSURE_MARGIN,
        };
        let mut bones = vec![[near; BONE_COUNT]; frames];
        bones[0][4].single_root = true;
        s.choices.push(LiftChoices {
            skeleton: skeleton.clone(),
            bones,
        });
        if let Some(p) = &mut s.project {
            p.skeleton = Some(skeleton);
        }
    }

    #[test]
    fn a_flip_that_cannot_change_the_bone_says_why_and_records_nothing() {
        let mut s = state_with_tracks(3);
        lifted(&mut s, 3);
        s.apply(Intent::Flip(Bone::ALL[4]));
        assert!(
            s.status().contains("cannot flip on frame 0"),
            "{}",
            s.status()
        );
        assert!(s.project().unwrap().overrides.is_empty());
        assert_eq!(s.undo_name(), None);
        // Another bone flips (an override, an undo step named for it).
        s.apply(Intent::Flip(Bone::ALL[5]));
        assert_eq!(s.project().unwrap().overrides.len(), 1);
        let name = format!("flip {} on frame 0", Bone::ALL[5].key());
        assert_eq!(s.undo_name(), Some(name.as_str()));
    }

    /// A subject seen from behind: once both shoulders are placed with the left one on the
    /// image's left, the guide says so (mirrored diagram, "on the image's left"), whatever the
    /// toggle said; before that the toggle decides.
    #[test]
    fn the_marking_guide_follows_a_subject_seen_from_behind() {
        use crate::views::marking::side_words;
        let mut s = state_with_tracks(3);
        s.apply(Intent::StartMarking);
        assert!(!s.seen_from_behind());
        s.apply(Intent::SeenFromBehind(true));
        assert!(s.seen_from_behind());
        s.apply(Intent::SeenFromBehind(false));
        // Head, neck, chest, then the left shoulder on the image's left and the left arm, then
        // the right shoulder on the image's right.
        for x in [30.0, 30.0, 30.0, 20.0, 18.0, 16.0, 40.0] {
            s.apply(Intent::Click(Point2::new(x, 20.0)));
        }
        assert!(s.seen_from_behind());
        assert_eq!(s.asking().map(|(_, j)| j), Some(Joint::RightElbow));
        assert_eq!(
            side_words(Joint::RightElbow, s.seen_from_behind()).unwrap(),
            "the subject's own right: on the image's right (seen from behind)"
        );
        assert_eq!(
            side_words(Joint::LeftWrist, false).unwrap(),
            "the subject's own left: on the image's right (facing you)"
        );
        assert!(side_words(Joint::Neck, true).is_none());
    }

    /// With unsaved work, opening something that cannot open is refused before "save
    /// changes?" is asked: nothing is asked, nothing closed, the work still unsaved.
    #[test]
    fn a_failed_open_leaves_unsaved_work_as_it_was() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = state_with_tracks(3);
        s.edit("place", |p| {
            p.keys
                .set(FrameIndex(1), Joint::Neck, Point2::new(12.0, 9.0))
        });
        assert!(s.dirty());
        let broken = dir.path().join("broken.videomocap.json");
        std::fs::write(&broken, "{ not a project").unwrap();
        let empty = dir.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        for (path, says) in [
            (broken, "not a project"),
            (empty.clone(), "neither video frames"),
            (dir.path().join("missing.mp4"), "no such file"),
        ] {
            s.apply(Intent::Open(path.clone()));
            assert!(s.leaving().is_none(), "{}", path.display());
            assert!(
                s.status().contains(&path.display().to_string()) && s.status().contains(says),
                "{}",
                s.status()
            );
            assert!(s.dirty());
            assert!(s.project().unwrap().keys.is_key(FrameIndex(1), Joint::Neck));
        }
    }

    /// The lift's unsure depth choices are offered on their own frame only, and only for the
    /// skeleton they came from.
    #[test]
    fn the_bones_the_lift_was_unsure_of_are_named_on_their_frame() {
        let mut s = state_with_tracks(2);
        // A person 3 m in front of the camera (camera space, Y down).
        let body = PerJoint::from_fn(|j| {
            let x = if j.name().starts_with("left") {
                0.2
            } else if j.name().starts_with("right") {
                -0.2
            } else {
                0.0
            };
            let y = match j {
                Joint::HeadTop => -0.8,
                Joint::Neck => -0.6,
                Joint::Chest | Joint::LeftShoulder | Joint::RightShoulder => -0.45,
                Joint::LeftElbow | Joint::RightElbow => -0.2,
                Joint::LeftWrist | Joint::RightWrist => 0.05,
                Joint::LeftKnee | Joint::RightKnee => 0.45,
                Joint::LeftAnkle | Joint::RightAnkle => 0.9,
                _ => 0.0,
            };
            nalgebra::Point3::new(x, y, 3.0)
        });
        let skeleton = Arc::new(Skeleton3d {
            camera: PinholeCamera::centred(60.0, 64, 48),
            fps: Some(30.0),
            bone_lengths_m: Default::default(),
            frames: (0..2)
                .map(|i| videomocap_core::formats::Frame3d {
                    index: FrameIndex(i),
                    points: body,
                    flags: Vec::new(),
                })
                .collect(),
        });
        let sure = BoneDepth {
            root: Root::Near,
            single_root: false,
            margin: 2.0 * videomocap_core::lift::UNSURE_MARGIN,
        };
        let mut bones = vec![[sure; BONE_COUNT]; 2];
        let forearm = Bone::new(Joint::LeftElbow, Joint::LeftWrist);
        bones[1][forearm.index()].margin = 0.0;
        // A single root has nothing to choose, however small its margin.
        bones[1][Bone::ALL[4].index()] = BoneDepth {
            single_root: true,
            margin: 0.0,
            ..sure
        };
        s.choices.push(LiftChoices {
            skeleton: skeleton.clone(),
            bones,
        });
        s.edit("lift", |p| p.skeleton = Some(skeleton));
        assert!(s.unsure_bones(0).is_empty());
        assert_eq!(s.unsure_bones(1), [forearm]);
        assert_eq!(forearm.plain_name(), "left forearm");
    }

    #[test]
    fn undo_and_redo_say_what_they_took_back() {
        let mut s = state_with_tracks(3);
        s.apply(Intent::StartMarking);
        s.apply(Intent::Click(Point2::new(5.0, 6.0)));
        assert_eq!(s.undo_name(), Some("mark the head top"));
        s.apply(Intent::Undo);
        assert_eq!(s.status(), "Undid: mark the head top");
        assert_eq!(s.redo_name(), Some("mark the head top"));
        s.apply(Intent::Redo);
        assert_eq!(s.status(), "Redid: mark the head top");
        let mut settings = s.project().unwrap().settings;
        settings.height_m = 1.8;
        s.apply(Intent::Settings {
            settings: Box::new(settings),
            dragging: false,
        });
        s.apply(Intent::Undo);
        assert_eq!(s.status(), "Undid: change the subject height");
    }
}
