//! Volumes as users get them (issue 91, item 3): what carving from real silhouettes adds to a
//! clip's clouds, taken off before the pipeline sees them, from the clip alone (no ground
//! truth, no camera). Runs between reading the clouds and the per-frame pipeline.
//!
//! 1. **The floor sheet** (a shadow or a reflection joined to the feet, carved into a slab):
//!    the clip's floor is the median of the frames' lowest points; the lowest layers whose
//!    typical point count (the median over the clip) is more than [`CleanParams::sheet_ratio`]
//!    times that of the shins' layers form the sheet's band. In the band (and one layer above
//!    it, where the slab's top tapers; counted from the frame's lowest point when that is above
//!    the clip's floor), a point stays only when the body stands over it: within
//!    [`CleanParams::support_radius_m`], horizontally, of a point in the two layers above that.
//!    Feet and a hand on the floor have a limb over them; the sheet does not.
//! 2. **Points no neighbouring frame has** (ghost voxels where silhouette cones cross, a
//!    passer-by's blob joined for one frame): a point stays when one of the two frames before or
//!    after has a point within [`CleanParams::neighbour_radius_m`] (after step 1).
//!
//! Each frame's pipeline then keeps its largest connected component, as before.

use crate::point_spacing;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Point3;
use rayon::prelude::*;

/// How [`clean_clip`] decides what to take off.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CleanParams {
    /// A low layer belongs to the floor sheet when its median point count over the clip is more
    /// than this many times the shins' layers'. Two: a pair of feet never doubles the shins'
    /// cross-section (the clean carvings and voxelised takes of dev show at most 1.3×), a
    /// shadow's slab at 40 mm holds 5–10 times it (dev, `carved 4 faulty views`).
    pub sheet_ratio: f64,
    /// The sheet is sought below this height above the floor, metres (ankle height and a slab's
    /// thickness from cameras 2–3 m up: the shadow's slab on dev reaches 0.2 m).
    pub sheet_max_height_m: f64,
    /// The shins' layers, from and to this height above the floor, metres (below the knees of
    /// a 1.5 m person, above a foot).
    pub shins_m: [f64; 2],
    /// A point in the sheet's band stays within this horizontal distance of the body above
    /// it, metres: a foot's reach forward of the shin (0.16: no point within 10 cm of the true
    /// skeleton is removed on the dev carving the rule was drawn on).
    pub support_radius_m: f64,
    /// A point stays when one of the two frames before or after has a point this near, metres (a limb's
    /// travel in one frame at 15 fps: 0.25 removes 12 of 51,000 body voxels of jumping jacks
    /// at 40 mm, 0.2 removes 142).
    pub neighbour_radius_m: f64,
}

impl Default for CleanParams {
    fn default() -> Self {
        CleanParams {
            sheet_ratio: 2.0,
            sheet_max_height_m: 0.28,
            shins_m: [0.2, 0.4],
            support_radius_m: 0.16,
            neighbour_radius_m: 0.25,
        }
    }
}

/// What [`clean_clip`] took off.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Cleaned {
    /// The floor sheet's band, metres (the floor and the band's top), when the clip has one.
    pub sheet_m: Option<[f64; 2]>,
    /// Per frame, the points taken off as the floor sheet.
    pub sheet_points: Vec<usize>,
    /// Per frame, the points no neighbouring frame had.
    pub lonely_points: Vec<usize>,
}

impl Cleaned {
    /// One sentence per kind of point taken off, for the clip's warnings.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        let say = |what: &str, per: &[usize]| {
            let total: usize = per.iter().sum();
            let frames = per.iter().filter(|&&n| n > 0).count();
            (total > 0)
                .then(|| format!("cleaning: took off {total} points {what} on {frames} frames"))
        };
        if let Some([floor, top]) = self.sheet_m {
            out.extend(say(
                &format!(
                    "of a floor sheet (from {:.0} to {:.0} mm up, under no limb)",
                    floor * 1000.0,
                    top * 1000.0
                ),
                &self.sheet_points,
            ));
        }
        out.extend(say(
            "that no neighbouring frame had (ghosts)",
            &self.lonely_points,
        ));
        out
    }
}

/// Takes the floor sheet and the points no neighbouring frame has off the clip's `clouds`
/// (in order, one per frame; Y up); says what it took off.
pub fn clean_clip(clouds: &mut [Vec<Point3<f64>>], params: &CleanParams) -> Cleaned {
    let mut cleaned = Cleaned {
        sheet_points: vec![0; clouds.len()],
        lonely_points: vec![0; clouds.len()],
        ..Cleaned::default()
    };
    if let Some(sheet) = find_sheet(clouds, params) {
        cleaned.sheet_m = Some([sheet.floor_m, sheet.floor_m + sheet.band_m]);
        clouds
            .par_iter_mut()
            .zip(cleaned.sheet_points.par_iter_mut())
            .for_each(|(c, n)| *n = remove_sheet(c, &sheet, params));
    }
    let keep = lonely_mask(clouds, params.neighbour_radius_m);
    for ((c, k), n) in clouds.iter_mut().zip(keep).zip(&mut cleaned.lonely_points) {
        let before = c.len();
        let mut it = k.iter();
        c.retain(|_| it.next().copied().unwrap_or(true));
        *n = before - c.len();
    }
    cleaned
}

/// The floor sheet of a clip: the floor's height, the layers' thickness and the band's height.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sheet {
    floor_m: f64,
    layer_m: f64,
    /// Height of the band above the floor (whole layers).
    band_m: f64,
}

impl Sheet {
    /// The layer of height `y` (0: the floor's).
    fn layer(&self, y: f64) -> i64 {
        ((y - self.floor_m) / self.layer_m).round() as i64
    }
}

/// The clip's floor sheet, when its lowest layers hold more than `sheet_ratio` times the shins'.
fn find_sheet(clouds: &[Vec<Point3<f64>>], params: &CleanParams) -> Option<Sheet> {
    let lows: Vec<f64> = clouds
        .iter()
        .filter(|c| !c.is_empty())
        .map(|c| c.iter().map(|p| p.y).fold(f64::INFINITY, f64::min))
        .collect();
    let floor_m = median(lows)?;
    let mut spacings: Vec<f64> = clouds
        .par_iter()
        .filter(|c| c.len() >= 2)
        .map(|c| point_spacing(c))
        .collect();
    spacings.retain(|s| *s > 0.0);
    let layer_m = median(spacings)?;
    let sheet = Sheet {
        floor_m,
        layer_m,
        band_m: 0.0,
    };
    let layers = (params.shins_m[1] / layer_m).ceil() as usize + 1;
    // Per layer, the median over the frames of its point count.
    let typical: Vec<f64> = (0..layers)
        .map(|l| {
            let counts = clouds
                .iter()
                .filter(|c| !c.is_empty())
                .map(|c| c.iter().filter(|p| sheet.layer(p.y) == l as i64).count() as f64)
                .collect();
            median(counts).unwrap_or(0.0)
        })
        .collect();
    let height = |l: usize| l as f64 * layer_m;
    let shins = median(
        (0..layers)
            .filter(|&l| height(l) >= params.shins_m[0] && height(l) < params.shins_m[1])
            .map(|l| typical[l])
            .collect(),
    )?;
    if shins <= 0.0 {
        return None;
    }
    let band = (0..layers)
        .filter(|&l| height(l) < params.sheet_max_height_m)
        .filter(|&l| typical[l] > params.sheet_ratio * shins)
        .max()?
        + 1;
    Some(Sheet {
        band_m: band as f64 * layer_m,
        ..sheet
    })
}

/// Takes off the points of `cloud` in the sheet's band (and the layer above) with no point of
/// the two layers above within the support radius, horizontally; returns how many.
fn remove_sheet(cloud: &mut Vec<Point3<f64>>, sheet: &Sheet, params: &CleanParams) -> usize {
    let band = (sheet.band_m / sheet.layer_m).round() as i64 + 1;
    // A frame wholly above the floor (a jump, a shadow carved higher) counts from its own
    // lowest point.
    let low = cloud.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    let sheet = &Sheet {
        floor_m: sheet.floor_m.max(low),
        ..*sheet
    };
    let above: Vec<[f64; 2]> = cloud
        .iter()
        .filter(|p| (band..band + 2).contains(&sheet.layer(p.y)))
        .map(|p| [p.x, p.z])
        .collect();
    let r2 = params.support_radius_m * params.support_radius_m;
    let before = cloud.len();
    cloud.retain(|p| {
        sheet.layer(p.y) >= band
            || above
                .iter()
                .any(|a| (a[0] - p.x).powi(2) + (a[1] - p.z).powi(2) <= r2)
    });
    before - cloud.len()
}

/// Per frame, per point: whether one of the two frames before or after has a point within
/// `radius_m` (two each way: a neighbour missing part of the body, half of it outside the
/// carving volume, takes nothing off the next; every point of a frame whose neighbours are all
/// empty or absent stays).
fn lonely_mask(clouds: &[Vec<Point3<f64>>], radius_m: f64) -> Vec<Vec<bool>> {
    let trees: Vec<Option<ImmutableKdTree<f64, 3>>> = clouds
        .par_iter()
        .map(|c| {
            let coords: Vec<[f64; 3]> = c.iter().map(|p| [p.x, p.y, p.z]).collect();
            (!coords.is_empty()).then(|| ImmutableKdTree::new_from_slice(&coords))
        })
        .collect();
    let r2 = radius_m * radius_m;
    (0..clouds.len())
        .into_par_iter()
        .map(|t| {
            let near: Vec<&ImmutableKdTree<f64, 3>> =
                [t.checked_sub(2), t.checked_sub(1), Some(t + 1), Some(t + 2)]
                    .into_iter()
                    .flatten()
                    .filter_map(|s| trees.get(s).and_then(Option::as_ref))
                    .collect();
            clouds[t]
                .iter()
                .map(|p| {
                    near.is_empty()
                        || near.iter().any(|tree| {
                            tree.nearest_one::<SquaredEuclidean>(&[p.x, p.y, p.z])
                                .distance
                                <= r2
                        })
                })
                .collect()
        })
        .collect()
}

/// The median of `v` (the upper one of an even count), `None` when empty.
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    const VOXEL: f64 = 0.04;

    /// A standing body of 40 mm voxels at `x`: two legs (0–0.8 m), a trunk (0.8–1.4 m), a head.
    fn body(x: f64) -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        let mut put = |x0: f64, x1: f64, y0: f64, y1: f64, z0: f64, z1: f64| {
            let n = |a: f64, b: f64| ((b - a) / VOXEL).round() as i64;
            for i in 0..n(x0, x1) {
                for j in 0..n(y0, y1) {
                    for k in 0..n(z0, z1) {
                        out.push(Point3::new(
                            x0 + i as f64 * VOXEL,
                            y0 + j as f64 * VOXEL,
                            z0 + k as f64 * VOXEL,
                        ));
                    }
                }
            }
        };
        put(x - 0.16, x - 0.04, 0.0, 0.8, -0.04, 0.08); // left leg
        put(x + 0.04, x + 0.16, 0.0, 0.8, -0.04, 0.08); // right leg
        put(x - 0.16, x + 0.16, 0.8, 1.4, -0.08, 0.12); // trunk
        put(x - 0.08, x + 0.08, 1.4, 1.64, -0.04, 0.08); // head
        out
    }

    /// A slab on the floor, 3 layers thick, from the feet 0.8 m along +X.
    fn sheet(x: f64) -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        for i in 0..20 {
            for j in 0..3 {
                for k in -4..6 {
                    out.push(Point3::new(
                        x + 0.2 + i as f64 * VOXEL,
                        j as f64 * VOXEL,
                        k as f64 * VOXEL,
                    ));
                }
            }
        }
        out
    }

    #[test]
    fn a_floor_sheet_and_a_one_frame_ghost_are_taken_off_and_the_body_kept() {
        let frames = 12;
        let bodies: Vec<Vec<Point3<f64>>> = (0..frames).map(|t| body(t as f64 * 0.04)).collect();
        let mut clouds: Vec<Vec<Point3<f64>>> = bodies
            .iter()
            .enumerate()
            .map(|(t, b)| [b.clone(), sheet(t as f64 * 0.04)].concat())
            .collect();
        // A ghost blob 0.6 m beside the chest on frame 5 only.
        let ghost: Vec<Point3<f64>> = (0..8)
            .map(|i| {
                Point3::new(
                    0.8 + f64::from(i % 2) * VOXEL,
                    1.1 + f64::from(i / 2) * VOXEL,
                    0.0,
                )
            })
            .collect();
        clouds[5].extend(ghost.iter().copied());
        let cleaned = clean_clip(&mut clouds, &CleanParams::default());
        let [floor, top] = cleaned.sheet_m.expect("the sheet is found");
        assert!(
            floor.abs() < 1e-9 && top > 0.07 && top < 0.2,
            "{floor} {top}"
        );
        for (t, (c, b)) in clouds.iter().zip(&bodies).enumerate() {
            for p in b {
                assert!(c.contains(p), "frame {t}: body point {p} taken off");
            }
            // Nothing of the sheet farther than the support radius from a leg survives.
            let far = c
                .iter()
                .filter(|p| p.y < 0.1 && p.x > t as f64 * 0.04 + 0.4)
                .count();
            assert_eq!(far, 0, "frame {t}: sheet left");
            assert!(
                ghost.iter().all(|g| !c.contains(g)),
                "frame {t}: ghost left"
            );
        }
        assert_eq!(cleaned.lonely_points[5], ghost.len());
        assert!(cleaned.sheet_points.iter().all(|&n| n > 400));
        assert_eq!(cleaned.warnings().len(), 2);
    }

    #[test]
    fn a_clip_without_a_sheet_or_ghosts_is_left_as_it_is() {
        let mut clouds: Vec<Vec<Point3<f64>>> = (0..8).map(|t| body(t as f64 * 0.04)).collect();
        let before = clouds.clone();
        let cleaned = clean_clip(&mut clouds, &CleanParams::default());
        assert_eq!(cleaned.sheet_m, None);
        assert_eq!(clouds, before);
        assert!(cleaned.warnings().is_empty());
    }

    #[test]
    fn empty_frames_and_a_single_frame_are_no_problem() {
        let mut clouds = vec![Vec::new(), body(0.0), Vec::new()];
        let before = clouds.clone();
        let cleaned = clean_clip(&mut clouds, &CleanParams::default());
        assert_eq!(clouds, before);
        assert_eq!(cleaned.lonely_points, vec![0, 0, 0]);
        let mut none: Vec<Vec<Point3<f64>>> = Vec::new();
        assert_eq!(clean_clip(&mut none, &CleanParams::default()).sheet_m, None);
    }
}
