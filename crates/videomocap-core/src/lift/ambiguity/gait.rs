//! The gait's left–right symmetry, for [`super::AmbiguityWeights::gait_symmetry`]: in walking
//! and running each arm repeats the other's swing half a stride later, mirrored left to right.
//! The lag is read from the thighs (solved before the arms), whose forward swing alternates.

use super::super::prior::TrunkFrame;
use super::{Group, LeftElbow, LeftShoulder, LeftWrist, RightElbow, RightShoulder, RightWrist};
use super::{Joint, LeftHip, LeftKnee, RightHip, RightKnee};
use crate::skeleton::PerJoint;
use nalgebra::{Point3, Vector3};

/// The shortest lag (frames) taken for half a stride (a sprint at 30 frames/s takes about 8).
pub(super) const MIN_LAG: usize = 5;

/// How closely (Pearson correlation) the right thigh's forward swing must repeat the left's
/// at the lag for the motion to count as a gait. The suite's walks and runs reach 0.97 to 1.00
/// at their calibrated pose; its dances 0.39 to 0.84 (below, or gated by the arms themselves:
/// [`SYMMETRY_MAX_DISCREPANCY`]).
pub(super) const MIN_CORRELATION: f64 = 0.8;

/// The least standard deviation of a thigh's forward component (the sine of its swing) for the
/// legs to be moving at all.
pub(super) const MIN_SWING: f64 = 0.05;

/// The largest median (over the frames) of an arm's first-pass squared distance from its
/// partner's mirrored pose (unit directions, upper arm plus forearm) for the arm to be steered:
/// the suite's walking and running arms measure 0.05 to 0.13 at their calibrated pose,
/// dribble_oblique's 1.3 to 1.5 (one hand bounces the ball), dance_turns_frontal's 1.2 to 1.4.
/// At 0.15 / 0.3 / 0.6 the suite's wrong roots from exact 2D are the same (722).
pub(super) const SYMMETRY_MAX_DISCREPANCY: f64 = 0.3;

/// How many passes over the arms follow the first (each reads the other arm's previous one).
/// The suite from exact 2D with true lengths: 1 / 2 passes, 732 / 722 wrong roots.
pub(super) const SYMMETRY_ROUNDS: usize = 2;

/// The lag (frames, half a stride) at which the right thigh's forward swing best repeats the
/// left's, when it does so closely enough ([`MIN_CORRELATION`]) and both thighs swing
/// ([`MIN_SWING`]); `None` otherwise. Lags up to half the clip are tried, so a clip must hold a
/// whole stride.
pub(super) fn gait_lag(points: &[PerJoint<Point3<f64>>], trunks: &[TrunkFrame]) -> Option<usize> {
    let swing = |hip: Joint, knee: Joint| -> Vec<f64> {
        points
            .iter()
            .zip(trunks)
            .map(|(p, trunk)| trunk.forward_sine(&p[hip], &p[knee]))
            .collect()
    };
    let (left, right) = (swing(LeftHip, LeftKnee), swing(RightHip, RightKnee));
    let n = left.len();
    let correlation = |lag: usize| {
        let (a, b) = (&left[..n - lag], &right[lag..]);
        let m = a.len() as f64;
        let (mean_a, mean_b) = (a.iter().sum::<f64>() / m, b.iter().sum::<f64>() / m);
        let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
        for (x, y) in a.iter().zip(b) {
            ab += (x - mean_a) * (y - mean_b);
            aa += (x - mean_a).powi(2);
            bb += (y - mean_b).powi(2);
        }
        let moving = (aa / m).sqrt() >= MIN_SWING && (bb / m).sqrt() >= MIN_SWING;
        if moving { ab / (aa * bb).sqrt() } else { -1.0 }
    };
    let (lag, best) = (MIN_LAG..n / 2)
        .map(|lag| (lag, correlation(lag)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    // The thighs must alternate (one forward while the other is back): moving together
    // (sitting down, bending) they also repeat each other a few frames later.
    (best >= MIN_CORRELATION && correlation(0) < 0.0).then_some(lag)
}

/// The other arm's poses of a previous pass and the lag they are compared at.
pub(super) struct Symmetry<'a> {
    /// Half a stride, frames ([`gait_lag`]).
    pub lag: usize,
    /// Every joint of every frame as the previous pass left them.
    pub previous: &'a [PerJoint<Point3<f64>>],
    /// The key triangle's frame of every frame.
    pub trunks: &'a [TrunkFrame],
}

/// An arm's shoulder, elbow and wrist.
fn arm(left: bool) -> [Joint; 3] {
    if left {
        [LeftShoulder, LeftElbow, LeftWrist]
    } else {
        [RightShoulder, RightElbow, RightWrist]
    }
}

impl Symmetry<'_> {
    /// For an arm posed as in `p` on frame `t`: the squared distance of its upper arm's and
    /// forearm's unit directions from the other arm's, mirrored left to right, in the previous
    /// pass half a stride before and after (their mean; `None` when neither frame exists).
    fn discrepancy(&self, group: &Group, p: &PerJoint<Point3<f64>>, t: usize) -> Option<[f64; 2]> {
        let left = group.bones[0].parent == LeftShoulder;
        let (own, other) = (arm(left), arm(!left));
        let local = |v: Vector3<f64>, trunk: &TrunkFrame| {
            v.try_normalize(f64::EPSILON).map_or(Vector3::zeros(), |d| {
                Vector3::new(d.dot(&trunk.left), d.dot(&trunk.up), d.dot(&trunk.forward))
            })
        };
        let partners = [t.checked_sub(self.lag), Some(t + self.lag)]
            .into_iter()
            .flatten()
            .filter(|&u| u < self.previous.len());
        let mut sum = [0.0; 2];
        let mut count = 0;
        for u in partners {
            count += 1;
            let q = &self.previous[u];
            for (k, s) in sum.iter_mut().enumerate() {
                let mine = local(p[own[k + 1]] - p[own[k]], &self.trunks[t]);
                let theirs = local(q[other[k + 1]] - q[other[k]], &self.trunks[u]);
                *s += (mine - Vector3::new(-theirs.x, theirs.y, theirs.z)).norm_squared();
            }
        }
        (count > 0).then(|| sum.map(|s| s / f64::from(count)))
    }

    /// [`super::AmbiguityWeights::gait_symmetry`]'s cost (unweighted, squared metres) of an arm
    /// posed as in `p` on frame `t`: each bone's [`Symmetry::discrepancy`] times its length
    /// squared.
    pub(super) fn cost(&self, group: &Group, p: &PerJoint<Point3<f64>>, t: usize) -> f64 {
        self.discrepancy(group, p, t).map_or(0.0, |d| {
            group
                .bones
                .iter()
                .zip(d)
                .map(|(bone, d)| d * (p[bone.child] - p[bone.parent]).norm_squared())
                .sum()
        })
    }

    /// Whether an arm follows the other closely enough in the previous pass to be steered
    /// by it: the median of its [`Symmetry::discrepancy`] (both bones) at most
    /// [`SYMMETRY_MAX_DISCREPANCY`].
    pub(super) fn holds(&self, group: &Group) -> bool {
        let mut d: Vec<f64> = (0..self.previous.len())
            .filter_map(|t| self.discrepancy(group, &self.previous[t], t))
            .map(|d| d[0] + d[1])
            .collect();
        if d.is_empty() {
            return false;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2] <= SYMMETRY_MAX_DISCREPANCY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The key triangle's frame of a body facing −Z (the camera), upright (camera Y down).
    fn facing() -> TrunkFrame {
        TrunkFrame {
            left: Vector3::new(1.0, 0.0, 0.0),
            up: Vector3::new(0.0, -1.0, 0.0),
            forward: Vector3::new(0.0, 0.0, -1.0),
        }
    }

    /// A body whose thighs swing forward by `left(t)` and `right(t)` (sines), and whose arms
    /// hang with forward tilts `arms(t) = (left, right)`, all in [`facing`]'s frame.
    fn body(
        n: usize,
        thighs: impl Fn(usize) -> (f64, f64),
        arms: impl Fn(usize) -> (f64, f64),
    ) -> Vec<PerJoint<Point3<f64>>> {
        let down = |sine: f64, side: f64| {
            Vector3::new(0.1 * side, (1.0 - sine * sine - 0.01).sqrt(), -sine)
        };
        (0..n)
            .map(|t| {
                let mut p = PerJoint::from_fn(|_| Point3::new(0.0, 0.0, 3.0));
                let (l, r) = thighs(t);
                let (al, ar) = arms(t);
                p.0[LeftHip.index()] = Point3::new(0.1, 0.0, 3.0);
                p.0[RightHip.index()] = Point3::new(-0.1, 0.0, 3.0);
                p.0[LeftKnee.index()] = p[LeftHip] + down(l, 0.0) * 0.45;
                p.0[RightKnee.index()] = p[RightHip] + down(r, 0.0) * 0.45;
                p.0[LeftShoulder.index()] = Point3::new(0.2, -0.5, 3.0);
                p.0[RightShoulder.index()] = Point3::new(-0.2, -0.5, 3.0);
                p.0[LeftElbow.index()] = p[LeftShoulder] + down(al, 1.0) * 0.3;
                p.0[RightElbow.index()] = p[RightShoulder] + down(ar, -1.0) * 0.3;
                p.0[LeftWrist.index()] = p[LeftElbow] + down(al, 1.0) * 0.25;
                p.0[RightWrist.index()] = p[RightElbow] + down(ar, -1.0) * 0.25;
                p
            })
            .collect()
    }

    /// A stride of `period` frames: the thighs swing 0.4 either way, half a stride apart, and
    /// each arm against its own thigh.
    fn walk(n: usize, period: f64) -> Vec<PerJoint<Point3<f64>>> {
        let phase = move |t: usize| (t as f64 * std::f64::consts::TAU / period).sin();
        let against = move |t: usize| phase(t + (period / 2.0) as usize);
        body(
            n,
            move |t| (0.4 * phase(t), 0.4 * against(t)),
            move |t| (0.3 * against(t), 0.3 * phase(t)),
        )
    }

    #[test]
    fn the_lag_is_half_a_stride_of_alternating_thighs() {
        let points = walk(120, 40.0);
        let trunks = vec![facing(); points.len()];
        assert_eq!(gait_lag(&points, &trunks), Some(20));
    }

    #[test]
    fn thighs_moving_together_or_standing_still_make_no_gait() {
        let together = body(
            120,
            |t| {
                let s = 0.5 * (t as f64 * 0.05).sin();
                (s, s)
            },
            |_| (0.0, 0.0),
        );
        let still = body(120, |_| (0.1, 0.1), |_| (0.0, 0.0));
        let trunks = vec![facing(); 120];
        assert_eq!(gait_lag(&together, &trunks), None);
        assert_eq!(gait_lag(&still, &trunks), None);
        // Half a stride (20 frames) is more than half of a 12-frame clip.
        assert_eq!(gait_lag(&walk(12, 40.0), &trunks[..12]), None);
    }

    #[test]
    fn an_arm_pays_for_leaving_its_partners_swing_and_only_a_following_arm_is_steered() {
        let points = walk(120, 40.0);
        let trunks = vec![facing(); points.len()];
        let symmetry = Symmetry {
            lag: 20,
            previous: &points,
            trunks: &trunks,
        };
        let left_arm = &super::super::GROUPS[super::super::ARM_GROUPS[0]];
        let right_arm = &super::super::GROUPS[super::super::ARM_GROUPS[1]];
        // The true arm repeats its partner; the same arm tilted the other way does not.
        let t = 50;
        assert!(symmetry.cost(left_arm, &points[t], t) < 1e-9);
        let mut mirror = points[t];
        let tilt = |v: Vector3<f64>| Vector3::new(v.x, v.y, -v.z);
        let upper = tilt(points[t][LeftElbow] - points[t][LeftShoulder]);
        let fore = tilt(points[t][LeftWrist] - points[t][LeftElbow]);
        mirror.0[LeftElbow.index()] = points[t][LeftShoulder] + upper;
        mirror.0[LeftWrist.index()] = mirror[LeftElbow] + fore;
        assert!(symmetry.cost(left_arm, &mirror, t) > 0.01);
        assert!(symmetry.holds(left_arm) && symmetry.holds(right_arm));
        // A right arm held out sideways throughout does not follow the left.
        let mut dribbling = points.clone();
        for p in &mut dribbling {
            p.0[RightElbow.index()] = p[RightShoulder] + Vector3::new(-0.3, 0.0, 0.0);
            p.0[RightWrist.index()] = p[RightElbow] + Vector3::new(0.0, 0.0, -0.25);
        }
        let symmetry = Symmetry {
            previous: &dribbling,
            ..symmetry
        };
        assert!(!symmetry.holds(right_arm) && !symmetry.holds(left_arm));
    }
}
