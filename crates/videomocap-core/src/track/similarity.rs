//! Sub-pixel morph-block similarity (Pan et al., "Morph-block match", eqs. 3–5 of the
//! feature-tracking section) — the tracker's hot loop.
//!
//! A [`Template`] is the colour model of a block: `rows × cols` sub-pixels laid along θ and
//! θ + 90°, each the bilinear interpolation of the image at that point. A candidate block of any
//! size and angle is sampled on the same grid (the paper's "row = m, column = n of the smaller
//! block"; the grid is capped at [`MAX_ROWS`] × [`MAX_COLS`] so the cost per candidate does not
//! grow with the image size) and compared cell by cell:
//!
//! - eq. 3: `diff_ij = W_R·|ΔR| + W_G·|ΔG| + W_B·|ΔB|`
//! - eq. 5: cells with `m/4 ≤ i ≤ 3m/4` and `n/4 ≤ j ≤ 3n/4` form the centre region b1, the
//!   rest the margin b2
//! - eq. 4: `S = 1 / (W1·Σ_b1 diff + W2·Σ_b2 diff)`.
//!
//! We return the *cost* `C = (W1·Σ_b1 diff + W2·Σ_b2 diff) / (W1·|b1| + W2·|b2|)`, the mean
//! weighted difference in 8-bit levels: `S = 1 / (C · const)`, so the ranking is the paper's, but
//! the number means the same for every block size. Beyond the paper, each cell is compared with
//! two colour models at once — the key frame's appearance (drift control) and the adaptive model
//! updated with a linear weight (Akita 1984) — mixed by [`SimilarityWeights::key`].
//!
//! Speed: each frame is converted once to four `f32` lanes per pixel ([`FloatFrame`]), so a
//! sample loads pixels as vectors instead of widening bytes. A candidate whose grid lies wholly
//! inside the frame (nearly all of them) is sampled without clamping and in fixed point
//! (`FixedGrid`: a cell's pixel and fraction are a shift and a mask, where Rust's saturating
//! float-to-integer conversion cost a compare and two conditional moves per coordinate); the
//! rest clamp every sample. The template is sampled the same way, so a block compared with
//! itself costs nothing. A row-by-row early exit drops a candidate as soon as it cannot win.
//! Fixed point took `bench track`'s 640×480 one-thread figure from 85.4 to 104.4 frames/s and
//! the 1080×1920 tracking-to-decoding ratio from 2.04 to 1.57.

use super::block::MorphBlock;
pub use super::frame::FloatFrame;
pub(super) use super::frame::FrameView;
use super::frame::{FRAC_BITS, FRAC_ONE};

/// Most rows in a block's sampling grid.
pub(super) const MAX_ROWS: usize = 24;
/// Most columns in a block's sampling grid.
pub(super) const MAX_COLS: usize = 10;

/// The weights of eqs. 3–5 and of the colour-model mix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SimilarityWeights {
    /// `W_R, W_G, W_B` of eq. 3. Default equal thirds: clothes and skin differ as much in hue as
    /// in brightness, so no channel is favoured.
    pub rgb: [f32; 3],
    /// `W1`, the centre region's weight (eq. 4). Default 1.0.
    pub centre: f32,
    /// `W2`, the margin region's weight (eq. 4); `W1 > W2` as in the paper because the margin
    /// mixes in background that changes as the body moves. Default 0.5.
    pub margin: f32,
    /// Weight of the key-frame model against the adaptive one (0 = adaptive only, 1 = key only).
    /// Default 0.5.
    pub key: f32,
}

impl Default for SimilarityWeights {
    fn default() -> Self {
        SimilarityWeights {
            rgb: [1.0 / 3.0; 3],
            centre: 1.0,
            margin: 0.5,
            key: 0.5,
        }
    }
}

/// Where the grid's cells sit for one candidate block: cell `(i, j)` is at
/// `start + i·du + j·dv`.
#[derive(Clone, Copy)]
struct GridGeometry {
    start: [f32; 2],
    du: [f32; 2],
    dv: [f32; 2],
}

impl GridGeometry {
    /// Whether every cell of a `rows × cols` grid lies inside `[0, width − 1) ×
    /// [0, height − 1)`, with a hundredth of a pixel to spare for rounding (the grid is a
    /// parallelogram: its four corner cells bound it).
    fn inside(&self, rows: usize, cols: usize, frame: &FrameView) -> bool {
        let (fi, fj) = ((rows - 1) as f32, (cols - 1) as f32);
        let (xmax, ymax) = ((frame.width() - 1) as f32, (frame.height() - 1) as f32);
        [(0.0, 0.0), (fi, 0.0), (0.0, fj), (fi, fj)]
            .iter()
            .all(|&(i, j)| {
                let x = self.start[0] + i * self.du[0] + j * self.dv[0];
                let y = self.start[1] + i * self.du[1] + j * self.dv[1];
                x >= 0.01 && x < xmax - 0.01 && y >= 0.01 && y < ymax - 0.01
            })
    }

    /// Cell `(i, j)`'s position.
    #[inline]
    fn at(&self, i: usize, j: usize) -> (f32, f32) {
        // Through i32: cheaper than from usize, and i, j < MAX_ROWS.
        let (fi, fj) = (i as i32 as f32, j as i32 as f32);
        (
            self.start[0] + fi * self.du[0] + fj * self.dv[0],
            self.start[1] + fi * self.du[1] + fj * self.dv[1],
        )
    }

    /// The same grid in fixed point ([`FRAC_BITS`] fraction bits; positions differ from the
    /// float ones by under 10⁻³ px) when all its `rows × cols` cells lie inside `frame` and
    /// the frame is narrower and lower than [`MAX_FIXED_PX`]; `None` otherwise.
    fn fixed_inside(&self, rows: usize, cols: usize, frame: &FrameView) -> Option<FixedGrid> {
        let fits = frame.width() < MAX_FIXED_PX && frame.height() < MAX_FIXED_PX;
        let fix = |v: f32| (v * FRAC_ONE).round() as i32;
        (fits && self.inside(rows, cols, frame)).then(|| FixedGrid {
            start: self.start.map(fix),
            du: self.du.map(fix),
            dv: self.dv.map(fix),
        })
    }

    fn new(block: &MorphBlock, extent: Extent, rows: usize, cols: usize) -> GridGeometry {
        let span = extent.end - extent.start;
        let d = block.direction() * (block.m * span / rows as f64);
        let a = block.across() * (block.n / cols as f64);
        // Cell centres: u = start + (i + ½)·span/rows, v = (j + ½)/cols − ½.
        let s = block.origin
            + block.direction() * (block.m * extent.start)
            + d * 0.5
            + a * (0.5 - cols as f64 / 2.0);
        GridGeometry {
            start: [s.x as f32, s.y as f32],
            du: [d.x as f32, d.y as f32],
            dv: [a.x as f32, a.y as f32],
        }
    }
}

/// Frames up to this size (pixels, either side) are sampled in fixed point: positions inside
/// such a frame fit an `i32` with [`FRAC_BITS`] fraction bits.
const MAX_FIXED_PX: usize = 1 << (30 - FRAC_BITS);

/// A [`GridGeometry`] in fixed point, for grids inside the frame: stepping from cell to cell
/// is integer arithmetic, and a position's pixel and fraction are a shift and a mask.
#[derive(Clone, Copy)]
struct FixedGrid {
    start: [i32; 2],
    du: [i32; 2],
    dv: [i32; 2],
}

impl FixedGrid {
    /// Cell `(i, j)`'s position.
    #[inline]
    fn at(&self, i: usize, j: usize) -> [i32; 2] {
        let (i, j) = (i as i32, j as i32); // i, j < MAX_ROWS
        [0, 1].map(|k| self.start[k] + i * self.du[k] + j * self.dv[k])
    }
}

/// How far along the middle line the sampled area runs, in units of `m`: from `start` (0 = the
/// anchor joint) to `end` (1 = the other joint). Beyond the paper, limb blocks reach a little
/// past their far joint so the boundary there (hand, shoe, background) pins the joint down; a
/// block that stops exactly at a joint of a uniformly coloured limb can shrink along it at no
/// cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Extent {
    /// Start, units of m.
    pub start: f64,
    /// End, units of m.
    pub end: f64,
}

impl Extent {
    /// Exactly the block (the paper's).
    pub(super) const BLOCK: Extent = Extent {
        start: 0.0,
        end: 1.0,
    };
}

/// The colour model of one block: `rows × cols` cells, each with its key-frame colour, its
/// adaptive colour and its region weight (eq. 5).
#[derive(Debug, Clone)]
pub(super) struct Template {
    rows: usize,
    cols: usize,
    /// Per cell: the key model's R, G, B, foreground and the adaptive model's (four lanes,
    /// like [`FloatFrame`]).
    cells: Vec<[[f32; 4]; 2]>,
    /// Per cell: `W1` in the centre region, `W2` in the margin (eq. 5).
    region: Vec<f32>,
    /// The order rows are compared in, all rows and the even ones (the coarse level): the
    /// centre region's first, so a losing candidate reaches its bound sooner.
    row_order: [Vec<usize>; 2],
    /// Sum of the region weights over all cells, and over the even rows and columns only (the
    /// coarse level).
    total: [f32; 2],
    weights: SimilarityWeights,
    extent: Extent,
    /// Weight of the foreground lane against the colour ([`Template::set_foreground`]).
    foreground: f32,
}

/// Grid size for a block of `m × n` pixels: one cell per pixel, capped.
pub(super) fn grid_size(m: f64, n: f64) -> (usize, usize) {
    let rows = (m.round() as usize).clamp(4, MAX_ROWS);
    let cols = (n.round() as usize).clamp(3, MAX_COLS);
    (rows, cols)
}

impl Template {
    /// Samples a block of `frame` as both the key and the adaptive model.
    pub(super) fn sample(
        frame: FrameView,
        block: &MorphBlock,
        extent: Extent,
        weights: SimilarityWeights,
    ) -> Template {
        let (rows, cols) = grid_size(block.m * (extent.end - extent.start), block.n);
        let mut region = Vec::with_capacity(rows * cols);
        let (mut all, mut coarse) = (0.0f32, 0.0f32);
        for i in 0..rows {
            for j in 0..cols {
                // eq. 5, in cell units: centre when m/4 ≤ i ≤ 3m/4 and n/4 ≤ j ≤ 3n/4.
                let (fi, fj) = (i as f32 + 0.5, j as f32 + 0.5);
                let centre = fi >= rows as f32 / 4.0
                    && fi <= 0.75 * rows as f32
                    && fj >= cols as f32 / 4.0
                    && fj <= 0.75 * cols as f32;
                let w = if centre {
                    weights.centre
                } else {
                    weights.margin
                };
                region.push(w);
                all += w;
                if i % 2 == 0 && j % 2 == 0 {
                    coarse += w;
                }
            }
        }
        let mut t = Template {
            foreground: 0.0,
            rows,
            cols,
            cells: vec![[[0.0; 4]; 2]; rows * cols],
            row_order: {
                let centre = |i: usize| {
                    let fi = i as f32 + 0.5;
                    fi >= rows as f32 / 4.0 && fi <= 0.75 * rows as f32
                };
                let order = |step: usize| -> Vec<usize> {
                    let all = (0..rows).step_by(step);
                    all.clone()
                        .filter(|&i| centre(i))
                        .chain(all.filter(|&i| !centre(i)))
                        .collect()
                };
                [order(1), order(2)]
            },
            region,
            total: [all, coarse],
            weights,
            extent,
        };
        let g = GridGeometry::new(block, extent, rows, cols);
        for (cell, c) in t.cells.iter_mut().zip(sample_grid(frame, g, rows, cols)) {
            *cell = [c, c];
        }
        t
    }

    /// `Σ region · (w_key·|colour − key| + w_ada·|colour − adaptive|)` over every `STEP`-th row
    /// and column (eqs. 3–5), or infinity as soon as a row ends above `limit`. `sample(i, j)`
    /// gives the frame's colour at cell `(i, j)` as four lanes.
    #[inline(always)]
    fn weighted_sum<const STEP: usize>(
        &self,
        [w_key, w_ada]: [[f32; 4]; 2],
        limit: f32,
        sample: impl Fn(usize, usize) -> [f32; 4],
    ) -> f32 {
        let mut sum = 0.0f32;
        for &i in &self.row_order[usize::from(STEP > 1)] {
            let base = i * self.cols;
            // This row's cells and weights as slices of one length, so that indexing by `j`
            // needs no bounds checks.
            let cells = &self.cells[base..base + self.cols];
            let region = &self.region[base..base + self.cols];
            let mut row = [0.0f32; 4];
            // An index loop: `enumerate().step_by()` kept its state in memory.
            let mut j = 0;
            while j < cells.len() {
                let ([key, ada], r) = (&cells[j], region[j]);
                let c = sample(i, j);
                for k in 0..4 {
                    row[k] +=
                        r * (w_key[k] * (c[k] - key[k]).abs() + w_ada[k] * (c[k] - ada[k]).abs());
                }
                j += STEP;
            }
            // The fourth lane has zero weight, but summing it keeps all four lanes one vector
            // operation.
            sum += row.iter().sum::<f32>();
            if sum > limit {
                return f32::INFINITY;
            }
        }
        sum
    }

    /// [`Template::weighted_sum`] at every `STEP`-th row and column of `g` in `frame`: in fixed
    /// point without clamping when the grid lies inside the frame (nearly every candidate),
    /// clamping every sample otherwise.
    #[inline(always)]
    fn sum_over<const STEP: usize>(
        &self,
        frame: FrameView,
        g: &GridGeometry,
        weights: [[f32; 4]; 2],
        limit: f32,
    ) -> f32 {
        if let Some(fixed) = g.fixed_inside(self.rows, self.cols, &frame) {
            self.weighted_sum::<STEP>(weights, limit, |i, j| {
                frame.bilinear_fixed(fixed.at(i, j)).unwrap_or_else(|| {
                    let (x, y) = g.at(i, j);
                    frame.bilinear4(x, y)
                })
            })
        } else {
            self.weighted_sum::<STEP>(weights, limit, |i, j| {
                let (x, y) = g.at(i, j);
                frame.bilinear4(x, y)
            })
        }
    }

    /// Rows of the grid.
    #[cfg(test)]
    pub(super) fn rows(&self) -> usize {
        self.rows
    }

    /// Columns of the grid.
    #[cfg(test)]
    pub(super) fn cols(&self) -> usize {
        self.cols
    }

    /// The key-frame colour of cell `(i, j)`.
    #[cfg(test)]
    pub(super) fn key_colour(&self, i: usize, j: usize) -> [f32; 3] {
        let [c, _] = self.cells[i * self.cols + j];
        [c[0], c[1], c[2]]
    }

    /// The adaptive colour of cell `(i, j)`.
    #[cfg(test)]
    pub(super) fn adaptive_colour(&self, i: usize, j: usize) -> [f32; 3] {
        let [_, c] = self.cells[i * self.cols + j];
        [c[0], c[1], c[2]]
    }

    /// The sampled extent along the middle line.
    #[cfg(test)]
    pub(super) fn extent(&self) -> Extent {
        self.extent
    }

    /// The weights in use.
    #[cfg(test)]
    pub(super) fn weights(&self) -> SimilarityWeights {
        self.weights
    }

    /// Updates the adaptive model with the block found in a new frame by a linear weight:
    /// `model ← (1 − rate)·model + rate·observed` (the paper's self-adapting colour model).
    pub(super) fn update(&mut self, frame: FrameView, block: &MorphBlock, rate: f32) {
        let g = GridGeometry::new(block, self.extent, self.rows, self.cols);
        for ([_, adaptive], c) in self
            .cells
            .iter_mut()
            .zip(sample_grid(frame, g, self.rows, self.cols))
        {
            for (a, c) in adaptive.iter_mut().zip(c) {
                *a += rate * (c - *a);
            }
        }
    }

    /// The cost (mean weighted difference, 8-bit levels; similarity `S ∝ 1 / cost`) of a
    /// candidate block in `frame`. `coarse` compares only every other row and column (4× fewer
    /// samples, for the wide first search). Returns `f32::INFINITY` as soon as the partial sum
    /// proves the cost exceeds `bound` (early exit: the candidate already loses).
    pub(super) fn cost(
        &self,
        frame: FrameView,
        block: &MorphBlock,
        coarse: bool,
        bound: f32,
    ) -> f32 {
        self.cost_lanes(frame, block, coarse, bound, self.foreground)
    }

    /// [`Template::cost`] on the colour alone, the foreground lane left out: what the
    /// reliability is read from, so that it means the same with and without a background.
    pub(super) fn appearance_cost(&self, frame: FrameView, block: &MorphBlock) -> f32 {
        self.cost_lanes(frame, block, false, f32::INFINITY, 0.0)
    }

    /// Makes [`Template::cost`] weigh the foreground lane by `weight` (levels of foreground
    /// difference against levels of colour difference): the part must stand out from the
    /// background where it stood out on the key frame. 0 (the default) leaves it out.
    pub(super) fn set_foreground(&mut self, weight: f32) {
        self.foreground = weight;
    }

    /// [`Template::cost`] with the foreground lane weighed by `foreground`.
    fn cost_lanes(
        &self,
        frame: FrameView,
        block: &MorphBlock,
        coarse: bool,
        bound: f32,
        foreground: f32,
    ) -> f32 {
        let total = self.total[usize::from(coarse)];
        let limit = if bound.is_finite() {
            bound * total
        } else {
            f32::INFINITY
        };
        let g = GridGeometry::new(block, self.extent, self.rows, self.cols);
        // eq. 3's channel weights times the two models' mix, per lane (the fourth is the
        // foreground level's).
        let [wr, wg, wb] = self.weights.rgb;
        let wk = self.weights.key;
        let wa = 1.0 - wk;
        let w_key = [wk * wr, wk * wg, wk * wb, wk * foreground];
        let w_ada = [wa * wr, wa * wg, wa * wb, wa * foreground];
        let sum = if coarse {
            self.sum_over::<2>(frame, &g, [w_key, w_ada], limit)
        } else {
            self.sum_over::<1>(frame, &g, [w_key, w_ada], limit)
        };
        sum / total
    }
}

/// Every cell's colour and foreground level in row-major order, sampled exactly as
/// [`Template::cost`] samples it (in fixed point when the grid lies inside the frame), so that
/// a block compared with itself costs nothing.
fn sample_grid(
    frame: FrameView<'_>,
    g: GridGeometry,
    rows: usize,
    cols: usize,
) -> impl Iterator<Item = [f32; 4]> + '_ {
    let fixed = g.fixed_inside(rows, cols, &frame);
    (0..rows).flat_map(move |i| {
        (0..cols).map(move |j| {
            fixed
                .and_then(|f| frame.bilinear_fixed(f.at(i, j)))
                .unwrap_or_else(|| {
                    let (x, y) = g.at(i, j);
                    frame.bilinear4(x, y)
                })
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::background::Background;
    use image::RgbImage;
    use nalgebra::Point2;
    use proptest::prelude::*;

    fn textured(w: u32, h: u32, seed: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            let v = |k: u32| {
                let s = (x.wrapping_mul(73) ^ y.wrapping_mul(151) ^ (seed + k).wrapping_mul(977))
                    .wrapping_mul(2_654_435_761);
                ((s >> 24) as u8) / 2 + ((x * 3 + y * 5 + k * 40) % 128) as u8
            };
            image::Rgb([v(0), v(1), v(2)])
        })
    }

    /// Bilinear interpolation written out from its definition, in f64.
    fn slow_bilinear(img: &RgbImage, x: f64, y: f64) -> [f64; 3] {
        let x = x.clamp(0.0, f64::from(img.width() - 1));
        let y = y.clamp(0.0, f64::from(img.height() - 1));
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let px = |xx: f64, yy: f64| {
            let xx = (xx as u32).min(img.width() - 1);
            let yy = (yy as u32).min(img.height() - 1);
            img.get_pixel(xx, yy).0.map(f64::from)
        };
        let mut out = [0.0; 3];
        for (k, o) in out.iter_mut().enumerate() {
            *o = (1.0 - fx) * (1.0 - fy) * px(x0, y0)[k]
                + fx * (1.0 - fy) * px(x0 + 1.0, y0)[k]
                + (1.0 - fx) * fy * px(x0, y0 + 1.0)[k]
                + fx * fy * px(x0 + 1.0, y0 + 1.0)[k];
        }
        out
    }

    /// Eq. 3–5 written out directly: every cell's centre from the block's (u, v) coordinates,
    /// the two regions summed separately, both models compared.
    fn slow_cost(t: &Template, img: &RgbImage, block: &MorphBlock) -> f64 {
        let w = t.weights();
        let e = t.extent();
        let (rows, cols) = (t.rows(), t.cols());
        let (mut b1, mut b2, mut n1, mut n2) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..rows {
            for j in 0..cols {
                let u = e.start + (e.end - e.start) * (i as f64 + 0.5) / rows as f64;
                let v = (j as f64 + 0.5) / cols as f64 - 0.5;
                let p = block.to_image(u, v);
                let x = slow_bilinear(img, p.x, p.y);
                let diff = |m: [f32; 3]| -> f64 {
                    (0..3)
                        .map(|k| f64::from(w.rgb[k]) * (x[k] - f64::from(m[k])).abs())
                        .sum()
                };
                let d = f64::from(w.key) * diff(t.key_colour(i, j))
                    + f64::from(1.0 - w.key) * diff(t.adaptive_colour(i, j));
                let (fi, fj) = (i as f64 + 0.5, j as f64 + 0.5);
                let centre = fi >= rows as f64 / 4.0
                    && fi <= 0.75 * rows as f64
                    && fj >= cols as f64 / 4.0
                    && fj <= 0.75 * cols as f64;
                if centre {
                    b1 += d;
                    n1 += 1.0;
                } else {
                    b2 += d;
                    n2 += 1.0;
                }
            }
        }
        let (w1, w2) = (f64::from(w.centre), f64::from(w.margin));
        (w1 * b1 + w2 * b2) / (w1 * n1 + w2 * n2)
    }

    proptest! {
        #[test]
        fn fast_cost_matches_the_reference(
            x in -10.0f64..110.0, y in -10.0f64..90.0, m in 3.0f64..60.0, n in 2.0f64..25.0,
            theta in -3.2f64..3.2, dx in -6.0f64..6.0, dy in -6.0f64..6.0, dm in 0.7f64..1.3,
            dt in -0.4f64..0.4,
        ) {
            let a = textured(100, 80, 1);
            let b = textured(100, 80, 2);
            let block = MorphBlock { origin: Point2::new(x, y), m, n, theta };
            let extent = Extent { start: -0.1, end: 1.2 };
            let mut t = Template::sample(FloatFrame::new(&a).view(), &block, extent, SimilarityWeights::default());
            t.update(FloatFrame::new(&b).view(), &block, 0.3);
            let cand = MorphBlock {
                origin: Point2::new(x + dx, y + dy), m: m * dm, n: n * dm, theta: theta + dt,
            };
            let fast = f64::from(t.cost(FloatFrame::new(&b).view(), &cand, false, f32::INFINITY));
            let slow = slow_cost(&t, &b, &cand);
            prop_assert!((fast - slow).abs() < 1e-3 * (1.0 + slow), "fast {fast} slow {slow}");
            // Early exit never changes a winner: below the bound the value is exact, above it
            // the answer is infinity.
            let bounded = t.cost(FloatFrame::new(&b).view(), &cand, false, (slow * 0.5) as f32);
            prop_assert!(slow < 1e-6 || bounded.is_infinite());
            let loose = f64::from(t.cost(FloatFrame::new(&b).view(), &cand, false, (slow * 2.0 + 1.0) as f32));
            prop_assert!((loose - slow).abs() < 1e-3 * (1.0 + slow));
        }
    }

    #[test]
    fn a_block_matches_itself_exactly_and_a_shifted_one_worse() {
        let img = FloatFrame::new(&textured(120, 100, 3));
        let f = img.view();
        let block = MorphBlock::along(Point2::new(40.0, 20.0), Point2::new(60.0, 70.0), 14.0);
        let t = Template::sample(f, &block, Extent::BLOCK, SimilarityWeights::default());
        assert!(t.cost(f, &block, false, f32::INFINITY) < 1e-4);
        let moved = MorphBlock {
            origin: block.origin + nalgebra::Vector2::new(3.0, 0.0),
            ..block
        };
        assert!(t.cost(f, &moved, false, f32::INFINITY) > 5.0);
    }

    #[test]
    fn the_foreground_lane_tells_an_arm_from_a_wall_of_its_colour() {
        // A plain scene with a red stripe painted on the wall at x 70–79; the person's red arm
        // stands at x 20–29 on the key frame and at x 40–49 on the next.
        let red = image::Rgb([200, 40, 40]);
        let scene = RgbImage::from_fn(100, 60, |x, _| {
            if (70..80).contains(&x) {
                red
            } else {
                image::Rgb([90, 110, 100])
            }
        });
        let with_arm = |x0: u32| {
            let mut im = scene.clone();
            for y in 10..50 {
                for x in x0..x0 + 10 {
                    im.put_pixel(x, y, red);
                }
            }
            im
        };
        let background =
            Background::estimate(&[&scene, &scene, &scene], 20.0).expect("a static camera");
        let frame = |im: &RgbImage| {
            let mut f = FloatFrame::default();
            f.fill_with(im, Some(&background));
            f
        };
        let (key, next) = (frame(&with_arm(20)), frame(&with_arm(40)));
        let at = |x: f64| MorphBlock::along(Point2::new(x, 15.0), Point2::new(x, 45.0), 6.0);
        let mut t = Template::sample(key.view(), &at(24.5), Extent::BLOCK, Default::default());
        let (arm, wall) = (at(44.5), at(74.5));
        let cost = |t: &Template, b: &MorphBlock| t.cost(next.view(), b, false, f32::INFINITY);
        // By colour alone the wall is as good a match as the arm.
        assert!((cost(&t, &arm) - cost(&t, &wall)).abs() < 1e-3);
        t.set_foreground(0.2);
        assert!(
            cost(&t, &arm) + 10.0 < cost(&t, &wall),
            "the wall stands out no more"
        );
        // The reliability's cost reads the colours alone.
        assert_eq!(
            t.appearance_cost(next.view(), &arm),
            t.appearance_cost(next.view(), &wall)
        );
        // Without a background the lane is 0 everywhere and changes nothing.
        let plain = FloatFrame::new(&with_arm(40));
        let mut u = Template::sample(
            FloatFrame::new(&with_arm(20)).view(),
            &at(24.5),
            Extent::BLOCK,
            Default::default(),
        );
        u.set_foreground(0.2);
        let c = |b: &MorphBlock| u.cost(plain.view(), b, false, f32::INFINITY);
        assert!((c(&arm) - c(&wall)).abs() < 1e-3);
    }

    #[test]
    fn bilinear_matches_the_definition_at_edges_and_inside() {
        let img = textured(20, 10, 4);
        let floats = FloatFrame::new(&img);
        let f = floats.view();
        for &(x, y) in &[
            (0.0, 0.0),
            (19.0, 9.0),
            (3.25, 4.75),
            (-2.0, 5.5),
            (25.0, 12.0),
        ] {
            let fast = f.bilinear(x as f32, y as f32);
            let slow = slow_bilinear(&img, x, y);
            for k in 0..3 {
                assert!((f64::from(fast[k]) - slow[k]).abs() < 1e-3);
            }
        }
    }

    /// The unclamped path reads each sample's right and lower neighbours without clamping:
    /// blocks reaching into the last rows and columns must take the clamped path and still
    /// agree with the reference.
    #[test]
    fn blocks_at_the_bottom_right_corner_agree_with_the_reference() {
        let (a, b) = (textured(60, 40, 5), textured(60, 40, 6));
        for reach in [-3.0, -1.5, -1.0, -0.5, 0.0, 0.5, 2.0] {
            let block = MorphBlock::along(
                Point2::new(40.0, 20.0),
                Point2::new(59.0 + reach, 39.0 + reach),
                6.0,
            );
            let t = Template::sample(
                FloatFrame::new(&a).view(),
                &block,
                Extent::BLOCK,
                SimilarityWeights::default(),
            );
            let fast = f64::from(t.cost(FloatFrame::new(&b).view(), &block, false, f32::INFINITY));
            let slow = slow_cost(&t, &b, &block);
            assert!(
                (fast - slow).abs() < 1e-3 * (1.0 + slow),
                "reach {reach}: fast {fast} slow {slow}"
            );
        }
    }
}
