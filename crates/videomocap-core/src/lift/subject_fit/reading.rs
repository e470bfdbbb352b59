//! What the subject's reading found, for the user: each part's length and where it came from.

use std::fmt;

/// The chest's drop below the shoulder line, as a fraction of the trunk (chest–neck plus
/// pelvis–chest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChestDrop {
    /// What the tracks show (the median over frames, clamped to the plausible range).
    pub measured: f64,
    /// What the subject model had.
    pub model: f64,
    /// Frames measured.
    pub frames: usize,
}

/// Where a length of the subject model came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthOrigin {
    /// Read from the clip (its upper envelope over the frames, scaled).
    Read,
    /// The proportions table scaled to the height (the clip showed too little).
    Table,
    /// Read from the clip above [`super::LIMB_RANGE`] of the table, so held at the range's end.
    Held,
    /// The clip never showed it square (its envelope below [`super::LIMB_RANGE`] of the table): the
    /// table's.
    Unseen,
    /// Given by the user (`--lengths`).
    Given,
}

impl LengthOrigin {
    fn word(self) -> &'static str {
        match self {
            LengthOrigin::Read => "read",
            LengthOrigin::Table => "table",
            LengthOrigin::Held => "held to the table's range",
            LengthOrigin::Unseen => "table: never seen face-on",
            LengthOrigin::Given => "given",
        }
    }
}

/// One part of the body as the lift will use it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartLength {
    /// What it is, in plain words ("upper arm", "shoulders apart").
    pub name: &'static str,
    /// Metres (for a pair of sides, each side's).
    pub metres: f64,
    /// Where it came from.
    pub origin: LengthOrigin,
}

/// What was read from the tracks.
#[derive(Debug, Clone, PartialEq)]
pub struct SubjectFit {
    /// The chest's drop, when any frame showed it.
    pub chest_drop: Option<ChestDrop>,
    /// Each measured limb group's new length over the table's, before the stature scaling.
    pub limbs: Vec<(&'static str, f64)>,
    /// The factor applied to every length to keep the stature.
    pub stature_scale: f64,
    /// The body's parts as the lift uses them (empty when only the first, trunk-relative
    /// reading ran).
    pub parts: Vec<PartLength>,
    /// The scale came from lengths the user gave (else from the height).
    pub scale_from_given: bool,
}

impl fmt::Display for SubjectFit {
    /// One line for the user: the lengths the lift uses, where each came from.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.parts.is_empty() {
            return f.write_str(
                "body: the proportions table scaled to the height (the video showed too little to read the lengths)",
            );
        }
        let parts: Vec<String> = self
            .parts
            .iter()
            .map(|p| format!("{} {:.2} m ({})", p.name, p.metres, p.origin.word()))
            .collect();
        write!(
            f,
            "body lengths: {}; scaled to {}",
            parts.join(", "),
            if self.scale_from_given {
                "the lengths you gave"
            } else {
                "the height"
            }
        )
    }
}
