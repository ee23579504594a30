//! Run control kernels (`shaders/control.wgsl`), one workgroup each: `control_dt` finishes the
//! stable-step reduction and sets dt^{n+1/2} and dt_n; `control_end` finishes the sample sums,
//! writes the history row, advances the time and decides the next step's flags, with the same
//! rules as [`crate::step::Clock`]. Failures (inverted element, non-finite node, step too large)
//! set the state to failed and every later dispatch returns at once.

use super::shader::{compute_pipeline, Features};

/// WGSL source.
pub const SOURCE: &str = include_str!("../../shaders/control.wgsl");

pub(crate) fn dt_pipeline(device: &wgpu::Device, features: Features) -> wgpu::ComputePipeline {
    compute_pipeline(device, "control_dt", SOURCE, features, "control_dt", None)
}

pub(crate) fn end_pipeline(device: &wgpu::Device, features: Features) -> wgpu::ComputePipeline {
    compute_pipeline(device, "control_end", SOURCE, features, "control_end", None)
}
