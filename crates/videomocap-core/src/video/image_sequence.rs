//! Image sequences: a directory of PNG/JPEG frames in natural sort order (`f2.png` before
//! `f10.png`), all of one size, at a frame rate given by the user.

use super::{VideoError, VideoInfo, VideoSource};
use image::RgbImage;
use std::path::{Path, PathBuf};

/// Frame rate assumed for an image sequence when the user gives none.
pub const DEFAULT_SEQUENCE_FPS: f64 = 30.0;

/// A directory of images read as a video.
pub struct ImageSequence {
    files: Vec<PathBuf>,
    info: VideoInfo,
}

fn is_image(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"))
}

impl ImageSequence {
    /// Lists the images of `dir` and checks that they all have the same size (headers only).
    pub fn open(dir: &Path, fps: f64) -> Result<ImageSequence, VideoError> {
        let io = |source| VideoError::Io {
            path: dir.to_owned(),
            source,
        };
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(io)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_image(p))
            .collect();
        files.sort_by(|a, b| {
            natord::compare(
                &a.file_name().unwrap_or_default().to_string_lossy(),
                &b.file_name().unwrap_or_default().to_string_lossy(),
            )
        });
        let Some(first) = files.first() else {
            return Err(VideoError::NoImages {
                path: dir.to_owned(),
            });
        };
        let dims = |p: &Path| {
            image::image_dimensions(p).map_err(|e| VideoError::Image {
                path: p.to_owned(),
                reason: e.to_string(),
            })
        };
        let (width, height) = dims(first)?;
        for f in &files[1..] {
            let (w, h) = dims(f)?;
            if (w, h) != (width, height) {
                let name = |p: &Path| {
                    p.file_name()
                        .unwrap_or_default()
                        .to_string_lossy()
                        .into_owned()
                };
                return Err(VideoError::MixedSizes {
                    path: dir.to_owned(),
                    first_file: name(first),
                    first_width: width,
                    first_height: height,
                    other_file: name(f),
                    other_width: w,
                    other_height: h,
                });
            }
        }
        let fps = if fps.is_finite() && fps > 0.0 {
            fps
        } else {
            DEFAULT_SEQUENCE_FPS
        };
        let codec = first
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("image")
            .to_ascii_lowercase();
        let info = VideoInfo {
            path: dir.to_owned(),
            width,
            height,
            fps,
            frame_count: files.len(),
            duration_s: files.len() as f64 / fps,
            rotation_deg: 0,
            codec,
            variable_frame_rate: false,
            keyframe_interval: 1,
        };
        Ok(ImageSequence { files, info })
    }

    /// The image files in frame order.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }
}

impl VideoSource for ImageSequence {
    fn info(&self) -> &VideoInfo {
        &self.info
    }

    fn reopen(&self) -> Option<Box<dyn VideoSource>> {
        Some(Box::new(ImageSequence {
            files: self.files.clone(),
            info: self.info.clone(),
        }))
    }

    fn time_of(&self, index: usize) -> f64 {
        index as f64 / self.info.fps
    }

    fn decode(&mut self, index: usize) -> Result<RgbImage, VideoError> {
        let path = self
            .files
            .get(index)
            .ok_or_else(|| VideoError::FrameOutOfRange {
                path: self.info.path.clone(),
                index,
                count: self.files.len(),
            })?;
        let img = image::open(path).map_err(|e| VideoError::Image {
            path: path.clone(),
            reason: e.to_string(),
        })?;
        let rgb = img.to_rgb8();
        if rgb.dimensions() != (self.info.width, self.info.height) {
            return Err(VideoError::Image {
                path: path.clone(),
                reason: format!(
                    "size changed to {}×{} after opening (was {}×{})",
                    rgb.width(),
                    rgb.height(),
                    self.info.width,
                    self.info.height
                ),
            });
        }
        Ok(rgb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, w: u32, h: u32, v: u8) {
        RgbImage::from_pixel(w, h, image::Rgb([v, v, v]))
            .save(dir.join(name))
            .unwrap();
    }

    #[test]
    fn frames_come_in_natural_order() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "f10.png", 4, 3, 10);
        write(dir.path(), "f2.png", 4, 3, 2);
        write(dir.path(), "f1.png", 4, 3, 1);
        std::fs::write(dir.path().join("notes.txt"), "x").unwrap();
        let mut s = ImageSequence::open(dir.path(), 25.0).unwrap();
        assert_eq!(s.info().frame_count, 3);
        assert_eq!((s.info().width, s.info().height), (4, 3));
        let values: Vec<u8> = (0..3)
            .map(|i| s.decode(i).unwrap().get_pixel(0, 0)[0])
            .collect();
        assert_eq!(values, vec![1, 2, 10]);
        assert!((s.time_of(2) - 0.08).abs() < 1e-12);
    }

    #[test]
    fn mixed_sizes_name_both_files() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "a.png", 4, 3, 0);
        write(dir.path(), "b.png", 5, 3, 0);
        let err = ImageSequence::open(dir.path(), 25.0)
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("a.png") && err.contains("b.png") && err.contains("5×3"),
            "{err}"
        );
    }

    #[test]
    fn an_empty_directory_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let err = ImageSequence::open(dir.path(), 25.0).err().unwrap();
        assert!(matches!(err, VideoError::NoImages { .. }));
    }
}
