//! The end of the contact step on the device (`shaders/contact_report.wgsl`): corrected velocities
//! and u_{n+1}, the work of the impulses, and the interface reports (impulse on the first body,
//! active slaves, largest penetration) by fixed-order reductions; its pipelines and dispatches.
//! CPU reference: the end of [`crate::contact::ContactSet::apply`] and
//! [`crate::contact::ContactSet::sample`] (`crate::contact::report`).

use super::kernels::{module, pipeline, Layouts};
use super::{groups, Dispatch};
use crate::gpu::kernels::Features;

/// WGSL source.
pub const SOURCE: &str = include_str!("../../../shaders/contact_report.wgsl");

/// The report's shader module: its label and stage files (after contact_common.wgsl).
pub const MODULE: (&str, &[&str]) = ("contact_report", &[super::narrow::SOURCE, SOURCE]);

/// The report's pipelines.
#[derive(Debug)]
pub struct ReportKernels {
    finish: wgpu::ComputePipeline,
    report_slots: wgpu::ComputePipeline,
    report_end: wgpu::ComputePipeline,
}

impl ReportKernels {
    /// Compiles the report kernels.
    pub(crate) fn new(device: &wgpu::Device, layouts: &Layouts, features: Features) -> Self {
        let m = module(device, MODULE, features);
        ReportKernels {
            finish: pipeline(device, &m, &layouts.main, "finish"),
            report_slots: pipeline(device, &m, &layouts.main, "report_slots"),
            report_end: pipeline(device, &m, &layouts.main, "report_end"),
        }
    }

    /// Records `finish` over the contact nodes, `report_slots` over the active slots and
    /// `report_end` in one workgroup.
    pub(crate) fn record(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.direct(pass, &self.finish, groups(d.params.n_local));
        d.active(pass, &self.report_slots);
        d.direct(pass, &self.report_end, 1);
    }
}
