//! The BVH text parser: HIERARCHY (joints, offsets, channels, End Sites) and MOTION.

use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// One channel of a joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

/// A joint of the hierarchy (End Sites are joints with no channels and `end_site` set).
#[derive(Debug, Clone, PartialEq)]
pub struct BvhJoint {
    /// Name as in the file (`"<parent>_end"` for End Sites).
    pub name: String,
    /// Index of the parent joint, `None` for the root.
    pub parent: Option<usize>,
    /// Offset from the parent in the parent's frame, file units.
    pub offset: Vector3<f64>,
    /// Channels in file order.
    pub channels: Vec<Channel>,
    /// Column of the first channel in a motion row.
    pub first_channel: usize,
    /// Whether this is an End Site.
    pub end_site: bool,
}

/// A parsed BVH file.
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    /// Joints in file order (every parent before its children).
    pub joints: Vec<BvhJoint>,
    /// Seconds per frame.
    pub frame_time_s: f64,
    channel_count: usize,
    /// All motion values, `frame_count × channel_count`, row-major.
    values: Vec<f64>,
}

/// A BVH file could not be read or parsed.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}: {message}")]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: several ROOT joints; only files with one skeleton are supported")]
    SeveralRoots { path: PathBuf },
    #[error("{path}: the motion has no frames")]
    NoFrames { path: PathBuf },
    #[error(
        "{path}: joint \"{joint}\" needed for the 16-joint model is not in the file (looked for {candidates})"
    )]
    MissingJoint {
        path: PathBuf,
        joint: String,
        candidates: String,
    },
}

struct Tokens<'a> {
    words: Vec<(usize, &'a str)>,
    pos: usize,
    path: &'a Path,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, path: &'a Path) -> Self {
        let words = text
            .lines()
            .enumerate()
            .flat_map(|(i, l)| l.split_whitespace().map(move |w| (i + 1, w)))
            .collect();
        Tokens {
            words,
            pos: 0,
            path,
        }
    }

    fn line(&self) -> usize {
        self.words
            .get(self.pos.min(self.words.len().saturating_sub(1)))
            .map_or(0, |w| w.0)
    }

    fn error(&self, message: impl Into<String>) -> BvhError {
        BvhError::Syntax {
            path: self.path.to_owned(),
            line: self.line(),
            message: message.into(),
        }
    }

    fn next(&mut self) -> Result<&'a str, BvhError> {
        let w = self
            .words
            .get(self.pos)
            .map(|w| w.1)
            .ok_or_else(|| self.error("unexpected end of file"))?;
        self.pos += 1;
        Ok(w)
    }

    fn peek(&self) -> Option<&'a str> {
        self.words.get(self.pos).map(|w| w.1)
    }

    fn expect(&mut self, word: &str) -> Result<(), BvhError> {
        let w = self.next()?;
        if w.eq_ignore_ascii_case(word) {
            Ok(())
        } else {
            self.pos -= 1;
            Err(self.error(format!("expected \"{word}\", found \"{w}\"")))
        }
    }

    fn number(&mut self) -> Result<f64, BvhError> {
        let w = self.next()?;
        match w.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => {
                self.pos -= 1;
                Err(self.error(format!("expected a finite number, found \"{w}\"")))
            }
        }
    }
}

impl Bvh {
    /// Reads and parses a BVH file.
    pub fn load(path: &Path) -> Result<Bvh, BvhError> {
        let text = std::fs::read_to_string(path).map_err(|source| BvhError::Io {
            path: path.to_owned(),
            source,
        })?;
        Bvh::parse(&text, path)
    }

    /// Parses BVH text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Bvh, BvhError> {
        let mut t = Tokens::new(text, path);
        t.expect("HIERARCHY")?;
        let mut joints = Vec::new();
        let mut channel_count = 0;
        t.expect("ROOT")?;
        parse_joint(&mut t, &mut joints, None, &mut channel_count)?;
        if t.peek().is_some_and(|w| w.eq_ignore_ascii_case("ROOT")) {
            return Err(BvhError::SeveralRoots {
                path: path.to_owned(),
            });
        }
        t.expect("MOTION")?;
        t.expect("Frames:")?;
        let frames = t.number()?;
        if frames < 0.0 || frames.fract() != 0.0 {
            return Err(t.error(format!("frame count {frames} is not a whole number")));
        }
        let frame_count = frames as usize;
        t.expect("Frame")?;
        t.expect("Time:")?;
        let frame_time_s = t.number()?;
        if frame_time_s <= 0.0 {
            return Err(t.error(format!("frame time {frame_time_s} must be positive")));
        }
        if frame_count == 0 {
            return Err(BvhError::NoFrames {
                path: path.to_owned(),
            });
        }
        let total = frame_count
            .checked_mul(channel_count)
            .ok_or_else(|| t.error("motion too large"))?;
        let mut values = Vec::with_capacity(total.min(1 << 26));
        for _ in 0..total {
            values.push(t.number()?);
        }
        if let Some(extra) = t.peek() {
            return Err(t.error(format!(
                "more values than {frame_count} frames × {channel_count} channels (found \"{extra}\")"
            )));
        }
        Ok(Bvh {
            joints,
            frame_time_s,
            channel_count,
            values,
        })
    }

    /// Number of motion frames.
    pub fn frame_count(&self) -> usize {
        self.values.len() / self.channel_count.max(1)
    }

    /// Frames per second (1 / frame time).
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time_s
    }

    /// The channel values of frame `f` (empty if out of range).
    pub fn frame(&self, f: usize) -> &[f64] {
        let n = self.channel_count;
        self.values.get(f * n..(f + 1) * n).unwrap_or(&[])
    }

    /// Index of the joint with this name (case-insensitive, any `namespace:` before it
    /// ignored), End Sites excluded.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| {
            // A namespace before the name (Mixamo's `mixamorig:`) is not part of it.
            let bare = j.name.rsplit(':').next().unwrap_or(&j.name);
            !j.end_site && bare.eq_ignore_ascii_case(name)
        })
    }
}

fn parse_offset(t: &mut Tokens) -> Result<Vector3<f64>, BvhError> {
    t.expect("OFFSET")?;
    Ok(Vector3::new(t.number()?, t.number()?, t.number()?))
}

fn parse_joint(
    t: &mut Tokens,
    joints: &mut Vec<BvhJoint>,
    parent: Option<usize>,
    channel_count: &mut usize,
) -> Result<(), BvhError> {
    let name = t.next()?.to_owned();
    t.expect("{")?;
    let offset = parse_offset(t)?;
    t.expect("CHANNELS")?;
    let n = t.number()?;
    if !(0.0..=6.0).contains(&n) || n.fract() != 0.0 {
        return Err(t.error(format!(
            "joint \"{name}\" has {n} channels (0 to 6 allowed)"
        )));
    }
    let mut channels = Vec::new();
    for _ in 0..n as usize {
        let w = t.next()?;
        channels.push(match w.to_ascii_lowercase().as_str() {
            "xposition" => Channel::Xposition,
            "yposition" => Channel::Yposition,
            "zposition" => Channel::Zposition,
            "xrotation" => Channel::Xrotation,
            "yrotation" => Channel::Yrotation,
            "zrotation" => Channel::Zrotation,
            _ => {
                t.pos -= 1;
                return Err(t.error(format!("unknown channel \"{w}\"")));
            }
        });
    }
    let index = joints.len();
    joints.push(BvhJoint {
        name: name.clone(),
        parent,
        offset,
        first_channel: *channel_count,
        channels,
        end_site: false,
    });
    *channel_count += n as usize;
    loop {
        let w = t.next()?;
        if w == "}" {
            return Ok(());
        }
        if w.eq_ignore_ascii_case("JOINT") {
            parse_joint(t, joints, Some(index), channel_count)?;
        } else if w.eq_ignore_ascii_case("End") {
            t.expect("Site")?;
            t.expect("{")?;
            let offset = parse_offset(t)?;
            t.expect("}")?;
            joints.push(BvhJoint {
                name: format!("{name}_end"),
                parent: Some(index),
                offset,
                channels: Vec::new(),
                first_channel: *channel_count,
                end_site: true,
            });
        } else {
            t.pos -= 1;
            return Err(t.error(format!("expected JOINT, End Site or \"}}\", found \"{w}\"")));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_roots_are_refused_by_name() {
        let text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nROOT b\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n\n";
        let err = Bvh::parse(text, Path::new("two.bvh")).unwrap_err();
        assert!(matches!(err, BvhError::SeveralRoots { .. }), "{err}");
        assert!(err.to_string().contains("two.bvh"));
    }

    #[test]
    fn syntax_errors_give_the_line() {
        let text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 zero\n";
        let err = Bvh::parse(text, Path::new("x.bvh"))
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("x.bvh:4:") && err.contains("zero"), "{err}");
    }

    #[test]
    fn too_few_values_is_an_error() {
        let text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5\n";
        assert!(Bvh::parse(text, Path::new("x.bvh")).is_err());
    }
}
