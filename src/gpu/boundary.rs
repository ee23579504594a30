//! Velocity boundary kernel (`shaders/boundary.wgsl`), compiled and dispatched only for scenes with
//! prescribed velocities. CPU reference: the `VelocityBoundaries` stage of
//! [`crate::step::cpu::CpuSolver`].

use super::kernels::{compute_pipeline, Features};

/// WGSL source.
pub const SOURCE: &str = include_str!("../../shaders/boundary.wgsl");

/// Threads per workgroup.
pub const WORKGROUP: u32 = 64;

pub(crate) fn pipeline(device: &wgpu::Device, features: Features) -> wgpu::ComputePipeline {
    compute_pipeline(
        device,
        "boundary",
        SOURCE,
        features,
        "main",
        Some(WORKGROUP),
    )
}
