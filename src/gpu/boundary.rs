//! Velocity boundary kernel (`shaders/boundary.wgsl`), compiled and dispatched only for scenes with
//! prescribed velocities; the mirror of its `Constraint` and the load curves' table (shared with
//! the pressure loads). CPU reference: the `VelocityBoundaries` stage of
//! [`crate::step::cpu::CpuSolver`].

use bytemuck::{Pod, Zeroable};

use super::shader::{compute_pipeline, Features};
use crate::model::Model;

/// WGSL source (with the load curves' evaluation).
pub const SOURCE: &str = concat!(
    include_str!("../../shaders/curve.wgsl"),
    include_str!("../../shaders/boundary.wgsl")
);

/// The load curves of `model` and the pressure curves after them, as the kernels read them
/// (`shaders/curve.wgsl`): a header (first point, point count, bitcast) per curve, then the
/// points; at least one entry. Returns the table and, per pressure load, its curve's index.
pub fn curve_table(model: &Model) -> (Vec<[f32; 2]>, Vec<Option<u32>>) {
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

/// Mirror of WGSL `Constraint`: a node's prescribed velocities (fields documented in
/// `shaders/boundary.wgsl`).
#[allow(missing_docs)]
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuConstraint {
    pub node: u32,
    pub mask: u32,
    pub vx: f32,
    pub vy: f32,
    pub mass: f32,
    pub curve_x: u32,
    pub curve_y: u32,
    pub _pad: f32,
}

const _: () = assert!(std::mem::size_of::<GpuConstraint>() == 32);

/// The velocity boundaries of `model` as the kernel reads them.
pub fn constraints(model: &Model) -> Vec<GpuConstraint> {
    model
        .constraints
        .iter()
        .map(|c| GpuConstraint {
            node: c.node,
            mask: u32::from(c.vx.is_some()) | (u32::from(c.vy.is_some()) << 1),
            vx: c.vx.unwrap_or(0.0) as f32,
            vy: c.vy.unwrap_or(0.0) as f32,
            mass: model.mass[c.node as usize] as f32,
            curve_x: c.cx.unwrap_or(u32::MAX),
            curve_y: c.cy.unwrap_or(u32::MAX),
            _pad: 0.0,
        })
        .collect()
}

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
