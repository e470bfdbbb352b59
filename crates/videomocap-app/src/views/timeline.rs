//! The timeline: Play, a scrubber with frame number and time, key frames and the frames the
//! lift flagged marked above one strip per joint, each strip labelled with its joint and
//! coloured by state (tracked, weak, interpolated, off the frame, lost) for every frame.
//! Hovering a strip names the joint, the frame and the state; clicking jumps there. The strips
//! fold into one (each frame coloured by its most worrying joint) when they would take height
//! from the video, as on a portrait clip; "each joint" beside the scrubber unfolds them.

use super::view3d::PLANTED;
use crate::intent::Intent;
use crate::state::State;
use egui::{Color32, Rect, Sense, Stroke, Vec2};
use videomocap_core::formats::{CONTACT_FLAG, FrameIndex};
use videomocap_core::skeleton::{JOINT_COUNT, Joint, PerJoint};
use videomocap_core::track::KeyFrames;

/// Width of the joint names left of the strips, points.
pub(crate) const LABEL_W: f32 = 44.0;
/// Height of one joint's strip, points (and its label's font: at 9 the names read about 7 px
/// tall, too small to read at a glance).
pub(crate) const STRIP_H: f32 = 11.0;
/// Height of the rows of ticks above the strips (key frames, then flagged frames), points.
const TICKS_H: f32 = 5.0;

/// The height the unfolded strips take beyond the folded one, points: what folding gives back
/// to the video.
pub(crate) const UNFOLDED_EXTRA_H: f32 = STRIP_H * (JOINT_COUNT - 1) as f32;

/// A joint's name short enough for the strip's label.
pub(crate) fn short_name(j: Joint) -> &'static str {
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

/// What the timeline marks on the frames: the key frames (white ticks), the frames the lift
/// flagged (red ticks) and where it held each ankle planted (brown bars under its strip).
struct Marked<'a> {
    keys: &'a KeyFrames,
    flagged: Vec<usize>,
    planted: Vec<(usize, PerJoint<bool>)>,
}

impl Marked<'_> {
    /// Whether the lift held `ankle` planted on frame `f`.
    fn planted_at(&self, f: usize, ankle: Joint) -> bool {
        self.planted
            .binary_search_by_key(&f, |(k, _)| *k)
            .is_ok_and(|i| self.planted[i].1[ankle])
    }
}

/// Where the strips lie: frame k's centre at `x_of(k)`, lined up with the slider's handle.
struct Geometry {
    rect: Rect,
    rail_left: f32,
    span: f32,
    last: f32,
    frames: usize,
    strips_top: f32,
}

impl Geometry {
    /// Centre of frame `k`; a frame covers ±0.5 around it.
    fn x_of(&self, k: f32) -> f32 {
        self.rail_left + k / self.last * self.span
    }

    /// The frame under `x`.
    fn frame_at(&self, x: f32) -> usize {
        ((((x - self.rail_left) / self.span * self.last).round()).max(0.0) as usize)
            .min(self.frames.saturating_sub(1))
    }

    /// The rectangle of frames `a..=b` between heights `top` and `bottom`.
    fn span_rect(&self, a: usize, b: usize, top: f32, bottom: f32) -> Rect {
        let left = self.x_of(a as f32 - 0.5);
        Rect::from_min_max(
            egui::pos2(left, top),
            egui::pos2(self.x_of(b as f32 + 0.5).max(left + 1.0), bottom),
        )
    }
}

/// Draws the timeline, a strip per joint when `each_joint`, else the folded strip; Play and
/// jumps go to `out`. Returns `true` when the user asked to fold or unfold the strips.
pub(crate) fn show(
    ui: &mut egui::Ui,
    state: &State,
    each_joint: bool,
    out: &mut Vec<Intent>,
) -> bool {
    let marked = marked(state);
    let (rail, fold) = scrubber(ui, state, each_joint, out);
    // Before tracking there is nothing to show in the strips: the ticks alone, and the frame
    // above takes the height (16 empty strips took 180 points from a portrait clip).
    let rows = match state.strips() {
        None => 0,
        Some(_) if each_joint => JOINT_COUNT,
        Some(_) => 1,
    };
    let height = 2.0 * TICKS_H + 2.0 + STRIP_H * rows as f32;
    let size = Vec2::new(ui.available_width(), height);
    let (rect, response) = ui.allocate_exact_size(size, Sense::click());
    let frames = state.frame_count();
    let geometry = Geometry {
        rect,
        rail_left: rail.0,
        span: (rail.1 - rail.0).max(1.0),
        last: frames.saturating_sub(1).max(1) as f32,
        frames,
        strips_top: rect.top() + 2.0 * TICKS_H + 2.0,
    };
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::from_gray(30));
    draw_strips(&painter, &geometry, state, each_joint, rows, &marked);
    draw_ticks(&painter, &geometry, state.current_frame(), &marked);
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
    {
        out.push(Intent::GoTo(geometry.frame_at(pos.x)));
    }
    if let Some(pos) = response.hover_pos() {
        let text = hover_text(pos, &geometry, state, each_joint, &marked);
        // At the pointer: the strip spans the window, and a tooltip placed by the widget sat at
        // its far left.
        response.on_hover_text_at_pointer(text);
    }
    fold
}

/// The key frames, the flagged frames and the planted feet of what is shown.
fn marked(state: &State) -> Marked<'_> {
    static NO_KEYS: std::sync::LazyLock<KeyFrames> = std::sync::LazyLock::new(KeyFrames::default);
    let keys = state.project().map_or(&*NO_KEYS, |p| &p.keys);
    let world = state.shown_world().map(|(_, s)| s);
    let flagged = world.map_or_else(Vec::new, |s| {
        s.frames
            .iter()
            .filter(|f| f.flagged())
            .map(|f| f.index.get())
            .collect()
    });
    let planted = world.map_or_else(Vec::new, |s| {
        s.frames
            .iter()
            .map(|f| (f.index.get(), f.joint_flags(CONTACT_FLAG)))
            .filter(|(_, c)| c.0.iter().any(|&b| b))
            .collect()
    });
    Marked {
        keys,
        flagged,
        planted,
    }
}

/// Play, the scrubber with the time, and (once there are strips) the "each joint" toggle.
/// Returns the rail's ends (frame 0's and the last frame's x: egui keeps the handle's centre a
/// radius inside the rail) and whether the toggle was clicked.
fn scrubber(
    ui: &mut egui::Ui,
    state: &State,
    each_joint: bool,
    out: &mut Vec<Intent>,
) -> ((f32, f32), bool) {
    let current = state.current_frame();
    ui.horizontal(|ui| {
        let label = if state.playing() { "Pause" } else { "Play" };
        let play = ui.add_sized(
            [LABEL_W - ui.spacing().item_spacing.x, 18.0],
            egui::Button::new(label),
        );
        if play.on_hover_text("play / pause (Space)").clicked() {
            out.push(Intent::TogglePlay);
        }
        let mut index = current;
        let rail = (ui.available_width() - 290.0).max(100.0);
        ui.spacing_mut().slider_width = rail;
        let left = ui.cursor().left();
        let last = state.frame_count().saturating_sub(1);
        let response = ui.add(egui::Slider::new(&mut index, 0..=last).text("frame"));
        if response.changed() {
            out.push(Intent::GoTo(index));
        }
        ui.label(format!("{:.3} s", current as f64 / state.fps().max(1e-9)));
        let fold = state.strips().is_some()
            && ui
                .selectable_label(each_joint, "each joint")
                .on_hover_text(if each_joint {
                    "Fold the strips into one (each frame coloured by its most worrying \
                     joint): the video gets their height"
                } else {
                    "A strip per joint (they take height from the video)"
                })
                .clicked();
        let radius = response.rect.height() / 2.5;
        ((left + radius, left + rail - radius), fold)
    })
    .inner
}

/// The strips: one per joint, or the folded one; a planted foot as a brown bar along the
/// bottom of its ankle's strip.
fn draw_strips(
    painter: &egui::Painter,
    g: &Geometry,
    state: &State,
    each_joint: bool,
    rows: usize,
    marked: &Marked<'_>,
) {
    let Some(strips) = state.strips() else {
        return;
    };
    let label_font = egui::FontId::proportional(STRIP_H);
    for row in 0..rows {
        let top = g.strips_top + row as f32 * STRIP_H;
        let joint = Joint::ALL.get(row).copied().filter(|_| each_joint);
        painter.text(
            egui::pos2(g.rect.left() + 2.0, top + STRIP_H / 2.0),
            egui::Align2::LEFT_CENTER,
            joint.map_or("joints", short_name),
            label_font.clone(),
            Color32::from_gray(190),
        );
        let runs = match joint {
            Some(_) => strips.runs(row),
            None => Some(strips.worst()),
        };
        for &(a, b, point) in runs.into_iter().flatten() {
            painter.rect_filled(
                g.span_rect(a, b, top, top + STRIP_H - 1.0),
                0.0,
                point.colour(),
            );
        }
        let Some(j) = joint else { continue };
        for (f, _) in marked.planted.iter().filter(|(_, c)| c[j]) {
            let r = g.span_rect(*f, *f, top + STRIP_H - 4.0, top + STRIP_H - 1.0);
            painter.rect_filled(r, 0.0, PLANTED);
        }
    }
}

/// The key frames' and flagged frames' ticks, and the current frame's line.
fn draw_ticks(painter: &egui::Painter, g: &Geometry, current: usize, marked: &Marked<'_>) {
    let tick = |f: usize, row: f32, colour: Color32| {
        let x = g.x_of(f as f32);
        let top = g.rect.top() + row * TICKS_H;
        painter.line_segment(
            [egui::pos2(x, top), egui::pos2(x, top + TICKS_H)],
            Stroke::new(2.0, colour),
        );
    };
    for &f in marked.keys.frames.keys() {
        tick(f.get(), 0.0, Color32::WHITE);
    }
    for &f in &marked.flagged {
        tick(f, 1.0, Color32::from_rgb(230, 60, 60));
    }
    let x = g.x_of(current as f32);
    painter.line_segment(
        [egui::pos2(x, g.rect.top()), egui::pos2(x, g.rect.bottom())],
        Stroke::new(1.0, Color32::YELLOW),
    );
}

/// What the pointer at `pos` is over: the frame and its ticks, a joint's state there, or on
/// the folded strip the most worrying state and the joints in it.
fn hover_text(
    pos: egui::Pos2,
    g: &Geometry,
    state: &State,
    each_joint: bool,
    marked: &Marked<'_>,
) -> String {
    let f = g.frame_at(pos.x);
    if pos.y < g.strips_top {
        let mut t = format!("frame {f}");
        if marked.keys.frames.contains_key(&FrameIndex(f)) {
            t += " · key frame (white)";
        }
        if marked.flagged.contains(&f) {
            t += " · the 3D is flagged here (red): see the 3D view";
        }
        return t;
    }
    if !each_joint {
        return match state.strips().and_then(|s| s.worst_at(f)) {
            Some((p, joints)) => format!(
                "frame {f} · {}: {} · \"each joint\" above shows every joint",
                p.word(),
                joints
                    .iter()
                    .map(|&j| super::marking::joint_words(j))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None => format!("frame {f} · not tracked yet"),
        };
    }
    let row = ((pos.y - g.strips_top) / STRIP_H).floor();
    let Some(j) = Joint::ALL.get(row as usize).copied() else {
        return format!("frame {f}");
    };
    let words = super::marking::joint_words(j);
    match state.strips().and_then(|s| s.state_at(j, f)) {
        Some(p) => format!(
            "{words} · frame {f} · {}{}",
            p.word(),
            if marked.planted_at(f, j) {
                " · planted: the lift holds the foot still on the floor (brown bar)"
            } else {
                ""
            }
        ),
        None => format!("{words} · frame {f} · not tracked yet"),
    }
}
