//! Which way the fitted body faces, stretch by stretch: the clip is tracked from its first
//! frame's best fit and from that fit turned round (`track`, a track never turning the body
//! round between two frames), and each stretch of frames takes the track whose fits explain its
//! points better; a stretch where the two fit about as well is named in a warning.

use super::Tracked;
use super::model::Pose;
use nalgebra::{Point3, Rotation3, Vector3};
use videomocap_core::skeleton::PerJoint;

/// What a switch between the two tracks costs (in the log of the fits' cost ratio summed
/// over the frames): a stretch of frames takes the other track only when its fits explain the
/// points better by this much together; one frame's doubtful fit does not turn the body round.
const SWITCH_PRICE: f64 = 2.0;
/// What a frame facing against the curve's pose costs (same unit): where the two tracks fit
/// about as well (a capsule body standing straight), the curve's facing decides.
const AGAINST_CURVE: f64 = 0.02;

/// For each frame whether track `b` (the clip turned round) is taken rather than `a`: the path
/// over the frames (a dynamic programme over the two tracks) whose summed log costs, prices
/// for facing against the curve's pose and [`SWITCH_PRICE`] for each change are lowest.
/// Frames where the two tracks face the same way hold no evidence about the facing; there the
/// cheaper fit still wins.
pub(super) fn facing_chosen(
    a: &Tracked,
    b: &Tracked,
    curve: &[Option<PerJoint<Point3<f64>>>],
) -> Vec<bool> {
    let n = a.done.len();
    let front = |r: &Rotation3<f64>| r * Vector3::z();
    let price = |t: &Tracked, i: usize| -> f64 {
        let Some(d) = t.done[i] else {
            return f64::INFINITY;
        };
        let against = curve[i].is_some_and(|c| {
            front(&d.pose.pelvis).dot(&front(&Pose::from_joints(&c).pelvis)) < 0.0
        });
        d.quality.cost.max(1e-12).ln() + if against { AGAINST_CURVE } else { 0.0 }
    };
    // total[s]: the cheapest path's price ending in state s; back[i][s]: its state at i − 1.
    let mut total = [0.0_f64; 2];
    let mut back = vec![[0_usize; 2]; n];
    for (i, step) in back.iter_mut().enumerate() {
        let mut p = [price(a, i), price(b, i)];
        if p.iter().all(|x| !x.is_finite()) {
            p = [0.0; 2];
        }
        let mut next = [0.0; 2];
        for s in 0..2 {
            let stay = total[s];
            let switch = total[1 - s] + SWITCH_PRICE;
            step[s] = if stay <= switch { s } else { 1 - s };
            next[s] = stay.min(switch) + p[s];
        }
        total = next;
    }
    let mut s = if total[0] <= total[1] { 0 } else { 1 };
    let mut out = vec![false; n];
    for i in (0..n).rev() {
        out[i] = s == 1;
        s = back[i][s];
    }
    out
}

/// The frames of `t` facing the opposite way from the other track's, with the log of their fit's
/// cost (`None`: no fit, or the two tracks face the same way there).
fn opposed(t: &Tracked, other: &Tracked, i: usize) -> Option<(f64, f64)> {
    let (x, y) = (t.done[i]?, other.done[i]?);
    let front = |r: &Rotation3<f64>| r * Vector3::z();
    (front(&x.pose.pelvis).dot(&front(&y.pose.pelvis)) < 0.0).then(|| {
        (
            x.quality.cost.max(1e-12).ln(),
            y.quality.cost.max(1e-12).ln(),
        )
    })
}

/// A warning for each stretch of frames whose facing was taken from one track while the body
/// turned round (the other track, facing the other way there) fits it within [`SWITCH_PRICE`]
/// of as well: which way the body faces there is a guess (a capsule body standing straight,
/// a volume whose limbs are merged).
pub(super) fn unsure(a: &Tracked, b: &Tracked, pick: &[bool], names: &[String]) -> Vec<String> {
    let name = |i: usize| names.get(i).map_or("?", String::as_str);
    let mut out = Vec::new();
    let mut i = 0;
    while i < pick.len() {
        let (t, o) = if pick[i] { (b, a) } else { (a, b) };
        let mut j = i;
        let mut margin = 0.0;
        while j < pick.len() && pick[j] == pick[i] {
            let Some((x, y)) = opposed(t, o, j) else {
                break;
            };
            margin += y - x;
            j += 1;
        }
        if j > i && margin < SWITCH_PRICE {
            out.push(format!(
                "frames {i}–{} ({} to {}): which way the body faces is unsure (turned round it explains the points about as well: summed log cost ratio {margin:.2})",
                j - 1,
                name(i),
                name(j - 1)
            ));
        }
        i = j.max(i + 1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::articulated::solve::Quality;
    use crate::articulated::{Done, body, turned_round};

    /// A track facing +z (`back`: −z), frame i's fit costing `costs[i]`.
    fn tracked(costs: &[f64], back: bool) -> Tracked {
        let mut pose = Pose::default_standing();
        if back {
            pose = turned_round(&pose);
        }
        let done = costs
            .iter()
            .map(|&cost| {
                let quality = Quality {
                    cost,
                    unexplained: 0.0,
                    worst_gap: (0, 0.0),
                };
                Some(Done {
                    pose,
                    quality,
                    from_curve: false,
                })
            })
            .collect();
        Tracked { done }
    }

    #[test]
    fn each_stretch_takes_the_facing_that_fits_clearly_better_and_the_curve_breaks_a_tie() {
        let body = body::typical(1.75).expect("a typical body");
        let front = Pose::default_standing().posed(&body).joints;
        let back = turned_round(&Pose::default_standing()).posed(&body).joints;
        let (curve_front, curve_back) = (vec![Some(front); 12], vec![Some(back); 12]);
        // The turned-round track fits the first 6 frames twice as well, the other the rest.
        let a_costs: Vec<f64> = (0..12).map(|i| if i < 6 { 2.0 } else { 1.0 }).collect();
        let b_costs: Vec<f64> = (0..12).map(|i| if i < 6 { 1.0 } else { 2.0 }).collect();
        let (a, b) = (tracked(&a_costs, false), tracked(&b_costs, true));
        let want: Vec<bool> = (0..12).map(|i| i < 6).collect();
        assert_eq!(facing_chosen(&a, &b, &curve_front), want);
        assert_eq!(facing_chosen(&a, &b, &curve_back), want);
        // One frame clearly cheaper turned round does not turn the body round there.
        let mut b_costs = vec![1.1; 12];
        b_costs[5] = 0.6;
        let b = tracked(&b_costs, true);
        let a = tracked(&[1.0; 12], false);
        assert_eq!(facing_chosen(&a, &b, &curve_front), vec![false; 12]);
        // About as cheap everywhere: the curve's facing.
        let b = tracked(&[0.99; 12], true);
        assert_eq!(facing_chosen(&a, &b, &curve_front), vec![false; 12]);
        assert_eq!(facing_chosen(&a, &b, &curve_back), vec![true; 12]);
    }
}
