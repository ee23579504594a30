//! Run control kernels (`shaders/control.wgsl`), one workgroup each: `control_dt` finishes the
//! stable-step reduction and sets dt^{n+1/2} and dt_n; `control_end` finishes the sample sums,
//! writes the history row, advances the time and decides the next step's flags, with the same
//! rules as [`crate::step::Clock`]. Failures (inverted element, non-finite node, step too large)
//! set the state to failed and every later dispatch returns at once. Small models on CPU adapters
//! reduce here directly, with the lanes' shares and trees of [`super::reduce`]
//! (`shaders/reduce_common.wgsl`, `shaders/tree.wgsl`).

use wgpu::{ComputePipeline, Device};

use super::shader::{compute_pipeline, Features};

/// WGSL source (the sum tree and the parts shared with [`super::reduce`] first).
pub const SOURCE: &str = concat!(
    include_str!("../../shaders/tree.wgsl"),
    include_str!("../../shaders/reduce_common.wgsl"),
    include_str!("../../shaders/control.wgsl")
);

/// The pipeline of entry point `entry` (`control_dt`, `control_end`), in a workgroup of
/// [`Features::control_group`] threads (its WGSL `RG`; the first level of the reductions keeps
/// [`Features::reduce_group`]).
///
/// On lavapipe each group of 8 lanes of a workgroup runs as a coroutine, and each barrier of the
/// trees switches all of them: the 10^4 pile's `control_dt` and `control_end` (both reducing
/// directly, `state::FUSED_LIMIT`) took 33-53 us a step less at 8 threads than at 64, of about
/// 1 400 (BENCHMARKS.md, 2026-11-29).
pub(crate) fn pipeline(device: &Device, features: Features, entry: &str) -> ComputePipeline {
    let control = Features {
        reduce_group: features.control_group,
        ..features
    };
    compute_pipeline(device, entry, SOURCE, control, entry, None)
}
