//! The timeline: Play, a scrubber with frame number and time, key frames and the frames the
//! lift flagged marked above one strip per joint, each strip labelled with its joint and
//! coloured by state (tracked, weak, interpolated, off the frame, lost) for every frame.
//! Hovering a strip names the joint, the frame and the state; clicking jumps there.

use super::frame_view::PointState;
use super::view3d::PLANTED;
use crate::intent::Intent;
use crate::state::State;
use egui::{Color32, Rect, Sense, Stroke, Vec2};
use videomocap_core::formats::{CONTACT_FLAG, FrameIndex, Tracks2d};
use videomocap_core::skeleton::{JOINT_COUNT, Joint, PerJoint};
use videomocap_core::track::KeyFrames;

/// Width of the joint names left of the strips, points.
pub const LABEL_W: f32 = 44.0;
/// Height of one joint's strip, points (and its label's font: at 9 the names read about 7 px
/// tall, too small to read at a glance).
pub(crate) const STRIP_H: f32 = 11.0;
/// Height of the rows of ticks above the strips (key frames, then flagged frames), points.
const TICKS_H: f32 = 5.0;

/// Per joint, runs of frames in one state: `(first, last, state)` as positions in the tracks.
#[derive(Debug, Clone, Default)]
pub struct Strips {
    runs: Vec<Vec<(usize, usize, PointState)>>,
}

impl Strips {
    /// Strips from tracks and the key frames; `weak` is the tracker's reliability threshold.
    pub fn new(tracks: &Tracks2d, keys: &KeyFrames, weak: f32) -> Strips {
        let runs = Joint::ALL
            .iter()
            .map(|&j| {
                let mut runs: Vec<(usize, usize, PointState)> = Vec::new();
                for (k, f) in tracks.frames.iter().enumerate() {
                    let state = if keys.is_key(f.index, j) {
                        PointState::Key
                    } else {
                        PointState::of(&f.points[j], weak)
                    };
                    match runs.last_mut() {
                        Some(last) if last.2 == state && last.1 + 1 == k => last.1 = k,
                        _ => runs.push((k, k, state)),
                    }
                }
                runs
            })
            .collect();
        Strips { runs }
    }

    /// The state of `joint` at position `k` of the tracks.
    pub fn state_at(&self, joint: Joint, k: usize) -> Option<PointState> {
        let runs = self.runs.get(joint.index())?;
        let i = runs.partition_point(|r| r.1 < k);
        runs.get(i).filter(|r| r.0 <= k).map(|r| r.2)
    }
}

/// A joint's name short enough for the strip's label.
pub fn short_name(j: Joint) -> &'static str {
    match j {
        Joint::HeadTop => "head",
        Joint::Neck => "neck",
        Joint::Chest => "chest",
        Joint::Pelvis => "pelvis",
        Joint::LeftShoulder => "L sho",
        Joint::LeftElbow => "L elb",
        Joint::LeftWrist => "L wri",
        Joint::RightShoulder => "R sho",
        Joint::RightElbow => "R elb",
        Joint::RightWrist => "R wri",
        Joint::LeftHip => "L hip",
        Joint::LeftKnee => "L knee",
        Joint::LeftAnkle => "L ank",
        Joint::RightHip => "R hip",
        Joint::RightKnee => "R knee",
        Joint::RightAnkle => "R ank",
    }
}

/// Draws the timeline; Play and jumps go to `out`.
pub fn show(ui: &mut egui::Ui, state: &State, out: &mut Vec<Intent>) {
    let frames = state.frame_count();
    let current = state.current_frame();
    let no_keys = KeyFrames::default();
    let keys = state.project().map_or(&no_keys, |p| &p.keys);
    let flagged: Vec<usize> = state
        .shown_world()
        .map(|(_, s)| {
            s.frames
                .iter()
                .filter(|f| f.flagged())
                .map(|f| f.index.get())
                .collect()
        })
        .unwrap_or_default();
    // The frames where the lift held each ankle planted (drawn under the ankles' strips).
    let planted: Vec<(usize, PerJoint<bool>)> = state
        .shown_world()
        .map(|(_, s)| {
            s.frames
                .iter()
                .map(|f| (f.index.get(), f.joint_flags(CONTACT_FLAG)))
                .filter(|(_, c)| c.0.iter().any(|&b| b))
                .collect()
        })
        .unwrap_or_default();
    let planted_at = |f: usize, j: Joint| {
        planted
            .binary_search_by_key(&f, |(k, _)| *k)
            .is_ok_and(|i| planted[i].1[j])
    };
    // The strips below line up with the slider's rail: frame k is under the slider's handle
    // at k (egui keeps the handle's centre a radius inside the rail's ends).
    let (rail_left, rail_right) = ui
        .horizontal(|ui| {
            let label = if state.playing() { "Pause" } else { "Play" };
            let play = ui.add_sized(
                [LABEL_W - ui.spacing().item_spacing.x, 18.0],
                egui::Button::new(label),
            );
            if play.on_hover_text("play / pause (Space)").clicked() {
                out.push(Intent::TogglePlay);
            }
            let mut index = current;
            let rail = (ui.available_width() - 190.0).max(100.0);
            ui.spacing_mut().slider_width = rail;
            let left = ui.cursor().left();
            let slider = egui::Slider::new(&mut index, 0..=frames.saturating_sub(1)).text("frame");
            let response = ui.add(slider);
            if response.changed() {
                out.push(Intent::GoTo(index));
            }
            ui.label(format!("{:.3} s", current as f64 / state.fps().max(1e-9)));
            let radius = response.rect.height() / 2.5;
            (left + radius, left + rail - radius)
        })
        .inner;
    let width = ui.available_width();
    // Before tracking there is nothing to show in the strips: the ticks alone, and the frame
    // above takes the height (16 empty strips took 180 points from a portrait clip).
    let rows = if state.strips().is_some() {
        JOINT_COUNT
    } else {
        0
    };
    let height = 2.0 * TICKS_H + 2.0 + STRIP_H * rows as f32;
    let (rect, response) = ui.allocate_exact_size(Vec2::new(width, height), Sense::click());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::from_gray(30));
    let last = frames.saturating_sub(1).max(1) as f32;
    let span = (rail_right - rail_left).max(1.0);
    // Centre of frame k; a frame covers ±0.5 around it.
    let x_of = |k: f32| rail_left + k / last * span;
    let strips_top = rect.top() + 2.0 * TICKS_H + 2.0;
    let label_font = egui::FontId::proportional(STRIP_H);
    for (row, j) in Joint::ALL.into_iter().enumerate().take(rows) {
        let top = strips_top + row as f32 * STRIP_H;
        painter.text(
            egui::pos2(rect.left() + 2.0, top + STRIP_H / 2.0),
            egui::Align2::LEFT_CENTER,
            short_name(j),
            label_font.clone(),
            Color32::from_gray(190),
        );
        let Some(runs) = state.strips().and_then(|s| s.runs.get(row)) else {
            continue;
        };
        for &(a, b, point) in runs {
            let r = Rect::from_min_max(
                egui::pos2(x_of(a as f32 - 0.5), top),
                egui::pos2(
                    x_of(b as f32 + 0.5).max(x_of(a as f32 - 0.5) + 1.0),
                    top + STRIP_H - 1.0,
                ),
            );
            painter.rect_filled(r, 0.0, point.colour());
        }
        // A planted foot: a brown bar along the bottom of its ankle's strip.
        for (f, _) in planted.iter().filter(|(_, c)| c[j]) {
            let r = Rect::from_min_max(
                egui::pos2(x_of(*f as f32 - 0.5), top + STRIP_H - 4.0),
                egui::pos2(
                    x_of(*f as f32 + 0.5).max(x_of(*f as f32 - 0.5) + 1.0),
                    top + STRIP_H - 1.0,
                ),
            );
            painter.rect_filled(r, 0.0, PLANTED);
        }
    }
    let tick = |f: usize, row: f32, colour: Color32| {
        let x = x_of(f as f32);
        let top = rect.top() + row * TICKS_H;
        painter.line_segment(
            [egui::pos2(x, top), egui::pos2(x, top + TICKS_H)],
            Stroke::new(2.0, colour),
        );
    };
    for &f in keys.frames.keys() {
        tick(f.get(), 0.0, Color32::WHITE);
    }
    for &f in &flagged {
        tick(f, 1.0, Color32::from_rgb(230, 60, 60));
    }
    let x = x_of(current as f32);
    painter.line_segment(
        [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
        Stroke::new(1.0, Color32::YELLOW),
    );
    let frame_at = |x: f32| {
        ((((x - rail_left) / span * last).round()).max(0.0) as usize).min(frames.saturating_sub(1))
    };
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
    {
        out.push(Intent::GoTo(frame_at(pos.x)));
    }
    if let Some(pos) = response.hover_pos() {
        let f = frame_at(pos.x);
        let row = ((pos.y - strips_top) / STRIP_H).floor();
        let text = if pos.y < strips_top {
            let mut t = format!("frame {f}");
            if keys.frames.contains_key(&FrameIndex(f)) {
                t += " · key frame (white)";
            }
            if flagged.contains(&f) {
                t += " · the 3D is flagged here (red): see the 3D view";
            }
            t
        } else {
            let joint = Joint::ALL.get(row as usize).copied();
            let point = joint.and_then(|j| state.strips()?.state_at(j, f));
            match (joint, point) {
                (Some(j), Some(p)) => format!(
                    "{} · frame {f} · {}{}",
                    super::marking::joint_words(j),
                    p.word(),
                    if planted_at(f, j) {
                        " · planted: the lift holds the foot still on the floor (brown bar)"
                    } else {
                        ""
                    }
                ),
                (Some(j), None) => format!(
                    "{} · frame {f} · not tracked yet",
                    super::marking::joint_words(j)
                ),
                _ => format!("frame {f}"),
            }
        };
        // At the pointer: the strip spans the window, and a tooltip placed by the widget sat at
        // its far left.
        response.on_hover_text_at_pointer(text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;
    use videomocap_core::formats::{FrameTracks, PointSource, SourceInfo, TrackedPoint};

    #[test]
    fn strips_keep_each_state_and_say_which_at_a_frame() {
        // Left wrist: tracked, weak, interpolated, off the frame, lost.
        let states = [
            (0.9, PointSource::Tracked),
            (0.2, PointSource::Tracked),
            (0.2, PointSource::Interpolated),
            (0.0, PointSource::OffFrame),
            (0.1, PointSource::Lost),
        ];
        let tracks = Tracks2d {
            source: SourceInfo {
                path: "clip.mp4".into(),
                width: 64,
                height: 48,
                fps: 30.0,
                frame_count: states.len(),
            },
            frames: states
                .iter()
                .enumerate()
                .map(|(i, &(confidence, source))| FrameTracks {
                    index: FrameIndex(i),
                    body3d: None,
                    points: PerJoint::from_fn(|j| TrackedPoint {
                        pos: Point2::new(10.0, 10.0),
                        confidence: if j == Joint::LeftWrist {
                            confidence
                        } else {
                            0.9
                        },
                        source: if j == Joint::LeftWrist {
                            source
                        } else {
                            PointSource::Tracked
                        },
                    }),
                })
                .collect(),
        };
        let strips = Strips::new(&tracks, &KeyFrames::default(), 0.45);
        let states: Vec<PointState> = strips.runs[Joint::LeftWrist.index()]
            .iter()
            .map(|r| r.2)
            .collect();
        assert_eq!(
            states,
            [
                PointState::Tracked,
                PointState::Weak,
                PointState::Interpolated,
                PointState::OffFrame,
                PointState::Lost,
            ]
        );
        assert_eq!(strips.state_at(Joint::LeftWrist, 4), Some(PointState::Lost));
        assert_eq!(strips.state_at(Joint::Neck, 4), Some(PointState::Tracked));
        assert_eq!(strips.state_at(Joint::Neck, 5), None);
    }
}
