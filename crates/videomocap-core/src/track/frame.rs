//! A video frame as the tracker samples it: four `f32` lanes per pixel (R, G, B and the
//! foreground level), and a read-only view with bilinear sampling, in floating and in fixed
//! point. The similarity's hot loop (`similarity`) reads frames only through this.

use super::background::Background;
use image::RgbImage;

/// Fraction bits of the similarity's fixed-point grid positions: a 65536th of a pixel.
pub(super) const FRAC_BITS: u32 = 16;
pub(super) const FRAC_ONE: f32 = (1u32 << FRAC_BITS) as f32;
const FRAC_MASK: i32 = (1 << FRAC_BITS) - 1;
const FRAC_STEP: f32 = 1.0 / FRAC_ONE;

/// A frame as four `f32` lanes per pixel (R, G, B and the foreground level, 0 without a
/// background: [`FloatFrame::fill_with`]), converted once per frame (0.3 ms at
/// 640×480): the hot loop then loads a pixel as one vector instead of widening its bytes at
/// every sample.
#[derive(Clone, Default)]
pub struct FloatFrame {
    px: Vec<[f32; 4]>,
    width: usize,
    height: usize,
}

/// Its size only: a frame's pixels would fill a log.
impl std::fmt::Debug for FloatFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FloatFrame")
            .field("width", &self.width)
            .field("height", &self.height)
            .finish_non_exhaustive()
    }
}

impl FloatFrame {
    /// Converts an RGB8 image.
    pub fn new(image: &RgbImage) -> FloatFrame {
        let mut frame = FloatFrame::default();
        frame.fill(image);
        frame
    }

    /// Converts an RGB8 image into this frame's buffer, reusing its memory (a fresh buffer per
    /// frame would cost its page faults every frame).
    pub fn fill(&mut self, image: &RgbImage) {
        self.fill_with(image, None);
    }

    /// [`FloatFrame::fill`] with the fourth lane set to each pixel's foreground level against
    /// `background` (`Background::levels`); 0 without one, or when its size differs.
    pub fn fill_with(&mut self, image: &RgbImage, background: Option<&Background>) {
        self.width = image.width() as usize;
        self.height = image.height() as usize;
        self.px.clear();
        let rgb = image.as_raw().as_chunks::<3>().0.iter();
        match background.and_then(|b| b.levels(image)) {
            Some(levels) => self.px.extend(
                rgb.zip(levels)
                    .map(|(c, f)| [f32::from(c[0]), f32::from(c[1]), f32::from(c[2]), f]),
            ),
            None => self
                .px
                .extend(rgb.map(|c| [f32::from(c[0]), f32::from(c[1]), f32::from(c[2]), 0.0])),
        }
    }

    /// A view for sampling.
    pub fn view(&self) -> FrameView<'_> {
        FrameView {
            px: &self.px,
            width: self.width,
            height: self.height,
        }
    }
}

/// A read-only view of a [`FloatFrame`] for bilinear sampling.
#[derive(Clone, Copy)]
pub struct FrameView<'a> {
    px: &'a [[f32; 4]],
    width: usize,
    height: usize,
}

impl FrameView<'_> {
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The pixel at index `i` (row-major); black where a caller's index runs off the frame
    /// (not reached: callers clamp).
    #[inline]
    pub(super) fn at(&self, i: usize) -> [f32; 4] {
        self.px.get(i).copied().unwrap_or([0.0; 4])
    }

    /// The colour at a sub-pixel position by bilinear interpolation; points off the image take
    /// the nearest edge pixel's colour.
    #[inline]
    pub fn bilinear(&self, x: f32, y: f32) -> [f32; 3] {
        let [r, g, b, _] = self.interpolate(x, y);
        [r, g, b]
    }

    /// All four lanes at a sub-pixel position (see [`FrameView::bilinear`]).
    #[inline]
    pub(super) fn interpolate(&self, x: f32, y: f32) -> [f32; 4] {
        let xmax = (self.width - 1) as f32;
        let ymax = (self.height - 1) as f32;
        let x = x.clamp(0.0, xmax);
        let y = y.clamp(0.0, ymax);
        let x0 = x as usize; // x ≥ 0, so truncation is floor
        let y0 = y as usize;
        let fx = x - x0 as f32;
        let fy = y - y0 as f32;
        let x1 = (x0 + 1).min(self.width - 1);
        let y1 = (y0 + 1).min(self.height - 1);
        let row0 = y0 * self.width;
        let row1 = y1 * self.width;
        let (a, b, c, e) = (
            self.at(row0 + x0),
            self.at(row0 + x1),
            self.at(row1 + x0),
            self.at(row1 + x1),
        );
        let mut out = [0.0f32; 4];
        for (k, o) in out.iter_mut().enumerate() {
            let top = a[k] + fx * (b[k] - a[k]);
            let bottom = c[k] + fx * (e[k] - c[k]);
            *o = top + fy * (bottom - top);
        }
        out
    }

    /// The colour at a point known to lie inside `[0, width − 1) × [0, height − 1)`, given in
    /// fixed point ([`FRAC_BITS`] fraction bits), as four lanes (R, G, B, foreground) so the
    /// compiler keeps a pixel in one vector register: no clamping, no float-to-integer
    /// conversion (a saturating one per coordinate in Rust), and each pair of neighbouring
    /// pixels is one slice. `None` when the point is not inside after all.
    #[inline]
    pub(super) fn bilinear_fixed(&self, [x, y]: [i32; 2]) -> Option<[f32; 4]> {
        // A negative coordinate (not inside after all) becomes an index `get` refuses.
        let (x0, y0) = ((x >> FRAC_BITS) as usize, (y >> FRAC_BITS) as usize);
        let fx = (x & FRAC_MASK) as f32 * FRAC_STEP;
        let fy = (y & FRAC_MASK) as f32 * FRAC_STEP;
        let i0 = y0 * self.width + x0;
        let i1 = i0 + self.width;
        let pair = |i: usize| self.px.get(i..).and_then(|s| s.first_chunk::<2>());
        let ([p00, p10], [p01, p11]) = (pair(i0)?, pair(i1)?);
        let mut out = [0.0f32; 4];
        for (k, o) in out.iter_mut().enumerate() {
            let top = p00[k] + fx * (p10[k] - p00[k]);
            let bottom = p01[k] + fx * (p11[k] - p01[k]);
            *o = top + fy * (bottom - top);
        }
        Some(out)
    }

    /// [`FrameView::bilinear`] as four lanes (R, G, B and the foreground level).
    #[cold]
    pub(super) fn bilinear4(&self, x: f32, y: f32) -> [f32; 4] {
        self.interpolate(x, y)
    }

    /// Colour at an integer pixel (caller keeps `x < width`, `y < height`).
    #[inline]
    pub fn pixel(&self, x: usize, y: usize) -> [f32; 3] {
        let [r, g, b, _] = self.at(y * self.width + x);
        [r, g, b]
    }
}
