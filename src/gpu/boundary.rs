//! Velocity boundary kernel (`shaders/boundary.wgsl`), compiled and dispatched only for scenes with
//! prescribed velocities. CPU reference: the `VelocityBoundaries` stage of
//! [`crate::step::cpu::CpuSolver`].

use super::shader::{compute_pipeline, Features};

/// WGSL source (with the load curves' evaluation).
pub const SOURCE: &str = concat!(
    include_str!("../../shaders/curve.wgsl"),
    include_str!("../../shaders/boundary.wgsl")
);

/// The load curves of `model` and the pressure curves after them, as the kernels read them
/// (`shaders/curve.wgsl`): a header (first point, point count, bitcast) per curve, then the
/// points; at least one entry. Returns the table and, per pressure load, its curve's index.
pub fn curve_table(model: &crate::model::Model) -> (Vec<[f32; 2]>, Vec<Option<u32>>) {
    let mut curves: Vec<&crate::scene::LoadCurve> = model.curves.iter().collect();
    let mut pressure = Vec::with_capacity(model.pressures.len());
    for p in &model.pressures {
        pressure.push(p.curve.as_ref().map(|c| {
            curves.push(c);
            (curves.len() - 1) as u32
        }));
    }
    let mut table = vec![[0.0f32; 2]; curves.len()];
    for (k, c) in curves.iter().enumerate() {
        let start = table.len() as u32;
        table[k] = [f32::from_bits(start), f32::from_bits(c.points.len() as u32)];
        table.extend(c.points.iter().map(|p| [p[0] as f32, p[1] as f32]));
    }
    if table.is_empty() {
        table.push([0.0; 2]);
    }
    (table, pressure)
}

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
