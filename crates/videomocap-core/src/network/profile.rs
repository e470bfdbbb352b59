//! Where the network's time goes: tract's own evaluation loop run with a timer around each
//! operator (`SimpleState::run_plan_with_eval`), and the graph's operator counts at each stage
//! of loading (the ONNX file and the plan the product runs). Its figures are in
//! `docs/method.md` (issue 95).

use super::{INPUT_PX, NetworkError, PoseNetwork};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};
use tract_onnx::prelude::*;
use tract_onnx::tract_core::plan::{SimpleState, eval};

/// The time of one kind of operator in the optimised plan.
#[derive(Debug, Clone, PartialEq)]
pub struct OpTime {
    /// tract's name of the operator (e.g. `Optimized` for a fused matrix product,
    /// `DepthWiseConv`).
    pub op: String,
    /// How many nodes of the plan run it.
    pub nodes: usize,
    /// Median time per run of the network, milliseconds (each node's median, summed).
    pub ms: f64,
}

/// The network's profile (see the module's text).
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkProfile {
    /// Operator counts of the ONNX file as read (every output).
    pub onnx_ops: BTreeMap<String, usize>,
    /// Operator counts of the plan the product runs.
    pub plan_ops: BTreeMap<String, usize>,
    /// Time per operator kind, slowest first.
    pub times: Vec<OpTime>,
    /// Median time of a whole run, milliseconds (the timers' own cost included).
    pub run_ms: f64,
}

fn counts<'a>(names: impl Iterator<Item = std::borrow::Cow<'a, str>>) -> BTreeMap<String, usize> {
    let mut m = BTreeMap::new();
    for n in names {
        *m.entry(n.into_owned()).or_insert(0) += 1;
    }
    m
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

impl PoseNetwork {
    /// Profiles the bundled network on a fixed synthetic input, `runs` times after one warm-up
    /// run, on this network's threads.
    pub fn profile(&self, runs: usize) -> Result<NetworkProfile, NetworkError> {
        let run_err = |e: &dyn std::fmt::Display| NetworkError::Run(e.to_string());
        let onnx = tract_onnx::onnx()
            .model_for_read(&mut std::io::Cursor::new(super::BUNDLED))
            .map_err(|e| run_err(&e))?;
        let onnx_ops = counts(onnx.nodes().iter().map(|n| n.op().name()));
        let model = self.plan.model();
        let plan_ops = counts(model.nodes().iter().map(|n| n.op().name()));
        let input: Tensor = tract_ndarray::Array4::<f32>::from_shape_fn(
            (1, INPUT_PX, INPUT_PX, 3),
            |(_, y, x, c)| ((x * 7 + y * 3 + c * 11) % 255) as f32 / 255.0,
        )
        .into();
        let mut state = SimpleState::new(&self.plan).map_err(|e| run_err(&e))?;
        let mut per_node: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
        let mut whole = Vec::new();
        for r in 0..=runs.max(1) {
            let mut this: BTreeMap<usize, Duration> = BTreeMap::new();
            let t0 = Instant::now();
            let mut go = || {
                state.run_plan_with_eval(tvec!(input.clone().into()), |ctx, st, node, inputs| {
                    let t = Instant::now();
                    let out = eval(ctx, st, node, inputs);
                    *this.entry(node.id).or_default() += t.elapsed();
                    out
                })
            };
            match &self.pool {
                Some(pool) => multithread::multithread_tract_scope(pool.clone(), go),
                None => go(),
            }
            .map_err(|e| run_err(&e))?;
            if r > 0 {
                whole.push(t0.elapsed().as_secs_f64() * 1e3);
                for (id, d) in this {
                    per_node.entry(id).or_default().push(d.as_secs_f64() * 1e3);
                }
            }
        }
        let mut by_op: BTreeMap<String, (usize, f64)> = BTreeMap::new();
        for (id, times) in per_node {
            let e = by_op
                .entry(model.node(id).op().name().into_owned())
                .or_default();
            e.0 += 1;
            e.1 += median(times);
        }
        let mut times: Vec<OpTime> = by_op
            .into_iter()
            .map(|(op, (nodes, ms))| OpTime { op, nodes, ms })
            .collect();
        times.sort_by(|a, b| b.ms.total_cmp(&a.ms));
        Ok(NetworkProfile {
            onnx_ops,
            plan_ops,
            times,
            run_ms: median(whole),
        })
    }
}
