//! The network's graph made cheaper to run before tract compiles it (issue 95; the profile and
//! the measurements are in `docs/method.md`). Both steps leave the numbers the product reads
//! as they were (a test compares them with the model run plainly):
//! - only the outputs read are kept, so that the layers that make only the segmentation mask
//!   (256 × 256) and the 64 × 64 heatmaps are dropped (5 resizes, 10 depthwise and 11
//!   pointwise convolutions);
//! - the convolutions run with the channels last. The converted file is NCHW inside (ONNX's
//!   convolutions are), and tract's depthwise kernel is vectorised across channels only when
//!   they are the innermost axis; turned per plane it took half the run.

use tract_onnx::prelude::*;
use tract_onnx::tract_core::ops::change_axes::{AxisChange, AxisOp};
use tract_onnx::tract_core::ops::cnn::Conv;
use tract_onnx::tract_core::ops::nn::DataFormat;
use tract_onnx::tract_core::optim::change_axes::change_axes;

/// Keeps only the model's outputs whose sizes are `sizes` (in any order), each once.
pub(crate) fn keep_read_outputs(model: &mut TypedModel, sizes: &[usize]) -> TractResult<()> {
    let mut read = Vec::new();
    for &outlet in &model.outputs {
        let fact = model.outlet_fact(outlet)?;
        let size = fact
            .shape
            .as_concrete()
            .map(|s| s.iter().product::<usize>());
        if size.is_some_and(|n| sizes.contains(&n)) {
            read.push(outlet);
        }
    }
    if read.len() != sizes.len() {
        return Err(TractError::msg(format!(
            "expected outputs of {sizes:?} values among {:?}",
            model.outputs
        )));
    }
    model.select_output_outlets(&read)
}

/// Turns every convolution that reads its channels first (NCHW, CHW) to read them last, one
/// at a time, each change carried through the graph by tract's own axis-change rules (the
/// element-wise operators follow, the matrix products absorb it); a change tract cannot carry
/// is left out. The model's inputs and outputs keep their layout.
pub(crate) fn channels_last(model: &mut TypedModel) -> TractResult<()> {
    let mut tried = std::collections::HashSet::new();
    // Each applied change turns one more convolution; the bound only guards against a cycle.
    for _ in 0..model.nodes().len() {
        let interfaces: Vec<OutletId> = model
            .input_outlets()?
            .iter()
            .chain(model.output_outlets()?.iter())
            .copied()
            .collect();
        let mut patch = None;
        for node in model.nodes() {
            let Some(conv) = node.op_as::<Conv>() else {
                continue;
            };
            let (c, last) = match conv.pool_spec.data_format {
                DataFormat::CHW => (0, 2),
                DataFormat::NCHW => (1, 3),
                DataFormat::HWC | DataFormat::NHWC => continue,
            };
            let Some(&input) = node.inputs.first() else {
                continue;
            };
            let change = AxisChange {
                outlet: input,
                op: AxisOp::Move(c, last),
            };
            if !tried.insert(change.clone()) {
                continue;
            }
            let mut explored = Default::default();
            if let Some((p, _)) = change_axes(model, &change, &interfaces, &[], &mut explored)? {
                patch = Some(p);
                break;
            }
        }
        let Some(patch) = patch else { break };
        patch.apply(model)?;
        tried.clear();
    }
    model.compact()?;
    model.declutter()
}
