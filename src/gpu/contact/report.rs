//! The end of the contact step on the device (`shaders/contact_report.wgsl`): corrected velocities
//! and u_{n+1}, the work of the impulses, and the interface reports (impulse on the first body,
//! active slaves, largest penetration) by fixed-order reductions; its pipelines and dispatches.
//! CPU reference: the end of [`crate::contact::ContactSet::apply`] and
//! [`crate::contact::ContactSet::sample`] (`crate::contact::report`).

use super::kernels::stage_kernels;
use super::{groups, Dispatch};
use crate::gpu::reduce::TREE;

/// WGSL source (compiled after [`super::narrow::SOURCE`] and the sum tree, [`TREE`]).
pub const SOURCE: &str = include_str!("../../../shaders/contact_report.wgsl");

/// The report's shader module: its label and stage files (after contact_common.wgsl).
pub const MODULE: (&str, &[&str]) = ("contact_report", &[super::narrow::SOURCE, TREE, SOURCE]);

stage_kernels! {
    /// The report's pipelines (`finish`, `report_slots`, `report_end`).
    ReportKernels: finish, report_slots, report_end
}

impl ReportKernels {
    /// Records `finish` over the contact nodes, `report_slots` over the active slots and
    /// `report_end` in one workgroup.
    pub(crate) fn record(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.direct(pass, &self.finish, groups(d.params.n_local));
        d.active(pass, &self.report_slots);
        d.direct(pass, &self.report_end, 1);
    }
}
