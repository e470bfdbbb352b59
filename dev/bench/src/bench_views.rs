//! Accuracy per view (frontal, oblique, side, behind, real) for the tracking benches: PCK@0.1
//! beside PCK@0.2 of the 13 limb joints and of all scored joints per method, and each joint's
//! mean error (torso lengths) per view, the methods side by side (the baseline among them).

use crate::bench_suite::{BenchClip, ViewFamily};
use std::collections::BTreeMap;
use videomocap_core::skeleton::{Joint, PerJoint};
use videomocap_testkit::eval::suite::Split;
use videomocap_testkit::eval::{Accuracy, ClipScore, is_limb_joint};

/// Per split and view, each method's per-joint accuracy summed over the clips.
#[derive(Debug, Clone)]
pub(crate) struct ViewTable {
    methods: Vec<&'static str>,
    cells: BTreeMap<(Split, ViewFamily), Vec<PerJoint<Accuracy>>>,
}

impl ViewTable {
    /// A table of `methods` (one score per method and clip, in this order).
    pub(crate) fn new(methods: &[&'static str]) -> ViewTable {
        ViewTable {
            methods: methods.to_vec(),
            cells: BTreeMap::new(),
        }
    }

    /// Adds a clip's scores, one per method.
    pub(crate) fn add(&mut self, clip: &BenchClip, scores: &[&ClipScore]) {
        let cell = self
            .cells
            .entry((clip.split, clip.view))
            .or_insert_with(|| vec![PerJoint::default(); self.methods.len()]);
        for (sum, s) in cell.iter_mut().zip(scores) {
            for j in Joint::ALL {
                sum[j].merge(&s.per_joint[j]);
            }
        }
    }

    /// The limb joints' (or all joints') samples of a per-joint sum.
    fn pooled(p: &PerJoint<Accuracy>, limbs: bool) -> Accuracy {
        let mut a = Accuracy::default();
        for j in Joint::ALL
            .into_iter()
            .filter(|&j| !limbs || is_limb_joint(j))
        {
            a.merge(&p[j]);
        }
        a
    }

    /// The split's views with clips, in table order.
    fn views(&self, split: Split) -> Vec<ViewFamily> {
        ViewFamily::ALL
            .into_iter()
            .filter(|v| self.cells.contains_key(&(split, *v)))
            .collect()
    }

    /// The tables as text: per split, PCK@0.1 / PCK@0.2 per view and method (13 limb joints,
    /// then all scored joints), then each joint's mean error per view and method.
    pub(crate) fn lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        for split in [Split::Dev, Split::Test] {
            let views = self.views(split);
            if views.is_empty() {
                continue;
            }
            for (limbs, what) in [(true, "13 limb joints"), (false, "all scored joints")] {
                lines.push(format!(
                    "{}, {what}, PCK@0.1 / PCK@0.2 per view (synthetic views pooled over their clips)",
                    split.name()
                ));
                let mut head = format!("{:<10}", "view");
                for m in &self.methods {
                    head += &format!(" {m:>13}");
                }
                lines.push(head);
                let mut all = vec![Accuracy::default(); self.methods.len()];
                for v in &views {
                    let mut row = format!("{:<10}", v.name());
                    for (k, p) in self.cells[&(split, *v)].iter().enumerate() {
                        let a = Self::pooled(p, limbs);
                        if *v != ViewFamily::Real {
                            all[k].merge(&a);
                        }
                        row += &format!(" {:>6.3}/{:>6.3}", a.pck01(), a.pck02());
                    }
                    lines.push(row);
                }
                let mut row = format!("{:<10}", "synthetic");
                for a in &all {
                    row += &format!(" {:>6.3}/{:>6.3}", a.pck01(), a.pck02());
                }
                lines.push(row);
                lines.push(String::new());
            }
            lines.push(format!(
                "{}, mean error per joint and view, torso lengths ({} per view)",
                split.name(),
                self.methods.join(" / ")
            ));
            let mut head = format!("{:<15}", "joint");
            for v in &views {
                head += &format!(" {:>w$}", v.name(), w = 6 * self.methods.len());
            }
            lines.push(head);
            for j in Joint::ALL {
                if views
                    .iter()
                    .all(|v| self.cells[&(split, *v)][0][j].count == 0)
                {
                    continue;
                }
                let mut row = format!("{:<15}", j.name());
                for v in &views {
                    for p in &self.cells[&(split, *v)] {
                        row += &format!(" {:>5.3}", p[j].mean_torso());
                    }
                }
                lines.push(row);
            }
            lines.push(String::new());
        }
        lines
    }

    /// Every cell as JSON: per split and view, per method, PCK@0.1/0.2 of the limb joints and
    /// each joint's mean error in torso lengths.
    pub(crate) fn json(&self) -> serde_json::Value {
        let mut out = serde_json::Map::new();
        for ((split, view), cell) in &self.cells {
            let methods: serde_json::Map<String, serde_json::Value> = self
                .methods
                .iter()
                .zip(cell)
                .map(|(m, p)| {
                    let limbs = Self::pooled(p, true);
                    let joints: serde_json::Map<String, serde_json::Value> = Joint::ALL
                        .iter()
                        .filter(|&&j| p[j].count > 0)
                        .map(|&j| (j.name().to_owned(), serde_json::json!(p[j].mean_torso())))
                        .collect();
                    (
                        (*m).to_owned(),
                        serde_json::json!({
                            "limbs_pck01": limbs.pck01(), "limbs_pck02": limbs.pck02(),
                            "mean_torso": joints,
                        }),
                    )
                })
                .collect();
            out.insert(
                format!("{} {}", split.name(), view.name()),
                serde_json::Value::Object(methods),
            );
        }
        serde_json::Value::Object(out)
    }
}
