//! Element stage kernel (`shaders/element.wgsl`): stress, hourglass and bulk-viscosity forces per
//! element, the element stable step, and on sample steps the element energies. The CPU reference
//! is [`crate::element::evaluate`]; `tests/gpu.rs` compares the two on random inputs.

use super::shader::{compute_pipeline, Features};

/// WGSL source.
pub const SOURCE: &str = include_str!("../../shaders/element.wgsl");

/// Threads per workgroup.
pub const WORKGROUP: u32 = 64;

pub(crate) fn pipeline(device: &wgpu::Device, features: Features) -> wgpu::ComputePipeline {
    compute_pipeline(device, "element", SOURCE, features, "main", Some(WORKGROUP))
}
