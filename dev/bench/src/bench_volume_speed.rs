//! `videomocap bench volume`'s speed table: the volume pipeline's time per frame on one core
//! at about 3,000, 11,000 and 30,000 points.

use crate::args::GlobalArgs;
use crate::say;
use std::time::Instant;
use videomocap_testkit::synth::{Motion, VoxelParams, stature_of, voxelise};
use videomocap_volume::{VolumeParams, assemble_and_fit, process_frame, process_frame_for_fit};

/// Speed on one core: voxel sizes chosen so that a marching frame has about N points; the
/// paper's pipeline as it was (the curve on every point) against the product's (the curve on at
/// most `curve_points`, then the articulated fit over the clip), same frames, same run.
pub(crate) fn speed_table(
    march: &Motion,
    params: &VolumeParams,
    global: &GlobalArgs,
    lines: &mut Vec<String>,
) {
    let stature = stature_of(march);
    let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(3);
    let at_40 = voxelise(&march.frames[0], stature, &VoxelParams::default(), &mut rng).len();
    let before = VolumeParams {
        curve_points: usize::MAX,
        ..*params
    };
    lines.push("Speed on one core (marching, 10 consecutive frames): the curve on every point (before) and the product (curve on fewer points + the fitted body)".to_owned());
    lines.push(format!(
        "{:>8} {:>8} {:>8} {:>12} {:>12} {:>9} {:>7}",
        "N target", "voxel", "points", "before ms", "after ms", "fit ms", "ratio"
    ));
    for target in [3_000.0, 11_000.0, 30_000.0] {
        let voxel_m = 0.04 * (at_40 as f64 / target).cbrt();
        let voxel = VoxelParams {
            voxel_m,
            ..VoxelParams::default()
        };
        let clouds: Vec<_> = march
            .frames
            .iter()
            .take(10)
            .map(|j| voxelise(j, stature, &voxel, &mut rng))
            .collect();
        say(global, &format!("speed at N ≈ {target:.0} …"));
        let t0 = Instant::now();
        for c in &clouds {
            let _ = process_frame(c, &before);
        }
        let old = t0.elapsed().as_secs_f64();
        let t0 = Instant::now();
        let (results, points): (Vec<_>, Vec<_>) = clouds
            .iter()
            .map(|c| process_frame_for_fit(c, params))
            .unzip();
        let t1 = Instant::now();
        let names: Vec<String> = (0..clouds.len()).map(|i| i.to_string()).collect();
        let _ = assemble_and_fit(&results, &points, &names, march.fps, params);
        let fit = t1.elapsed().as_secs_f64();
        let new = t0.elapsed().as_secs_f64();
        let n = clouds.len().max(1) as f64;
        lines.push(format!(
            "{:>8.0} {:>6.1}mm {:>8.0} {:>12.1} {:>12.1} {:>9.1} {:>7.2}",
            target,
            voxel_m * 1000.0,
            clouds.iter().map(Vec::len).sum::<usize>() as f64 / n,
            1000.0 * old / n,
            1000.0 * new / n,
            1000.0 * fit / n,
            new / old.max(1e-12)
        ));
    }
    lines.push(String::new());
}
