//! The compiled kernels of a scene (stateless; built once from the device and the plan's
//! features), kept apart from the simulation buffers in [`super::state::GpuState`].

pub use super::shader::Features;
use super::{boundary, contact, control, element, loads, node, reduce};

/// Compute pipelines for one combination of features.
#[derive(Debug)]
pub struct Kernels {
    /// Features compiled in.
    pub features: Features,
    /// Element stage.
    pub element: wgpu::ComputePipeline,
    /// First level of the stable-step minimum.
    pub min_dt: wgpu::ComputePipeline,
    /// Second level and step control.
    pub control_dt: wgpu::ComputePipeline,
    /// Node stage.
    pub node: wgpu::ComputePipeline,
    /// Velocity boundaries (only for scenes that have them).
    pub boundary: Option<wgpu::ComputePipeline>,
    /// Contact (only for scenes with contact or rigid walls).
    pub contact: Option<contact::ContactKernels>,
    /// Pressure forces (only for scenes with pressure loads).
    pub pressure: Option<wgpu::ComputePipeline>,
    /// Work of pressure and damping impulses (only for scenes with either; `features.loads`).
    pub load_work: Option<wgpu::ComputePipeline>,
    /// First level of the sample sums.
    pub sum: wgpu::ComputePipeline,
    /// Second level of the sample sums, one workgroup per instance.
    pub sum_instances: wgpu::ComputePipeline,
    /// Second level of the sums, history row, time and flags.
    pub control_end: wgpu::ComputePipeline,
}

impl Kernels {
    /// Compiles the kernels a scene needs.
    pub fn new(
        device: &wgpu::Device,
        features: Features,
        boundaries: bool,
        contact: bool,
        pressure: bool,
    ) -> Self {
        Self {
            features,
            element: element::pipeline(device, features),
            min_dt: reduce::pipeline(device, features, "min_dt"),
            control_dt: control::pipeline(device, features, "control_dt"),
            node: node::pipeline(device, features),
            boundary: boundaries.then(|| boundary::pipeline(device, features)),
            contact: contact.then(|| contact::ContactKernels::new(device, features)),
            pressure: pressure.then(|| loads::pipeline(device, features, "pressure_force")),
            load_work: features
                .loads
                .then(|| loads::pipeline(device, features, "load_work")),
            sum: reduce::pipeline(device, features, "sum"),
            sum_instances: reduce::pipeline(device, features, "sum_instances"),
            control_end: control::pipeline(device, features, "control_end"),
        }
    }

    /// Every kernel source with its name, for validation (the contact stages with their shared
    /// contact declarations; `shader::source` prepends `common.wgsl`).
    pub fn sources() -> Vec<(&'static str, String)> {
        let c = |parts: &[&str]| {
            let mut s = String::from(contact::COMMON);
            for p in parts {
                s.push('\n');
                s.push_str(p);
            }
            s
        };
        let mut v: Vec<(&'static str, String)> = contact::MODULES
            .iter()
            .map(|(label, parts)| (*label, c(parts)))
            .collect();
        v.extend([
            ("loads", loads::SOURCE.into()),
            ("element", element::SOURCE.into()),
            ("node", node::SOURCE.into()),
            ("boundary", boundary::SOURCE.into()),
            ("reduce", reduce::SOURCE.into()),
            ("control", control::SOURCE.into()),
        ]);
        v
    }
}
