//! The timeline: a scrubber with frame number and time, key frames marked, and one thin strip
//! per joint coloured by state (tracked, weak, interpolated, off the frame, lost) for every frame;
//! clicking a strip jumps there.

use super::frame_view::PointState;
use egui::{Color32, Rect, Sense, Stroke, Vec2};
use videomocap::formats::Tracks2d;
use videomocap::skeleton::{JOINT_COUNT, Joint};
use videomocap::track::KeyFrames;

/// Per joint, runs of frames with one colour: `(first, last, colour)`.
#[derive(Debug, Clone, Default)]
pub struct Strips {
    runs: Vec<Vec<(usize, usize, Color32)>>,
}

impl Strips {
    /// Strips from tracks and the key frames; `weak` is the tracker's reliability threshold.
    pub fn new(tracks: &Tracks2d, keys: &KeyFrames, weak: f32) -> Strips {
        let runs = Joint::ALL
            .iter()
            .map(|&j| {
                let mut runs: Vec<(usize, usize, Color32)> = Vec::new();
                for (k, f) in tracks.frames.iter().enumerate() {
                    let colour = if keys.is_key(f.index, j) {
                        PointState::Key.colour()
                    } else {
                        PointState::of(&f.points[j], weak).colour()
                    };
                    match runs.last_mut() {
                        Some(last) if last.2 == colour && last.1 + 1 == k => last.1 = k,
                        _ => runs.push((k, k, colour)),
                    }
                }
                runs
            })
            .collect();
        Strips { runs }
    }
}

/// Draws the timeline; returns a frame to jump to.
pub fn show(
    ui: &mut egui::Ui,
    current: usize,
    frames: usize,
    fps: f64,
    strips: Option<&Strips>,
    keys: &KeyFrames,
) -> Option<usize> {
    let mut jump = None;
    // The strips below line up with the slider's rail: frame k is under the slider's handle
    // at k (egui keeps the handle's centre a radius inside the rail's ends).
    let (rail_left, rail_right) = ui
        .horizontal(|ui| {
            let mut index = current;
            let rail = (ui.available_width() - 190.0).max(100.0);
            ui.spacing_mut().slider_width = rail;
            let left = ui.cursor().left();
            let slider = egui::Slider::new(&mut index, 0..=frames.saturating_sub(1)).text("frame");
            let response = ui.add(slider);
            if response.changed() {
                jump = Some(index);
            }
            ui.label(format!("{:.3} s", current as f64 / fps.max(1e-9)));
            let radius = response.rect.height() / 2.5;
            (left + radius, left + rail - radius)
        })
        .inner;
    let strip_h = 4.0;
    let width = ui.available_width();
    let height = strip_h * JOINT_COUNT as f32 + 6.0;
    let (rect, response) = ui.allocate_exact_size(Vec2::new(width, height), Sense::click());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::from_gray(30));
    let last = frames.saturating_sub(1).max(1) as f32;
    let span = (rail_right - rail_left).max(1.0);
    // Centre of frame k; a frame covers ±0.5 around it.
    let x_of = |k: f32| rail_left + k / last * span;
    if let Some(strips) = strips {
        for (row, runs) in strips.runs.iter().enumerate() {
            let top = rect.top() + 6.0 + row as f32 * strip_h;
            for &(a, b, colour) in runs {
                let r = Rect::from_min_max(
                    egui::pos2(x_of(a as f32 - 0.5), top),
                    egui::pos2(
                        x_of(b as f32 + 0.5).max(x_of(a as f32 - 0.5) + 1.0),
                        top + strip_h - 1.0,
                    ),
                );
                painter.rect_filled(r, 0.0, colour);
            }
        }
    }
    for &f in keys.frames.keys() {
        let x = x_of(f as f32);
        painter.line_segment(
            [egui::pos2(x, rect.top()), egui::pos2(x, rect.top() + 5.0)],
            Stroke::new(2.0, Color32::WHITE),
        );
    }
    let x = x_of(current as f32);
    painter.line_segment(
        [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
        Stroke::new(1.0, Color32::YELLOW),
    );
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
    {
        let k = ((pos.x - rail_left) / span * last).round();
        jump = Some((k.max(0.0) as usize).min(frames.saturating_sub(1)));
    }
    response.on_hover_text("one strip per joint, top to bottom in model order: white key frame, green tracked, orange weak, blue interpolated, purple off the frame, red lost, pink from the gait; click to jump");
    jump
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;
    use videomocap::formats::{FrameTracks, PointSource, SourceInfo, TrackedPoint};
    use videomocap::skeleton::PerJoint;

    #[test]
    fn strips_colour_each_state() {
        // Left wrist: tracked, weak, interpolated, off the frame, lost, from the gait.
        let states = [
            (0.9, PointSource::Tracked),
            (0.2, PointSource::Tracked),
            (0.2, PointSource::Interpolated),
            (0.0, PointSource::OffFrame),
            (0.1, PointSource::Lost),
            (0.5, PointSource::Gait),
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
                    index: i,
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
        let colours: Vec<Color32> = strips.runs[Joint::LeftWrist.index()]
            .iter()
            .map(|r| r.2)
            .collect();
        assert_eq!(
            colours,
            [
                PointState::Tracked.colour(),
                PointState::Weak.colour(),
                PointState::Interpolated.colour(),
                PointState::OffFrame.colour(),
                PointState::Lost.colour(),
                PointState::Gait.colour(),
            ]
        );
    }
}
