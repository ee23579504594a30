//! Element stage kernel (`shaders/element.wgsl`): stress, hourglass and bulk-viscosity forces per
//! element, the element stable step, and on sample steps the element energies; the mirrors of its
//! `Body` (with the Johnson-Cook thermal softening and heating), `Element` and `Failure` and their
//! tables from the model. The CPU reference is
//! [`crate::element::evaluate`] (and, for failure, [`crate::element::failure`] with the erosion of
//! [`crate::step::cpu`]); `tests/gpu.rs` compares the two on random inputs.

use bytemuck::{Pod, Zeroable};

use super::shader::{compute_pipeline, Features};
use crate::model::Model;
use crate::scene::{Formulation, HourglassForm, MaterialModel};

/// WGSL source.
pub const SOURCE: &str = include_str!("../../shaders/element.wgsl");

/// Threads per workgroup.
pub const WORKGROUP: u32 = 64;

/// Mirror of WGSL `Body`: a body's material and element parameters (fields documented in
/// `shaders/element.wgsl`).
#[allow(missing_docs)]
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBody {
    pub model: u32,
    pub formulation: u32,
    pub hourglass: u32,
    pub _pad0: u32,
    pub density: f32,
    pub thickness: f32,
    pub lambda: f32,
    pub mu: f32,
    pub lambda_plane: f32,
    pub wave_modulus: f32,
    pub hourglass_coefficient: f32,
    pub bulk_linear: f32,
    pub bulk_quadratic: f32,
    pub mass: f32,
    pub yield_stress: f32,
    pub hardening: f32,
    pub jc_b: f32,
    pub jc_n: f32,
    pub jc_c: f32,
    pub jc_rate0: f32,
    pub jc_m: f32,
    pub melt_rise: f32,
    pub heating: f32,
    pub _pad1: u32,
}

/// Mirror of WGSL `Element`: corners relative to the centre, nodes, body (fields documented in
/// `shaders/element.wgsl`).
#[allow(missing_docs)]
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuElement {
    pub c01: [f32; 4],
    pub c23: [f32; 4],
    pub nodes: [u32; 4],
    pub body: u32,
    pub radius: f32,
    pub _pad: [u32; 2],
}

/// Mirror of WGSL `Failure`: a body's failure criteria (fields documented in
/// `shaders/element.wgsl`; all zero for a body whose material has none).
#[allow(missing_docs)]
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuFailure {
    pub flags: u32,
    pub plastic_strain: f32,
    pub principal_strain: f32,
    pub tensile_pressure: f32,
    pub d1: f32,
    pub d2: f32,
    pub d3: f32,
    pub d4: f32,
    pub d5: f32,
    pub rate0: f32,
    pub inverted: u32,
    /// `run.erosion.min_time_step` over `time_step_scale` (s): an element whose stable step falls
    /// below it erodes (0: never).
    pub min_dt: f32,
}

/// The erosion state's fourth word of an element eroded about to invert (`run.erosion.inverted`).
pub const ERODED_INVERTED: f32 = 1.0;
/// The erosion state's fourth word of an element eroded for a stable step below
/// `run.erosion.min_time_step`.
pub const ERODED_SMALL_STEP: f32 = 2.0;

/// `GpuFailure::flags`: an equivalent plastic strain limit.
pub const FAIL_PLASTIC: u32 = 1;
/// `GpuFailure::flags`: Johnson-Cook damage.
pub const FAIL_JOHNSON_COOK: u32 = 2;
/// `GpuFailure::flags`: a largest principal strain limit.
pub const FAIL_PRINCIPAL: u32 = 4;
/// `GpuFailure::flags`: a spall (tensile mean stress) limit.
pub const FAIL_TENSILE: u32 = 8;

const _: () = assert!(std::mem::size_of::<GpuBody>() == 96);
const _: () = assert!(std::mem::size_of::<GpuFailure>() == 48);
const _: () = assert!(std::mem::size_of::<GpuElement>() == 64);

pub(crate) fn pipeline(device: &wgpu::Device, features: Features) -> wgpu::ComputePipeline {
    compute_pipeline(device, "element", SOURCE, features, "main", Some(WORKGROUP))
}

/// The bodies of `model` as the kernel reads them.
pub fn bodies(model: &Model) -> Vec<GpuBody> {
    model
        .bodies
        .iter()
        .map(|b| {
            let p = &b.params;
            GpuBody {
                model: match p.model {
                    MaterialModel::LinearElastic => 0,
                    MaterialModel::NeoHookean => 1,
                    MaterialModel::J2Plastic => 2,
                },
                formulation: match p.formulation {
                    Formulation::PlaneStrain => 0,
                    Formulation::PlaneStress => 1,
                    Formulation::Axisymmetric => 2,
                },
                hourglass: match p.hourglass {
                    HourglassForm::None => 0,
                    HourglassForm::Viscous => 1,
                    HourglassForm::Stiffness => 2,
                },
                density: p.density as f32,
                thickness: p.thickness as f32,
                lambda: p.lambda as f32,
                mu: p.mu as f32,
                lambda_plane: p.lambda_plane as f32,
                wave_modulus: p.wave_modulus as f32,
                hourglass_coefficient: p.hourglass_coefficient as f32,
                bulk_linear: p.bulk_linear as f32,
                bulk_quadratic: p.bulk_quadratic as f32,
                mass: b.mass as f32,
                yield_stress: p.yield_stress.min(f32::MAX as f64) as f32,
                hardening: p.hardening as f32,
                jc_b: p.jc_b as f32,
                jc_n: p.jc_n as f32,
                jc_c: p.jc_c as f32,
                jc_rate0: p.jc_rate0 as f32,
                jc_m: p.jc_m as f32,
                melt_rise: p.melt_rise as f32,
                heating: p.heating as f32,
                ..Default::default()
            }
        })
        .collect()
}

/// The failure criteria of `model`'s bodies as the kernel reads them (for scenes with failure or
/// `run.erosion.inverted`, which every body's `inverted` carries).
pub fn failures(model: &Model) -> Vec<GpuFailure> {
    let inverted = u32::from(model.erode_inverted);
    let min_dt = model.erode_min_dt as f32;
    model
        .bodies
        .iter()
        .map(|b| {
            let Some(c) = b.params.failure else {
                return GpuFailure {
                    inverted,
                    min_dt,
                    ..Default::default()
                };
            };
            let mut g = GpuFailure {
                inverted,
                min_dt,
                ..Default::default()
            };
            if let Some(x) = c.plastic_strain {
                g.flags |= FAIL_PLASTIC;
                g.plastic_strain = x as f32;
            }
            if let Some(d) = c.johnson_cook {
                g.flags |= FAIL_JOHNSON_COOK;
                g.d1 = d.d1 as f32;
                g.d2 = d.d2 as f32;
                g.d3 = d.d3 as f32;
                g.d4 = d.d4 as f32;
                g.d5 = d.d5 as f32;
                g.rate0 = d.reference_strain_rate as f32;
            }
            if let Some(x) = c.principal_strain {
                g.flags |= FAIL_PRINCIPAL;
                g.principal_strain = x as f32;
            }
            if let Some(x) = c.tensile_pressure {
                g.flags |= FAIL_TENSILE;
                g.tensile_pressure = x as f32;
            }
            g
        })
        .collect()
}

/// The elements of `model` as the kernel reads them.
pub fn elements(model: &Model) -> Vec<GpuElement> {
    (0..model.element_count())
        .map(|e| {
            let c = model.corners[e];
            GpuElement {
                c01: [
                    c[0][0] as f32,
                    c[0][1] as f32,
                    c[1][0] as f32,
                    c[1][1] as f32,
                ],
                c23: [
                    c[2][0] as f32,
                    c[2][1] as f32,
                    c[3][0] as f32,
                    c[3][1] as f32,
                ],
                nodes: model.quads[e],
                body: model.element_body[e],
                radius: model.radius.get(e).copied().unwrap_or(0.0) as f32,
                _pad: [0; 2],
            }
        })
        .collect()
}
