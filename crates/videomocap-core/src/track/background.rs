//! Beyond the paper: the static camera's background, and how far each pixel of a frame differs
//! from it (foreground evidence for the arms' blocks).
//!
//! The background is the per-pixel median of [`SAMPLES`] frames spread over the clip: a person
//! who moves leaves each pixel bare in most of them. A frame's pixel then counts as foreground
//! by its largest channel difference from that median, 0 at no difference and 1 from
//! `tau` levels up (`foreground_level`). The arms' blocks compare this fourth lane too
//! ([`super::params::TrackerParams::arm_foreground`]): an arm seen against a wall matches its
//! colours, but a forearm dropped onto the wall itself no longer does.
//!
//! A moving camera has no background: when fewer than [`MIN_STATIC_SHARE`] of the pixels stay
//! within `tau` of their median in [`STABLE_SHARE`] of the samples, there is none.

use image::RgbImage;
use std::sync::Arc;

/// Frames sampled for the median.
pub(super) const SAMPLES: usize = 25;

/// A pixel is steady when at least this share of the samples lie within `tau` of its median.
pub(super) const STABLE_SHARE: f32 = 0.7;

/// The camera counts as static when at least this share of the pixels are steady. The suite's
/// clips (static cameras, people of 200–450 px in 640×480) have 0.92 to 1.00, the real sample
/// 0.92; a camera panning over a textured scene has far less.
pub(super) const MIN_STATIC_SHARE: f32 = 0.6;

/// The per-pixel median of frames from a static camera, at the tracker's working size.
#[derive(Debug, Clone)]
pub struct Background {
    pixels: RgbImage,
    /// The foreground level of every largest channel difference, 0 to 255
    /// (`foreground_level`).
    levels: [f32; 256],
}

/// What a run found of a clip's background (one, or none: a moving camera), kept so that a
/// re-track of the same video need not read the clip again (it costs a 1080p clip's app a
/// good part of a second after every correction).
#[derive(Debug, Clone)]
pub struct KnownBackground {
    /// The working size it was estimated at.
    size: (u32, u32),
    /// The foreground threshold it was estimated with.
    tau: f32,
    /// The background, `None` when the camera moves.
    background: Option<Arc<Background>>,
}

impl KnownBackground {
    /// What a run found at working size `size` with threshold `tau`.
    pub fn new(size: (u32, u32), tau: f32, background: Option<Arc<Background>>) -> Self {
        KnownBackground {
            size,
            tau,
            background,
        }
    }
    /// The background, when it was found at `size` with `tau` (else the run estimates it anew).
    pub fn get(&self, size: (u32, u32), tau: f32) -> Option<Option<Arc<Background>>> {
        (self.size == size && self.tau == tau).then(|| self.background.clone())
    }
}

impl Background {
    /// The median of `samples` (all of one size), or `None` when there are fewer than three,
    /// they differ in size, `tau` is not positive, or the camera moves (see the module).
    pub fn estimate(samples: &[&RgbImage], tau: f32) -> Option<Background> {
        let first = samples.first()?;
        let (w, h) = first.dimensions();
        if samples.len() < 3
            || tau.is_nan()
            || tau <= 0.0
            || samples.iter().any(|s| s.dimensions() != (w, h))
        {
            return None;
        }
        let raws: Vec<&[u8]> = samples.iter().map(|s| s.as_raw().as_slice()).collect();
        let mut median = vec![0u8; raws[0].len()];
        let mut values = Vec::with_capacity(raws.len());
        let mid = raws.len() / 2;
        for (i, m) in median.iter_mut().enumerate() {
            values.clear();
            values.extend(raws.iter().map(|r| r[i]));
            *m = *values.select_nth_unstable(mid).1;
        }
        // A steady pixel: enough samples within `tau` of the median in every channel.
        let need = (STABLE_SHARE * raws.len() as f32).ceil() as usize;
        let mut near = vec![0usize; w as usize * h as usize];
        for raw in &raws {
            for ((n, px), m) in near
                .iter_mut()
                .zip(raw.as_chunks::<3>().0)
                .zip(median.as_chunks::<3>().0)
            {
                *n += usize::from(f32::from(max_abs_diff(px, m)) < tau);
            }
        }
        let steady = near.iter().filter(|&&n| n >= need).count();
        let pixels = near.len().max(1);
        if (steady as f32) < MIN_STATIC_SHARE * pixels as f32 {
            return None;
        }
        let pixels = RgbImage::from_raw(w, h, median)?;
        Some(Background {
            pixels,
            levels: level_table(tau),
        })
    }

    /// The median image.
    pub fn image(&self) -> &RgbImage {
        &self.pixels
    }

    /// The foreground level (0–255) of each pixel of `image`, row-major, or `None` when its
    /// size is not the background's.
    pub fn levels<'a>(&'a self, image: &'a RgbImage) -> Option<impl Iterator<Item = f32> + 'a> {
        (image.dimensions() == self.pixels.dimensions()).then(|| {
            image
                .as_raw()
                .as_chunks::<3>()
                .0
                .iter()
                .zip(self.pixels.as_raw().as_chunks::<3>().0)
                .map(|(c, b)| self.levels[usize::from(max_abs_diff(c, b))])
        })
    }
}

/// How much a pixel `c` stands out from its background `b`: 255 times its largest channel
/// difference over `tau`, at most 255 (one pixel; the tracker reads whole frames).
#[cfg(test)]
pub(super) fn foreground_level(c: &[u8; 3], b: &[u8; 3], tau: f32) -> f32 {
    level(max_abs_diff(c, b), tau)
}

/// The foreground level of a largest channel difference `diff`.
fn level(diff: u8, tau: f32) -> f32 {
    255.0 * (f32::from(diff) / tau).min(1.0)
}

/// The largest channel difference between two pixels.
#[inline]
fn max_abs_diff(c: &[u8; 3], b: &[u8; 3]) -> u8 {
    c[0].abs_diff(b[0])
        .max(c[1].abs_diff(b[1]))
        .max(c[2].abs_diff(b[2]))
}

/// [`foreground_level`] of every difference 0 to 255 (read per pixel and frame).
fn level_table(tau: f32) -> [f32; 256] {
    std::array::from_fn(|d| level(u8::try_from(d).unwrap_or(u8::MAX), tau))
}

/// Indices of `count` frames spread evenly over `0..n`, first and last included (all of them
/// when `n ≤ count`).
pub(super) fn sample_indices(n: usize, count: usize) -> Vec<usize> {
    if n <= count || count < 2 {
        return (0..n).collect();
    }
    (0..count).map(|k| k * (n - 1) / (count - 1)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn textured(w: u32, h: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            image::Rgb([
                (x * 7 % 200) as u8,
                (y * 11 % 200) as u8,
                ((x + y) * 5 % 200) as u8,
            ])
        })
    }

    /// The scene with a bright square at `x`.
    fn with_square(scene: &RgbImage, x: u32) -> RgbImage {
        let mut im = scene.clone();
        for yy in 10..20 {
            for xx in x..x + 10 {
                im.put_pixel(xx, yy, image::Rgb([255, 255, 255]));
            }
        }
        im
    }

    #[test]
    fn the_median_removes_a_moving_person_and_marks_them_as_foreground() {
        let scene = textured(80, 40);
        let frames: Vec<RgbImage> = (0..7).map(|k| with_square(&scene, 5 + 10 * k)).collect();
        let refs: Vec<&RgbImage> = frames.iter().collect();
        let bg = Background::estimate(&refs, 20.0).expect("a static camera");
        assert_eq!(bg.image(), &scene, "the square is gone from the median");
        let levels: Vec<f32> = bg.levels(&frames[2]).expect("same size").collect();
        let at = |x: u32, y: u32| levels[(y * 80 + x) as usize];
        assert_eq!(at(30, 15), 255.0, "on the square");
        assert_eq!(at(60, 30), 0.0, "on the bare scene");
    }

    #[test]
    fn a_panning_camera_has_no_background() {
        let wide = textured(200, 40);
        let frames: Vec<RgbImage> = (0..7)
            .map(|k| image::imageops::crop_imm(&wide, 9 * k, 0, 80, 40).to_image())
            .collect();
        let refs: Vec<&RgbImage> = frames.iter().collect();
        assert!(Background::estimate(&refs, 20.0).is_none());
    }

    #[test]
    fn too_few_or_mismatched_samples_give_none() {
        let a = textured(20, 10);
        let b = textured(21, 10);
        assert!(Background::estimate(&[&a, &a], 20.0).is_none());
        assert!(Background::estimate(&[&a, &a, &b], 20.0).is_none());
        assert!(Background::estimate(&[&a, &a, &a], 0.0).is_none());
        let bg = Background::estimate(&[&a, &a, &a], 20.0).expect("three equal frames");
        assert!(bg.levels(&b).is_none(), "a frame of another size");
    }

    #[test]
    fn samples_spread_over_the_clip() {
        assert_eq!(sample_indices(5, 25), vec![0, 1, 2, 3, 4]);
        assert_eq!(sample_indices(101, 5), vec![0, 25, 50, 75, 100]);
        assert_eq!(sample_indices(0, 25), Vec::<usize>::new());
    }

    #[test]
    fn the_level_grows_with_the_largest_channel_difference() {
        assert_eq!(foreground_level(&[10, 10, 10], &[10, 10, 10], 20.0), 0.0);
        assert_eq!(foreground_level(&[20, 10, 10], &[10, 10, 10], 20.0), 127.5);
        assert_eq!(foreground_level(&[10, 10, 90], &[10, 10, 10], 20.0), 255.0);
    }
}
