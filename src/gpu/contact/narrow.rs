//! Contact narrow phase on the device (`shaders/contact_narrow.wgsl`): one thread per active slot
//! picks its constraint among its candidates (or against its wall), with the corner rule, the
//! penalty impulse and the Lagrange warm start; a per-node gather applies the penalty and
//! warm-start impulses in slot order. Its pipelines and dispatches, and the size of the
//! constraint records it writes. CPU reference: [`crate::contact::ContactSet::apply`] (its narrow
//! phase) and [`crate::contact::narrow`].

use super::kernels::stage_kernels;
use super::{groups, Dispatch};

/// WGSL source (also compiled into the solve module, whose re-check calls it).
pub const SOURCE: &str = include_str!("../../../shaders/contact_narrow.wgsl");

/// The narrow phase's shader module: its label and stage files (after contact_common.wgsl).
pub const MODULE: (&str, &[&str]) = ("contact_narrow", &[SOURCE]);

/// Bytes of WGSL `Cons`, the constraint the narrow phase writes per slot (device scratch, never
/// read by the host: no mirror).
pub const CONS_SIZE: u64 = 64;

stage_kernels! {
    /// The narrow phase's pipelines (`narrow`, `gather`).
    NarrowKernels: narrow, gather
}

impl NarrowKernels {
    /// Records the narrow phase over the active slots, then the gather over the contact nodes.
    pub(crate) fn record(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        d.active(pass, &self.narrow);
        d.direct(pass, &self.gather, groups(d.params.n_local));
    }
}
